/*
 * CommonRigidBodyState: failed steps, found without a blocking read inside a step, and undone.
 *
 * The failing kernel sets the device's flag to 1 + the index of its step since the last check;
 * later kernels then change nothing, and the step's first launch stops backing up once an
 * earlier step failed, so the backup holds the state from before the failed step. Every
 * FlagCopyInterval-th step the flag is copied into the plugin's own host memory behind an
 * event and read when the next copy is queued (a failure is found at most 2 FlagCopyInterval
 * steps late); the blocking check comes at the end of step(n), before checkpoints and kinetic
 * energies, and at reorderings. A failure found puts back positions, velocities, box, step
 * count, time and the integrator's declared arrays from before the failed step, and throws;
 * where the hard wall failed it, the message names the Drude pair its work item recorded
 * (read from the device only then: takeDrudeWallFailure).
 */
#include "CommonRigidBodyState.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/common/ContextSelector.h"
#include <cstdlib>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

bool sameBox(const Vec3* a, const Vec3* b) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/** x rounded to float, as a double (through a volatile: the compiler here dropped the rounding of a plain cast). */
double roundToFloat(double x) {
    volatile float rounded = (float) x;
    return rounded;
}

void* allocatePlain(size_t bytes) {
    return std::calloc(1, bytes);
}

void releasePlain(void* memory) {
    std::free(memory);
}

CommonRigidBodyState::HostMemory hostMemory = {allocatePlain, releasePlain};

} // namespace

void CommonRigidBodyState::setHostMemory(const HostMemory& memory) {
    hostMemory = memory;
}

CommonRigidBodyState::~CommonRigidBodyState() {
    if (flagCopy == nullptr)
        return;
    try {
        if (copyEnqueued)
            flagCopied->wait();  // the device may still be writing into it
    } catch (...) {
    }
    hostMemory.release(flagCopy);
}

void CommonRigidBodyState::initializeFailure() {
    failure.initialize<int>(cc, 1, "mrattleFailure");
    failure.upload(vector<int>(1, 0));
    if (const char* step = std::getenv("MRATTLE_TEST_FAIL_AT_STEP"))
        testFailAtStep = std::atoll(step);
    posqBackup.initialize(cc, cc.getPaddedNumAtoms(), cc.getPosq().getElementSize(), "mrattlePosqBackup");
    if (cc.getUseMixedPrecision())
        correctionBackup.initialize(cc, cc.getPaddedNumAtoms(), cc.getPosq().getElementSize(), "mrattleCorrectionBackup");
    velmBackup.initialize(cc, cc.getPaddedNumAtoms(), cc.getVelm().getElementSize(), "mrattleVelmBackup");
    flagCopied = cc.createEvent();
    if (flagCopy == nullptr) {
        flagCopy = (int*) hostMemory.allocate(sizeof(int));
        if (flagCopy == nullptr)
            throw OpenMMException(integratorName + ": no host memory for the failure flag's copy");
    }
    rememberOrder();
}

int CommonRigidBodyState::stepStarted(double size) {
    if (unchecked > 0 && size != stepSize)
        synchronize();  // the clock of the unchecked steps is replayed with one step size
    if (unchecked == 0) {
        stepSize = size;
        timeAtCheck = cc.getTime();
        stepCountAtCheck = cc.getStepCount();
    }
    BoxAtStep box;
    box.step = unchecked;
    cc.getPeriodicBoxVectors(box.box[0], box.box[1], box.box[2]);
    if (boxes.empty() || !sameBox(boxes.back().box, box.box))
        boxes.push_back(box);
    if (testFailAtStep >= 0 && cc.getStepCount() == testFailAtStep)
        failure.upload(vector<int>(1, unchecked + 1));
    return unchecked++;
}

void CommonRigidBodyState::stepQueued() {
    if (!deferred.empty())
        synchronize();
    if (++stepsSinceCopy < FlagCopyInterval)
        return;
    stepsSinceCopy = 0;
    if (copyQueued) {
        // The last copy's flag: the device has the steps since still queued, so it stays busy.
        flagCopied->wait();
        copyQueued = false;
        if (flagCopy[0] != 0)
            synchronize();  // puts the state back and throws
    }
    failure.download(flagCopy, false);
    flagCopied->enqueue();
    copyQueued = copyEnqueued = true;
}

void CommonRigidBodyState::synchronize() {
    copyQueued = false;  // what it copied is read here, blocking
    if (!deferred.empty()) {
        const std::string text = deferred;
        deferred.clear();
        checked();
        throw OpenMMException(text);
    }
    if (unchecked == 0)
        return;
    int failed;
    failure.download(&failed);
    if (failed == 0) {
        checked();
        return;
    }
    const int failedStep = failed - 1;
    const long long failedStepCount = stepCountAtCheck + failedStep;
    const std::string drudeWall = takeDrudeWallFailure();
    restore(failedStep);
    checked();
    throw OpenMMException(failureMessage(failedStepCount, drudeWall));
}

