#include "RigidBodyMinimizer.h"
#include "MRattlePlatforms.h"
#include "RigidBodyIntegrator.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/CompoundIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/State.h"
#include "openmm/VerletIntegrator.h"
#include "openmm/internal/ContextImpl.h"
#include <Eigen/Dense>
#include <lbfgs.h>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

using namespace MRattlePlugin;
using namespace OpenMM;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using std::vector;

namespace {

const std::string Prefix = "RigidBodyMinimizer::minimize: ";

RigidBodyIntegrator* findRigidBodyIntegrator(Integrator& integrator) {
    if (RigidBodyIntegrator* rigid = dynamic_cast<RigidBodyIntegrator*>(&integrator))
        return rigid;
    CompoundIntegrator* compound = dynamic_cast<CompoundIntegrator*>(&integrator);
    if (compound == nullptr)
        return nullptr;
    if (RigidBodyIntegrator* current = findRigidBodyIntegrator(compound->getIntegrator(compound->getCurrentIntegrator())))
        return current;
    for (int i = 0; i < compound->getNumIntegrators(); i++)
        if (RigidBodyIntegrator* member = findRigidBodyIntegrator(compound->getIntegrator(i)))
            return member;
    return nullptr;
}

Vector3d toEigen(const Vec3& v) {
    return Vector3d(v[0], v[1], v[2]);
}

Matrix3d cross(const Vector3d& v) {
    Matrix3d m;
    m << 0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0;
    return m;
}

/** d/dt exp([theta + t d]x) = [J(theta) d]x exp([theta]x): the left Jacobian of SO(3). */
Matrix3d leftJacobian(const Vector3d& theta) {
    const double angle = theta.norm();
    const Matrix3d K = cross(theta);
    if (angle < 1e-4)  // series: the closed form loses digits to cancellation
        return Matrix3d::Identity() + K / 2 + K * K / 6;
    return Matrix3d::Identity() + (1 - std::cos(angle)) / (angle * angle) * K +
           (angle - std::sin(angle)) / (angle * angle * angle) * K * K;
}

/**
 * One body: atom i sits at center + u/sqrt(n) + R(theta) base a_i, with a_i its offset from
 * the centroid at the start (the shape, never changed) and theta = axes v. The variables u
 * and v make the metric of the atoms' displacements the identity at the restart point
 * (|dx|^2 = |du|^2 + |dv|^2 about the centroid, with unit masses), so L-BFGS sees the same
 * scale as LocalEnergyMinimizer's Cartesian search and |gradient| is the force projected
 * on rigid motion. Any centre would give the same configurations; the centroid makes the
 * translation and rotation orthogonal in that metric.
 */
struct BodyCoordinates {
    vector<int> atoms;
    vector<Vector3d> shape;
    Matrix3d base = Matrix3d::Identity();
    Vector3d center = Vector3d::Zero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> axes;  // columns: principal axis / sqrt(moment)
    double sqrtAtoms = 1;
    int offset = 0;  // of its variables in x
    int numVariables() const { return 3 + (int) axes.cols(); }
    /** Its centroid and its rotation vector, from its variables (in units of the search's length scale). */
    Vector3d centroid(const double* variables, double scale) const {
        const double* u = variables + offset;
        return center + scale * Vector3d(u[0], u[1], u[2]) / sqrtAtoms;
    }
    Vector3d rotationVector(const double* variables, double scale) const {
        Vector3d theta = Vector3d::Zero();
        for (int k = 0; k < axes.cols(); k++)
            theta += axes.col(k) * (scale * variables[offset + 3 + k]);
        return theta;
    }
};

/** Codes the progress callback returns to stop liblbfgs (it passes them through). */
enum Stop { Converged = 1, Rebase, IterationLimit, Aborted };

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

class Search {
public:
    /**
     * impl: the Context's implementation, for LocalEnergyMinimizer's evaluation (no kinetic
     * energy, no State); searching(true) has the integrator skip its work at each
     * setPositions() (shapes, velocities) until searching(false).
     */
    Search(Context& context, ContextImpl& impl, const std::function<void(bool)>& searching,
           RigidBodyIntegrator& integrator, double tolerance, int maxIterations)
        : context(context), impl(impl), searching(searching), system(context.getSystem()),
          topology(integrator.getTopology()), tolerance(tolerance), maxIterations(maxIterations) {
        groups = context.getIntegrator().getIntegrationForceGroups();
        // The device platforms (OpenMM's common compute platforms) sum forces in fixed point.
        const std::string platform = context.getPlatform().getName();
        clipsLargeForces = false;
        for (const BuiltPlatform& built : BuiltPlatforms)
            clipsLargeForces |= (built.device && platform == built.name);
        workingConstraintTolerance = std::max(1e-4, integrator.getConstraintTolerance());
        springConstant = 100 / workingConstraintTolerance;
    }

