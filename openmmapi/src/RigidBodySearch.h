#ifndef MRATTLE_RIGID_BODY_SEARCH_H_
#define MRATTLE_RIGID_BODY_SEARCH_H_

/*
 * The rigid minimizer's search (internal to the API library; RigidBodyMinimizer is its
 * facade): L-BFGS over the bodies' rigid-body coordinates (core's RigidBodyCoordinates) and
 * the free particles' Cartesian ones, with LocalEnergyMinimizer's evaluation, springs and
 * restarts.
 */
#include "RigidBodyMinimizer.h"
#include "RigidBodyTopology.h"
#include "openmm/Context.h"
#include "openmm/VerletIntegrator.h"
#include "openmm/internal/ContextImpl.h"
#include <lbfgs.h>
#include <functional>
#include <memory>
#include <string>
#include <vector>

// The core's classes and this one are internal to the library: hidden, so that no symbol of
// theirs (templates of them included) is exported by libMRattlePlugin.so.
#if defined(__GNUC__)
#pragma GCC visibility push(hidden)
#endif
#include "mrattle/RigidBodyCoordinates.h"

namespace MRattlePlugin {

/** How the minimizer's messages begin. */
inline const std::string MinimizerPrefix = "RigidBodyMinimizer::minimize: ";

class RigidBodySearch {
public:
    /**
     * impl: the Context's implementation, for LocalEnergyMinimizer's evaluation (no kinetic
     * energy, no State); searching(true) has the integrator skip its work at each
     * setPositions() (shapes, velocities) until searching(false).
     */
    RigidBodySearch(OpenMM::Context& context, OpenMM::ContextImpl& impl, const std::function<void(bool)>& searching,
                    const RigidBodyTopology& topology, double constraintTolerance, double tolerance, int maxIterations,
                    RigidBodyMinimizationReporter* reporter);

    /** Minimize; the Context ends at the best point found (also when it throws). */
    RigidBodyMinimizationReport run();

private:
    static lbfgsfloatval_t evaluateCallback(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g, int,
                                            lbfgsfloatval_t) {
        return static_cast<RigidBodySearch*>(instance)->evaluate(x, g);
    }
    static int progressCallback(void* instance, const lbfgsfloatval_t*, const lbfgsfloatval_t* g, lbfgsfloatval_t,
                                lbfgsfloatval_t, lbfgsfloatval_t, lbfgsfloatval_t, int, int, int) {
        return static_cast<RigidBodySearch*>(instance)->progress(g);
    }

    void restartAt(const std::vector<OpenMM::Vec3>& positions, bool resetOrientations);
    void positionsOf(const double* x, std::vector<OpenMM::Vec3>& positions) const;
    double evaluate(const double* x, double* g);
    double evaluateUnchecked(const double* x, double* g);
    double addSprings(double* g);
    /** After each iteration (g: liblbfgs's gradient there): report it, test it; nonzero stops liblbfgs (Stop). */
    int progress(const double* g);
    /** Call the reporter with the iterate in OpenMM's terms (RigidBodySearchReport.cpp); true: stop. */
    bool reportIteration(const double* g);
    struct Point;
    /**
     * sqrt(3 |g|^2 / D): the rms generalized force per degree of freedom (D of them, the
     * variables), in units of one particle's force; converged when it is <= tolerance
     * (docs/minimization.md, convergence).
     */
    double rmsForce(const Point& point) const;
    bool converged(const Point& point) const;
    void rebase();
    double maxFreeConstraintError(const std::vector<OpenMM::Vec3>& positions) const;
    void setContextPositions(const std::vector<OpenMM::Vec3>& positions);
    double hostForces();
    void makeHostContext(OpenMM::Platform& host);
    void search();
    [[noreturn]] void fail(const std::string& what);

    OpenMM::Context& context;
    OpenMM::ContextImpl& impl;
    std::function<void(bool)> searching;
    /**
     * Platforms that sum forces in fixed point clip very large ones: then, as
     * LocalEnergyMinimizer does, the forces are recomputed on the CPU (or Reference) platform.
     */
    bool clipsLargeForces = false;
    std::unique_ptr<OpenMM::VerletIntegrator> hostIntegrator;  // one per host Context (OpenMM binds it once)
    std::unique_ptr<OpenMM::Context> hostContext;
    const OpenMM::System& system;
    const RigidBodyTopology& topology;
    double tolerance;
    int maxIterations;
    RigidBodyMinimizationReporter* reporter;
    int groups;
    double workingConstraintTolerance, springConstant;

    std::vector<RigidBodyMath::RigidBodyCoordinates> bodies;
    /** Where each body's variables start in x. */
    std::vector<int> offsets;
    std::vector<int> freeParticles;
    int numVariables = 0;
    /** The liblbfgs vector (padded to a multiple of 8 with variables of zero gradient, for SSE builds). */
    std::unique_ptr<lbfgsfloatval_t, void (*)(lbfgsfloatval_t*)> x{nullptr, lbfgs_free};
    int paddedVariables = 0;
    std::vector<OpenMM::Vec3> startPositions, trial, forces;
    /** nm per unit of liblbfgs's variables (FirstStepRms). */
    double lengthScale = 1;

    /** The last evaluation, and the last accepted point (liblbfgs's iterate). */
    struct Point {
        double energy = 0, springEnergy = 0, gradientNorm2 = 0;
    } last, accepted;
    /** An evaluation of the objective at some variables. */
    struct Evaluation {
        bool valid = false;
        std::vector<double> variables, gradient;
        Point point;
        double value = 0;
    };
    /** The last evaluation, for liblbfgs's repeat of it; invalid once the variables or springs change meaning. */
    Evaluation cached;
    /**
     * The lowest evaluation since the variables last changed meaning. On huge forces a line
     * search can fail (its sufficient decrease out of reach) after a trial far below the
     * iterate: the search goes on from that trial, as LocalEnergyMinimizer ends at its last.
     */
    Evaluation best;
    /** After a failed line search (status < 0): move to the best trial if it is lower, updating status; true if moved. */
    bool continueFromBestTrial(int& status);
    /** Over the whole search; since the springs were last stiffened (the reporter's iteration). */
    int iterations = 0, roundIterations = 0, evaluations = 0;
    std::string failure;  // set when an evaluation found something not finite
};

} // namespace MRattlePlugin

#if defined(__GNUC__)
#pragma GCC visibility pop
#endif

#endif
