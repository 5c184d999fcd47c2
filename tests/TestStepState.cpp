/*
 * RigidBodyStepState on its own: what a rigid-body integrator may do after each event
 * (positions or velocities set or refused, a checkpoint loaded or refused, a step taken),
 * and that reset() (what initialize() calls) forgets every one of them, an unfinished
 * checkpoint load too. The integrator-level behaviour is TestCheckpoint's, TestFaults'
 * and TestCompound's.
 */
#include "internal/RigidBodyStepState.h"
#include "openmm/OpenMMException.h"
#include <gtest/gtest.h>
#include <string>

using MRattlePlugin::RigidBodyStepState;
using OpenMM::OpenMMException;
using Use = RigidBodyStepState::VelocityUse;

namespace {

/** The message requireSteppable() throws, or "" if it does not throw. */
std::string refusal(const RigidBodyStepState& state, double stepSize = 0.002) {
    try {
        state.requireSteppable(stepSize);
    } catch (const OpenMMException& e) {
        return e.what();
    }
    return "";
}

/** A state ready to step: positions and velocities set and used, one step taken at step count 1. */
RigidBodyStepState readyState() {
    RigidBodyStepState state;
    state.positionsAccepted();
    EXPECT_EQ(Use::ProjectNow, state.velocitiesChanged(false, true));
    state.stepTaken(1);
    return state;
}

} // namespace

TEST(StepState, FreshStateRefusesToStepUntilPositionsAreSet) {
    RigidBodyStepState state;
    EXPECT_NE(std::string::npos, refusal(state).find("positions have not been set"));
    EXPECT_FALSE(state.havePositions());
    // Velocities before positions wait for them.
    EXPECT_EQ(Use::ProjectBeforeStep, state.velocitiesChanged(false, true));
    state.positionsAccepted();
    EXPECT_EQ("", refusal(state));
    EXPECT_NE(std::string::npos, refusal(state, 0).find("finite nonzero"));
    EXPECT_NE(std::string::npos, refusal(state, 1e-320).find("too small"));
}

TEST(StepState, RefusedValuesWaitForNewOnes) {
    RigidBodyStepState state = readyState();
    state.positionsRefused();
    EXPECT_NE(std::string::npos, refusal(state).find("positions are not finite"));
    state.positionsAccepted();
    EXPECT_EQ("", refusal(state));
    state.velocitiesRefused();
    EXPECT_NE(std::string::npos, refusal(state).find("velocities are not finite"));
    // New positions do not make refused velocities usable; new velocities do.
    EXPECT_EQ(Use::WaitForNew, state.velocitiesChanged(true, true));
    EXPECT_NE("", refusal(state));
    EXPECT_EQ(Use::ProjectNow, state.velocitiesChanged(false, true));
    EXPECT_EQ("", refusal(state));
}

TEST(StepState, VelocitiesSetWhileAnotherIntegratorIsCurrentAreProjectedBeforeTheStep) {
    RigidBodyStepState state = readyState();
    EXPECT_FALSE(state.mustProjectBeforeStep(1));
    EXPECT_EQ(Use::ProjectBeforeStep, state.velocitiesChanged(false, false));
    state.forcesAreValid() = true;
    EXPECT_TRUE(state.mustProjectBeforeStep(1));
    EXPECT_FALSE(state.forcesAreValid());
    state.projectedBeforeStep();
    EXPECT_FALSE(state.mustProjectBeforeStep(1));
    // Another integrator stepped: the step count moved on without this one.
    EXPECT_TRUE(state.mustProjectBeforeStep(2));
}

TEST(StepState, RefusedCheckpointBlocksStepsUntilResetOrAFittingOne) {
    RigidBodyStepState state = readyState();
    state.forcesAreValid() = true;
    state.checkpointRefused();
    EXPECT_FALSE(state.forcesAreValid());
    EXPECT_NE(std::string::npos, refusal(state).find("loadCheckpoint() was refused"));
    // Its velocities are not projected now (they may be garbage), but once the refusal is lifted.
    EXPECT_EQ(Use::ProjectBeforeStep, state.velocitiesChanged(false, true));
    EXPECT_NE("", refusal(state));
    state.checkpointLoaded();
    EXPECT_EQ("", refusal(state));
    state.checkpointRefused();
    state.reset();
    EXPECT_NE(std::string::npos, refusal(state).find("positions have not been set"));
    EXPECT_EQ(std::string::npos, refusal(state).find("refused"));
}

TEST(StepState, FittingCheckpointKeepsItsVelocitiesAndContinuesItsRun) {
    RigidBodyStepState state = readyState();
    state.velocitiesRefused();
    state.checkpointLoaded();
    EXPECT_EQ(Use::KeepLoaded, state.velocitiesChanged(true, true));
    EXPECT_EQ(Use::KeepLoaded, state.velocitiesChanged(false, true));
    EXPECT_TRUE(state.finishCheckpointLoad(40));
    EXPECT_FALSE(state.finishCheckpointLoad(40));  // a later energy notification is not a load
    EXPECT_EQ("", refusal(state));
    EXPECT_FALSE(state.mustProjectBeforeStep(40));
    EXPECT_EQ(Use::ProjectNow, state.velocitiesChanged(false, true));
}

TEST(StepState, ResetForgetsAnUnfinishedCheckpointLoad) {
    RigidBodyStepState state = readyState();
    state.checkpointLoaded();
    state.reset();
    state.positionsAccepted();
    // Velocities set after reset() are the user's, to be made rigid, not a checkpoint's.
    EXPECT_EQ(Use::ProjectNow, state.velocitiesChanged(false, true));
    EXPECT_FALSE(state.finishCheckpointLoad(0));
    EXPECT_TRUE(state.mustProjectBeforeStep(0));
}