    RigidBodyMinimizationReport run();

private:
    static lbfgsfloatval_t evaluateCallback(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g, int,
                                            lbfgsfloatval_t) {
        return static_cast<Search*>(instance)->evaluate(x, g);
    }
    static int progressCallback(void* instance, const lbfgsfloatval_t*, const lbfgsfloatval_t*, lbfgsfloatval_t,
                                lbfgsfloatval_t, lbfgsfloatval_t, lbfgsfloatval_t, int, int, int) {
        return static_cast<Search*>(instance)->progress();
    }

    void setUpBodies(const vector<Vec3>& positions);
    void restartAt(const vector<Vec3>& positions, bool resetOrientations);
    void positionsOf(const double* x, vector<Vec3>& positions) const;
    double evaluate(const double* x, double* g);
    double evaluateUnchecked(const double* x, double* g);
    int progress();
    struct Point;
    /** LocalEnergyMinimizer's test: |g| <= tolerance * max(1, |x|) / max(1, rms|x0|). */
    bool converged(const Point& point) const {
        return std::sqrt(point.gradientNorm2) <= tolerance / startNorm * std::max(1.0, point.positionNorm);
    }
    void rebase();
    double maxFreeConstraintError(const vector<Vec3>& positions) const;
    void setContextPositions(const vector<Vec3>& positions);
    static bool hasLargeForce(const vector<Vec3>& forces);
    double hostForces();
    void search();
    [[noreturn]] void fail(const std::string& what);

    Context& context;
    ContextImpl& impl;
    std::function<void(bool)> searching;
    /**
     * Platforms that sum forces in fixed point clip very large ones: then, as
     * LocalEnergyMinimizer does, the forces are recomputed on the CPU (or Reference) platform.
     */
    bool clipsLargeForces;
    VerletIntegrator hostIntegrator{1.0};
    std::unique_ptr<Context> hostContext;
    const System& system;
    const RigidBodyTopology& topology;
    double tolerance;
    int maxIterations;
    int groups;
    double workingConstraintTolerance, springConstant;

    vector<BodyCoordinates> bodies;
    vector<int> freeParticles;
    int numVariables = 0;
    /** The liblbfgs vector (padded to a multiple of 8 with variables of zero gradient, for SSE builds). */
    std::unique_ptr<lbfgsfloatval_t, void (*)(lbfgsfloatval_t*)> x{nullptr, lbfgs_free};
    int paddedVariables = 0;
    vector<Vec3> startPositions, trial, forces;
    double startNorm = 1;
    /** nm per unit of liblbfgs's variables (FirstStepRms). */
    double lengthScale = 1;

