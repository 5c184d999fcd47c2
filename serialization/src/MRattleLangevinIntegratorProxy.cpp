#include "MRattleLangevinIntegratorProxy.h"
#include "openmm/OpenMMException.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

// MRattleLangevinIntegrator's own settings in its XML: temperature, friction, random seed.

template <>
void RigidBodyIntegratorProxy<MRattleLangevinIntegrator>::writeOwnSettings(const MRattleLangevinIntegrator& integrator,
                                                                           SerializationNode& node) {
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("friction", integrator.getFriction());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
}

template <>
MRattleLangevinIntegrator* RigidBodyIntegratorProxy<MRattleLangevinIntegrator>::create(const SerializationNode& node,
                                                                                       const std::string& typeName) {
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", typeName);
    const double friction = RigidBodyIntegratorSerialization::getDouble(node, "friction", typeName);
    // Outside the try: its message already names the type.
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    std::unique_ptr<MRattleLangevinIntegrator> integrator;
    try {
        integrator.reset(new MRattleLangevinIntegrator(temperature, friction, stepSize));
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", typeName));
    return integrator.release();
}
