#include "MRattleNoseHooverIntegratorProxy.h"
#include "openmm/OpenMMException.h"
#include <memory>

using namespace MRattlePlugin;
using namespace OpenMM;

// MRattleNoseHooverIntegrator's own settings in its XML: temperature, collision frequency,
// chain length, multiple time steps and Yoshida-Suzuki order.

template <>
void RigidBodyIntegratorProxy<MRattleNoseHooverIntegrator>::writeOwnSettings(
    const MRattleNoseHooverIntegrator& integrator, SerializationNode& node) {
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("collisionFrequency", integrator.getCollisionFrequency());
    node.setIntProperty("chainLength", integrator.getChainLength());
    node.setIntProperty("numMTS", integrator.getNumMultiTimeSteps());
    node.setIntProperty("numYoshidaSuzuki", integrator.getNumYoshidaSuzukiTimeSteps());
}

template <>
MRattleNoseHooverIntegrator* RigidBodyIntegratorProxy<MRattleNoseHooverIntegrator>::create(
    const SerializationNode& node, const std::string& typeName) {
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", typeName);
    const double frequency = RigidBodyIntegratorSerialization::getDouble(node, "collisionFrequency", typeName);
    const int chainLength = RigidBodyIntegratorSerialization::getInteger(node, "chainLength", typeName);
    const int numMTS = RigidBodyIntegratorSerialization::getInteger(node, "numMTS", typeName);
    const int numYoshidaSuzuki = RigidBodyIntegratorSerialization::getInteger(node, "numYoshidaSuzuki", typeName);
    // Outside the try: its message already names the type.
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    try {
        return new MRattleNoseHooverIntegrator(temperature, frequency, stepSize, chainLength, numMTS, numYoshidaSuzuki);
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
}
