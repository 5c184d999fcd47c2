/*
 * CommonRigidBodyState: the step's phases, its device program and the kernels' arguments.
 */
#include "CommonRigidBodyState.h"
#include "CommonMRattleKernelSources.h"
#include "RigidBodyIntegrator.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** SHAKE and RATTLE iterations allowed for a cluster of free constraints. */
const int MaxConstraintIterations = 1000;
/** Single precision: the rotation solve converges, and velocities count as rigid, at float's round-off. */
const double SingleChordConvergence = 1e-6, SingleRigidVelocityTolerance = 1e-5;
/** A squared velocity or centre, or a rotation vector's length, beyond this counts as not finite on the device. */
const double DeviceFiniteBound = 1e30;
/**
 * How far (nm) a body's atoms may be from its reference geometry before they become its new
 * reference (something else moved it): far above float's round-off, far below a step's motion.
 */
const double StaleReference = 1e-4;
/**
 * Positions set from the host fit a body's reference geometry if no atom is further from it
 * turned than this many times the round-off of the body's stored coordinates (plus a box).
 */
const double FitTolerance = 4;
/**
 * In double precision steps do not rebuild bodies from their reference, which their shapes
 * leave by round-off step by step: there a body (not linear, which the host straightens)
 * also fits within this many nm, far below what the host would correct (1e-6 of a constraint).
 */
const double DoubleFitDistance = 1e-9;

/** A constant as the device code reads it: in the integration arithmetic's precision. */
std::string mixedConstant(double value) {
    std::ostringstream text;
    text.precision(17);
    text << "((mixed) " << value << ")";
    return text.str();
}

} // namespace

int CommonRigidBodyState::shapeCode(RigidBodyMath::Shape shape) {
    return static_cast<int>(shape);
}

std::map<std::string, std::string> CommonRigidBodyState::programDefines(bool useDouble, bool useMixed) {
    const bool doublePrecision = useDouble || useMixed;
    std::map<std::string, std::string> defines;
    if (doublePrecision)
        defines["USE_DOUBLE_MIXED"] = "1";
    if (!useDouble)
        defines["REBUILD_SHAPES"] = "1";  // rebuildsShapes()
    defines["MAX_ROTATION_ITERATIONS"] = std::to_string(RigidBodyMath::MaxRotationIterations);
    defines["MAX_CONSTRAINT_ITERATIONS"] = std::to_string(MaxConstraintIterations);
    defines["CHORD_CONVERGED"] = mixedConstant(doublePrecision ? RigidBodyMath::ChordConvergence : SingleChordConvergence);
    defines["CHORD_SWITCH"] = mixedConstant(RigidBodyMath::ChordSwitch);
    defines["RIGID_TOLERANCE"] =
        mixedConstant(doublePrecision ? RigidBodyMath::RigidVelocityTolerance : SingleRigidVelocityTolerance);
    defines["COLLISION_THRESHOLD"] = mixedConstant(RigidBodyMath::CollisionThreshold);
    defines["FINITE_BOUND"] = mixedConstant(DeviceFiniteBound);
    defines["STALE_REFERENCE"] = mixedConstant(StaleReference);
    defines["FIT_TOLERANCE"] = mixedConstant(FitTolerance);
    defines["DOUBLE_FIT_DISTANCE"] = mixedConstant(DoubleFitDistance);
    defines["LARGEST_SPEED"] = mixedConstant(LargestSpeed);
    defines["REDUCTION_THREADS"] = std::to_string(ReductionThreads);
    defines["LARGE_BODY_ATOMS"] = std::to_string(LargeBodyAtoms);
    defines["LARGE_BODY_THREADS"] = std::to_string(LargeBodyThreads);
    defines["SHAPE_GENERAL"] = std::to_string(shapeCode(RigidBodyMath::Shape::General));
    defines["SHAPE_LINEAR"] = std::to_string(shapeCode(RigidBodyMath::Shape::Linear));
    defines["SHAPE_POINT"] = std::to_string(shapeCode(RigidBodyMath::Shape::Point));
    return defines;
}

std::string CommonRigidBodyState::programSource(const std::string& sources) {
    return CommonMRattleKernelSources::bodyMath + CommonMRattleKernelSources::rotation + CommonMRattleKernelSources::step +
           CommonMRattleKernelSources::freeConstraints + CommonMRattleKernelSources::projection +
           CommonMRattleKernelSources::advance + CommonMRattleKernelSources::largeBodies +
           CommonMRattleKernelSources::reduction + CommonMRattleKernelSources::fitReference +
           CommonMRattleKernelSources::bodyKineticEnergy + sources;
}

