#ifndef MRATTLE_RIGID_BODY_INTEGRATOR_PROXY_H_
#define MRATTLE_RIGID_BODY_INTEGRATOR_PROXY_H_

#include "RigidBodyIntegratorSerialization.h"
#include "openmm/Integrator.h"
#include "openmm/serialization/SerializationProxy.h"
#include "internal/windowsExportMRattle.h"
#include <memory>
#include <string>

namespace MRattlePlugin {

/**
 * XmlSerializer support for a RigidBodyIntegrator subclass T: one proxy for the whole
 * family (all registered when libMRattlePlugin is loaded, in
 * MRattleSerializationProxyRegistration.cpp, under the class's name). It writes "version",
 * T's own settings, then the shared ones (RigidBodyIntegratorSerialization); it reads
 * them back in the same order. An integrator whose only constructor argument is the step
 * size needs nothing more; one with settings of its own specializes writeOwnSettings()
 * and create() in MRattleSerializationProxyRegistration.cpp, before the registration.
 */
template <class T>
class RigidBodyIntegratorProxy : public OpenMM::SerializationProxy {
public:
    /** The version written; deserialize() reads versions 1 to this. */
    static const int Version = 1;
    /** @param typeName  the name the XML uses for T (its class name) */
    explicit RigidBodyIntegratorProxy(const std::string& typeName) : SerializationProxy(typeName) {
    }
    void serialize(const void* object, OpenMM::SerializationNode& node) const override {
        // XmlSerializer passes the object as the type it was given (usually Integrator*); with
        // single inheritance that is the same address as the T.
        const T& integrator = *static_cast<const T*>(reinterpret_cast<const OpenMM::Integrator*>(object));
        node.setIntProperty("version", Version);
        writeOwnSettings(integrator, node);
        RigidBodyIntegratorSerialization::serialize(integrator, node);
    }
    void* deserialize(const OpenMM::SerializationNode& node) const override {
        RigidBodyIntegratorSerialization::checkVersion(node, getTypeName(), Version);
        std::unique_ptr<T> integrator(create(node, getTypeName()));
        RigidBodyIntegratorSerialization::deserialize(node, getTypeName(), *integrator);
        return static_cast<OpenMM::Integrator*>(integrator.release());
    }

private:
    /** T's own settings, written before the shared ones: none unless specialized. */
    static void writeOwnSettings(const T& /*integrator*/, OpenMM::SerializationNode& /*node*/) {
    }
    /** A new T with node's own settings: by default, constructed from the step size. */
    static T* create(const OpenMM::SerializationNode& node, const std::string& typeName) {
        return new T(RigidBodyIntegratorSerialization::getStepSize(node, typeName));
    }
};

} // namespace MRattlePlugin

#endif
