#include "RigidBodyIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <random>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

RigidBodyIntegrator::RigidBodyIntegrator() {
    setConstraintTolerance(1e-5);
}

int RigidBodyIntegrator::addRigidBody(const vector<int>& particles) {
    if (owner != nullptr)
        throw OpenMMException("addRigidBody: bodies cannot be added once the integrator is bound to a Context");
    RigidBodySet::checkBodyDefinition(declaredBodies.size(), particles);
    declaredBodies.push_back(particles);
    return declaredBodies.size() - 1;
}

int RigidBodyIntegrator::getNumRigidBodies() const {
    return declaredBodies.size();
}

const vector<int>& RigidBodyIntegrator::getRigidBodyParticles(int index) const {
    if (index < 0 || index >= (int) declaredBodies.size())
        throw OpenMMException("getRigidBodyParticles: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(declaredBodies.size()) + " bodies declared)");
    return declaredBodies[index];
}

void RigidBodyIntegrator::requireContext() const {
    if (context == nullptr)
        throw OpenMMException("This Integrator is not bound to a context!");
}

const RigidBodySet& RigidBodyIntegrator::getRigidBodySet() const {
    requireContext();
    return bodySet;
}

const vector<vector<int> >& RigidBodyIntegrator::getBodiesInEffect() const {
    return getRigidBodySet().getBodies();
}

int RigidBodyIntegrator::getNumBodiesInEffect() const {
    return getRigidBodySet().getNumBodies();
}

bool RigidBodyIntegrator::isBodyLinear(int index) const {
    const RigidBodySet& set = getRigidBodySet();
    if (index < 0 || index >= set.getNumBodies())
        throw OpenMMException("isBodyLinear: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(set.getNumBodies()) + " bodies in effect)");
    return set.isLinear(index);
}

const vector<int>& RigidBodyIntegrator::getFreeParticles() const {
    return getRigidBodySet().getFreeParticles();
}

int RigidBodyIntegrator::getNumDegreesOfFreedom() const {
    return getRigidBodySet().getNumDegreesOfFreedom();
}

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != nullptr && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    const System& system = contextRef.getSystem();
    bodySet = RigidBodySet(system, declaredBodies, contextRef.getMolecules());
    hasVelocityChangingForce = false;
    for (int i = 0; i < system.getNumForces(); i++)
        if (dynamic_cast<const AndersenThermostat*>(&system.getForce(i)) != nullptr)
            hasVelocityChangingForce = true;
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = contextRef.getPlatform().createKernel(getStepKernelName(), contextRef);
    kernel.getAs<RigidBodyKernel>().initialize(system, bodySet);
    forcesAreValid = false;
    restoringCheckpoint = false;
}

void RigidBodyIntegrator::cleanup() {
    kernel = Kernel();
}

vector<std::string> RigidBodyIntegrator::getKernelNames() {
    return {getStepKernelName()};
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    forcesAreValid = false;
    if (context == nullptr || inProjection)
        return;
    if (changed == State::Positions) {
        vector<Vec3> positions;
        context->getPositions(positions);
        bodySet.updateShapes(positions);
    }
    if (changed == State::Energy)
        restoringCheckpoint = false;  // the last notification of a checkpoint load
    // Velocities the user sets are made rigid at once, so what the Context reports is
    // what the integrator uses. A checkpoint holds velocities that are already rigid:
    // projecting them again would change them at round-off and break exact restarts.
    if ((changed == State::Positions || changed == State::Velocities) && !restoringCheckpoint) {
        inProjection = true;
        kernel.getAs<RigidBodyKernel>().projectContextVelocities(*context, getConstraintTolerance());
        inProjection = false;
    }
}

void RigidBodyIntegrator::loadCheckpoint(std::istream& stream) {
    restoringCheckpoint = true;
}

double RigidBodyIntegrator::computeKineticEnergy() {
    return kernel.getAs<RigidBodyKernel>().computeKineticEnergy(*context);
}

vector<Vec3> RigidBodyIntegrator::getVelocitiesForTemperature(const System& system, double temperature,
                                                               int randomSeed) const {
    requireContext();
    if (!(temperature >= 0) || !std::isfinite(temperature))
        throw OpenMMException("setVelocitiesToTemperature: the temperature must be a finite number >= 0, got " +
                              std::to_string(temperature));
    // Maxwell-Boltzmann per particle, then the rigid-body projection (which keeps the
    // distribution's form on the rigid degrees of freedom), then an exact rescale to the
    // requested kinetic temperature with the rigid-body degrees of freedom.
    std::mt19937_64 generator(randomSeed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    const int numParticles = system.getNumParticles();
    vector<Vec3> velocities(numParticles, Vec3());
    for (int i = 0; i < numParticles; i++) {
        double mass = system.getParticleMass(i);
        if (mass != 0 && !system.isVirtualSite(i)) {
            double scale = std::sqrt(BOLTZ * temperature / mass);
            double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * scale;
        }
    }
    kernel.getAs<RigidBodyKernel>().projectVelocities(*context, velocities, getConstraintTolerance());
    double totalMass = 0;
    Vec3 momentum;
    for (int i = 0; i < numParticles; i++) {
        totalMass += system.getParticleMass(i);
        momentum += velocities[i] * system.getParticleMass(i);
    }
    if (bodySet.removesCenterOfMassMotion() && totalMass > 0) {
        Vec3 centerVelocity = momentum / totalMass;
        for (int i = 0; i < numParticles; i++)
            if (system.getParticleMass(i) != 0)
                velocities[i] -= centerVelocity;
    }
    double kinetic = 0;
    for (int i = 0; i < numParticles; i++)
        kinetic += 0.5 * system.getParticleMass(i) * velocities[i].dot(velocities[i]);
    int dof = bodySet.getNumDegreesOfFreedom();
    if (kinetic > 0 && dof > 0) {
        double scale = std::sqrt(0.5 * dof * BOLTZ * temperature / kinetic);
        for (Vec3& v : velocities)
            v *= scale;
    }
    return velocities;
}

void RigidBodyIntegrator::beginStep() {
    restoringCheckpoint = false;
    if (getStepSize() == 0 || !std::isfinite(getStepSize()))
        throw OpenMMException("The step size must be a finite nonzero number of picoseconds, got " +
                              std::to_string(getStepSize()));
    if (context->updateContextState())
        forcesAreValid = false;
    if (hasVelocityChangingForce)
        kernel.getAs<RigidBodyKernel>().projectContextVelocities(*context, getConstraintTolerance());
}

void RigidBodyIntegrator::ensureForces() {
    if (!forcesAreValid || context->getLastForceGroups() != getIntegrationForceGroups())
        computeForces();
}

void RigidBodyIntegrator::computeForces() {
    context->calcForcesAndEnergy(true, false, getIntegrationForceGroups());
    forcesAreValid = true;
}
