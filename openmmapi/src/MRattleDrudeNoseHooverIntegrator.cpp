#include "MRattleDrudeNoseHooverIntegrator.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {
const char* const ClassName = IntegratorNames::MRattleDrudeNoseHoover.integrator;
}

MRattleDrudeNoseHooverIntegrator::MRattleDrudeNoseHooverIntegrator(double temperature, double collisionFrequency,
                                                                   double drudeTemperature,
                                                                   double drudeCollisionFrequency, double stepSize,
                                                                   int chainLength, int numMTS, int numYoshidaSuzuki)
    : RigidBodyIntegrator(IntegratorNames::MRattleDrudeNoseHoover), chainLength(chainLength), numMTS(numMTS),
      numYoshidaSuzuki(numYoshidaSuzuki) {
    setTemperature(temperature);
    setCollisionFrequency(collisionFrequency);
    setDrudeTemperature(drudeTemperature);
    setDrudeCollisionFrequency(drudeCollisionFrequency);
    setStepSize(stepSize);
    RigidBodyThermostats::requireChainSettings(ClassName, chainLength, numMTS, numYoshidaSuzuki);
}

void MRattleDrudeNoseHooverIntegrator::setTemperature(double value) {
    requireNonNegativeSetting(ClassName, "temperature", "K", value, false);
    temperature = value;
}

void MRattleDrudeNoseHooverIntegrator::setCollisionFrequency(double frequency) {
    requireNonNegativeSetting(ClassName, "collision frequency", "/ps", frequency);
    collisionFrequency = frequency;
}

void MRattleDrudeNoseHooverIntegrator::setDrudeTemperature(double value) {
    requireNonNegativeSetting(ClassName, "Drude temperature", "K", value, false);
    drudeTemperature = value;
}

void MRattleDrudeNoseHooverIntegrator::setDrudeCollisionFrequency(double frequency) {
    requireNonNegativeSetting(ClassName, "Drude collision frequency", "/ps", frequency);
    drudeCollisionFrequency = frequency;
}

void MRattleDrudeNoseHooverIntegrator::setMaxDrudeDistance(double distance) {
    requireNonNegativeSetting(ClassName, "maximum Drude distance", "nm", distance);
    maxDrudeDistance = distance;
}

double MRattleDrudeNoseHooverIntegrator::computeDrudeTemperature() {
    int numDrudes;
    const double relative = getStepKernel().computeDrudeKineticEnergy(*context, numDrudes);
    return DrudeGroups::drudeTemperature(relative, numDrudes);
}

double MRattleDrudeNoseHooverIntegrator::computeBodyTemperature() {
    int numDrudes;
    const double relative = getStepKernel().computeDrudeKineticEnergy(*context, numDrudes);
    return DrudeGroups::bodyTemperature(computeKineticEnergy(), relative, getNumDegreesOfFreedom(), numDrudes);
}

double MRattleDrudeNoseHooverIntegrator::computeHeatBathEnergy() {
    return getStepKernel().computeHeatBathEnergy(*context, *this);
}

std::vector<Vec3> MRattleDrudeNoseHooverIntegrator::getVelocitiesForTemperature(const System& system, double temperature, int randomSeed) const {
    std::vector<Vec3> velocities = RigidBodyIntegrator::getVelocitiesForTemperature(system, temperature, randomSeed);
    DrudeGroups::scaleRelativeMotion(*context, getTopology(), getIntegratorName(),
                                     temperature > 0 ? std::sqrt(drudeTemperature / temperature) : 0.0, velocities);
    return velocities;
}
