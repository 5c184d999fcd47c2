#include "MRattleBussiIntegratorProxy.h"
#include "openmm/OpenMMException.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

// MRattleBussiIntegrator's own settings in its XML: temperature, collision frequency, random seed.

template <>
void RigidBodyIntegratorProxy<MRattleBussiIntegrator>::writeOwnSettings(const MRattleBussiIntegrator& integrator,
                                                                        SerializationNode& node) {
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("collisionFrequency", integrator.getCollisionFrequency());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
}

template <>
MRattleBussiIntegrator* RigidBodyIntegratorProxy<MRattleBussiIntegrator>::create(const SerializationNode& node,
                                                                                 const std::string& typeName) {
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", typeName);
    const double frequency = RigidBodyIntegratorSerialization::getDouble(node, "collisionFrequency", typeName);
    // Outside the try: its message already names the type.
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    std::unique_ptr<MRattleBussiIntegrator> integrator;
    try {
        integrator.reset(new MRattleBussiIntegrator(temperature, frequency, stepSize));
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", typeName));
    return integrator.release();
}
