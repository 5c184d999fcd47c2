#include "RigidSplittingIntegratorProxy.h"
#include "RigidSplittingIntegrator.h"
#include "RigidBodyIntegratorSerialization.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

static const char* const TypeName = "RigidSplittingIntegrator";

RigidSplittingIntegratorProxy::RigidSplittingIntegratorProxy() : SerializationProxy(TypeName) {
}

void RigidSplittingIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    // XmlSerializer passes the object as the type it was given (usually Integrator*); with
    // single inheritance that is the same address as the RigidSplittingIntegrator.
    const RigidSplittingIntegrator& integrator = *static_cast<const RigidSplittingIntegrator*>(reinterpret_cast<const Integrator*>(object));
    node.setIntProperty("version", Version);
    RigidBodyIntegratorSerialization::serialize(integrator, node);
}

void* RigidSplittingIntegratorProxy::deserialize(const SerializationNode& node) const {
    RigidBodyIntegratorSerialization::checkVersion(node, TypeName, Version);
    std::unique_ptr<RigidSplittingIntegrator> integrator(
        new RigidSplittingIntegrator(RigidBodyIntegratorSerialization::getStepSize(node, TypeName)));
    RigidBodyIntegratorSerialization::deserialize(node, TypeName, *integrator);
    return static_cast<Integrator*>(integrator.release());
}