    /** The last evaluation, and the last accepted point (liblbfgs's iterate). */
    struct Point {
        double energy = 0, gradientNorm2 = 0, positionNorm = 0;
    } last, accepted;
    /** The last evaluation, for liblbfgs's repeat of it; invalid once the variables or springs change meaning. */
    struct {
        bool valid = false;
        vector<double> variables, gradient;
        Point point;
        double value = 0;
    } cached;
    int iterations = 0, evaluations = 0;
    std::string failure;  // set when an evaluation found something not finite
};

void Search::setUpBodies(const vector<Vec3>& positions) {
    bodies.clear();
    for (int b = 0; b < topology.getNumBodies(); b++) {
        BodyCoordinates body;
        body.atoms = topology.getBodyParticles(b);
        body.sqrtAtoms = std::sqrt((double) body.atoms.size());
        Vector3d centroid = Vector3d::Zero();
        for (int i : body.atoms)
            centroid += toEigen(positions[i]);
        centroid /= body.atoms.size();
        for (int i : body.atoms)
            body.shape.push_back(toEigen(positions[i]) - centroid);
        body.center = centroid;
        bodies.push_back(body);
    }
}

void Search::restartAt(const vector<Vec3>& positions, bool resetOrientations) {
    cached.valid = false;
    // The variables describe moves from here: bodies at u = v = 0 about their present frame.
    const vector<double>& masses = topology.getMasses();
    int offset = 0;
    for (BodyCoordinates& body : bodies) {
        if (resetOrientations)
            body.base = Matrix3d::Identity();
        Vector3d centroid = Vector3d::Zero();
        for (int i : body.atoms)
            centroid += toEigen(positions[i]);
        body.center = centroid / body.atoms.size();
        // Rotations: the principal axes of the unit-mass inertia of the present orientation;
        // a linear body has no rotation about its line, a point none at all. The kernel's rule
        // (isBodyLinear()) classifies, from the mass-weighted second moment.
        Matrix3d inertia = Matrix3d::Zero(), secondMoment = Matrix3d::Zero();
        Vector3d centerOfMass = Vector3d::Zero();
        double mass = 0;
        for (size_t k = 0; k < body.atoms.size(); k++) {
            centerOfMass += masses[body.atoms[k]] * (body.base * body.shape[k]);
            mass += masses[body.atoms[k]];
        }
        centerOfMass /= mass;
        for (size_t k = 0; k < body.atoms.size(); k++) {
            const Vector3d r = body.base * body.shape[k];
            inertia += r.squaredNorm() * Matrix3d::Identity() - r * r.transpose();
            const Vector3d a = r - centerOfMass;
            secondMoment += masses[body.atoms[k]] * a * a.transpose();
        }
        const RigidBodyMath::Shape shape = RigidBodyMath::classifyShape(secondMoment, mass);
        const int rotations = shape == RigidBodyMath::Shape::General ? 3 : shape == RigidBodyMath::Shape::Linear ? 2 : 0;
        Eigen::SelfAdjointEigenSolver<Matrix3d> principal(inertia);  // eigenvalues ascending
        body.axes.resize(3, rotations);
        for (int k = 0; k < rotations; k++) {
            const int column = 3 - rotations + k;
            body.axes.col(k) = principal.eigenvectors().col(column) / std::sqrt(principal.eigenvalues()[column]);
        }
        body.offset = offset;
        offset += body.numVariables();
    }
    numVariables = offset + 3 * freeParticles.size();
    paddedVariables = std::max(8, (numVariables + 7) / 8 * 8);
    x.reset(lbfgs_malloc(paddedVariables));
    if (x == nullptr)
        throw OpenMMException(Prefix + "out of memory for " + std::to_string(paddedVariables) + " variables");
    std::fill(x.get(), x.get() + paddedVariables, 0.0);
    for (size_t k = 0; k < freeParticles.size(); k++)
        for (int d = 0; d < 3; d++)
            x.get()[offset + 3 * k + d] = positions[freeParticles[k]][d] / lengthScale;
}

void Search::positionsOf(const double* variables, vector<Vec3>& positions) const {
    for (const BodyCoordinates& body : bodies) {
        const Vector3d center = body.centroid(variables, lengthScale);
        const Vector3d theta = body.rotationVector(variables, lengthScale);
        const Matrix3d rotation = RigidBodyMath::rotationFromVector(theta) * body.base;
        for (size_t k = 0; k < body.atoms.size(); k++) {
            const Vector3d r = center + rotation * body.shape[k];
            positions[body.atoms[k]] = Vec3(r[0], r[1], r[2]);
        }
    }
    const double* free = variables + (numVariables - 3 * freeParticles.size());
    for (size_t k = 0; k < freeParticles.size(); k++)
        positions[freeParticles[k]] = Vec3(free[3 * k], free[3 * k + 1], free[3 * k + 2]) * lengthScale;
}

void Search::setContextPositions(const vector<Vec3>& positions) {
    context.setPositions(positions);
    context.computeVirtualSites();
}

bool Search::hasLargeForce(const vector<Vec3>& forces) {
    for (const Vec3& f : forces)
        if (!(std::fabs(f[0]) < 2e9 && std::fabs(f[1]) < 2e9 && std::fabs(f[2]) < 2e9))
            return true;
    return false;
}

double Search::hostForces() {
    if (hostContext == nullptr) {
        Platform* host;
        try {
            host = &Platform::getPlatformByName("CPU");
        } catch (const OpenMMException&) {
            host = &Platform::getPlatformByName("Reference");
        }
        hostContext.reset(new Context(system, hostIntegrator, *host));
        hostContext->setState(context.getState(State::Positions | State::Parameters));
    }
    hostContext->setPositions(trial);
    hostContext->computeVirtualSites();
    const State state = hostContext->getState(State::Forces | State::Energy, false, groups);
    forces = state.getForces();
    return state.getPotentialEnergy();
}

double Search::evaluate(const double* variables, double* g) {
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
            return value;
        } catch (const std::exception& e) {
            failure = e.what();
        }
    }
    std::fill(g, g + paddedVariables, 0.0);
    return std::numeric_limits<double>::infinity();
}

