#ifndef MRATTLE_COMMON_RIGID_BODY_STATE_H_
#define MRATTLE_COMMON_RIGID_BODY_STATE_H_

#include "RigidBodyTopology.h"
#include "internal/BodyShapeConstraints.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyState.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/System.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeEvent.h"
#include "openmm/common/ComputeKernel.h"
#include "openmm/common/ComputeProgram.h"
#include "openmm/common/ComputeVectorTypes.h"
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace MRattlePlugin {

class RigidBodyIntegrator;

/**
 * The rigid-body state on OpenMM's common compute platforms (OpenCL, CUDA), one per Context
 * whatever the integrator: the bodies and free constraints on the device (mapped anew when
 * OpenMM reorders atoms), their shapes and reference geometry, the step's phases, the
 * integrator's own device arrays, and what a failed step puts back. Files, one class:
 * CommonRigidBodyState.cpp (set-up, kinetic energies, velocities), CommonRigidBodyStep.cpp
 * (the phases, the program, kernel arguments), CommonRigidBodyShapes.cpp (shapes,
 * checkpoints), CommonRigidBodyFailure.cpp (failed steps found lazily and undone).
 *
 * A step is a list of phases (beginStep ... endStep). Consecutive phases that a group of
 * atoms (a body, a cluster of free constraints, a free atom) can do alone are queued and
 * run as one launch (advanceGroups in kernels/advance.cc) when a phase that needs the whole
 * device comes: computeForces, endStep, sumKineticEnergy, an integrator's own kernel.
 * Failures are found lazily: a failing kernel sets a device flag, read at most
 * 2 FlagCopyInterval steps later or at the end of step(n).
 */
class CommonRigidBodyState : public RigidBodyState {
public:
    /** @param integratorName  what failures are reported as ("MRattleIntegrator") */
    CommonRigidBodyState(OpenMM::ComputeContext& cc, const std::string& integratorName);
    ~CommonRigidBodyState() override;
    CommonRigidBodyState(const CommonRigidBodyState&) = delete;
    CommonRigidBodyState& operator=(const CommonRigidBodyState&) = delete;

    /**
     * Upload the bodies and free constraints and compile the program: the step's device code
     * with an integrator's own (sources), whose kernels it takes from program().
     */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology, const std::string& sources = "");
    OpenMM::ComputeContext& computeContext() {
        return cc;
    }
    OpenMM::ComputeProgram& program() {
        return stepProgram;
    }
    /** Start OpenMM's device random numbers, unless an AndersenThermostat already did (OpenMM has one generator). */
    void initRandomNumbers(int seed);

    /** The step's device code with these sources appended, and its defines (static: platforms/cuda/check compiles them). */
    static std::string programSource(const std::string& sources);
    static std::map<std::string, std::string> programDefines(bool useDouble, bool useMixed);

    // ---- The phases of a step, in the order an integrator lists them.
    /** Andersen collisions of whole bodies, then the forces unless valid for these positions and atom order. */
    void beginStep(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /** Every velocity times the factor an integrator's own kernel left in velocityScale[0] (a thermostat's). */
    void scaleVelocities();
    /** Velocities kicked over this time by the Context's forces. */
    void kick(double time);
    /** A kick over kickTime (0: none), then a drift over h with M-RATTLE's reset of each body and SHAKE for the free constraints. */
    void driftAndReset(double kickTime, double h, double tolerance);
    /** Langevin's friction and noise over h (v = a v + sqrt((1 - a^2) kT / m) g, a = exp(-friction h)); a project() must follow. */
    void addNoise(double friction, double temperature, double h);
    /** RATTLE's velocity step: bodies onto rigid-body motion, free constraints to the tolerance. */
    void project(double tolerance);
    /**
     * The Drude integrators' noise (drudeFriction 0 for the plain split): each Drude group's
     * rigid motion R at the temperature, the rest C at the Drude temperature, every other atom
     * as addNoise (kernels/drude.cc); a project() must follow. Needs setDrudeGroups().
     */
    void addDrudeNoise(double friction, double temperature, double drudeFriction, double drudeTemperature, double h);
    /** The hard wall after the drift (nothing if maxDistance <= 0); beyond twice it the step fails. */
    void bounceDrudes(double maxDistance, double drudeTemperature, double h);
    /**
     * sumKineticEnergy(), and twice the Drude groups' KE_C summed per work group into
     * drudeRelativeEnergies() (their count in drudeRelativeCount()), for a two-chain thermostat's kernel (which puts its factors for R and C into velocityScale[0], [1]).
     */
    void sumDrudeKineticEnergies();
    /** The Drude groups' KE_C now (their relative-energy kernels, outside a step; one read). */
    double computeDrudeKineticEnergy();
    /** Every Drude group's R scaled by velocityScale[0], its C by velocityScale[1]; every other atom by [0]. */
    void scaleDrudeVelocities();
    /** Virtual sites at the new positions, then the forces there. */
    void computeForces(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /** The clock, OpenMM's reordering, and the lazy failure check (a failure found is undone and thrown). */
    void endStep(double stepSize, bool& forcesAreValid);

    // ---- What an integrator's own kernels use.
    /**
     * Declare the integrator's own device variables once (a thermostat's chain): each a name
     * (a State's integrator parameter) and a size, in 'mixed' precision. The state backs them
     * up with each step, puts them back when a step fails, checkpoints them
     * (writeIntegratorVariables; lengthFirst: their common length first) and returns them as
     * integrator parameters. Returns each one's offset in the state's one array of them.
     */
    std::vector<int> declareIntegratorArrays(const std::vector<std::pair<std::string, int> >& arrays, bool lengthFirst);
    /**
     * Add an integrator kernel's first arguments, STATE_ARGUMENTS in kernels/bodyMath.cc:
     * the failure flag and step index, the declared arrays, the velocity scale and
     * sumKineticEnergy's partial sums. Its own arguments follow (Arguments::add).
     */
    class Arguments;
    Arguments integratorArguments(OpenMM::ComputeKernel& kernel);
    /** Arguments of a kernel from the start, each add returning its index for setMixedArg/setArg. */
    Arguments arguments(OpenMM::ComputeKernel& kernel);
    /** Set a number in the integration arithmetic's precision ('mixed'). */
    void setMixedArg(OpenMM::ComputeKernel& kernel, int index, double value) const;
    /**
     * Twice the kinetic energy as partial sums per work group, for the kernel that adds them
     * up (addPartialSums in the device code).
     */
    void sumKineticEnergy();
    /**
     * The System's Drude groups (DrudeGroups), on the device for the Drude phases above; after
     * initialize() with CommonMRattleKernelSources::drude among its sources.
     */
    void setDrudeGroups(const DrudeGroups& groups);
    /** Twice the Drude groups' KE_C, as sumDrudeKineticEnergies() leaves it (one partial sum per work group). */
    OpenMM::ComputeArray& drudeRelativeEnergies() {
        return drudeRelative;
    }
    OpenMM::ComputeArray& drudeRelativeCount() {
        return drudeRelativeCountArray;
    }
    /** Launch an integrator kernel (made with integratorArguments) in the step's order. */
    void launch(OpenMM::ComputeKernel& kernel, int workItems, int groupSize = -1);
    /** The work-group size of sumKineticEnergy and of an integrator's one-group kernels (REDUCTION_THREADS). */
    static constexpr int ReductionThreads = 128;
    /** A device array of these numbers in the integration arithmetic's precision ('mixed'). */
    void initializeMixedArray(OpenMM::ComputeArray& array, const std::vector<double>& values, const std::string& name);
    /** The System's degrees of freedom, by the plugin's rule. */
    int degreesOfFreedom() const;

    // ---- RigidBodyState.
    void updateShapes(OpenMM::ContextImpl& context) override;
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override;
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override;
    void finishSteps(OpenMM::ContextImpl& context) override;
    bool isBodyLinear(int index) const override;
    int getBodyDegreesOfFreedom() const override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context) override;
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override;
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override;

    /**
     * A speed (nm/ps) no atom reaches in a simulation that is right (3% of light's): beyond
     * it a kicked velocity counts as not finite, which is how the device sees a force that is
     * not finite (OpenMM's fixed-point forces turn infinity into about 2e9 kJ/mol/nm).
     */
    static constexpr double LargestSpeed = 1e4;
    /** Steps between lazy copies of the failure flag to the host. */
    static constexpr int FlagCopyInterval = 16;
    /**
     * Bodies of more atoms than this (not linear) are moved, projected and collided by a work
     * group of LargeBodyThreads each (kernels/largeBodies.cc, collisions.cc), their sums reduced in
     * local memory (their kinetic energies too, linear or not); smaller ones by one work item.
     */
    static constexpr int LargeBodyAtoms = 64;
    static constexpr int LargeBodyThreads = 64;
    /**
     * Host memory for the flag's asynchronous copy, the plugin's own (OpenMM overwrites its
     * pinned buffer). Plain memory unless a platform sets its own: CUDA copies asynchronously
     * only into page-locked memory. Each platform's plugin links its own copy of this class.
     */
    struct HostMemory {
        void* (*allocate)(size_t bytes);
        void (*release)(void* memory);
    };
    static void setHostMemory(const HostMemory& memory);

    /** A device array of floats or doubles (perElement numbers each: 1, or 4 for real4 and mixed4) as doubles. */
    static std::vector<double> downloadAsDouble(const OpenMM::ArrayInterface& array, int perElement = 1);
    static void uploadFromDouble(OpenMM::ArrayInterface& array, const std::vector<double>& values, int perElement = 1);

private:
    class ReorderListener;
    /** The phases queued for one launch of advanceGroups, in its order (Slot). */
    enum class Slot { None, Scale, Kick, ProjectAfterKick, Drift, Noise, NoiseProjected, ProjectAtEnd };
    struct Pass {
        Slot last = Slot::None;
        bool scaleVelocities = false, projectAfterKick = false, projectAtEnd = false, resetFollows = false;
        double kickTime = 0, driftTime = 0, noiseDecay = 1, noiseScale = 0;
    };
    /** Start a new pass if this phase cannot follow the queued ones in advanceGroups' order. */
    Pass& queue(Slot slot);
    /** Launch the queued phases, if any. */
    void flush();
    /** One launch of advanceGroups; the step's first launch also backs up the state. */
    void launchPass(const Pass& pass);
    /** The backup of the step's state if no launch of this step has made it yet (before an integrator's kernel). */
    void requireBackup();
    /** RATTLE's velocity step outside a step (velocities set from the host, collisions). */
    void projectNow(double tolerance, bool onlyIfNotRigid);
    /** Device atom indices of the bodies' atoms and the constraints' ends, after a reorder. */
    void mapAtoms();
    void setKernelArguments();
    /** The Drude kernels' arguments (CommonRigidBodyDrude.cpp). */
    void setDrudeKernelArguments();
    /** DRUDE_GROUP_ARGUMENTS of the device code. */
    void addDrudeGroupArguments(Arguments& arguments);
    /** A *LargeGroups Drude kernel, a work group per large group, where there are any. */
    void launchOnLargeDrudeGroups(OpenMM::ComputeKernel& kernel);
    /** BODY_ARGUMENTS of the device code. */
    void addBodyArguments(Arguments& arguments);
    /** BACKUP_ARGUMENTS of the device code; returns the index of backupStepIndex. */
    int addBackupArrays(Arguments& arguments);
    /** 0 for general bodies, ...: the device's code of a shape (SHAPE_* in the device code). */
    static int shapeCode(RigidBodyMath::Shape shape);
    /** Whether steps rebuild bodies from their reference geometry (single and mixed precision, against round-off drift). */
    bool rebuildsShapes() const {
        return !cc.getUseDoublePrecision();
    }
    /** The bodies' reference geometry and identity orientations from these positions (made exact in place in single and mixed precision). */
    void setReference(std::vector<OpenMM::Vec3>& positions);
    /** Each body's three atoms from which fitsReference() turns its reference (bodyFrame). */
    void chooseFrames(const std::vector<OpenMM::Vec3>& positions);
    /**
     * Whether the positions on the device are every body's reference geometry turned (the
     * bodies' orientations then set to those turns): no download, one 4-byte read.
     */
    bool fitsReference(OpenMM::ContextImpl& context);
    /** Whether the screen just launched found anything (one 4-byte read); the verdict is cleared for the next. */
    bool screenFound();
    /** projectVelocities' check on the host, for velocities the device's screen found unusable. */
    void projectVelocitiesOnHost(OpenMM::ContextImpl& context, double tolerance);
    std::vector<double> identityOrientations() const;
    void uploadIdentityOrientations();
    /** How far a stored coordinate of these positions may be from what was set (storage round-off). */
    double storageError(OpenMM::ContextImpl& context, const std::vector<OpenMM::Vec3>& positions) const;
    /** A stored coordinate's relative round-off, and the longest box vector (by which OpenMM may shift one). */
    double coordinateRoundoff() const;
    static double largestBoxVector(OpenMM::ContextImpl& context);
    bool doubleMixed() const {
        return cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
    }

    // Failures (CommonRigidBodyFailure.cpp).
    void initializeFailure();
    /** A step begins: its index since the last check, which its kernels record in the flag if they fail. */
    int stepStarted(double stepSize);
    /** What a failing kernel records: the index of the step begun last. */
    int failureStepIndex() const {
        return unchecked > 0 ? unchecked - 1 : 0;
    }
    /** Every FlagCopyInterval-th step: read the last copy of the flag, queue a new one. */
    void stepQueued();
    /** The blocking check: put the state back and throw if a step failed. */
    void synchronize();
    void atomsReordered();
    void rememberOrder();
    void resetFailure();
    void restore(int failedStep);
    void restoreAcrossReorder();
    void restoreClock(int failedStep);
    /**
     * Where a failure was found: the Drude particle, its core and the wall, if the hard wall
     * failed the step ("" if not), read from the device and cleared.
     */
    std::string takeDrudeWallFailure();
    std::string failureMessage(long long failedStepCount, const std::string& drudeWall = "") const;
    void checked();

    OpenMM::ComputeContext& cc;
    const std::string integratorName;
    RigidBodyTopology bodies;
    // System atom indices: body-major, cluster-major (constraint ends; each atom once), the rest.
    std::vector<int> systemBodyAtoms, systemConstraintAtoms, systemClusterAtoms, systemFreeAtoms;
    std::vector<RigidBodyMath::Shape> shapes;
    std::vector<double> inverseMasses;
    std::unique_ptr<BodyShapeConstraints> shapeConstraints;
    int numBodies = 0, numClusters = 0, numFree = 0;
    double tolerance = 1e-5;
    bool hasAndersen = false, hasRandomNumbers = false, argumentsSet = false;
    /** Set by OpenMM's reorder of atoms: the force buffer then belongs to the old order. */
    bool reordered = false;
    bool forcesComputed = false;  // the step under way has had its computeForces phase
    /** Set by a checkpoint's load: the positions OpenMM reads next come with the reference geometry it held. */
    bool keepReference = false;
    /** Whether bodyReference and bodyFrame hold what the host last classified (fitsReference() can check positions). */
    bool referenceOnDevice = false;
    /** Set while updateShapes() writes corrected positions (the Context notifies the integrator again). */
    bool writingCorrectedShapes = false;
    Pass pending;
    /** Host buffers of positions and velocities set from the host, kept to reuse their memory. */
    std::vector<OpenMM::Vec3> hostPositions;
    std::vector<OpenMM::mm_float4> referenceSingle;
    std::vector<OpenMM::mm_double4> referenceDouble;
    std::vector<float> identitySingle;
    std::vector<double> identityDouble;
    /** The shape codes bodyShape holds. */
    std::vector<int> uploadedShapeCodes;
    /** The step's index for the flag until its first launch has backed up the state, then -1. */
    int backupStepIndex = -1;

    OpenMM::ComputeProgram stepProgram;
    OpenMM::ComputeArray bodyStart, bodyAtoms, bodyShape, clusterStart, constraintAtoms, constraintDistance;
    OpenMM::ComputeArray clusterAtomStart, clusterAtoms, freeAtoms;
    /** Each body atom about its body's centre of mass when positions were set: the shape rebuilt every step. */
    OpenMM::ComputeArray bodyReference;
    /** Each body's orientation (9 numbers, row-major) turning its reference geometry into its shape now. */
    OpenMM::ComputeArray bodyOrientation;
    OpenMM::ComputeArray velocityScale;
    /** sumKineticEnergy's partial sums (1 per work group) and their count. */
    OpenMM::ComputeArray partials, partialCount;
    /** Each body's three atoms (offsets) from which fitBodies turns its reference. */
    OpenMM::ComputeArray bodyFrame;
    std::vector<OpenMM::mm_int4> hostFrames;
    OpenMM::ComputeKernel fitBodies;
    int fitRoundoff = 0;
    /** The verdict of a screen of values set from the host (fitBodiesToReference, findUnusableVelocities): 1 if it found any. */
    OpenMM::ComputeArray screenVerdict;
    /** The bodies' kinetic energies (3 per body), computeKineticEnergies' kernels created at its first call. */
    OpenMM::ComputeArray bodyEnergies;
    /** The bodies of more than LargeBodyAtoms atoms (body indices), and their count. */
    OpenMM::ComputeArray largeBodies;
    int numLargeBodies = 0;
    OpenMM::ComputeKernel advanceLargeBodies, projectLargeBodies;
    OpenMM::ComputeKernel advanceGroups, projectBodies, constrainFreeVelocities, collideBodies, collideLargeBodies,
        partialSums, bodyKineticEnergy, largeBodyKineticEnergy, findUnusable;
    // The Drude groups (setDrudeGroups, CommonRigidBodyDrude.cpp): System indices, group-major
    // (a group's atoms, then its Drude particles), where each is placed in R (itself, a Drude particle's
    // core), the atoms in no group, (Drude, core) pairs group-major.
    std::vector<int> systemDrudeGroupAtoms, systemDrudeGroupPlaces, systemUngroupedAtoms, systemDrudePairAtoms;
    int numDrudeGroupsOnDevice = 0, numUngrouped = 0;
    bool hasDrudeGroups = false;
    OpenMM::ComputeArray drudeGroupStart, drudeGroupAtoms, drudeGroupPlaces, drudeGroupRotates, ungroupedAtoms, drudePairStart,
        drudePairAtoms, drudeNoiseField, drudeRelative, drudeRelativeCountArray;
    /** 1 + the index (in systemDrudePairAtoms / 2) of a pair the hard wall failed on; 0: none. */
    OpenMM::ComputeArray drudeFailedPair;
    /** The hard wall's maxDrudeDistance at the last bounceDrudes, for a failure's message. */
    double drudeWallDistance = 0;
    OpenMM::ComputeKernel drudeNoise, drudeHardWall, drudeRelativeEnergy, drudeScale;
    /** The groups of bodies of more than LargeBodyAtoms particles (group indices), a work group each, and their KE_C. */
    OpenMM::ComputeArray largeDrudeGroups, largeDrudeRelative;
    int numLargeDrudeGroups = 0;
    OpenMM::ComputeKernel drudeNoiseLarge, drudeHardWallLarge, drudeRelativeEnergyLarge, drudeScaleLarge;
    int drudeNoiseArguments, drudeNoiseRandomIndex, drudeWallArguments, drudeWallLargeArguments;
    int advanceBackupIndex, advanceKickTime, advanceProjectAfterKick, advanceDriftTime, advanceTolerance,
        advanceNoiseDecay, advanceNoiseScale, advanceRandomIndex, advanceProjectAtEnd, advanceResetFollows,
        advanceStepIndex, advanceScaleVelocities, projectOnlyIfNotRigid, freeVelocitiesTolerance,
        freeVelocitiesStepIndex, collideKT, collideRandomIndex, sumsBackupIndex;

    // The integrator's declared arrays, one device array (integratorArrays) and its backup.
    struct DeclaredArray {
        std::string name;
        int offset, size;
    };
    std::vector<DeclaredArray> declared;
    /** The declared arrays by name, from the device. */
    IntegratorParameterValues integratorValues() const;
    int integratorSize = 0;
    bool lengthFirst = false;
    OpenMM::ComputeArray integratorArrays, integratorBackup;

    // The failure flag and the step's backup (CommonRigidBodyFailure.cpp).
    struct BoxAtStep {
        int step;
        OpenMM::Vec3 box[3];
    };
    OpenMM::ComputeArray failure;
    OpenMM::ComputeArray posqBackup, correctionBackup, velmBackup;
    OpenMM::ComputeEvent flagCopied;
    /** The flag's last asynchronous copy (HostMemory), read once the event has passed. */
    int* flagCopy = nullptr;
    bool copyQueued = false;
    bool copyEnqueued = false;
    int stepsSinceCopy = 0;
    /** Steps since the last check, their step size, and the step count and time at it. */
    int unchecked = 0;
    double stepSize = 0, timeAtCheck = 0;
    long long stepCountAtCheck = 0;
    /** The box at each change since the last check (a barostat acts in a step's updateContextState). */
    std::vector<BoxAtStep> boxes;
    /** The device order and cell offsets the backups are in. */
    std::vector<int> backupOrder;
    std::vector<OpenMM::mm_int4> backupCellOffsets;
    /** A failure found at a reordering, where nothing may throw: thrown by the next check. */
    std::string deferred;
    /** Test hook (MRATTLE_TEST_FAIL_AT_STEP, read at initialize): the step beginning at this count fails first; -1: none. */
    long long testFailAtStep = -1;
};

/** A device kernel's arguments in the order of its signature; each add returns the argument's index. */
class CommonRigidBodyState::Arguments {
public:
    Arguments(OpenMM::ComputeKernel& kernel, bool doubleMixed) : kernel(kernel), doubleMixed(doubleMixed) {
    }
    template <class T>
    int add(const T& value) {
        kernel->addArg(value);
        return count++;
    }
    int add(OpenMM::ArrayInterface& array) {
        kernel->addArg(array);
        return count++;
    }
    int add(OpenMM::ComputeArray& array) {
        kernel->addArg(array);
        return count++;
    }
    /** A number in the integration arithmetic's precision ('mixed'). */
    int addMixed(double value) {
        if (doubleMixed)
            kernel->addArg(value);
        else
            kernel->addArg((float) value);
        return count++;
    }

private:
    OpenMM::ComputeKernel& kernel;
    bool doubleMixed;
    int count = 0;
};

} // namespace MRattlePlugin

#endif
