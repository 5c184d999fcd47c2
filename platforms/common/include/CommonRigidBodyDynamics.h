#ifndef MRATTLE_COMMON_RIGID_BODY_DYNAMICS_H_
#define MRATTLE_COMMON_RIGID_BODY_DYNAMICS_H_

#include "internal/BodyShapeConstraints.h"
#include "CommonBodyKineticEnergy.h"
#include "CommonStepFailure.h"
#include "RigidBodyTopology.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/System.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeKernel.h"
#include "openmm/common/ComputeProgram.h"
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyIntegrator;

/**
 * What every rigid-body integrator does the same way on the common compute platforms
 * (OpenCL, CUDA), as ReferenceRigidBodyDynamics does on Reference and CPU: the body and
 * free-constraint arrays on the device (mapped to the device's atom order whenever OpenMM
 * reorders atoms), the phases of a step (kicks, drift and reset, projection, forces), the
 * failure check (CommonStepFailure: lazy within step(n), the state put back), shapes, temperature
 * velocities, kinetic energy and checkpoints. One work item per body or per cluster of
 * free constraints. An integrator's kernel (CommonMRattleKernels.h, ...) sequences the
 * phases.
 */
class CommonRigidBodyDynamics {
public:
    /** @param integratorName  what failures are reported as ("MRattleIntegrator") */
    CommonRigidBodyDynamics(OpenMM::ComputeContext& cc, const std::string& integratorName);
    ~CommonRigidBodyDynamics();
    CommonRigidBodyDynamics(const CommonRigidBodyDynamics&) = delete;
    CommonRigidBodyDynamics& operator=(const CommonRigidBodyDynamics&) = delete;

    /** Upload the bodies and free constraints and compile the step's kernels. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology);
    OpenMM::ComputeContext& computeContext() {
        return cc;
    }
    /** A program of the step's device code with these sources appended (an integrator's own kernels). */
    OpenMM::ComputeProgram compileWith(const std::string& sources);
    /**
     * What compileWith hands to ComputeContext::compileProgram, for a Context's precision
     * flags: the step's device code with these sources appended, and its defines (the host's
     * constants). Static, so the CUDA program check (platforms/cuda/check) compiles the same text.
     */
    static std::string programSource(const std::string& sources);
    static std::map<std::string, std::string> programDefines(bool useDouble, bool useMixed);
    /** Add or set a kernel argument in the precision of the integration arithmetic ('mixed'). */
    void addMixedArg(OpenMM::ComputeKernel& kernel, double value) const;
    void setMixedArg(OpenMM::ComputeKernel& kernel, int index, double value) const;
    /** Start OpenMM's device random numbers (before the first step): the passes' noise draws from them. */
    void initRandomNumbers(int seed);
    /** Whether the System has an AndersenThermostat (its seed then seeds OpenMM's device random numbers). */
    bool hasAndersenThermostat() const {
        return hasAndersen;
    }
    /** The failure flag, for an integrator's own kernels. */
    OpenMM::ComputeArray& failureFlag() {
        return stepFailure.flag();
    }
    /** What an integrator's own kernel that fails records in the flag (CommonStepFailure::stepIndex()). */
    int failureStepIndex() const {
        return stepFailure.stepIndex();
    }
    /**
     * The index of the step whose backup its first pass makes (-1: made already): an
     * integrator's own kernel that changes state of its own before that pass (a thermostat's
     * chain) backs that state up when this is >= 0.
     */
    int stepBackupIndex() const {
        return backupStepIndex;
    }
    /** What a pass with scaleVelocities multiplies every velocity by (one 'mixed' number, set on the device by a thermostat). */
    OpenMM::ComputeArray& velocityScale() {
        return velocityScaleArray;
    }
    /** An integrator's own device state and its backup, put back with the atoms' when a step fails (CommonStepFailure::addState). */
    void addStepState(OpenMM::ComputeArray& state, OpenMM::ComputeArray& backup) {
        stepFailure.addState(state, backup);
    }

