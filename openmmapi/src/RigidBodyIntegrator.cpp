#include "RigidBodyIntegrator.h"
#include "internal/OpenMMVersionCheck.h"
#include "internal/RigidBodyCheckpointHeader.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/CompoundIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {
/** 2 KE / (dof k_B); 0 without degrees of freedom. */
double temperatureOf(double kineticEnergy, double dof) {
    return dof > 0 ? 2 * kineticEnergy / (dof * BOLTZ) : 0.0;
}

} // namespace

RigidBodyIntegrator::RigidBodyIntegrator(const RigidBodyIntegratorName& names) : names(&names) {
    setConstraintTolerance(1e-5);
}

const char* RigidBodyIntegrator::getIntegratorName() const {
    return names->integrator;
}

RigidBodyStepKernel& RigidBodyIntegrator::getStepKernel() const {
    requireContext();
    return kernel.getAs<RigidBodyStepKernel>();
}

RigidBodyState& RigidBodyIntegrator::state() const {
    return kernel.getAs<RigidBodyStepKernel>().getState();
}

void RigidBodyIntegrator::setStepSize(double size) {
    if (!std::isfinite(size))
        throw OpenMMException("setStepSize: the step size must be a finite number of picoseconds, got " +
                              std::to_string(size));
    Integrator::setStepSize(size);
}

void RigidBodyIntegrator::setConstraintTolerance(double tolerance) {
    if (!(tolerance > 0) || !std::isfinite(tolerance))
        throw OpenMMException("setConstraintTolerance: the tolerance must be a finite positive number, got " +
                              std::to_string(tolerance));
    Integrator::setConstraintTolerance(tolerance);
}

int RigidBodyIntegrator::addRigidBody(const vector<int>& particles) {
    if (owner != nullptr)
        throw OpenMMException("addRigidBody: bodies cannot be added once the integrator is bound to a Context");
    RigidBodyTopology::checkBodyDefinition(declaredBodies.size(), particles);
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

const RigidBodyTopology& RigidBodyIntegrator::getTopology() const {
    requireContext();
    return topology;
}

const vector<vector<int> >& RigidBodyIntegrator::getBodiesInEffect() const {
    return getTopology().getBodies();
}

int RigidBodyIntegrator::getNumBodiesInEffect() const {
    return getTopology().getNumBodies();
}

bool RigidBodyIntegrator::isBodyLinear(int index) const {
    if (index < 0 || index >= getTopology().getNumBodies())
        throw OpenMMException("isBodyLinear: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(topology.getNumBodies()) + " bodies in effect)");
    return state().isBodyLinear(index);
}

const vector<int>& RigidBodyIntegrator::getFreeParticles() const {
    return getTopology().getFreeParticles();
}

vector<int> RigidBodyIntegrator::getLargeDefaultBodies() const {
    vector<int> large;
    if (!declaredBodies.empty())
        return large;
    const RigidBodyTopology& bound = getTopology();
    for (int b = 0; b < bound.getNumBodies(); b++)
        if ((int) bound.getBodyParticles(b).size() > LargeBodyAtoms)
            large.push_back(b);
    return large;
}

int RigidBodyIntegrator::getNumDegreesOfFreedom() const {
    return getTopology().getNumDegreesOfFreedom(state().getBodyDegreesOfFreedom());
}

double RigidBodyIntegrator::computeSystemTemperature() {
    requireContext();
    return temperatureOf(computeKineticEnergy(), getNumDegreesOfFreedom());
}

double RigidBodyIntegrator::kineticEnergyPart(int part) {
    requireContext();
    double energies[3];
    state().computeKineticEnergies(*context, energies[0], energies[1], energies[2]);
    return energies[part];
}

double RigidBodyIntegrator::computeTranslationalKineticEnergy() {
    return kineticEnergyPart(0);
}

double RigidBodyIntegrator::computeRotationalKineticEnergy() {
    return kineticEnergyPart(1);
}

double RigidBodyIntegrator::computeFreeKineticEnergy() {
    return kineticEnergyPart(2);
}

double RigidBodyIntegrator::getTranslationalDegreesOfFreedom() const {
    return getTopology().getTranslationalDegreesOfFreedom();
}

int RigidBodyIntegrator::getRotationalDegreesOfFreedom() const {
    return getTopology().getRotationalDegreesOfFreedom(state().getBodyDegreesOfFreedom());
}

double RigidBodyIntegrator::getFreeDegreesOfFreedom() const {
    return getTopology().getFreeDegreesOfFreedom();
}


double RigidBodyIntegrator::computeTranslationalTemperature() {
    return temperatureOf(computeTranslationalKineticEnergy(), getTranslationalDegreesOfFreedom());
}

double RigidBodyIntegrator::computeRotationalTemperature() {
    return temperatureOf(computeRotationalKineticEnergy(), getRotationalDegreesOfFreedom());
}

double RigidBodyIntegrator::computeFreeTemperature() {
    return temperatureOf(computeFreeKineticEnergy(), getFreeDegreesOfFreedom());
}

void RigidBodyIntegrator::requireNonNegativeSetting(const char* integrator, const char* what, const char* unit,
                                                    double value, bool zeroAllowed) {
    if (!std::isfinite(value) || value < 0 || (value == 0 && !zeroAllowed))
        throw OpenMMException(std::string(integrator) + ": the " + what + " must be a finite number " +
                              (zeroAllowed ? ">= 0 " : "> 0 ") + unit + ", got " + std::to_string(value));
}

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != nullptr && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    checkOpenMMVersion(Platform::getOpenMMVersion());
    const System& system = contextRef.getSystem();
    topology = RigidBodyTopology(system, declaredBodies, contextRef.getMolecules());
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = contextRef.getPlatform().createKernel(names->stepKernel, contextRef);
    kernel.getAs<RigidBodyStepKernel>().initialize(system, topology, *this);
    stepState.reset();
}

