#include "MRattleBussiIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <limits>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {
const char* const ClassName = IntegratorNames::MRattleBussi.integrator;
}

MRattleBussiIntegrator::MRattleBussiIntegrator(double temperature, double collisionFrequency, double stepSize)
    : RigidBodyIntegrator(IntegratorNames::MRattleBussi) {
    setTemperature(temperature);
    setCollisionFrequency(collisionFrequency);
    setStepSize(stepSize);
}

void MRattleBussiIntegrator::setTemperature(double value) {
    requireNonNegativeSetting(ClassName, "temperature", "K", value);
    temperature = value;
}

void MRattleBussiIntegrator::setCollisionFrequency(double frequency) {
    requireNonNegativeSetting(ClassName, "collision frequency", "/ps", frequency);
    collisionFrequency = frequency;
}

double MRattleBussiIntegrator::getTimeConstant() const {
    return collisionFrequency == 0 ? std::numeric_limits<double>::infinity() : 1 / collisionFrequency;
}

void MRattleBussiIntegrator::setTimeConstant(double tau) {
    if (!(tau > 0))  // NaN too
        throw OpenMMException(std::string(ClassName) + ": the time constant must be a number > 0 ps (infinity: "
                              "no coupling), got " + std::to_string(tau));
    setCollisionFrequency(std::isinf(tau) ? 0.0 : 1 / tau);
}

double MRattleBussiIntegrator::computeHeatBathEnergy() {
    return getStepKernel().computeHeatBathEnergy(*context, *this);
}
