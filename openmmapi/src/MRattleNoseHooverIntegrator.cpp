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
    if (chainLength < 1)
        throw OpenMMException(std::string(ClassName) + ": the chain length must be 1 or more, got " +
                              std::to_string(chainLength));
    if (numMTS < 1)
        throw OpenMMException(std::string(ClassName) + ": the number of multiple time steps must be 1 or more, got " +
                              std::to_string(numMTS));
    if (!RigidBodyThermostats::isSupportedYoshidaSuzukiOrder(numYoshidaSuzuki))
        throw OpenMMException(std::string(ClassName) + ": the number of Yoshida-Suzuki time steps must be 1, 3, 5 or 7, got " +
                              std::to_string(numYoshidaSuzuki));
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