CommonRigidBodyState::Arguments CommonRigidBodyState::arguments(ComputeKernel& kernel) {
    return Arguments(kernel, doubleMixed());
}

CommonRigidBodyState::Arguments CommonRigidBodyState::integratorArguments(ComputeKernel& kernel) {
    Arguments arguments(kernel, doubleMixed());
    arguments.add(failure);
    arguments.add(0);  // the step index, set by launch()
    arguments.add(integratorArrays);
    arguments.add(velocityScale);
    arguments.add(partials);
    arguments.add(partialCount);
    return arguments;
}

void CommonRigidBodyState::setMixedArg(ComputeKernel& kernel, int index, double value) const {
    if (doubleMixed())
        kernel->setArg(index, value);
    else
        kernel->setArg(index, (float) value);
}

void CommonRigidBodyState::addBodyArguments(Arguments& arguments) {
    // Only mixed precision has position corrections; the others pass posq in their place, unread.
    arguments.add(numBodies);
    arguments.add(bodyStart);
    arguments.add(bodyAtoms);
    arguments.add(bodyShape);
    arguments.add(cc.getPosq());
    arguments.add(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    arguments.add(cc.getVelm());
}

int CommonRigidBodyState::addBackupArrays(Arguments& arguments) {
    arguments.add(posqBackup);
    arguments.add(cc.getUseMixedPrecision() ? correctionBackup : posqBackup);
    arguments.add(velmBackup);
    arguments.add(integratorArrays);
    arguments.add(integratorBackup);
    arguments.add(integratorSize);
    return arguments.add(-1);
}

void CommonRigidBodyState::setKernelArguments() {
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    ArrayInterface& correction = cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq();
    // OpenMM's device random numbers where something made them; else any float4-sized array, unread.
    ArrayInterface& random = hasRandomNumbers ? integration.getRandom() : static_cast<ArrayInterface&>(velmBackup);

    // advanceLargeBodies takes advanceGroups' arguments, then its list of bodies.
    for (ComputeKernel* kernel : {&advanceGroups, &advanceLargeBodies}) {
        Arguments advance = arguments(*kernel);
        addBodyArguments(advance);
        advance.add(numClusters);
        advance.add(numFree);
        advance.add(bodyReference);
        advance.add(bodyOrientation);
        advance.add(clusterStart);
        advance.add(constraintAtoms);
        advance.add(constraintDistance);
        advance.add(clusterAtomStart);
        advance.add(clusterAtoms);
        advance.add(freeAtoms);
        advance.add(cc.getLongForceBuffer());
        advance.add(cc.getPaddedNumAtoms());
        advance.add(integration.getPosDelta());
        advanceBackupIndex = addBackupArrays(advance);
        advanceKickTime = advance.addMixed(0.0);
        advanceProjectAfterKick = advance.add(0);
        advanceDriftTime = advance.addMixed(0.0);
        advanceTolerance = advance.addMixed(0.0);
        advanceNoiseDecay = advance.addMixed(1.0);
        advanceNoiseScale = advance.addMixed(0.0);
        advance.add(random);
        advanceRandomIndex = advance.add(0u);
        advanceProjectAtEnd = advance.add(0);
        advanceResetFollows = advance.add(0);
        advance.add(failure);
        advanceStepIndex = advance.add(0);
        advance.add(velocityScale);
        advanceScaleVelocities = advance.add(0);
        if (kernel == &advanceLargeBodies) {
            advance.add(largeBodies);
            advance.add(numLargeBodies);
        }
    }

    for (ComputeKernel* kernel : {&projectBodies, &projectLargeBodies}) {
        Arguments projection = arguments(*kernel);
        addBodyArguments(projection);
        projectOnlyIfNotRigid = projection.add(0);
        projection.add(failure);
        if (kernel == &projectLargeBodies) {
            projection.add(largeBodies);
            projection.add(numLargeBodies);
        }
    }

    Arguments freeVelocities = arguments(constrainFreeVelocities);
    freeVelocities.add(numClusters);
    freeVelocities.add(clusterStart);
    freeVelocities.add(constraintAtoms);
    freeVelocities.add(cc.getPosq());
    freeVelocities.add(correction);
    freeVelocities.add(cc.getVelm());
    freeVelocitiesTolerance = freeVelocities.addMixed(0.0);
    freeVelocities.add(failure);
    freeVelocitiesStepIndex = freeVelocities.add(0);

    Arguments sums = arguments(partialSums);
    sums.add(cc.getNumAtoms());
    sums.add(cc.getPosq());
    sums.add(correction);
    sums.add(cc.getVelm());
    sums.add(partials);
    sums.add(partialCount);
    sumsBackupIndex = addBackupArrays(sums);
    sums.add(failure);

    if (hasAndersen)
        for (ComputeKernel* kernel : {&collideBodies, &collideLargeBodies}) {
            Arguments collide = arguments(*kernel);
            addBodyArguments(collide);
            collideKT = collide.addMixed(0.0);
            collide.add(integration.getRandom());
            collideRandomIndex = collide.add(0u);
            collide.add(failure);
            if (kernel == &collideLargeBodies) {
                collide.add(largeBodies);
                collide.add(numLargeBodies);
            }
        }
    if (hasDrudeGroups)
        setDrudeKernelArguments();
    argumentsSet = true;
}

void CommonRigidBodyState::beginStep(ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) {
    if (!argumentsSet)
        setKernelArguments();
    forcesComputed = false;
    cc.getIntegrationUtilities().setNextStepSize(integrator.getStepSize());
    tolerance = integrator.getConstraintTolerance();
    if (hasAndersen && numBodies > 0) {
        // The thermostat (updateContextState) re-drew single atoms: re-draw their whole bodies.
        const double kT = BOLTZ * context.getParameter(AndersenThermostat::Temperature());
        const unsigned int randomIndex = cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms());
        for (ComputeKernel* kernel : {&collideBodies, &collideLargeBodies}) {
            setMixedArg(*kernel, collideKT, kT);
            (*kernel)->setArg(collideRandomIndex, randomIndex);
        }
        collideBodies->execute(numBodies);
        if (numLargeBodies > 0)
            collideLargeBodies->execute(numLargeBodies * LargeBodyThreads, LargeBodyThreads);
        projectNow(tolerance, true);
    }
    // The step's first launch backs up the state (after the collisions: they are the step's start).
    backupStepIndex = stepStarted(integrator.getStepSize());
    if (reordered)
        forcesAreValid = false;  // computed for the atoms' old order
    reordered = false;
    if (!forcesAreValid)
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
}

