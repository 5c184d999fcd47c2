/*
 * CommonRigidBodyDynamics' device program: compiled with the host's constants as defines
 * (limits, tolerances, shape codes, the finiteness bound), and each kernel's arguments.
 */
#include "CommonRigidBodyDynamics.h"
#include "CommonKernelArguments.h"
#include "CommonMRattleKernelSources.h"
#include "openmm/common/IntegrationUtilities.h"
#include <map>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** SHAKE and RATTLE iterations allowed for a cluster of free constraints. */
const int MaxConstraintIterations = 1000;
/**
 * In single precision the rotation solve converges, and velocities count as rigid, at
 * float's round-off instead of double's (RigidBodyMath::ChordConvergence,
 * RigidVelocityTolerance).
 */
const double SingleChordConvergence = 1e-6, SingleRigidVelocityTolerance = 1e-5;
/**
 * A squared velocity, a squared body centre or a rotation vector's length beyond this
 * counts as not finite on the device (its only finiteness test: NaN fails the comparison).
 */
const double DeviceFiniteBound = 1e30;
/**
 * How far (nm) a body's atoms may be from its reference geometry in its orientation before
 * they are taken as its new reference (something else moved it): far above the storage's
 * round-off (float's at 30 nm from the origin: 2e-6 nm), far below a step's motion.
 */
const double StaleReference = 1e-4;

/** A constant as the device code reads it: in the integration arithmetic's precision. */
std::string mixedConstant(double value) {
    std::ostringstream text;
    text.precision(17);
    text << "((mixed) " << value << ")";
    return text.str();
}

} // namespace

int CommonRigidBodyDynamics::shapeCode(RigidBodyMath::Shape shape) {
    return static_cast<int>(shape);
}

std::map<std::string, std::string> CommonRigidBodyDynamics::programDefines(bool useDouble, bool useMixed) {
    const bool doublePrecision = useDouble || useMixed;
    std::map<std::string, std::string> defines;
    if (doublePrecision)
        defines["USE_DOUBLE_MIXED"] = "1";
    if (rebuildsShapes(useDouble))
        defines["REBUILD_SHAPES"] = "1";
    defines["MAX_ROTATION_ITERATIONS"] = std::to_string(RigidBodyMath::MaxRotationIterations);
    defines["MAX_CONSTRAINT_ITERATIONS"] = std::to_string(MaxConstraintIterations);
    defines["CHORD_CONVERGED"] = mixedConstant(doublePrecision ? RigidBodyMath::ChordConvergence : SingleChordConvergence);
    defines["CHORD_SWITCH"] = mixedConstant(RigidBodyMath::ChordSwitch);
    defines["RIGID_TOLERANCE"] =
        mixedConstant(doublePrecision ? RigidBodyMath::RigidVelocityTolerance : SingleRigidVelocityTolerance);
    defines["COLLISION_THRESHOLD"] = mixedConstant(RigidBodyMath::CollisionThreshold);
    defines["FINITE_BOUND"] = mixedConstant(DeviceFiniteBound);
    defines["STALE_REFERENCE"] = mixedConstant(StaleReference);
    defines["LARGEST_SPEED"] = mixedConstant(CommonStepFailure::LargestSpeed);
    defines["SHAPE_GENERAL"] = std::to_string(shapeCode(RigidBodyMath::Shape::General));
    defines["SHAPE_LINEAR"] = std::to_string(shapeCode(RigidBodyMath::Shape::Linear));
    defines["SHAPE_POINT"] = std::to_string(shapeCode(RigidBodyMath::Shape::Point));
    return defines;
}

std::string CommonRigidBodyDynamics::programSource(const std::string& sources) {
    return CommonMRattleKernelSources::bodyMath + CommonMRattleKernelSources::rotation + CommonMRattleKernelSources::step +
           CommonMRattleKernelSources::freeConstraints + CommonMRattleKernelSources::projection +
           CommonMRattleKernelSources::advance + sources;
}

ComputeProgram CommonRigidBodyDynamics::compileWith(const std::string& sources) {
    return cc.compileProgram(programSource(sources),
                             programDefines(cc.getUseDoublePrecision(), cc.getUseMixedPrecision()));
}

