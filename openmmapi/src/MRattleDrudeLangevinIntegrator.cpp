#include "MRattleDrudeLangevinIntegrator.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

MRattleDrudeLangevinIntegrator::MRattleDrudeLangevinIntegrator(double temperature, double frictionCoeff,
                                                               double drudeTemperature, double drudeFrictionCoeff,
                                                               double stepSize)
    : RigidBodyIntegrator(IntegratorNames::MRattleDrudeLangevin) {
    setTemperature(temperature);
    setFriction(frictionCoeff);
    setDrudeTemperature(drudeTemperature);
    setDrudeFriction(drudeFrictionCoeff);
    setStepSize(stepSize);
}

void MRattleDrudeLangevinIntegrator::setTemperature(double value) {
    requireNonNegativeSetting(getIntegratorName(), "temperature", "K", value);
    temperature = value;
}

void MRattleDrudeLangevinIntegrator::setFriction(double coeff) {
    requireNonNegativeSetting(getIntegratorName(), "friction", "/ps", coeff);
    friction = coeff;
}

void MRattleDrudeLangevinIntegrator::setDrudeTemperature(double value) {
    requireNonNegativeSetting(getIntegratorName(), "Drude temperature", "K", value);
    drudeTemperature = value;
}

void MRattleDrudeLangevinIntegrator::setDrudeFriction(double coeff) {
    requireNonNegativeSetting(getIntegratorName(), "Drude friction", "/ps", coeff);
    drudeFriction = coeff;
}

void MRattleDrudeLangevinIntegrator::setMaxDrudeDistance(double distance) {
    requireNonNegativeSetting(getIntegratorName(), "maximum Drude distance", "nm", distance);
    maxDrudeDistance = distance;
}

double MRattleDrudeLangevinIntegrator::computeDrudeTemperature() {
    int numDrudes;
    const double relative = getStepKernel().computeDrudeKineticEnergy(*context, numDrudes);
    return DrudeGroups::drudeTemperature(relative, numDrudes);
}

double MRattleDrudeLangevinIntegrator::computeBodyTemperature() {
    int numDrudes;
    const double relative = getStepKernel().computeDrudeKineticEnergy(*context, numDrudes);
    return DrudeGroups::bodyTemperature(computeKineticEnergy(), relative, getNumDegreesOfFreedom(), numDrudes);
}

std::vector<Vec3> MRattleDrudeLangevinIntegrator::getVelocitiesForTemperature(const System& system, double temperature, int randomSeed) const {
    std::vector<Vec3> velocities = RigidBodyIntegrator::getVelocitiesForTemperature(system, temperature, randomSeed);
    DrudeGroups::scaleRelativeMotion(*context, getTopology(), getIntegratorName(),
                                     temperature > 0 ? std::sqrt(drudeTemperature / temperature) : 0.0, velocities);
    return velocities;
}
