#include "ReferenceRigidBodyDynamics.h"
#include "internal/FiniteValues.h"
#include "RigidBodyIntegrator.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/kernels.h"
#include "openmm/reference/ReferencePlatform.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

ReferencePlatform::PlatformData& platformData(ContextImpl& context) {
    // The CPU platform derives from the Reference platform and keeps this data too.
    return *reinterpret_cast<ReferencePlatform::PlatformData*>(context.getPlatformData());
}

vector<Vec3>& positionsOf(ContextImpl& context) {
    return *platformData(context).positions;
}

vector<Vec3>& velocitiesOf(ContextImpl& context) {
    return *platformData(context).velocities;
}

} // namespace

ReferenceRigidBodyDynamics::ReferenceRigidBodyDynamics(const std::string& integratorName)
    : integratorName(integratorName) {
}

void ReferenceRigidBodyDynamics::initialize(const System& system, const RigidBodyTopology& topology) {
    ops.reset(new ReferenceRigidBodyOperations(system, topology));
    shapes.reset(new BodyShapeConstraints(system, topology));
    nextPositions.resize(system.getNumParticles());
    nextVelocities.resize(system.getNumParticles());
    hasVirtualSites = false;
    for (int i = 0; i < system.getNumParticles(); i++)
        hasVirtualSites |= system.isVirtualSite(i);
}

// ---- The phases of a step ----------------------------------------------------------------