void CommonRigidBodyDynamics::addMixedArg(ComputeKernel& kernel, double value) const {
    if (cc.getUseDoublePrecision() || cc.getUseMixedPrecision())
        kernel->addArg(value);
    else
        kernel->addArg((float) value);
}

void CommonRigidBodyDynamics::setMixedArg(ComputeKernel& kernel, int index, double value) const {
    if (cc.getUseDoublePrecision() || cc.getUseMixedPrecision())
        kernel->setArg(index, value);
    else
        kernel->setArg(index, (float) value);
}

void CommonRigidBodyDynamics::setKernelArguments() {
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    ArrayInterface& posq = cc.getPosq();
    // Only mixed precision has position corrections; the others pass posq in their place, unread.
    ArrayInterface& correction = cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq();
    const int padded = cc.getPaddedNumAtoms();
    const bool doubleMixed = cc.getUseDoublePrecision() || cc.getUseMixedPrecision();

    CommonKernelArguments advance(advanceGroups, doubleMixed);
    advance.add(numBodies);
    advance.add(numClusters);
    advance.add(numFree);
    advance.add(bodyStart);
    advance.add(bodyAtoms);
    advance.add(bodyShape);
    advance.add(bodyReference);
    advance.add(bodyOrientation);
    advance.add(clusterStart);
    advance.add(constraintAtoms);
    advance.add(constraintDistance);
    advance.add(clusterAtomStart);
    advance.add(clusterAtoms);
    advance.add(freeAtoms);
    advance.add(posq);
    advance.add(correction);
    advance.add(cc.getVelm());
    advance.add(cc.getLongForceBuffer());
    advance.add(padded);
    advance.add(integration.getPosDelta());
    advance.add(stepFailure.posqBackup());
    advance.add(stepFailure.correctionBackup());
    advance.add(stepFailure.velmBackup());
    advanceBackupIndex = advance.add(-1);
    advanceKickTime = advance.addMixed(0.0);
    advanceProjectAfterKick = advance.add(0);
    advanceDriftTime = advance.addMixed(0.0);
    advanceTolerance = advance.addMixed(0.0);
    advanceNoiseDecay = advance.addMixed(1.0);
    advanceNoiseScale = advance.addMixed(0.0);
    // OpenMM's device random numbers where a thermostat made them; else any float4-sized array, unread.
    if (hasRandomNumbers)
        advance.add(integration.getRandom());
    else
        advance.add(stepFailure.velmBackup());
    advanceRandomIndex = advance.add(0u);
    advanceProjectAtEnd = advance.add(0);
    advanceResetFollows = advance.add(0);
    advance.add(stepFailure.flag());
    advanceStepIndex = advance.add(0);
    advance.add(velocityScaleArray);
    advanceScaleVelocities = advance.add(0);

    CommonKernelArguments projection(projectBodies, doubleMixed);
    projection.add(numBodies);
    projection.add(bodyStart);
    projection.add(bodyAtoms);
    projection.add(bodyShape);
    projection.add(posq);
    projection.add(correction);
    projection.add(cc.getVelm());
    projectOnlyIfNotRigid = projection.add(0);
    projection.add(stepFailure.flag());

    CommonKernelArguments freeVelocities(constrainFreeVelocities, doubleMixed);
    freeVelocities.add(numClusters);
    freeVelocities.add(clusterStart);
    freeVelocities.add(constraintAtoms);
    freeVelocities.add(posq);
    freeVelocities.add(correction);
    freeVelocities.add(cc.getVelm());
    freeVelocitiesTolerance = freeVelocities.addMixed(0.0);
    freeVelocities.add(stepFailure.flag());
    freeVelocitiesStepIndex = freeVelocities.add(0);

    if (hasAndersen) {
        CommonKernelArguments collide(collideBodies, doubleMixed);
        collide.add(numBodies);
        collide.add(bodyStart);
        collide.add(bodyAtoms);
        collide.add(bodyShape);
        collide.add(posq);
        collide.add(correction);
        collide.add(cc.getVelm());
        collideKT = collide.addMixed(0.0);
        collide.add(integration.getRandom());
        collideRandomIndex = collide.add(0u);
        collide.add(stepFailure.flag());
    }
    argumentsSet = true;
}
