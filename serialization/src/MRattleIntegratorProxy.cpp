#include "MRattleIntegratorProxy.h"
#include "MRattleIntegrator.h"
#include "RigidBodyIntegratorSerialization.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

static const char* const TypeName = "MRattleIntegrator";

MRattleIntegratorProxy::MRattleIntegratorProxy() : SerializationProxy(TypeName) {
}

void MRattleIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    // XmlSerializer passes the object as the type it was given (usually Integrator*); with
    // single inheritance that is the same address as the MRattleIntegrator.
    const MRattleIntegrator& integrator = *static_cast<const MRattleIntegrator*>(reinterpret_cast<const Integrator*>(object));
    node.setIntProperty("version", Version);
    RigidBodyIntegratorSerialization::serialize(integrator, node);
}

void* MRattleIntegratorProxy::deserialize(const SerializationNode& node) const {
    RigidBodyIntegratorSerialization::checkVersion(node, TypeName, Version);
    std::unique_ptr<MRattleIntegrator> integrator(
        new MRattleIntegrator(RigidBodyIntegratorSerialization::getStepSize(node, TypeName)));
    RigidBodyIntegratorSerialization::deserialize(node, TypeName, *integrator);
    return static_cast<Integrator*>(integrator.release());
}
