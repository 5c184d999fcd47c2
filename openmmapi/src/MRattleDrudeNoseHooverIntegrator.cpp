#include "MRattleDrudeNoseHooverIntegrator.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"
#include "openmm/OpenMMException.h"
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
    if (chainLength < 1)
        throw OpenMMException(std::string(ClassName) + ": the chain length must be 1 or more, got " +
                              std::to_string(chainLength));
    if (numMTS < 1)
        throw OpenMMException(std::string(ClassName) + ": the number of multiple time steps must be 1 or more, got " +
                              std::to_string(numMTS));
    if (!RigidBodyThermostats::isSupportedYoshidaSuzukiOrder(numYoshidaSuzuki))
        throw OpenMMException(std::string(ClassName) +
                              ": the number of Yoshida-Suzuki time steps must be 1, 3, 5 or 7, got " +
                              std::to_string(numYoshidaSuzuki));
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

double MRattleDrudeNoseHooverIntegrator::relativeKineticEnergy(int& numDrudes) {
    return DrudeGroups::contextRelativeKineticEnergy(*context, getTopology(), getIntegratorName(), numDrudes);
}

double MRattleDrudeNoseHooverIntegrator::computeDrudeTemperature() {
    int numDrudes;
    const double relative = relativeKineticEnergy(numDrudes);
    return DrudeGroups::drudeTemperature(relative, numDrudes);
}

double MRattleDrudeNoseHooverIntegrator::computeBodyTemperature() {
    int numDrudes;
    const double relative = relativeKineticEnergy(numDrudes);
    return DrudeGroups::bodyTemperature(computeKineticEnergy(), relative, getNumDegreesOfFreedom(), numDrudes);
}

double MRattleDrudeNoseHooverIntegrator::computeHeatBathEnergy() {
    return getStepKernel().computeHeatBathEnergy(*context, *this);
}