CommonRigidBodyState::Pass& CommonRigidBodyState::queue(Slot slot) {
    if (pending.last >= slot)
        flush();
    pending.last = slot;
    return pending;
}

void CommonRigidBodyState::scaleVelocities() {
    queue(Slot::Scale).scaleVelocities = true;
}

void CommonRigidBodyState::kick(double time) {
    queue(Slot::Kick).kickTime = time;
}

void CommonRigidBodyState::driftAndReset(double kickTime, double h, double tolerance) {
    this->tolerance = tolerance;
    if (kickTime != 0)
        kick(kickTime);
    // A pass whose noise a drift follows leaves the bodies' projection after the noise to that
    // drift's reset, which reads only what the projection keeps (kernels/advance.cc).
    if (pending.last == Slot::NoiseProjected)
        pending.resetFollows = true;
    queue(Slot::Drift).driftTime = h;
}

void CommonRigidBodyState::addNoise(double friction, double temperature, double h) {
    const double a = std::exp(-friction * h);
    Pass& pass = queue(Slot::Noise);
    pass.noiseDecay = a;
    pass.noiseScale = std::sqrt((1 - a * a) * BOLTZ * temperature);
}

void CommonRigidBodyState::project(double tolerance) {
    this->tolerance = tolerance;
    // After a kick, or first in a pass (after a kernel of the whole device): the pass's first projection.
    if (pending.last == Slot::Kick || pending.last == Slot::None)
        pending.last = Slot::ProjectAfterKick, pending.projectAfterKick = true;
    else if (pending.last == Slot::Noise)
        pending.last = Slot::NoiseProjected;  // the noise's own projection
    else
        queue(Slot::ProjectAtEnd).projectAtEnd = true;
}

void CommonRigidBodyState::computeForces(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                         bool& forcesAreValid) {
    flush();
    cc.getIntegrationUtilities().computeVirtualSites();
    forcesAreValid = false;
    forcesComputed = true;
    context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
}

