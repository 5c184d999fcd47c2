#include "MRattleLangevinIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

MRattleLangevinIntegrator::MRattleLangevinIntegrator(double temperature, double frictionCoeff, double stepSize)
    : RigidBodyIntegrator(IntegratorNames::MRattleLangevin) {
    setTemperature(temperature);
    setFriction(frictionCoeff);
    setStepSize(stepSize);
}

void MRattleLangevinIntegrator::setTemperature(double value) {
    requireNonNegativeSetting(getIntegratorName(), "temperature", "K", value);
    temperature = value;
}

void MRattleLangevinIntegrator::setFriction(double coeff) {
    requireNonNegativeSetting(getIntegratorName(), "friction", "/ps", coeff);
    friction = coeff;
}
