#include "MRattleBussiIntegrator.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "MRattleIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "RigidBodyIntegratorProxy.h"
#include "RigidSplittingIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/serialization/SerializationProxy.h"
#include "internal/windowsExportMRattle.h"
#include <memory>

// The proxies are registered when the library is loaded, as OpenMM does for its own
// plugins: from DllMain on Windows, from a constructor function elsewhere.
#if defined(WIN32)
#include <windows.h>
extern "C" OPENMM_EXPORT_MRATTLE void registerMRattleSerializationProxies();
BOOL WINAPI DllMain(HANDLE hModule, DWORD reason, LPVOID reserved) {
    if (reason == DLL_PROCESS_ATTACH)
        registerMRattleSerializationProxies();
    return TRUE;
}
#else
extern "C" OPENMM_EXPORT_MRATTLE void __attribute__((constructor)) registerMRattleSerializationProxies();
#endif

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** An integrator from its XML settings: a setting its constructor refuses is reported as the XML's. */
template <class T, class... Arguments>
std::unique_ptr<T> construct(const std::string& typeName, Arguments... arguments) {
    try {
        return std::unique_ptr<T>(new T(arguments...));
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
}

} // namespace

// The settings of their own of the integrators that have some (the template's defaults
// serve the others): written before the shared ones, read back in the same order. The
// step size is read last, outside construct(): its message already names the type.

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
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    auto integrator = construct<MRattleLangevinIntegrator>(typeName, temperature, friction, stepSize);
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", typeName));
    return integrator.release();
}

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
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    return construct<MRattleNoseHooverIntegrator>(typeName, temperature, frequency, stepSize, chainLength, numMTS,
                                                  numYoshidaSuzuki)
        .release();
}

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
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    auto integrator = construct<MRattleBussiIntegrator>(typeName, temperature, frequency, stepSize);
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", typeName));
    return integrator.release();
}

template <>
void RigidBodyIntegratorProxy<MRattleDrudeLangevinIntegrator>::writeOwnSettings(
    const MRattleDrudeLangevinIntegrator& integrator, SerializationNode& node) {
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("friction", integrator.getFriction());
    node.setDoubleProperty("drudeTemperature", integrator.getDrudeTemperature());
    node.setDoubleProperty("drudeFriction", integrator.getDrudeFriction());
    node.setDoubleProperty("maxDrudeDistance", integrator.getMaxDrudeDistance());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
}

template <>
MRattleDrudeLangevinIntegrator* RigidBodyIntegratorProxy<MRattleDrudeLangevinIntegrator>::create(
    const SerializationNode& node, const std::string& typeName) {
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", typeName);
    const double friction = RigidBodyIntegratorSerialization::getDouble(node, "friction", typeName);
    const double drudeTemperature = RigidBodyIntegratorSerialization::getDouble(node, "drudeTemperature", typeName);
    const double drudeFriction = RigidBodyIntegratorSerialization::getDouble(node, "drudeFriction", typeName);
    const double maxDrudeDistance = RigidBodyIntegratorSerialization::getDouble(node, "maxDrudeDistance", typeName);
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    auto integrator = construct<MRattleDrudeLangevinIntegrator>(typeName, temperature, friction, drudeTemperature,
                                                                drudeFriction, stepSize);
    try {
        integrator->setMaxDrudeDistance(maxDrudeDistance);
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
    integrator->setRandomNumberSeed(RigidBodyIntegratorSerialization::getInteger(node, "randomSeed", typeName));
    return integrator.release();
}

template <>
void RigidBodyIntegratorProxy<MRattleDrudeNoseHooverIntegrator>::writeOwnSettings(
    const MRattleDrudeNoseHooverIntegrator& integrator, SerializationNode& node) {
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("collisionFrequency", integrator.getCollisionFrequency());
    node.setDoubleProperty("drudeTemperature", integrator.getDrudeTemperature());
    node.setDoubleProperty("drudeCollisionFrequency", integrator.getDrudeCollisionFrequency());
    node.setDoubleProperty("maxDrudeDistance", integrator.getMaxDrudeDistance());
    node.setIntProperty("chainLength", integrator.getChainLength());
    node.setIntProperty("numMTS", integrator.getNumMultiTimeSteps());
    node.setIntProperty("numYoshidaSuzuki", integrator.getNumYoshidaSuzukiTimeSteps());
}

template <>
MRattleDrudeNoseHooverIntegrator* RigidBodyIntegratorProxy<MRattleDrudeNoseHooverIntegrator>::create(
    const SerializationNode& node, const std::string& typeName) {
    const double temperature = RigidBodyIntegratorSerialization::getDouble(node, "temperature", typeName);
    const double frequency = RigidBodyIntegratorSerialization::getDouble(node, "collisionFrequency", typeName);
    const double drudeTemperature = RigidBodyIntegratorSerialization::getDouble(node, "drudeTemperature", typeName);
    const double drudeFrequency = RigidBodyIntegratorSerialization::getDouble(node, "drudeCollisionFrequency", typeName);
    const double maxDrudeDistance = RigidBodyIntegratorSerialization::getDouble(node, "maxDrudeDistance", typeName);
    const int chainLength = RigidBodyIntegratorSerialization::getInteger(node, "chainLength", typeName);
    const int numMTS = RigidBodyIntegratorSerialization::getInteger(node, "numMTS", typeName);
    const int numYoshidaSuzuki = RigidBodyIntegratorSerialization::getInteger(node, "numYoshidaSuzuki", typeName);
    const double stepSize = RigidBodyIntegratorSerialization::getStepSize(node, typeName);
    auto integrator = construct<MRattleDrudeNoseHooverIntegrator>(typeName, temperature, frequency, drudeTemperature,
                                                                  drudeFrequency, stepSize, chainLength, numMTS,
                                                                  numYoshidaSuzuki);
    try {
        integrator->setMaxDrudeDistance(maxDrudeDistance);
    } catch (const OpenMMException& e) {
        throw OpenMMException(typeName + " XML: " + e.what());
    }
    return integrator.release();
}

/** Register the XML proxy of a RigidBodyIntegrator subclass under its class name: one line per integrator. */
#define MRATTLE_REGISTER_PROXY(CLASS) \
    SerializationProxy::registerProxy(typeid(CLASS), new RigidBodyIntegratorProxy<CLASS>(#CLASS))

extern "C" OPENMM_EXPORT_MRATTLE void registerMRattleSerializationProxies() {
    MRATTLE_REGISTER_PROXY(MRattleIntegrator);
    MRATTLE_REGISTER_PROXY(RigidSplittingIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleLangevinIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleNoseHooverIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleBussiIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleDrudeLangevinIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleDrudeNoseHooverIntegrator);
}
