#include "RigidBodySearch.h"
#include "MRattlePlatforms.h"
#include "openmm/OpenMMException.h"
#include "openmm/State.h"
#include <algorithm>
#include <cmath>
#include <limits>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

/** OpenMM's positions and forces as the core's 3N arrays (Vec3 is three doubles). */
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
const double* array(const vector<Vec3>& values) {
    return reinterpret_cast<const double*>(values.data());
}
double* array(vector<Vec3>& values) {
    return reinterpret_cast<double*>(values.data());
}

bool hasLargeForce(const vector<Vec3>& forces) {
    for (const Vec3& f : forces)
        if (!(std::fabs(f[0]) < 2e9 && std::fabs(f[1]) < 2e9 && std::fabs(f[2]) < 2e9))
            return true;
    return false;
}

/** Codes the progress callback returns to stop liblbfgs (it passes them through). */
enum Stop { Converged = 1, Rebase, IterationLimit, Aborted, StoppedByReporter };

/**
 * Rotate a body's frame (theta) more than this and the search restarts about the new
 * orientation. Rotation vectors up to pi reach every orientation; there the exponential map
 * is still well conditioned (J's smallest singular value 2/pi; it vanishes at 2 pi). Each
 * restart discards the L-BFGS history and costs a few evaluations to rescale the first step
 * (tip3p.pdb: two restarts at pi/2, 1.2 evaluations per iteration; none at pi, 1.03).
 */
constexpr double RebaseAngle = M_PI;

/**
 * The first step of each L-BFGS search moves the particles this far, rms (nm). liblbfgs's
 * first trial step is one unit of its variables; in nm (LocalEnergyMinimizer's scale) that
 * moves them 1 nm in all, which every benchmark system backtracked at least once, an
 * evaluation lost at each search's start. The variables are scaled so that the unit step is
 * this one instead; L-BFGS's later steps do not depend on the scale (its H0 = s.y/y.y).
 */
constexpr double FirstStepRms = 0.003;

} // namespace

RigidBodySearch::RigidBodySearch(Context& context, ContextImpl& impl, const std::function<void(bool)>& searching,
                                 const RigidBodyTopology& topology, double constraintTolerance, double tolerance,
                                 int maxIterations, RigidBodyMinimizationReporter* reporter)
    : context(context), impl(impl), searching(searching), system(context.getSystem()), topology(topology),
      tolerance(tolerance), maxIterations(maxIterations), reporter(reporter) {
    groups = context.getIntegrator().getIntegrationForceGroups();
    // The device platforms (OpenMM's common compute platforms) sum forces in fixed point.
    const std::string platform = context.getPlatform().getName();
    for (const BuiltPlatform& built : BuiltPlatforms)
        clipsLargeForces |= (built.device && platform == built.name);
    workingConstraintTolerance = std::max(1e-4, constraintTolerance);
    springConstant = 100 / workingConstraintTolerance;
}

double RigidBodySearch::rmsForce(const Point& point) const {
    // Per degree of freedom, in the units of a particle's force (3 freedoms): for free
    // particles alone this is the rms over particles that OpenMM tests.
    return numVariables == 0 ? 0.0 : std::sqrt(3 * point.gradientNorm2 / numVariables);
}

bool RigidBodySearch::converged(const Point& point) const {
    return rmsForce(point) <= tolerance;
}

void RigidBodySearch::restartAt(const vector<Vec3>& positions, bool resetOrientations) {
    cached.valid = false;
    best.valid = false;
    // The variables describe moves from here: bodies at u = v = 0 about their present frame.
    int offset = 0;
    offsets.clear();
    for (RigidBodyMath::RigidBodyCoordinates& body : bodies) {
        body.restartAt(array(positions), topology.getMasses().data(), resetOrientations);
        offsets.push_back(offset);
        offset += body.numVariables();
    }
    numVariables = offset + 3 * freeParticles.size();
    paddedVariables = std::max(8, (numVariables + 7) / 8 * 8);
    x.reset(lbfgs_malloc(paddedVariables));
    if (x == nullptr)
        throw OpenMMException(MinimizerPrefix + "out of memory for " + std::to_string(paddedVariables) + " variables");
    std::fill(x.get(), x.get() + paddedVariables, 0.0);
    for (size_t k = 0; k < freeParticles.size(); k++)
        for (int d = 0; d < 3; d++)
            x.get()[offset + 3 * k + d] = positions[freeParticles[k]][d] / lengthScale;
}

void RigidBodySearch::positionsOf(const double* variables, vector<Vec3>& positions) const {
    for (size_t b = 0; b < bodies.size(); b++)
        bodies[b].place(variables + offsets[b], lengthScale, array(positions));
    const double* free = variables + (numVariables - 3 * freeParticles.size());
    for (size_t k = 0; k < freeParticles.size(); k++)
        positions[freeParticles[k]] = Vec3(free[3 * k], free[3 * k + 1], free[3 * k + 2]) * lengthScale;
}

