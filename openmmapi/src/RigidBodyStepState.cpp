#include "internal/RigidBodyStepState.h"
#include "openmm/OpenMMException.h"
#include <cmath>

using namespace MRattlePlugin;
using OpenMM::OpenMMException;

namespace {

/** What to do after a refused checkpoint, in the refusal and in every refused step after it. */
const char* const RefusedCheckpointRecovery =
    "OpenMM had already loaded its own part of that checkpoint (positions, velocities, time, box, parameters, random "
    "state), which may be damaged: call Context::reinitialize() (without preserving the state), then set the state "
    "again (Context::setState() with a saved State, or positions and velocities), or load a checkpoint that fits. "
    "The integrator will not step until then";

} // namespace

void RigidBodyStepState::reset() {
    *this = RigidBodyStepState();
}

void RigidBodyStepState::positionsAccepted() {
    positionsNotFinite = false;
    positionsSet = true;
}

void RigidBodyStepState::positionsRefused() {
    positionsNotFinite = true;
}

RigidBodyStepState::VelocityUse RigidBodyStepState::velocitiesChanged(bool byPositions, bool integratorIsCurrent) {
    // After a refused checkpoint the velocities are that checkpoint's (on some platforms
    // garbage): they are projected once new ones are set.
    if (byPositions && velocitiesNotFinite && !loadingCheckpoint)
        return VelocityUse::WaitForNew;
    // Otherwise the velocities are usable until a projection says they are not.
    velocitiesNotFinite = false;
    if (loadingCheckpoint)
        return VelocityUse::KeepLoaded;
    if (integratorIsCurrent && positionsSet && !refusedCheckpoint)
        return VelocityUse::ProjectNow;
    velocitiesNeedProjection = true;
    return VelocityUse::ProjectBeforeStep;
}

void RigidBodyStepState::checkpointLoaded() {
    loadingCheckpoint = true;
    refusedCheckpoint = false;
}

void RigidBodyStepState::checkpointRefused() {
    refusedCheckpoint = true;
    forcesValid = false;
}

bool RigidBodyStepState::finishCheckpointLoad(long long stepCount) {
    if (!loadingCheckpoint)
        return false;
    loadingCheckpoint = false;
    lastStepCount = stepCount;
    velocitiesNeedProjection = false;
    return true;
}

std::string RigidBodyStepState::refusedCheckpointMessage(const std::string& reason) {
    return "loadCheckpoint: " + reason + ". " + RefusedCheckpointRecovery;
}

void RigidBodyStepState::requireSteppable(double stepSize) const {
    if (stepSize == 0 || !std::isfinite(stepSize))
        throw OpenMMException("The step size must be a finite nonzero number of picoseconds, got " +
                              std::to_string(stepSize));
    if (!std::isfinite(1.0 / stepSize))
        throw OpenMMException("The step size " + std::to_string(stepSize) + " ps is too small: its inverse is not finite");
    if (refusedCheckpoint)
        throw OpenMMException(std::string("step: the last loadCheckpoint() was refused. ") + RefusedCheckpointRecovery);
    if (!positionsSet)
        throw OpenMMException("step: the Context's positions have not been set");
    if (positionsNotFinite)
        throw OpenMMException("step: the Context's positions are not finite; set finite ones before stepping");
    if (velocitiesNotFinite)
        throw OpenMMException("step: the Context's velocities are not finite, or could not be made rigid at its "
                              "positions; set velocities again before stepping");
}

bool RigidBodyStepState::mustProjectBeforeStep(long long stepCount) {
    if (stepCount == lastStepCount && !velocitiesNeedProjection)
        return false;
    forcesValid = false;
    return true;
}