void RigidBodyIntegrator::cleanup() {
    kernel = Kernel();
}

vector<std::string> RigidBodyIntegrator::getKernelNames() {
    return {names->stepKernel};
}

bool RigidBodyIntegrator::isCurrentIntegrator() const {
    const Integrator* integrator = &context->getIntegrator();
    // Members of a CompoundIntegrator (possibly nested) all hear stateChanged(); one steps.
    while (const CompoundIntegrator* compound = dynamic_cast<const CompoundIntegrator*>(integrator))
        integrator = &compound->getIntegrator(compound->getCurrentIntegrator());
    return integrator == this;
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    stepState.invalidateForces();
    if (context == nullptr || (minimizing && changed == State::Positions))
        return;
    // OpenMM's last notification of a checkpoint load: continue as the run that wrote it.
    if (changed == State::Energy && stepState.finishCheckpointLoad(context->getStepCount()))
        return;
    if (changed == State::Positions)
        useNewPositions();
    if (changed == State::Positions || changed == State::Velocities)
        useNewVelocities(changed == State::Positions);
}

void RigidBodyIntegrator::useNewPositions() {
    try {
        state().updateShapes(*context);
    } catch (const OpenMMException& e) {
        stepState.positionsRefused();
        throw OpenMMException(std::string("setPositions: ") + e.what() + "; the integrator will not step until "
                              "finite positions are set");
    }
    stepState.positionsAccepted();
}

void RigidBodyIntegrator::useNewVelocities(bool byPositions) {
    // Velocities the user sets are made rigid at once, so what the Context reports is what
    // the integrator uses; rigid ones (a checkpoint's, a saved State's) are kept bit for bit.
    if (stepState.velocitiesChanged(byPositions, isCurrentIntegrator()) != RigidBodyStepState::VelocityUse::ProjectNow)
        return;
    try {
        state().projectVelocities(*context, getConstraintTolerance());
    } catch (const OpenMMException& e) {
        // The kernel left the velocities as they were. Name the call that raised it.
        stepState.velocitiesRefused();
        if (byPositions)
            throw OpenMMException(std::string("setPositions: the Context's velocities (set before these positions) "
                                              "cannot be made rigid at them: ") + e.what() +
                                  "; the integrator will not step until velocities are set again");
        throw OpenMMException(std::string("setVelocities: ") + e.what() + "; the integrator will not step until "
                              "finite velocities are set");
    }
}

void RigidBodyIntegrator::createCheckpoint(std::ostream& stream) const {
    requireContext();
    std::ostringstream kernelState;
    state().createCheckpoint(*context, kernelState);
    RigidBodyCheckpointHeader::write(stream, names->stepKernel, topology, kernelState.str());
}

void RigidBodyIntegrator::loadCheckpoint(std::istream& stream) {
    requireContext();
    try {
        std::istringstream kernelState(RigidBodyCheckpointHeader::read(stream, names->stepKernel, topology));
        state().loadCheckpoint(*context, kernelState);
    } catch (const OpenMMException& e) {
        // OpenMM has already read its own part unchecked: positions, velocities, time, box,
        // parameters and its platform's random state (garbage there crashes a later step).
        // Only Context::reinitialize() rebuilds all of it, so stepping waits for it (or for
        // a checkpoint that fits); meanwhile the platform's unchecked state is made valid.
        stepState.checkpointRefused();
        state().discardRefusedCheckpoint(*context);
        throw OpenMMException(RigidBodyStepState::refusedCheckpointMessage(e.what()));
    }
    stepState.checkpointLoaded();
}

double RigidBodyIntegrator::computeKineticEnergy() {
    return state().computeKineticEnergy(*context);
}

vector<Vec3> RigidBodyIntegrator::getVelocitiesForTemperature(const System& system, double temperature,
                                                               int randomSeed) const {
    requireContext();
    if (!(temperature >= 0) || !std::isfinite(temperature))
        throw OpenMMException("setVelocitiesToTemperature: the temperature must be a finite number >= 0, got " +
                              std::to_string(temperature));
    if (!stepState.havePositions())
        throw OpenMMException("setVelocitiesToTemperature: set the positions first: rigid-body velocities depend on them");
    return state().getVelocitiesForTemperature(*context, temperature, randomSeed,
                                                                       getConstraintTolerance());
}

void RigidBodyIntegrator::step(int steps) {
    requireContext();
    stepState.requireSteppable(getStepSize());
    try {
        stepLoop(steps);
        state().finishSteps(*context);
    } catch (...) {
        // A failed step found late is the cause of anything else that went wrong after it.
        stepState.invalidateForces();
        state().finishSteps(*context);
        throw;
    }
}

void RigidBodyIntegrator::stepLoop(int steps) {
    for (int i = 0; i < steps; i++) {
        // Another integrator (of a CompoundIntegrator) stepped since this one did, or
        // velocities were set while it was not current: this integrator's bodies decide
        // now, before a thermostat's collisions (which the kernel must see as such).
        if (stepState.mustProjectBeforeStep(context->getStepCount())) {
            state().projectVelocities(*context, getConstraintTolerance());
            stepState.projectedBeforeStep();
        }
        // A getState() may have overwritten the forces with other force groups.
        if (context->updateContextState() || context->getLastForceGroups() != getIntegrationForceGroups())
            stepState.invalidateForces();
        kernel.getAs<RigidBodyStepKernel>().execute(*context, *this, stepState.forcesAreValid());
        stepState.stepTaken(context->getStepCount());
    }
}