    /**
     * The start of every step: back up the state (a failed step puts it back), the Andersen
     * collisions of whole bodies, then the forces unless they are valid for the current
     * positions and atom order.
     */
    void beginStep(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /**
     * The phases of one fused pass over the groups of atoms that move together (a body, a
     * cluster of free constraints, a free atom), in this order, each if asked for: a scaling
     * of the velocities (scaleVelocities); a kick over kickTime with the Context's forces;
     * RATTLE's velocity step; a drift over driftTime with the bodies' resets and SHAKE;
     * Langevin noise (v = a v + noiseScale sqrt(1/m) g, a = noiseDecay) followed by the
     * velocity step; the velocity step.
     * resetFollows: the next pass starts with a drift, so the bodies' velocity step after
     * the noise is left to it (kernels/advance.cc says why that is exact).
     */
    struct Pass {
        double kickTime = 0;
        bool projectAfterKick = false;
        double driftTime = 0;
        double noiseDecay = 1, noiseScale = 0;
        /** Multiply every velocity by velocityScale()[0], after the backup, before the kick (a thermostat's). */
        bool scaleVelocities = false;
        bool projectAtEnd = false;
        bool resetFollows = false;
    };
    /**
     * One launch of the device (kernels/advance.cc); the step's first pass also backs up the
     * state. Free constraints converge to the tolerance of the step (beginStep).
     */
    void advance(const Pass& pass);
    /** A kick over kickTime (0: none), a drift over h, the bodies' resets and the free constraints: one pass. */
    void driftAndReset(double kickTime, double h, double tolerance);
    /** A kick of the Context's velocities over this time with its forces: one pass. */
    void kick(double time);
    /**
     * RATTLE's velocity step: bodies onto rigid-body motion (only those not rigid, if asked),
     * free constraints (outside a step's passes: velocities set from the host, collisions).
     */
    void project(double tolerance, bool onlyIfNotRigid);
    /** Virtual sites at the new positions, then the forces there. */
    void computeForces(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /**
     * The end of every step: advance the clock, let OpenMM reorder atoms (the forces are
     * then no longer those of the atoms' order), and check the previous step's failure flag
     * without waiting for this one's (CommonStepFailure): a failure found puts back the
     * state from before the failed step and throws an OpenMMException.
     */
    void endStep(double stepSize, bool& forcesAreValid);
    /** The end of a step(n) call: the blocking check of the steps not yet checked. */
    void finishSteps();

    /** RigidBodyState's work, the same for every integrator. */
    void updateShapes(OpenMM::ContextImpl& context);
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance);
    std::vector<OpenMM::Vec3> velocitiesForTemperature(OpenMM::ContextImpl& context, double temperature, int randomSeed,
                                                       double tolerance);
    double kineticEnergy();
    /** The kinetic energy of the bodies' translation, their rotation, and the free particles. */
    void kineticEnergies(double& translational, double& rotational, double& free);
    bool isLinear(int body) const {
        return shapes[body] == RigidBodyMath::Shape::Linear;
    }
    int bodyDegreesOfFreedom() const;
    void createCheckpoint(std::ostream& stream) const;
    void loadCheckpoint(std::istream& stream);

private:
    class ReorderListener;
    /** The device's code of a body's shape (bodyShape[body]; SHAPE_* in the device code). */
    static int shapeCode(RigidBodyMath::Shape shape);
    /** Device atom indices of the bodies' atoms and the constraints' ends, after a reorder. */
    void mapAtoms();
    void setKernelArguments();
    /**
     * Whether each step rebuilds the bodies from their reference geometry and orientation:
     * in single and mixed precision, whose round-off would otherwise random-walk the shapes.
     * (In double it would only add state that a State does not hold.)
     */
    bool rebuildsShapes() const {
        return rebuildsShapes(cc.getUseDoublePrecision());
    }
    static bool rebuildsShapes(bool useDouble) {
        return !useDouble;
    }
    /** The bodies' reference geometry from these positions (System order). */
    void setReference(const std::vector<OpenMM::Vec3>& positions);
    /** 9 numbers per body: the identity. */
    std::vector<double> identityOrientations() const;
    /** How far (nm) the device's stored coordinates can be from these positions (0 in double precision). */
    double storageError(OpenMM::ContextImpl& context, const std::vector<OpenMM::Vec3>& positions) const;

    OpenMM::ComputeContext& cc;
    /** Mutable: a checkpoint (const) is written only after the unchecked steps are checked. */
    mutable CommonStepFailure stepFailure;
    RigidBodyTopology bodies;
    // System atom indices: body-major, cluster-major (constraint ends; each atom once), the rest.
    std::vector<int> systemBodyAtoms, systemConstraintAtoms, systemClusterAtoms, systemFreeAtoms;
    std::vector<RigidBodyMath::Shape> shapes;
    std::vector<double> inverseMasses;
    std::unique_ptr<BodyShapeConstraints> shapeConstraints;
    std::unique_ptr<CommonBodyKineticEnergy> bodyKineticEnergy;  // reads bodyStart and bodyAtoms
    int numBodies = 0, numClusters = 0, numFree = 0;
    /** The step's index for the failure flag until its first pass has backed up the state, then -1. */
    int backupStepIndex = -1;
    /** The free constraints' tolerance in this step's passes. */
    double tolerance = 1e-5;
    bool hasAndersen = false, hasRandomNumbers = false, argumentsSet = false;
    /** Set by OpenMM's reorder of atoms: the force buffer then belongs to the old order. */
    bool atomsReordered = false;
    /** Set by a checkpoint's load: the positions OpenMM read next come with the reference geometry it held. */
    bool keepReference = false;
    /** Set while updateShapes() writes corrected positions: the Context notifies the integrator again. */
    bool writingCorrectedShapes = false;
    OpenMM::ComputeProgram program;
    OpenMM::ComputeArray bodyStart, bodyAtoms, bodyShape, clusterStart, constraintAtoms, constraintDistance;
    OpenMM::ComputeArray clusterAtomStart, clusterAtoms, freeAtoms;
    /** Each body atom about its body's centre of mass when positions were set (bodyAtoms' order): the shape rebuilt every step. */
    OpenMM::ComputeArray bodyReference;
    /** Each body's orientation (9 numbers, row-major) turning its reference geometry into its shape now. */
    OpenMM::ComputeArray bodyOrientation;
    OpenMM::ComputeArray velocityScaleArray;
    OpenMM::ComputeKernel advanceGroups, projectBodies, constrainFreeVelocities, collideBodies;
    // Indices of the arguments set at each launch.
    int advanceBackupIndex, advanceKickTime, advanceProjectAfterKick, advanceDriftTime, advanceTolerance,
        advanceNoiseDecay, advanceNoiseScale, advanceRandomIndex, advanceProjectAtEnd, advanceResetFollows,
        advanceStepIndex, advanceScaleVelocities, projectOnlyIfNotRigid, freeVelocitiesTolerance,
        freeVelocitiesStepIndex, collideKT, collideRandomIndex;
};

} // namespace MRattlePlugin

#endif
