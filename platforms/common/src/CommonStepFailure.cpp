#include "CommonStepFailure.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cstdlib>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

bool sameBox(const Vec3* a, const Vec3* b) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/** Downloaded device coordinates or velocities, in double whatever the device keeps. */
vector<mm_double4> downloadAsDouble(ArrayInterface& array) {
    vector<mm_double4> values(array.getSize());
    if (array.getElementSize() == sizeof(mm_double4))
        array.download(values.data());
    else {
        vector<mm_float4> single(array.getSize());
        array.download(single.data());
        for (size_t i = 0; i < single.size(); i++)
            values[i] = mm_double4(single[i].x, single[i].y, single[i].z, single[i].w);
    }
    return values;
}

/** x rounded to float, as a double (through a volatile: the compiler here dropped the rounding of a plain cast). */
double roundToFloat(double x) {
    volatile float rounded = (float) x;
    return rounded;
}

void uploadFromDouble(ArrayInterface& array, const vector<mm_double4>& values) {
    if (array.getElementSize() == sizeof(mm_double4))
        array.upload(values.data());
    else {
        vector<mm_float4> single(values.size());
        for (size_t i = 0; i < values.size(); i++)
            single[i] = mm_float4(values[i].x, values[i].y, values[i].z, values[i].w);
        array.upload(single.data());
    }
}

void* allocatePlain(size_t bytes) {
    return std::calloc(1, bytes);
}

void releasePlain(void* memory) {
    std::free(memory);
}

CommonStepFailure::HostMemory hostMemory = {allocatePlain, releasePlain};

} // namespace

void CommonStepFailure::setHostMemory(const HostMemory& memory) {
    hostMemory = memory;
}

CommonStepFailure::CommonStepFailure(ComputeContext& cc, const std::string& integratorName)
    : cc(cc), integratorName(integratorName) {
}

CommonStepFailure::~CommonStepFailure() {
    if (copy == nullptr)
        return;
    try {
        if (copyEnqueued)
            copied->wait();  // the device may still be writing into it
    } catch (...) {
    }
    hostMemory.release(copy);
}

void CommonStepFailure::initialize() {
    failure.initialize<int>(cc, 1, "mrattleFailure");
    failure.upload(vector<int>(1, 0));
    if (const char* step = std::getenv("MRATTLE_TEST_FAIL_AT_STEP"))
        testFailAtStep = std::atoll(step);
    positions.initialize(cc, cc.getPaddedNumAtoms(), cc.getPosq().getElementSize(), "mrattlePosqBackup");
    if (cc.getUseMixedPrecision())
        corrections.initialize(cc, cc.getPaddedNumAtoms(), cc.getPosq().getElementSize(), "mrattleCorrectionBackup");
    velocities.initialize(cc, cc.getPaddedNumAtoms(), cc.getVelm().getElementSize(), "mrattleVelmBackup");
    copied = cc.createEvent();
    if (copy == nullptr) {
        copy = (int*) hostMemory.allocate(sizeof(int));
        if (copy == nullptr)
            throw OpenMMException(integratorName + ": no host memory for the failure flag's copy");
    }
    rememberOrder();
}

int CommonStepFailure::stepStarted(ContextImpl& context, double size) {
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
    if (cc.getStepCount() == testFailAtStep)
        failure.upload(vector<int>(1, unchecked + 1));
    return unchecked++;
}

void CommonStepFailure::stepQueued() {
    if (!deferred.empty())
        synchronize();
    if (++stepsSinceCopy < CopyInterval)
        return;
    stepsSinceCopy = 0;
    if (copyQueued) {
        // The last copy's flag: the device has the steps since still queued, so it stays busy.
        copied->wait();
        copyQueued = false;
        if (copy[0] != 0)
            synchronize();  // puts the state back and throws
    }
    failure.download(copy, false);
    copied->enqueue();
    copyQueued = copyEnqueued = true;
}

void CommonStepFailure::synchronize() {
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
    restore(failedStep);
    checked();
    throw OpenMMException(message(failedStepCount));
}

void CommonStepFailure::atomsReordered() {
    // OpenMM reorders only at the end of a step; its reorder has downloaded the state, so
    // this blocking read costs no extra wait.
    if (unchecked > 0 && deferred.empty()) {
        int failed;
        failure.download(&failed);
        if (failed != 0) {
            const int failedStep = failed - 1;
            const long long failedStepCount = stepCountAtCheck + failedStep;
            restoreClock(failedStep);
            restoreStates();
            restoreAcrossReorder();
            failure.upload(vector<int>(1, 0));
            deferred = message(failedStepCount);  // a listener must not throw: the next check does
        }
    }
    rememberOrder();
}

