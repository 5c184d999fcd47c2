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

/** What to do after a refused checkpoint, in the refusal and in every refused step after it. */
const char* const RefusedCheckpointRecovery =
    "OpenMM had already loaded its own part of that checkpoint (positions, velocities, time, box, parameters, random "
    "state), which may be damaged: call Context::reinitialize() (without preserving the state), then set the state "
    "again (Context::setState() with a saved State, or positions and velocities), or load a checkpoint that fits. "
    "The integrator will not step until then";

} // namespace

RigidBodyIntegrator::RigidBodyIntegrator() {
    setConstraintTolerance(1e-5);
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
    return kernel.getAs<const RigidBodyKernel>().isBodyLinear(index);
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
    return getTopology().getNumDegreesOfFreedom(kernel.getAs<const RigidBodyKernel>().getBodyDegreesOfFreedom());
}

double RigidBodyIntegrator::computeSystemTemperature() {
    requireContext();
    return temperatureOf(computeKineticEnergy(), getNumDegreesOfFreedom());
}

double RigidBodyIntegrator::kineticEnergyPart(int part) {
    requireContext();
    double energies[3];
    kernel.getAs<RigidBodyKernel>().computeKineticEnergies(*context, energies[0], energies[1], energies[2]);
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
    return getTopology().getRotationalDegreesOfFreedom(kernel.getAs<const RigidBodyKernel>().getBodyDegreesOfFreedom());
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

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != nullptr && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    checkOpenMMVersion(Platform::getOpenMMVersion());
    const System& system = contextRef.getSystem();
    topology = RigidBodyTopology(system, declaredBodies, contextRef.getMolecules());
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = contextRef.getPlatform().createKernel(getStepKernelName(), contextRef);
    kernel.getAs<RigidBodyKernel>().initialize(system, topology, *this);
    forcesAreValid = false;
    velocitiesNeedProjection = false;
    lastStepCount = -1;
    refusedCheckpoint = false;
    positionsNotFinite = velocitiesNotFinite = false;
    positionsSet = false;
}

void RigidBodyIntegrator::cleanup() {
    kernel = Kernel();
}

vector<std::string> RigidBodyIntegrator::getKernelNames() {
    return {getStepKernelName()};
}

bool RigidBodyIntegrator::isCurrentIntegrator() const {
    const Integrator* integrator = &context->getIntegrator();
    // Members of a CompoundIntegrator (possibly nested) all hear stateChanged(); one steps.
    while (const CompoundIntegrator* compound = dynamic_cast<const CompoundIntegrator*>(integrator))
        integrator = &compound->getIntegrator(compound->getCurrentIntegrator());
    return integrator == this;
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    forcesAreValid = false;
    if (context == nullptr || (minimizing && changed == State::Positions))
        return;
    if (changed == State::Energy && loadingCheckpoint) {
        // OpenMM's last notification of a checkpoint load: continue as the run that wrote it.
        loadingCheckpoint = false;
        lastStepCount = context->getStepCount();
        velocitiesNeedProjection = false;
        return;
    }
    RigidBodyKernel& stepKernel = kernel.getAs<RigidBodyKernel>();
    if (changed == State::Positions) {
        try {
            stepKernel.updateShapes(*context);
        } catch (const OpenMMException& e) {
            positionsNotFinite = true;
            throw OpenMMException(std::string("setPositions: ") + e.what() + "; the integrator will not step until "
                                  "finite positions are set");
        }
        positionsNotFinite = false;
        positionsSet = true;
    }
    // Velocities the user sets are made rigid at once, so what the Context reports is what
    // the integrator uses; rigid ones (a checkpoint's, a saved State's) are kept bit for bit.
    if (changed == State::Positions || changed == State::Velocities) {
        // After a refused checkpoint the velocities are that checkpoint's (on some platforms
        // garbage): they are projected once new ones are set.
        if (loadingCheckpoint)
            velocitiesNotFinite = false;  // a checkpoint's velocities are as they were written
        else if (changed == State::Positions && velocitiesNotFinite) {
            // The velocities last set were refused: nothing to project; step() waits for finite ones.
        }
        else if (isCurrentIntegrator() && positionsSet && !refusedCheckpoint) {
            try {
                stepKernel.projectVelocities(*context, getConstraintTolerance());
            } catch (const OpenMMException& e) {
                // The kernel left the velocities as they were. Name the call that raised it.
                velocitiesNotFinite = true;
                if (changed == State::Positions)
                    throw OpenMMException(std::string("setPositions: the Context's velocities (set before these "
                                                      "positions) cannot be made rigid at them: ") + e.what() +
                                          "; the integrator will not step until velocities are set again");
                throw OpenMMException(std::string("setVelocities: ") + e.what() + "; the integrator will not step "
                                      "until finite velocities are set");
            }
            if (changed == State::Velocities)
                velocitiesNotFinite = false;
        }
        else {
            velocitiesNeedProjection = true;
            if (changed == State::Velocities)
                velocitiesNotFinite = false;  // checked when projected
        }
    }
}