void RigidBodySearch::setContextPositions(const vector<Vec3>& positions) {
    context.setPositions(positions);
    context.computeVirtualSites();
}

double RigidBodySearch::hostForces() {
    if (hostContext == nullptr) {
        Platform* host;
        try {
            host = &Platform::getPlatformByName("CPU");
        } catch (const OpenMMException&) {
            host = &Platform::getPlatformByName("Reference");
        }
        makeHostContext(*host);
    }
    hostContext->setPositions(trial);
    hostContext->computeVirtualSites();
    const State state = hostContext->getState(State::Forces | State::Energy, false, groups);
    if (!std::isfinite(state.getPotentialEnergy()) && hostContext->getPlatform().getName() != "Reference") {
        // The CPU platform's single-precision nonbonded kernels overflow first: Reference computes in double.
        makeHostContext(Platform::getPlatformByName("Reference"));
        return hostForces();
    }
    forces = state.getForces();
    return state.getPotentialEnergy();
}

void RigidBodySearch::makeHostContext(Platform& host) {
    hostContext.reset();
    hostIntegrator.reset(new VerletIntegrator(1.0));
    hostContext.reset(new Context(system, *hostIntegrator, host));
    hostContext->setState(context.getState(State::Positions | State::Parameters));
}

double RigidBodySearch::evaluate(const double* variables, double* g) {
    // liblbfgs is C: nothing may be thrown through it. After a failure every further
    // evaluation is refused at once, so the line search gives up and liblbfgs returns its
    // last iterate, the best point found.
    if (failure.empty()) {
        try {
            // liblbfgs starts each search by evaluating its starting point, evaluated already.
            if (cached.valid && std::equal(variables, variables + paddedVariables, cached.variables.begin())) {
                std::copy(cached.gradient.begin(), cached.gradient.end(), g);
                last = cached.point;
                return cached.value;
            }
            cached.valid = false;
            const double value = evaluateUnchecked(variables, g);
            cached.variables.assign(variables, variables + paddedVariables);
            cached.gradient.assign(g, g + paddedVariables);
            cached.point = last;
            cached.value = value;
            cached.valid = true;
            if (!best.valid || value < best.value)
                best = cached;
            return value;
        } catch (const std::exception& e) {
            failure = e.what();
        }
    }
    std::fill(g, g + paddedVariables, 0.0);
    return std::numeric_limits<double>::infinity();
}

double RigidBodySearch::evaluateUnchecked(const double* variables, double* g) {
    positionsOf(variables, trial);
    double positionNorm2 = 0;
    for (const Vec3& r : trial)
        positionNorm2 += r.dot(r);
    if (!std::isfinite(positionNorm2))
        throw OpenMMException("the search reached positions that are not finite");
    // LocalEnergyMinimizer's calls (ReferenceMinimize.cpp): the integrator's own work at
    // setPositions() is deferred (searching), and no kinetic energy or State is made.
    impl.setPositions(trial);
    impl.computeVirtualSites();
    double potential = impl.calcForcesAndEnergy(true, true, groups);
    impl.getForces(forces);
    evaluations++;
    if (clipsLargeForces && hasLargeForce(forces))
        potential = hostForces();
    if (!std::isfinite(potential))
        throw OpenMMException("the potential energy is not finite (" + std::to_string(potential) + ")");
    double energy = potential, springEnergy = 0;
    auto checkFinite = [&](int i) {
        const Vec3& f = forces[i];
        if (!std::isfinite(f[0] + f[1] + f[2]))
            throw OpenMMException("the force on particle " + std::to_string(i) + " is not finite");
    };
    std::fill(g, g + paddedVariables, 0.0);
    double norm2 = 0;
    for (size_t b = 0; b < bodies.size(); b++) {
        for (int i : bodies[b].getAtoms())
            checkFinite(i);
        norm2 += bodies[b].gradient(variables + offsets[b], lengthScale, array(trial), array(forces), g + offsets[b]);
    }
    const int freeOffset = numVariables - 3 * freeParticles.size();
    for (size_t k = 0; k < freeParticles.size(); k++) {
        checkFinite(freeParticles[k]);
        for (int d = 0; d < 3; d++)
            g[freeOffset + 3 * k + d] = -forces[freeParticles[k]][d];
    }
    // LocalEnergyMinimizer's springs on the free particles' constraints.
    if (!topology.getFreeConstraints().empty()) {
        vector<int> slot(system.getNumParticles(), -1);
        for (size_t k = 0; k < freeParticles.size(); k++)
            slot[freeParticles[k]] = freeOffset + 3 * k;
        for (int c : topology.getFreeConstraints()) {
            int p1, p2;
            double distance;
            system.getConstraintParameters(c, p1, p2, distance);
            Vec3 delta = trial[p2] - trial[p1];
            const double r = std::sqrt(delta.dot(delta));
            const double dr = r - distance;
            const double spring = 0.5 * springConstant * dr * dr;
            energy += spring;
            springEnergy += spring;
            delta *= springConstant * dr / r;
            for (int d = 0; d < 3; d++) {
                if (slot[p1] >= 0)
                    g[slot[p1] + d] -= delta[d];
                if (slot[p2] >= 0)
                    g[slot[p2] + d] += delta[d];
            }
        }
    }
    for (size_t k = 0; k < 3 * freeParticles.size(); k++) {
        norm2 += g[freeOffset + k] * g[freeOffset + k];
        g[freeOffset + k] *= lengthScale;
    }
    last.energy = potential;
    last.springEnergy = springEnergy;
    last.gradientNorm2 = norm2;
    return energy;
}