void ReferenceRigidBodyDynamics::beginStep(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                           bool& forcesAreValid) {
    stepContext = &context;
    if (!threadsChecked) {
        // The platform's properties cannot be asked for while the Context is being made.
        threadsChecked = true;
        if (context.getPlatform().getName() == "CPU")
            ops->setThreads(std::stoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads")));
    }
    if (ops->hasAndersenThermostat())
        ops->collideBodies(positions(), velocities(), context.getParameter(AndersenThermostat::Temperature()),
                           integrator.getConstraintTolerance());
    if (!forcesAreValid)
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    startPositions = positions();
    startVelocities = velocities();
}

void ReferenceRigidBodyDynamics::driftAndReset(double kickTime, double h, double tolerance) {
    // Into the step buffers, which then become the state: a body that finds no rotation
    // leaves the Context as it was.
    ownPhase([&] {
        ops->driftAndReset(positions(), velocities(), h, tolerance, nextPositions, nextVelocities,
                           kickTime != 0 ? &forces() : nullptr, kickTime);
        acceptNewState();
    });
}

void ReferenceRigidBodyDynamics::kick(double time) {
    ops->kick(velocities(), forces(), time);
}

void ReferenceRigidBodyDynamics::project(double tolerance, bool onlyIfNotRigid) {
    ownPhase([&] {
        if (onlyIfNotRigid)
            ops->projectNonRigidVelocities(positions(), velocities(), tolerance);
        else
            ops->projectVelocities(positions(), velocities(), tolerance);
    });
}

void ReferenceRigidBodyDynamics::computeForces(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                               bool& forcesAreValid) {
    forcesAreValid = false;
    ownPhase([&] {
        // OpenMM's Reference code loops over every particle to find virtual sites: skipped without any.
        if (hasVirtualSites)
            context.computeVirtualSites();
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    });
}

void ReferenceRigidBodyDynamics::endStep(double stepSize, bool& forcesAreValid) {
    ownPhase([&] { requireFiniteStepResult(); });
    ReferencePlatform::PlatformData& data = platformData(*stepContext);
    data.time += stepSize;
    data.stepCount++;
    forcesAreValid = true;
    stepContext = nullptr;
}

void ReferenceRigidBodyDynamics::ownPhase(const std::function<void()>& work) {
    try {
        work();
    } catch (const OpenMMException& e) {
        failStep(e.what());
    }
}

vector<Vec3>& ReferenceRigidBodyDynamics::positions() {
    return positionsOf(*stepContext);
}

vector<Vec3>& ReferenceRigidBodyDynamics::velocities() {
    return velocitiesOf(*stepContext);
}

const vector<Vec3>& ReferenceRigidBodyDynamics::forces() {
    return *platformData(*stepContext).forces;
}

void ReferenceRigidBodyDynamics::acceptNewState() {
    positions().swap(nextPositions);
    velocities().swap(nextVelocities);
}

void ReferenceRigidBodyDynamics::failStep(const std::string& what) {
    positions() = startPositions;
    velocities() = startVelocities;
    stepContext = nullptr;
    throw OpenMMException(integratorName + ": " + what +
                          "; the step was not taken (positions and velocities are as before it)");
}

void ReferenceRigidBodyDynamics::requireFiniteStepResult() {
    const vector<Vec3>& x = positions();
    const vector<Vec3>& v = velocities();
    const vector<Vec3>& f = forces();
    const vector<double>& inverseMass = ops->inverseMasses();
    for (size_t i = 0; i < x.size(); i++) {
        if (inverseMass[i] == 0)
            continue;  // massless: never integrated, finite since set
        const char* what = !std::isfinite(x[i][0] + x[i][1] + x[i][2])   ? "position"
                           : !std::isfinite(f[i][0] + f[i][1] + f[i][2]) ? "force at the new positions"
                           : !std::isfinite(v[i][0] + v[i][1] + v[i][2]) ? "velocity"
                                                                         : nullptr;
        if (what != nullptr)
            throw OpenMMException(std::string("the ") + what + " of particle " + std::to_string(i) + " is not finite");
    }
}

// ---- RigidBodyState's work --------------------------------------------------------------

void ReferenceRigidBodyDynamics::updateShapes(ContextImpl& context) {
    vector<Vec3>& x = positionsOf(context);
    FiniteValues::require(x, "position");
    if (shapes->apply(x))
        context.computeVirtualSites();
    ops->updateShapes(x);
}

void ReferenceRigidBodyDynamics::projectVelocities(ContextImpl& context, double tolerance) {
    vector<Vec3>& v = velocitiesOf(context);
    FiniteValues::require(v, "velocity");
    const vector<Vec3> given = v;  // only when velocities are set, not in the step
    try {
        ops->projectNonRigidVelocities(positionsOf(context), v, tolerance);
        FiniteValues::require(v, "velocity projected at the current positions (a degenerate constraint?)");
    } catch (...) {
        v = given;  // a refused projection (not finite, or constraints not converged) changes nothing
        throw;
    }
}

vector<Vec3> ReferenceRigidBodyDynamics::velocitiesForTemperature(ContextImpl& context, double temperature,
                                                                  int randomSeed, double tolerance) {
    return ops->velocitiesForTemperature(positionsOf(context), temperature, randomSeed, tolerance);
}

double ReferenceRigidBodyDynamics::kineticEnergy(ContextImpl& context) {
    return ops->kineticEnergy(velocitiesOf(context));
}

void ReferenceRigidBodyDynamics::kineticEnergies(ContextImpl& context, double& translational, double& rotational,
                                                 double& free) {
    ops->kineticEnergies(velocitiesOf(context), translational, rotational, free);
}

void ReferenceRigidBodyDynamics::createCheckpoint(std::ostream& stream) const {
    ops->writeState(stream);
}

void ReferenceRigidBodyDynamics::loadCheckpoint(std::istream& stream) {
    ops->readState(stream);
}

void ReferenceRigidBodyDynamics::discardRefusedCheckpoint(ContextImpl& context) {
    // OpenMM's Reference and CPU platforms keep one process-wide random generator (the
    // AndersenThermostat's, among others) whose state a checkpoint overwrites unchecked,
    // garbage included. Initialising OpenMM's thermostat kernel reseeds it (with the
    // System's thermostat seed if it has one), so it rebuilds a valid state.
    AndersenThermostat seeded(0, 0);
    const System& system = context.getSystem();
    for (int f = 0; f < system.getNumForces(); f++)
        if (const auto* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f)))
            seeded.setRandomNumberSeed(thermostat->getRandomNumberSeed());
    Kernel reseed = context.getPlatform().createKernel(ApplyAndersenThermostatKernel::Name(), context);
    reseed.getAs<ApplyAndersenThermostatKernel>().initialize(system, seeded);
}
