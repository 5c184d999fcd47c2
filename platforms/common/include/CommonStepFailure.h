#ifndef MRATTLE_COMMON_STEP_FAILURE_H_
#define MRATTLE_COMMON_STEP_FAILURE_H_

#include "openmm/Vec3.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeEvent.h"
#include "openmm/common/ComputeVectorTypes.h"
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

/**
 * A failed step on the device, found without a blocking read inside a step.
 *
 * The device's failure flag (flag()[0]) is set by the kernel that fails, to 1 + the index of
 * its step since the last check (stepIndex()); every later kernel that would change the
 * state then does nothing, and the backup kernel (the first of each step) stops copying once
 * an earlier step failed (not when another work group of its own step did), so the backups
 * keep the state from before the failed step, all of it of that one time. The host learns
 * of it lazily: at the end of every CopyInterval-th step the flag is copied into host memory
 * of the plugin's own (HostMemory) behind an event, and read when the next copy is queued
 * (the device still has the steps after it queued), so a failure is found at most 2
 * CopyInterval steps late; the frozen state and the backups wait unchanged meanwhile. The
 * blocking check (synchronize()) is made where the state can be read: at the end of each
 * step(n), before checkpoints and kinetic energies, and at reorderings (which read the state
 * anyway). A failure found puts back the state from before the failed step (positions,
 * velocities, box, step count, time) and throws, naming the integrator.
 */
class CommonStepFailure {
public:
    /**
     * A speed (nm/ps) no atom reaches in a simulation that is right (3% of light's; a
     * hydrogen at 10^6 K moves at about 160 nm/ps): beyond it a kicked velocity counts as not
     * finite, which is how the device sees a force that is not finite (OpenMM's fixed-point
     * forces turn infinity into about 2e9 kJ/mol/nm; NaN into that too on x86, as through
     * pocl, but into 0 on CUDA, where it cannot be seen).
     */
    static constexpr double LargestSpeed = 1e4;
    /**
     * Steps between lazy copies of the flag. Copying and waiting every step cost 40 us a step
     * through pocl at 512 waters (a fifth of Verlet+SETTLE's whole step); every 16th step,
     * nothing measurable. A failure found later costs only the frozen steps' force work.
     */
    static constexpr int CopyInterval = 16;
    /**
     * Where the flag's asynchronous copy goes: host memory of the plugin's own, never
     * OpenMM's pinned buffer (which OpenMM overwrites: CUDA's energy sum lands there). Plain
     * memory unless a platform sets its own: OpenCL copies into any host memory without
     * waiting, CUDA only into page-locked memory (platforms/cuda sets cuMemHostAlloc's).
     * Each platform's plugin links its own copy of this class, so the setting is per platform.
     */
    struct HostMemory {
        void* (*allocate)(size_t bytes);
        void (*release)(void* memory);
    };
    static void setHostMemory(const HostMemory& memory);
    CommonStepFailure(OpenMM::ComputeContext& cc, const std::string& integratorName);
    ~CommonStepFailure();
    CommonStepFailure(const CommonStepFailure&) = delete;
    CommonStepFailure& operator=(const CommonStepFailure&) = delete;
    /** Allocate the flag and the backups (OpenMM's arrays must exist). */
    void initialize();
    /** The flag: 0, or 1 + the index of the failed step since the last check. */
    OpenMM::ComputeArray& flag() {
        return failure;
    }
    OpenMM::ComputeArray& posqBackup() {
        return positions;
    }
    /** The position corrections' backup (mixed precision), else the positions' (unused). */
    OpenMM::ComputeArray& correctionBackup() {
        return cc.getUseMixedPrecision() ? corrections : positions;
    }
    OpenMM::ComputeArray& velmBackup() {
        return velocities;
    }
    /**
     * A step begins (before its backup kernel): returns the step's index since the last
     * check, which its kernels record in the flag if they fail. The box is recorded if a
     * barostat changed it since the last step.
     */
    int stepStarted(OpenMM::ContextImpl& context, double stepSize);
    /** What a failing kernel records: the index of the step begun last (0 before the first since the last check). */
    int stepIndex() const {
        return unchecked > 0 ? unchecked - 1 : 0;
    }
    /** A step's kernels are queued: every CopyInterval-th step, the lazy check of the last copy, then a new copy of the flag. */
    void stepQueued();
    /** The blocking check: put the state back and throw if a step failed. No-op without unchecked steps. */
    void synchronize();
    /** Atoms were reordered (a ReorderListener): check now, the backups being in the old order. */
    void atomsReordered();
    /** Remember the device's order and cell offsets, which a reordering with a failure pending starts from. */
    void rememberOrder();
    /**
     * An integrator's own device state (a thermostat's) and its backup, which the
     * integrator's first kernel of each step fills while the flag is clear, as the backup
     * kernel does the atoms': a failure found puts the state back from it too.
     */
    void addState(OpenMM::ComputeArray& state, OpenMM::ComputeArray& backup) {
        states.push_back({&state, &backup});
    }
    /** Forget unchecked steps and clear the flag (a checkpoint was loaded: its state is the state). */
    void reset();

private:
    struct BoxAtStep {
        int step;
        OpenMM::Vec3 box[3];
    };
    /** The state, box, step count and time before the failed step, from the backups in the current order. */
    void restore(int failedStep);
    /** The same after a reordering: the backups permuted on the host, the cell offsets' change undone. */
    void restoreAcrossReorder();
    void restoreClock(int failedStep);
    /** The integrators' own states (addState()) from their backups. */
    void restoreStates();
    std::string message(long long failedStepCount) const;
    /** Forget the unchecked steps. */
    void checked();

    OpenMM::ComputeContext& cc;
    const std::string integratorName;
    OpenMM::ComputeArray failure, positions, corrections, velocities;
    OpenMM::ComputeEvent copied;
    /** The flag's last asynchronous copy (HostMemory), read once the event has passed. */
    int* copy = nullptr;
    /** copyQueued: a copy not read yet; copyEnqueued: a copy was ever queued (the destructor waits for it). */
    bool copyQueued = false, copyEnqueued = false;
    int stepsSinceCopy = 0;
    /** Steps since the last check, their step size, and the step count and time at it. */
    int unchecked = 0;
    double stepSize = 0, timeAtCheck = 0;
    long long stepCountAtCheck = 0;
    /** The box at each change since the last check (a barostat acts in a step's updateContextState). */
    std::vector<BoxAtStep> boxes;
    /** The device order and cell offsets the backups are in (rememberOrder()). */
    std::vector<int> backupOrder;
    std::vector<OpenMM::mm_int4> backupCellOffsets;
    struct StateAndBackup {
        OpenMM::ComputeArray* state;
        OpenMM::ComputeArray* backup;
    };
    std::vector<StateAndBackup> states;
    /** A failure found at a reordering, where nothing may throw: thrown by the next check. */
    std::string deferred;
    /**
     * Test hook (environment variable MRATTLE_TEST_FAIL_AT_STEP, read at initialize()): the
     * step that begins at this step count finds the flag set before its first kernel, as if
     * a work group of that step had failed first; -1: none.
     */
    long long testFailAtStep = -1;
};

} // namespace MRattlePlugin

#endif