void CommonRigidBodyState::atomsReordered() {
    // OpenMM reorders only at the end of a step; its reorder has downloaded the state, so
    // this blocking read costs no extra wait.
    if (unchecked > 0 && deferred.empty()) {
        int failed;
        failure.download(&failed);
        if (failed != 0) {
            const int failedStep = failed - 1;
            const long long failedStepCount = stepCountAtCheck + failedStep;
            restoreClock(failedStep);
            integratorBackup.copyTo(integratorArrays);
            restoreAcrossReorder();
            failure.upload(vector<int>(1, 0));
            deferred = failureMessage(failedStepCount, takeDrudeWallFailure());  // a listener must not throw: the next check does
        }
    }
    rememberOrder();
}

void CommonRigidBodyState::rememberOrder() {
    backupOrder = cc.getAtomIndex();
    backupCellOffsets = cc.getPosCellOffsets();
}

void CommonRigidBodyState::resetFailure() {
    failure.upload(vector<int>(1, 0));
    if (hasDrudeGroups)
        drudeFailedPair.upload(vector<int>(1, 0));
    copyQueued = false;
    deferred.clear();
    checked();
}

void CommonRigidBodyState::checked() {
    unchecked = 0;
    boxes.clear();
}

void CommonRigidBodyState::restoreClock(int failedStep) {
    // The box the failed step began with (a barostat may have changed it since).
    const BoxAtStep* box = nullptr;
    for (const BoxAtStep& b : boxes)
        if (b.step <= failedStep)
            box = &b;
    if (box != nullptr)
        cc.setPeriodicBoxVectors(box->box[0], box->box[1], box->box[2]);
    // The time as the steps before it added it up, bit for bit.
    double time = timeAtCheck;
    for (int i = 0; i < failedStep; i++)
        time += stepSize;
    cc.setTime(time);
    cc.setStepCount(stepCountAtCheck + failedStep);
}

void CommonRigidBodyState::restore(int failedStep) {
    restoreClock(failedStep);
    integratorBackup.copyTo(integratorArrays);
    posqBackup.copyTo(cc.getPosq());
    if (cc.getUseMixedPrecision())
        correctionBackup.copyTo(cc.getPosqCorrection());
    velmBackup.copyTo(cc.getVelm());
    failure.upload(vector<int>(1, 0));
}

void CommonRigidBodyState::restoreAcrossReorder() {
    // The backups are in backupOrder with backupCellOffsets; the device now holds atom
    // order[i] at i with offsets[i], where OpenMM reports posq - offset . box.
    const vector<int>& order = cc.getAtomIndex();
    const vector<mm_int4>& offsets = cc.getPosCellOffsets();
    vector<int> oldSlot(order.size());
    for (size_t i = 0; i < backupOrder.size(); i++)
        oldSlot[backupOrder[i]] = i;
    Vec3 box[3];
    cc.getPeriodicBoxVectors(box[0], box[1], box[2]);
    const vector<double> oldPosq = downloadAsDouble(posqBackup, 4), oldVelm = downloadAsDouble(velmBackup, 4);
    vector<double> oldCorrection;
    if (cc.getUseMixedPrecision())
        oldCorrection = downloadAsDouble(correctionBackup, 4);
    vector<double> posq = oldPosq, velm = oldVelm, correction(oldCorrection.size(), 0.0);
    for (size_t i = 0; i < order.size(); i++) {
        const int o = oldSlot[order[i]];
        const Vec3 move = box[0] * (offsets[i].x - backupCellOffsets[o].x) + box[1] * (offsets[i].y - backupCellOffsets[o].y) +
                          box[2] * (offsets[i].z - backupCellOffsets[o].z);
        for (int k = 0; k < 4; k++) {
            velm[4 * i + k] = oldVelm[4 * o + k];
            posq[4 * i + k] = (k < 3 ? oldPosq[4 * o + k] + move[k] : oldPosq[4 * o + k]);
        }
        if (cc.getUseMixedPrecision())
            for (int k = 0; k < 3; k++) {
                // Split again into a float and its correction.
                const double p = oldPosq[4 * o + k] + oldCorrection[4 * o + k] + move[k];
                posq[4 * i + k] = roundToFloat(p);
                correction[4 * i + k] = p - posq[4 * i + k];
            }
    }
    uploadFromDouble(cc.getPosq(), posq, 4);
    uploadFromDouble(cc.getVelm(), velm, 4);
    if (cc.getUseMixedPrecision())
        uploadFromDouble(cc.getPosqCorrection(), correction, 4);
}

std::string CommonRigidBodyState::failureMessage(long long failedStepCount, const std::string& drudeWall) const {
    if (!drudeWall.empty())
        return integratorName + ": at step " + std::to_string(failedStepCount) + " " + drudeWall +
               ": the step size is too large for the forces, or they are not finite. The Context holds the state "
               "from before that step.";
    return integratorName + ": at step " + std::to_string(failedStepCount) +
           " the position reset of a rigid body found no rotation, the free-particle constraints did not converge, " +
           (hasDrudeGroups ? "a Drude particle went beyond twice the hard wall's maxDrudeDistance from its core, " : "") +
           "or a velocity was not finite (or beyond " + std::to_string((int) LargestSpeed) + " nm/ps, what a force that is "
           "not finite gives on the device): the step size is too large for the forces, or they are not finite. The "
           "Context holds the state from before that step.";
}