int RigidBodySearch::progress(const double* g) {
    // liblbfgs calls this after each accepted line search, whose last evaluation is the new iterate.
    iterations++;
    accepted = last;
    if (!failure.empty())
        return Aborted;
    if (reporter != nullptr) {
        // liblbfgs is C: what the reporter throws ends the search as a failed evaluation does.
        try {
            if (reportIteration(g))
                return StoppedByReporter;
        } catch (const std::exception& e) {
            failure = std::string("the reporter threw: ") + e.what();
            return Aborted;
        }
    }
    if (converged(accepted))
        return Converged;
    if (maxIterations > 0 && iterations >= maxIterations)
        return IterationLimit;
    for (size_t b = 0; b < bodies.size(); b++)
        if (bodies[b].rotationVector(x.get() + offsets[b], lengthScale).norm() > RebaseAngle)
            return Rebase;
    return 0;
}

bool RigidBodySearch::continueFromBestTrial(int& status) {
    const double acceptedValue = accepted.energy + accepted.springEnergy;
    if (status >= 0 || !best.valid || !(best.value < acceptedValue - 1e-12 * std::fabs(acceptedValue)))
        return false;
    // The trial becomes the iterate (reported and tested as one), then a new L-BFGS search starts there.
    std::copy(best.variables.begin(), best.variables.end(), x.get());
    last = best.point;
    status = progress(best.gradient.data());
    if (status == 0)
        status = Rebase;
    return true;
}

void RigidBodySearch::rebase() {
    // Fold each body's rotation into its frame (composed with the rotations before: the
    // shape itself is never rotated in place) and restart about the new orientations.
    positionsOf(x.get(), trial);
    for (size_t b = 0; b < bodies.size(); b++)
        bodies[b].foldRotation(x.get() + offsets[b], lengthScale);
    restartAt(trial, false);
}

double RigidBodySearch::maxFreeConstraintError(const vector<Vec3>& positions) const {
    double maxError = 0;
    for (int c : topology.getFreeConstraints()) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        const Vec3 delta = positions[p2] - positions[p1];
        // In nm, as OpenMM 7.7's LocalEnergyMinimizer (OpenMM 8's relative error is 10x stricter for
        // bonds to hydrogen, for more iterations). Only the number of spring-stiffening rounds
        // depends on it: applyConstraints makes the constraints exact at the end.
        maxError = std::max(maxError, std::fabs(std::sqrt(delta.dot(delta)) - distance));
    }
    return maxError;
}

void RigidBodySearch::fail(const std::string& what) {
    // run() leaves the Context at liblbfgs's last iterate, the best point found.
    throw OpenMMException(MinimizerPrefix + what + " during the search, after " + std::to_string(iterations) +
                          " iterations; the Context holds the best point found (energy " +
                          std::to_string(accepted.energy) + " kJ/mol)");
}

