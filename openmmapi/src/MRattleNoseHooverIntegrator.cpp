#include "MRattleNoseHooverIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"
#include "openmm/OpenMMException.h"
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {
const char* const ClassName = IntegratorNames::MRattleNoseHoover.integrator;
}

MRattleNoseHooverIntegrator::MRattleNoseHooverIntegrator(double temperature, double collisionFrequency,
                                                         double stepSize, int chainLength, int numMTS,
                                                         int numYoshidaSuzuki)
    : RigidBodyIntegrator(IntegratorNames::MRattleNoseHoover), chainLength(chainLength), numMTS(numMTS),
      numYoshidaSuzuki(numYoshidaSuzuki) {
    setTemperature(temperature);
    setCollisionFrequency(collisionFrequency);
    setStepSize(stepSize);
    RigidBodyThermostats::requireChainSettings(ClassName, chainLength, numMTS, numYoshidaSuzuki);
}

void MRattleNoseHooverIntegrator::setTemperature(double value) {
    requireNonNegativeSetting(ClassName, "temperature", "K", value, false);
    temperature = value;
}

void MRattleNoseHooverIntegrator::setCollisionFrequency(double frequency) {
    requireNonNegativeSetting(ClassName, "collision frequency", "/ps", frequency);
    collisionFrequency = frequency;
}

double MRattleNoseHooverIntegrator::computeHeatBathEnergy() {
    return getStepKernel().computeHeatBathEnergy(*context, *this);
}
