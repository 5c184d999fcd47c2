#ifndef MRATTLE_RIGID_BODY_MINIMIZER_H_
#define MRATTLE_RIGID_BODY_MINIMIZER_H_

#include "openmm/Context.h"
#include "internal/windowsExportMRattle.h"
#include <map>
#include <string>
#include <vector>

namespace MRattlePlugin {

/** What one RigidBodyMinimizer::minimize() call did. Energies in kJ/mol, forces in kJ/mol/nm. */
struct OPENMM_EXPORT_MRATTLE RigidBodyMinimizationReport {
    /** L-BFGS iterations (accepted line searches), over all of its restarts. */
    int iterations = 0;
    /** Energy and force evaluations (of the Context, and the final energy when free constraints were projected). */
    int evaluations = 0;
    /** Potential energy at the start (after the free particles' constraints are applied) and at the end. */
    double initialEnergy = 0, finalEnergy = 0;
    /**
     * The root mean square generalized force at the end, per degree of freedom in units of
     * one particle's force, sqrt(3 |g|^2 / D), the quantity the tolerance bounds: |g|^2 is per
     * body |F|^2/n + tau . I^-1 tau (net force F and torque tau about its centroid, I its
     * inertia with unit masses: the force projected on rigid motion), plus each free
     * particle's |f|^2 with the constraint springs; D counts 6 per body (5 linear, 3 a
     * point) and 3 per free particle. For free particles alone it is OpenMM's rms force over
     * particles.
     */
    double rmsForce = 0;
};

/**
 * Called by RigidBodyMinimizer::minimize() after each iteration, with the arguments of OpenMM
 * 8's MinimizationReporter::report() (this class exists on every OpenMM version the plugin
 * builds with; ForwardingMinimizationReporter passes the calls on to an OpenMM reporter):
 *  - iteration: the index of the iteration within the present strength of the free
 *    particles' constraint springs (from 0; back to 0 when the springs are stiffened);
 *  - x: the Cartesian positions of the iterate, flattened (x0, y0, z0, x1, ...), virtual
 *    sites included; every body has its exact starting shape;
 *  - grad: the gradient of the objective (potential energy plus spring energy) that the
 *    search sees, as Cartesian components: for a body's atoms minus the force projected on
 *    the body's rigid motion (unit masses: net force / n + w x r, w = I^-1 torque), for a
 *    free particle minus its force with its springs, zero for others; |grad|^2 is the
 *    search's squared generalized force;
 *  - args: "system energy" (potential energy, kJ/mol), "restraint energy" (the free
 *    particles' constraint springs, kJ/mol), "restraint strength" (their force constant,
 *    kJ/mol/nm^2), "max constraint error" (the largest relative error |r - d| / d of any
 *    constraint of the System at x).
 * Returning true ends the L-BFGS search at this iterate: minimize() then returns, unless a
 * free particle's constraint is still off by more than the working tolerance, in which case
 * the springs are stiffened and the search goes on (as LocalEnergyMinimizer does).
 */
class OPENMM_EXPORT_MRATTLE RigidBodyMinimizationReporter {
public:
    virtual ~RigidBodyMinimizationReporter() {
    }
    virtual bool report(int iteration, const std::vector<double>& x, const std::vector<double>& grad,
                        std::map<std::string, double>& args) = 0;
};

/**
 * A RigidBodyMinimizationReporter that passes each call on to `reporter`, any object with
 * OpenMM 8's report(iteration, x, grad, args), e.g. an OpenMM::MinimizationReporter:
 *
 *     ForwardingMinimizationReporter<OpenMM::MinimizationReporter> forward(myReporter);
 *     RigidBodyMinimizer::minimize(context, 10, 0, &forward);
 */
template <class Reporter>
class ForwardingMinimizationReporter : public RigidBodyMinimizationReporter {
public:
    explicit ForwardingMinimizationReporter(Reporter& reporter) : reporter(reporter) {
    }
    bool report(int iteration, const std::vector<double>& x, const std::vector<double>& grad,
                std::map<std::string, double>& args) override {
        return reporter.report(iteration, x, grad, args);
    }

private:
    Reporter& reporter;
};

/**
 * LocalEnergyMinimizer for rigid bodies: searches for a local minimum of the potential energy
 * over the rigid-body coordinates of the bodies in effect of the Context's rigid-body
 * integrator (RigidBodyIntegrator::getBodiesInEffect()). Each body moves by a translation of
 * its centroid and a rotation applied to its shape at the start, which therefore never
 * changes (to round-off); a linear body has two rotations, a point body none. Free particles
 * move in Cartesian coordinates with their constraints held as LocalEnergyMinimizer holds
 * them: harmonic springs, stiffened tenfold until every constraint is within
 * max(1e-4, the integrator's constraint tolerance) nm of its length (OpenMM 7.7's test), then
 * Context::applyConstraints(). Massless particles stay where they are and virtual sites
 * follow their parents. The generalized forces are each body's net force and torque, from
 * the forces of the integrator's integration force groups; the search is L-BFGS (liblbfgs,
 * the code OpenMM's own minimizer embeds, with the same backtracking line search).
 *
 * It evaluates on the host with the ContextImpl calls of LocalEnergyMinimizer's host version
 * (setPositions, computeVirtualSites, calcForcesAndEnergy, getForces), so it runs unchanged
 * on every platform the integrator runs on (Reference, CPU, OpenCL): its own work is O(N) per
 * evaluation, next to the force evaluation that dominates both minimizers. During the search
 * the integrator skips its own work at setPositions(); the search's last setPositions() does it.
 *
 * C++ callers of OpenMM::LocalEnergyMinimizer::minimize() do not get this minimizer: the
 * plugin cannot intercept that call (up to OpenMM 8.4 a function of libOpenMM; from 8.5 a
 * MinimizeKernel that a plugin could only replace for every integrator). They get OpenMM's
 * Cartesian minimizer, which deforms bodies whose shapes no constraints determine; the
 * positions it sets become the bodies' shapes, as any positions set do. Call
 * RigidBodyMinimizer::minimize() instead, with the
 * same arguments. From Python, openmm.LocalEnergyMinimizer.minimize() (and so
 * app.Simulation.minimizeEnergy()) is this minimizer after 'import mrattle'.
 *
 * After it, the Context holds the best point found: the energy is never above the starting
 * one; the integrator's bodies keep their shapes, and the velocities are the integrator's
 * projection onto rigid motion at the new positions (as after any setPositions()).
 */
class OPENMM_EXPORT_MRATTLE RigidBodyMinimizer {
public:
    /**
     * Minimize the potential energy of a Context whose integrator is one of the plugin's
     * rigid-body integrators (or a CompoundIntegrator holding one: its current integrator if
     * that is a rigid-body one, else its first rigid-body member).
     *
     * @param context        the Context to minimize; on exit it holds the new positions
     * @param tolerance      in kJ/mol/nm: the search stops once the rms generalized force per
     *                       degree of freedom (RigidBodyMinimizationReport::rmsForce) is at most
     *                       this, unscaled, as OpenMM 8.5's device minimizer tests its rms force
     *                       (docs/minimization.md, convergence: why per degree of freedom and
     *                       not scaled by |x| as OpenMM 7.7 to 8.4). Must be finite and >= 0
     *                       (default 10).
     * @param maxIterations  the most L-BFGS iterations, as LocalEnergyMinimizer's (0: until
     *                       converged); here counted over all restarts. Must be >= 0.
     * @param reporter       called after each iteration (may be null); returning true stops
     *                       the search (RigidBodyMinimizationReporter). An exception it throws
     *                       ends the search as an error does.
     * @return what it did
     * @throws OpenMMException for a bad argument, a Context without a rigid-body integrator or
     *         without positions, or an energy, force or position that is not finite during the
     *         search (naming it; the Context is then left at the best point found)
     */
    static RigidBodyMinimizationReport minimize(OpenMM::Context& context, double tolerance = 10,
                                                int maxIterations = 0,
                                                RigidBodyMinimizationReporter* reporter = nullptr);
    /** True if minimize() applies: the Context's integrator is, or holds, a rigid-body integrator. */
    static bool appliesTo(OpenMM::Context& context);
};

} // namespace MRattlePlugin

#endif
