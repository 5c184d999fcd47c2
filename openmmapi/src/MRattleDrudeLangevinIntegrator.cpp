#include "MRattleDrudeLangevinIntegrator.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <vector>

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

double MRattleDrudeLangevinIntegrator::relativeKineticEnergy(int& numDrudes) {
    // From the Context's arrays on any platform: a host computation, as a reporter's.
    const RigidBodyTopology& bodies = getTopology();
    const System& system = context->getSystem();
    const DrudeGroups groups(system, bodies, getIntegratorName());
    std::vector<Vec3> x, v;
    context->getPositions(x);
    context->getVelocities(v);
    std::vector<double> masses(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        masses[i] = system.getParticleMass(i);
    numDrudes = groups.getNumDrudeParticles();
    return groups.relativeKineticEnergy(x, v, masses);
}

double MRattleDrudeLangevinIntegrator::computeDrudeTemperature() {
    int numDrudes;
    const double energy = relativeKineticEnergy(numDrudes);
    return numDrudes == 0 ? 0.0 : 2 * energy / (3 * numDrudes * BOLTZ);
}

double MRattleDrudeLangevinIntegrator::computeBodyTemperature() {
    int numDrudes;
    const double relative = relativeKineticEnergy(numDrudes);
    const int dof = getNumDegreesOfFreedom() - 3 * numDrudes;
    return dof <= 0 ? 0.0 : 2 * (computeKineticEnergy() - relative) / (dof * BOLTZ);
}
