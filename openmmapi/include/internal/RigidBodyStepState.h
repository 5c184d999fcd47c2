#ifndef MRATTLE_RIGID_BODY_STEP_STATE_H_
#define MRATTLE_RIGID_BODY_STEP_STATE_H_

#include "internal/windowsExportMRattle.h"
#include <string>

namespace MRattlePlugin {

/**
 * What a RigidBodyIntegrator knows about the state of its Context between calls: whether
 * the forces are still valid, whether positions and velocities were set and could be
 * used, whether the last checkpoint was refused or is still being loaded, and whether the
 * velocities must be made rigid before the next step. The integrator reports each event
 * (a named transition below) and asks this class what to do; reset() is the one way back
 * to the state of a newly bound Context. It holds flags only: the kernel calls stay in the
 * integrator.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyStepState {
public:
    /** What to do with the Context's velocities once positions or velocities were set. */
    enum class VelocityUse {
        /** They are a fitting checkpoint's, rigid by construction: keep them bit for bit. */
        KeepLoaded,
        /** The velocities last set were refused: nothing to project until new ones are set. */
        WaitForNew,
        /** Make them rigid now (then velocitiesRefused() if that fails). */
        ProjectNow,
        /** Make them rigid before the next step (another integrator is current, or no positions yet). */
        ProjectBeforeStep
    };

    /** The state of a newly bound (or reinitialized) Context: nothing set, nothing loaded. */
    void reset();

    /** Any change to the Context's state: the forces must be computed again. */
    void invalidateForces() { forcesValid = false; }
    /** The flag handed to the kernel's execute(): true if the Context's forces are those of the current positions. */
    bool& forcesAreValid() { return forcesValid; }

    /** New positions were set and the kernel could use them. */
    void positionsAccepted();
    /** New positions were set but are not finite: stepping waits until new ones are set. */
    void positionsRefused();
    /** Whether positions were ever set (or loaded): rigid-body velocities are defined only relative to them. */
    bool havePositions() const { return positionsSet; }

    /**
     * Positions (byPositions) or velocities were set: what to do with the Context's
     * velocities, the state updated accordingly.
     *
     * @param integratorIsCurrent  whether this integrator steps the Context (it may be a member of a CompoundIntegrator)
     */
    VelocityUse velocitiesChanged(bool byPositions, bool integratorIsCurrent);
    /** The velocities could not be made rigid (or are not finite): stepping waits until new ones are set. */
    void velocitiesRefused() { velocitiesNotFinite = true; }

    /** A checkpoint that fits was loaded; OpenMM's notifications of its data follow. */
    void checkpointLoaded();
    /**
     * A checkpoint was refused after OpenMM had loaded its own part: stepping waits for
     * reset() or a checkpoint that fits.
     */
    void checkpointRefused();
    /**
     * OpenMM's last notification of a checkpoint load (the energy): if a load is under way,
     * end it, continuing as the run that wrote the checkpoint, and return true.
     */
    bool finishCheckpointLoad(long long stepCount);
    /** The message of a refused checkpoint (reason: what did not fit), and what to do about it. */
    static std::string refusedCheckpointMessage(const std::string& reason);

    /**
     * Throw an OpenMMException saying why the integrator cannot step (a step size that is
     * zero or not finite, a refused checkpoint, positions not set or not finite, velocities
     * refused); return if it can.
     */
    void requireSteppable(double stepSize) const;
    /**
     * Before a step at the Context's step count: whether the velocities must be made rigid
     * first (another integrator stepped since this one did, or velocities were set while it
     * was not current). If so, the forces are invalidated.
     */
    bool mustProjectBeforeStep(long long stepCount);
    /** The velocities were made rigid before a step. */
    void projectedBeforeStep() { velocitiesNeedProjection = false; }
    /** This integrator took a step; the Context's step count is now stepCount. */
    void stepTaken(long long stepCount) { lastStepCount = stepCount; }

private:
    bool forcesValid = false;
    /** Velocities were set while another integrator was current (or before positions): project them before stepping. */
    bool velocitiesNeedProjection = false;
    /** The Context's step count after this integrator's last step; another value means another integrator stepped. */
    long long lastStepCount = -1;
    /** A refused checkpoint left mixed data: stepping waits for reset() or a checkpoint that fits. */
    bool refusedCheckpoint = false;
    /**
     * The last positions or velocities set were not finite (or the velocities could not be
     * made rigid at the positions): stepping waits until new ones are set.
     */
    bool positionsNotFinite = false, velocitiesNotFinite = false;
    bool positionsSet = false;
    /**
     * Between a checkpoint load that fits and its last notification: its velocities are
     * this integrator's, rigid by construction, and are kept untouched (bit for bit).
     */
    bool loadingCheckpoint = false;
};

} // namespace MRattlePlugin

#endif