void CommonRigidBodyState::endStep(double size, bool& forcesAreValid) {
    flush();
    // A step without a computeForces phase leaves the forces to the next step's start.
    if (!forcesComputed)
        cc.getIntegrationUtilities().computeVirtualSites();
    forcesAreValid = forcesComputed;
    forcesComputed = false;
    cc.setTime(cc.getTime() + size);
    cc.setStepCount(cc.getStepCount() + 1);
    reordered = false;
    cc.reorderAtoms();
    if (reordered)
        forcesAreValid = false;
    stepQueued();
}

void CommonRigidBodyState::flush() {
    if (pending.last == Slot::None)
        return;
    if (pending.last == Slot::Noise)
        throw OpenMMException(integratorName + ": internal error, addNoise() without the project() after it");
    const Pass pass = pending;
    pending = Pass();
    launchPass(pass);
}

void CommonRigidBodyState::requireBackup() {
    if (backupStepIndex >= 0)
        launchPass(Pass());
}

void CommonRigidBodyState::launchPass(const Pass& pass) {
    const unsigned int randomIndex =
        pass.noiseScale != 0 ? cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms()) : 0;
    for (ComputeKernel* kernel : {&advanceGroups, &advanceLargeBodies}) {
        if (kernel == &advanceLargeBodies && numLargeBodies == 0)
            break;  // setting arguments costs the host time on small systems
        (*kernel)->setArg(advanceBackupIndex, backupStepIndex);
        setMixedArg(*kernel, advanceKickTime, pass.kickTime);
        (*kernel)->setArg(advanceProjectAfterKick, pass.projectAfterKick ? 1 : 0);
        setMixedArg(*kernel, advanceDriftTime, pass.driftTime);
        setMixedArg(*kernel, advanceTolerance, tolerance);
        setMixedArg(*kernel, advanceNoiseDecay, pass.noiseDecay);
        setMixedArg(*kernel, advanceNoiseScale, pass.noiseScale);
        if (pass.noiseScale != 0)
            (*kernel)->setArg(advanceRandomIndex, randomIndex);
        (*kernel)->setArg(advanceProjectAtEnd, pass.projectAtEnd ? 1 : 0);
        (*kernel)->setArg(advanceResetFollows, pass.resetFollows ? 1 : 0);
        (*kernel)->setArg(advanceStepIndex, failureStepIndex());
        (*kernel)->setArg(advanceScaleVelocities, pass.scaleVelocities ? 1 : 0);
    }
    const int numGroups = numBodies + numClusters + numFree;
    if (numGroups > 0)
        advanceGroups->execute(numGroups);
    if (numLargeBodies > 0)  // after advanceGroups: they read the flag it may have set
        advanceLargeBodies->execute(numLargeBodies * LargeBodyThreads, LargeBodyThreads);
    backupStepIndex = -1;  // once per step
}

void CommonRigidBodyState::sumKineticEnergy() {
    flush();
    partialSums->setArg(sumsBackupIndex, backupStepIndex);
    partialSums->execute(cc.getNumAtoms(), ReductionThreads);
    backupStepIndex = -1;
}

void CommonRigidBodyState::launch(ComputeKernel& kernel, int workItems, int groupSize) {
    flush();
    requireBackup();
    kernel->setArg(1, failureStepIndex());
    kernel->execute(workItems, groupSize);
}

void CommonRigidBodyState::projectNow(double tolerance, bool onlyIfNotRigid) {
    if (!argumentsSet)
        setKernelArguments();
    if (numBodies > 0) {
        projectBodies->setArg(projectOnlyIfNotRigid, onlyIfNotRigid ? 1 : 0);
        projectBodies->execute(numBodies);
        if (numLargeBodies > 0) {
            projectLargeBodies->setArg(projectOnlyIfNotRigid, onlyIfNotRigid ? 1 : 0);
            projectLargeBodies->execute(numLargeBodies * LargeBodyThreads, LargeBodyThreads);
        }
    }
    if (numClusters > 0) {
        setMixedArg(constrainFreeVelocities, freeVelocitiesTolerance, tolerance);
        constrainFreeVelocities->setArg(freeVelocitiesStepIndex, failureStepIndex());
        constrainFreeVelocities->execute(numClusters);
    }
}