double Search::evaluateUnchecked(const double* variables, double* g) {
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
    double energy = potential;
    auto checkedForce = [&](int i) {
        const Vec3& f = forces[i];
        if (!std::isfinite(f[0] + f[1] + f[2]))
            throw OpenMMException("the force on particle " + std::to_string(i) + " is not finite");
        return toEigen(f);
    };
    std::fill(g, g + paddedVariables, 0.0);
    double norm2 = 0;
    for (const BodyCoordinates& body : bodies) {
        const Vector3d theta = body.rotationVector(variables, lengthScale);
        const Vector3d center = body.centroid(variables, lengthScale);
        Vector3d force = Vector3d::Zero(), torque = Vector3d::Zero();
        for (int i : body.atoms) {
            const Vector3d f = checkedForce(i);
            force += f;
            torque += (toEigen(trial[i]) - center).cross(f);
        }
        // dE/du = -F/sqrt(n); dE/dv = -axes^T J(theta)^T tau, exact for the line search.
        const Vector3d translation = -force / body.sqrtAtoms;
        const Eigen::VectorXd rotation = -body.axes.transpose() * (leftJacobian(theta).transpose() * torque);
        for (int d = 0; d < 3; d++)
            g[body.offset + d] = lengthScale * translation[d];
        for (int k = 0; k < rotation.size(); k++)
            g[body.offset + 3 + k] = lengthScale * rotation[k];
        // The force projected on rigid motion at this orientation: |F|^2/n + tau . I^-1 tau.
        const Eigen::VectorXd projected = body.axes.transpose() *
                                          (RigidBodyMath::rotationFromVector(theta).transpose() * torque);
        norm2 += translation.squaredNorm() + projected.squaredNorm();
    }
    const int freeOffset = numVariables - 3 * freeParticles.size();
    for (size_t k = 0; k < freeParticles.size(); k++) {
        const Vector3d f = checkedForce(freeParticles[k]);
        for (int d = 0; d < 3; d++)
            g[freeOffset + 3 * k + d] = -f[d];
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
            energy += 0.5 * springConstant * dr * dr;
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
    last.gradientNorm2 = norm2;
    last.positionNorm = std::sqrt(positionNorm2);
    return energy;
}

int Search::progress() {
    // liblbfgs calls this after each accepted line search, whose last evaluation is the new iterate.
    iterations++;
    accepted = last;
    if (!failure.empty())
        return Aborted;
    if (converged(accepted))
        return Converged;
    if (maxIterations > 0 && iterations >= maxIterations)
        return IterationLimit;
    for (const BodyCoordinates& body : bodies)
        if (body.rotationVector(x.get(), lengthScale).norm() > RebaseAngle)
            return Rebase;
    return 0;
}

void Search::rebase() {
    // Fold each body's rotation into its frame (composed with the rotations before: the
    // shape itself is never rotated in place) and restart about the new orientations.
    positionsOf(x.get(), trial);
    for (BodyCoordinates& body : bodies)
        body.base = RigidBodyMath::rotationFromVector(body.rotationVector(x.get(), lengthScale)) * body.base;
    restartAt(trial, false);
}

double Search::maxFreeConstraintError(const vector<Vec3>& positions) const {
    double maxError = 0;
    for (int c : topology.getFreeConstraints()) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        const Vec3 delta = positions[p2] - positions[p1];
        // In nm, as OpenMM 7.7's LocalEnergyMinimizer (OpenMM 8 divides by the length: 10x stricter
        // for bonds to hydrogen, and measured 3.4x the iterations on test.pdb). Only the number of
        // spring-stiffening rounds depends on it: applyConstraints makes the constraints exact at the end.
        maxError = std::max(maxError, std::fabs(std::sqrt(delta.dot(delta)) - distance));
    }
    return maxError;
}

