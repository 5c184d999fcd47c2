#include "MRattleBussiIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <limits>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {
const char* const ClassName = "MRattleBussiIntegrator";
}

MRattleBussiIntegrator::MRattleBussiIntegrator(double temperature, double collisionFrequency, double stepSize) {
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
    Kernel& kernel = getBoundKernel();
    return kernel.getAs<IntegrateMRattleBussiStepKernel>().computeHeatBathEnergy(*context);
}

std::string MRattleBussiIntegrator::getStepKernelName() const {
    return IntegrateMRattleBussiStepKernel::Name();
}

void MRattleBussiIntegrator::executeStep(Kernel& kernel, ContextImpl& context, bool& forcesAreValid) {
    kernel.getAs<IntegrateMRattleBussiStepKernel>().execute(context, *this, forcesAreValid);
}

// The key function of this integrator's kernel interface (its vtable lives in this library).
IntegrateMRattleBussiStepKernel::~IntegrateMRattleBussiStepKernel() {
}