/** The L-BFGS searches, with their restarts (new frames, stiffer springs), from the start set up by run(). */
void RigidBodySearch::search() {
    vector<lbfgsfloatval_t> gradient(paddedVariables);
    lbfgs_parameter_t parameters;
    lbfgs_parameter_init(&parameters);
    parameters.linesearch = LBFGS_LINESEARCH_BACKTRACKING_STRONG_WOLFE;  // LocalEnergyMinimizer's
    if (!context.getPlatform().supportsDoublePrecision())
        parameters.xtol = 1e-7;
    parameters.epsilon = 0;  // the convergence test is LocalEnergyMinimizer's, in progress()
    parameters.max_iterations = 0;
    double previousMaxError = 1e10;
    while (!converged(accepted) && !(maxIterations > 0 && iterations >= maxIterations)) {
        // One L-BFGS search, restarted about new orientations when a body has turned far.
        int status = Rebase;
        while (status == Rebase) {
            lbfgsfloatval_t value;
            status = lbfgs(paddedVariables, x.get(), &value, evaluateCallback, progressCallback, this, &parameters);
            if (!failure.empty())
                fail(failure);
            if (continueFromBestTrial(status) && !failure.empty())
                fail(failure);
            if (status == Rebase)
                rebase();
            else if (status == LBFGSERR_OUTOFMEMORY || status == LBFGSERR_INVALID_N_SSE ||
                     status == LBFGSERR_INVALID_X_SSE)
                throw OpenMMException(MinimizerPrefix + "liblbfgs refused the search (status " +
                                      std::to_string(status) + ")");
        }
        // Other statuses end the search at its last iterate: converged, at the iteration
        // limit, or a line search that can no longer lower the energy (as LocalEnergyMinimizer).
        if (topology.getFreeConstraints().empty())
            break;
        positionsOf(x.get(), trial);
        const double maxError = maxFreeConstraintError(trial);
        if (maxError <= workingConstraintTolerance || maxError >= previousMaxError)
            break;  // the constraints hold, or stiffer springs do not help (applyConstraints below)
        previousMaxError = maxError;
        springConstant *= 10;
        roundIterations = 0;
        cached.valid = false;
        best.valid = false;
        if (maxError > 100 * workingConstraintTolerance)
            restartAt(startPositions, true);  // far from valid: start again, as LocalEnergyMinimizer does
        else
            rebase();
        evaluate(x.get(), gradient.data());
        if (!failure.empty())
            fail(failure);
        accepted = last;
    }
}

RigidBodyMinimizationReport RigidBodySearch::run() {
    freeParticles = topology.getFreeParticles();
    try {
        // Refuses a Context whose positions were never set (getState(Positions) would not);
        // with no force group selected it computes nothing.
        context.getState(State::Energy, false, 0);
    } catch (const OpenMMException& e) {
        throw OpenMMException(MinimizerPrefix + e.what());
    }
    // Start from constrained free particles, as LocalEnergyMinimizer does; the bodies keep
    // the exact shapes the integrator gave them (applyConstraints would touch a body's own
    // constraints, e.g. SETTLE's water, at its tolerance).
    startPositions = context.getState(State::Positions).getPositions();
    if (!topology.getFreeConstraints().empty()) {
        context.applyConstraints(workingConstraintTolerance);
        const vector<Vec3> constrained = context.getState(State::Positions).getPositions();
        for (int i : freeParticles)
            startPositions[i] = constrained[i];
        setContextPositions(startPositions);
        startPositions = context.getState(State::Positions).getPositions();
    }
    trial = startPositions;
    lengthScale = FirstStepRms * std::sqrt((double) std::max(1, system.getNumParticles()));
    bodies.clear();
    for (int b = 0; b < topology.getNumBodies(); b++)
        bodies.emplace_back(topology.getBodyParticles(b), array(startPositions));
    restartAt(startPositions, true);

    RigidBodyMinimizationReport report;
    vector<lbfgsfloatval_t> gradient(paddedVariables);
    const double startEnergy = evaluate(x.get(), gradient.data());
    if (!failure.empty())
        throw OpenMMException(MinimizerPrefix + failure + " at the starting positions");
    report.initialEnergy = startEnergy;
    accepted = last;
    accepted.energy = startEnergy;  // with the springs' energy: zero, the free constraints hold

    searching(true);
    try {
        search();
    } catch (...) {
        // Leave the Context at liblbfgs's last iterate, the best point found, through a
        // setPositions() that the integrator sees (shapes, velocities).
        searching(false);
        positionsOf(x.get(), trial);
        setContextPositions(trial);
        throw;
    }
    searching(false);

    positionsOf(x.get(), trial);
    if (!topology.getFreeConstraints().empty()) {
        setContextPositions(trial);
        context.applyConstraints(workingConstraintTolerance);
        const vector<Vec3> constrained = context.getState(State::Positions).getPositions();
        for (int i : freeParticles)
            trial[i] = constrained[i];
    }
    setContextPositions(trial);
    double finalEnergy = accepted.energy;
    if (!topology.getFreeConstraints().empty()) {
        finalEnergy = context.getState(State::Energy, false, groups).getPotentialEnergy();
        evaluations++;
    }
    if (!(finalEnergy <= startEnergy)) {
        // Projecting the free constraints can cost energy: never end above the start.
        setContextPositions(startPositions);
        finalEnergy = startEnergy;
    }
    report.iterations = iterations;
    report.evaluations = evaluations;
    report.finalEnergy = finalEnergy;
    report.rmsForce = rmsForce(accepted);
    return report;
}