void Search::fail(const std::string& what) {
    // run() leaves the Context at liblbfgs's last iterate, the best point found.
    throw OpenMMException(Prefix + what + " during the search, after " + std::to_string(iterations) +
                          " iterations; the Context holds the best point found (energy " +
                          std::to_string(accepted.energy) + " kJ/mol)");
}

/** The L-BFGS searches, with their restarts (new frames, stiffer springs), from the start set up by run(). */
void Search::search() {
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
            if (status == Rebase)
                rebase();
            else if (status == LBFGSERR_OUTOFMEMORY || status == LBFGSERR_INVALID_N_SSE || status == LBFGSERR_INVALID_X_SSE)
                throw OpenMMException(Prefix + "liblbfgs refused the search (status " + std::to_string(status) + ")");
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
        cached.valid = false;
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

RigidBodyMinimizationReport Search::run() {
    freeParticles = topology.getFreeParticles();
    try {
        // Refuses a Context whose positions were never set (getState(Positions) would not);
        // with no force group selected it computes nothing.
        context.getState(State::Energy, false, 0);
    } catch (const OpenMMException& e) {
        throw OpenMMException(Prefix + e.what());
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
    double norm = 0;
    for (const Vec3& r : startPositions)
        norm += r.dot(r);
    norm /= std::max(1, system.getNumParticles());
    startNorm = norm < 1 ? 1 : std::sqrt(norm);
    lengthScale = FirstStepRms * std::sqrt((double) std::max(1, system.getNumParticles()));
    setUpBodies(startPositions);
    restartAt(startPositions, true);

    RigidBodyMinimizationReport report;
    vector<lbfgsfloatval_t> gradient(paddedVariables);
    const double startEnergy = evaluate(x.get(), gradient.data());
    if (!failure.empty())
        throw OpenMMException(Prefix + failure + " at the starting positions");
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
    report.rmsForce = std::sqrt(accepted.gradientNorm2 / std::max(1, system.getNumParticles()));
    return report;
}

} // namespace

bool RigidBodyMinimizer::appliesTo(Context& context) {
    return findRigidBodyIntegrator(context.getIntegrator()) != nullptr;
}

RigidBodyMinimizationReport RigidBodyMinimizer::minimize(Context& context, double tolerance, int maxIterations) {
    if (!(tolerance >= 0) || !std::isfinite(tolerance))
        throw OpenMMException(Prefix + "the tolerance must be a finite number >= 0 (kJ/mol/nm), got " +
                              std::to_string(tolerance));
    if (maxIterations < 0)
        throw OpenMMException(Prefix + "maxIterations must be >= 0 (0: until converged), got " +
                              std::to_string(maxIterations));
    RigidBodyIntegrator* integrator = findRigidBodyIntegrator(context.getIntegrator());
    if (integrator == nullptr)
        throw OpenMMException(Prefix + "the Context's integrator is not one of the plugin's rigid-body integrators "
                              "(nor a CompoundIntegrator holding one); use OpenMM's LocalEnergyMinimizer");
    // A friend of the integrator: its ContextImpl, and its flag that defers the work of setPositions().
    Search search(context, *integrator->context, [integrator](bool on) { integrator->minimizing = on; }, *integrator,
                  tolerance, maxIterations);
    return search.run();
}