void CommonStepFailure::rememberOrder() {
    backupOrder = cc.getAtomIndex();
    backupCellOffsets = cc.getPosCellOffsets();
}

void CommonStepFailure::reset() {
    failure.upload(vector<int>(1, 0));
    copyQueued = false;
    deferred.clear();
    checked();
}

void CommonStepFailure::checked() {
    unchecked = 0;
    boxes.clear();
}

void CommonStepFailure::restoreClock(int failedStep) {
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

void CommonStepFailure::restoreStates() {
    for (const StateAndBackup& s : states)
        s.backup->copyTo(*s.state);
}

void CommonStepFailure::restore(int failedStep) {
    restoreClock(failedStep);
    restoreStates();
    positions.copyTo(cc.getPosq());
    if (cc.getUseMixedPrecision())
        corrections.copyTo(cc.getPosqCorrection());
    velocities.copyTo(cc.getVelm());
    failure.upload(vector<int>(1, 0));
}

void CommonStepFailure::restoreAcrossReorder() {
    // The backups are in backupOrder with backupCellOffsets; the device now holds atom
    // order[i] at i with offsets[i], where OpenMM reports posq - offset . box.
    const vector<int>& order = cc.getAtomIndex();
    const vector<mm_int4>& offsets = cc.getPosCellOffsets();
    vector<int> oldSlot(order.size());
    for (size_t i = 0; i < backupOrder.size(); i++)
        oldSlot[backupOrder[i]] = i;
    Vec3 box[3];
    cc.getPeriodicBoxVectors(box[0], box[1], box[2]);
    vector<mm_double4> oldPosq = downloadAsDouble(positions), oldVelm = downloadAsDouble(velocities);
    vector<mm_double4> oldCorrection;
    if (cc.getUseMixedPrecision())
        oldCorrection = downloadAsDouble(corrections);
    vector<mm_double4> posq(oldPosq.size(), mm_double4(0, 0, 0, 0)), velm(oldVelm.size(), mm_double4(0, 0, 0, 0));
    vector<mm_double4> correction(oldCorrection.size(), mm_double4(0, 0, 0, 0));
    for (size_t i = 0; i < order.size(); i++) {
        const int o = oldSlot[order[i]];
        const mm_int4 shift(offsets[i].x - backupCellOffsets[o].x, offsets[i].y - backupCellOffsets[o].y,
                            offsets[i].z - backupCellOffsets[o].z, 0);
        const Vec3 move = box[0] * shift.x + box[1] * shift.y + box[2] * shift.z;
        posq[i] = mm_double4(oldPosq[o].x + move[0], oldPosq[o].y + move[1], oldPosq[o].z + move[2], oldPosq[o].w);
        velm[i] = oldVelm[o];
        if (cc.getUseMixedPrecision()) {
            // Split again into a float and its correction.
            const mm_double4 p(oldPosq[o].x + oldCorrection[o].x + move[0], oldPosq[o].y + oldCorrection[o].y + move[1],
                               oldPosq[o].z + oldCorrection[o].z + move[2], oldPosq[o].w);
            posq[i] = mm_double4(roundToFloat(p.x), roundToFloat(p.y), roundToFloat(p.z), p.w);
            correction[i] = mm_double4(p.x - posq[i].x, p.y - posq[i].y, p.z - posq[i].z, 0);
        }
    }
    for (size_t i = order.size(); i < posq.size(); i++) {
        posq[i] = oldPosq[i];
        velm[i] = oldVelm[i];
    }
    uploadFromDouble(cc.getPosq(), posq);
    uploadFromDouble(cc.getVelm(), velm);
    if (cc.getUseMixedPrecision())
        uploadFromDouble(cc.getPosqCorrection(), correction);
}

std::string CommonStepFailure::message(long long failedStepCount) const {
    return integratorName + ": at step " + std::to_string(failedStepCount) +
           " the position reset of a rigid body found no rotation, the free-particle constraints did not converge, or "
           "a velocity was not finite (or beyond " + std::to_string((int) LargestSpeed) + " nm/ps, what a force that is "
           "not finite gives on the device): the step size is too large for the forces, or they are not finite. The "
           "Context holds the state from before that step.";
}