void RigidBodyIntegrator::createCheckpoint(std::ostream& stream) const {
    requireContext();
    std::ostringstream kernelState;
    kernel.getAs<const RigidBodyKernel>().createCheckpoint(*context, kernelState);
    RigidBodyCheckpointHeader::write(stream, getStepKernelName(), topology, kernelState.str());
}

void RigidBodyIntegrator::loadCheckpoint(std::istream& stream) {
    requireContext();
    try {
        std::istringstream kernelState(RigidBodyCheckpointHeader::read(stream, getStepKernelName(), topology));
        kernel.getAs<RigidBodyKernel>().loadCheckpoint(*context, kernelState);
        loadingCheckpoint = true;
    } catch (const OpenMMException& e) {
        // OpenMM has already read its own part unchecked: positions, velocities, time, box,
        // parameters and its platform's random state (garbage there crashes a later step).
        // Only Context::reinitialize() rebuilds all of it, so stepping waits for it (or for
        // a checkpoint that fits); meanwhile the platform's unchecked state is made valid.
        refusedCheckpoint = true;
        forcesAreValid = false;
        kernel.getAs<RigidBodyKernel>().discardRefusedCheckpoint(*context);
        throw OpenMMException(std::string("loadCheckpoint: ") + e.what() + ". " + RefusedCheckpointRecovery);
    }
    refusedCheckpoint = false;
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
    if (!positionsSet)
        throw OpenMMException("setVelocitiesToTemperature: set the positions first: rigid-body velocities depend on them");
    return kernel.getAs<RigidBodyKernel>().getVelocitiesForTemperature(*context, temperature, randomSeed,
                                                                       getConstraintTolerance());
}

void RigidBodyIntegrator::step(int steps) {
    requireContext();
    if (getStepSize() == 0 || !std::isfinite(getStepSize()))
        throw OpenMMException("The step size must be a finite nonzero number of picoseconds, got " +
                              std::to_string(getStepSize()));
    if (!std::isfinite(1.0 / getStepSize()))
        throw OpenMMException("The step size " + std::to_string(getStepSize()) + " ps is too small: its inverse is "
                              "not finite");
    if (refusedCheckpoint)
        throw OpenMMException(std::string("step: the last loadCheckpoint() was refused. ") + RefusedCheckpointRecovery);
    if (!positionsSet)
        throw OpenMMException("step: the Context's positions have not been set");
    if (positionsNotFinite)
        throw OpenMMException("step: the Context's positions are not finite; set finite ones before stepping");
    if (velocitiesNotFinite)
        throw OpenMMException("step: the Context's velocities are not finite, or could not be made rigid at its "
                              "positions; set velocities again before stepping");
    RigidBodyKernel& stepKernel = kernel.getAs<RigidBodyKernel>();
    for (int i = 0; i < steps; i++) {
        // Another integrator (of a CompoundIntegrator) stepped since this one did, or
        // velocities were set while it was not current: this integrator's bodies decide
        // now, before a thermostat's collisions (which the kernel must see as such).
        if (context->getStepCount() != lastStepCount || velocitiesNeedProjection) {
            forcesAreValid = false;
            stepKernel.projectVelocities(*context, getConstraintTolerance());
            velocitiesNeedProjection = false;
        }
        if (context->updateContextState())
            forcesAreValid = false;
        // A getState() may have overwritten the forces with other force groups.
        if (context->getLastForceGroups() != getIntegrationForceGroups())
            forcesAreValid = false;
        executeStep(kernel, *context, forcesAreValid);
        lastStepCount = context->getStepCount();
    }
}
