#include "MRattleLangevinIntegratorProxy.h"
#include "MRattleLangevinIntegrator.h"
#include "RigidBodyIntegratorSerialization.h"
#include "openmm/OpenMMException.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

static const char* const TypeName = "MRattleLangevinIntegrator";

MRattleLangevinIntegratorProxy::MRattleLangevinIntegratorProxy() : SerializationProxy(TypeName) {
}

void MRattleLangevinIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    const MRattleLangevinIntegrator& integrator =
        *static_cast<const MRattleLangevinIntegrator*>(reinterpret_cast<const Integrator*>(object));
    node.setIntProperty("version", Version);
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("friction", integrator.getFriction());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
    RigidBodyIntegratorSerialization::serialize(integrator, node);
}

void* MRattleLangevinIntegratorProxy::deserialize(const SerializationNode& node) const {
    RigidBodyIntegratorSerialization::checkVersion(node, TypeName, Version);
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", TypeName);
    const double friction = RigidBodyIntegratorSerialization::getDouble(node, "friction", TypeName);
    // Outside the try: its message already names the type.
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, TypeName);
    std::unique_ptr<MRattleLangevinIntegrator> integrator;
    try {
        integrator.reset(new MRattleLangevinIntegrator(temperature, friction, stepSize));
    } catch (const OpenMMException& e) {
        throw OpenMMException(std::string(TypeName) + " XML: " + e.what());
    }
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", TypeName));
    RigidBodyIntegratorSerialization::deserialize(node, TypeName, *integrator);
    return static_cast<Integrator*>(integrator.release());
}
