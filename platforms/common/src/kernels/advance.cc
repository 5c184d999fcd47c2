/*
 * advanceGroups: a step's queued phases in one launch, one work item per group of atoms that
 * moves together (a body, a cluster of free constraints, a free atom). Each phase if asked
 * for, in this order: backup (the step's first launch), scaling by velocityScale[0], kick,
 * projection, drift and reset (M-RATTLE for a body, SHAKE for a cluster), Langevin noise and
 * projection, projection. A group touches only its own atoms, so no phase waits for another.
 * A body is not projected right before a reset (this pass's, or the next one's when
 * resetFollows): the reset reads only its momenta, which the projection keeps. Large bodies
 * (isLargeBody) are advanceLargeBodies', launched after this in the same pass.
 */

/** Group kinds. */
#define GROUP_BODY 0
#define GROUP_CLUSTER 1
#define GROUP_FREE 2

/** RATTLE's velocity step for a cluster of free constraints; false if it did not converge. */
INLINE_DEVICE bool projectCluster(int kind, int index, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, mixed tolerance, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    if (kind != GROUP_CLUSTER)
        return true;  // a free atom has nothing to project
    return rattleCluster(clusterStart[index], clusterStart[index+1], constraintAtoms, posq, posqCorrection, velm,
                         tolerance);
}

/**
 * The backup (if asked for), the scaling (if velocityFactor != 1) and the kick (if kickScale
 * != 0) of a group's atoms first, first + stride, ... < end; false if a kicked velocity is not finite.
 */
INLINE_DEVICE bool backupAndKick(int first, int end, int stride, GLOBAL const int* RESTRICT atoms, bool backup,
        GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm,
        GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup, GLOBAL mixed4* RESTRICT velmBackup,
        mixed velocityFactor, mixed kickScale, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms) {
    bool ok = true;
    for (int k = first; k < end; k += stride) {
        const int atom = atoms[k];
        if (backup)
            backupAtom(atom, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup);
        if (velocityFactor != 1) {
            const mixed4 v = velm[atom];
            velm[atom] = make_mixed4(velocityFactor*v.x, velocityFactor*v.y, velocityFactor*v.z, v.w);
        }
        if (kickScale != 0)
            ok = kickAtom(atom, kickScale, force, paddedNumAtoms, velm) && ok;
    }
    return ok;
}

/** Langevin's friction and noise for a group's atoms first, first + stride, ... < end. */
INLINE_DEVICE void noiseGroup(int first, int end, int stride, GLOBAL const int* RESTRICT atoms, mixed noiseDecay,
        mixed noiseScale, GLOBAL const float4* RESTRICT random, unsigned int randomIndex, GLOBAL mixed4* RESTRICT velm) {
    for (int k = first; k < end; k += stride)
        noiseAtom(atoms[k], noiseDecay, noiseScale, random, randomIndex, velm);
}

/** A pass's phases for one body (the backup and the kick a loop of their own, then one loop per projection or reset). */
INLINE_DEVICE bool advanceBody(int body, int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape,
        GLOBAL mixed4* RESTRICT reference, GLOBAL mixed* RESTRICT orientation, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force,
        int paddedNumAtoms, bool backup, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup, mixed velocityFactor, mixed kickScale, bool projectAfterKick,
        mixed driftTime, mixed noiseDecay, mixed noiseScale, GLOBAL const float4* RESTRICT random,
        unsigned int randomIndex, bool projectAtEnd, bool resetFollows) {
    bool ok = backupAndKick(start, end, 1, bodyAtoms, backup, posq, posqCorrection, velm, posqBackup, correctionBackup,
                            velmBackup, velocityFactor, kickScale, force, paddedNumAtoms);
    if (driftTime != 0)  // no projection before the reset: see above
        ok = resetBody(body, start, end, bodyAtoms, reference, orientation, shape, driftTime, posq, posqCorrection,
                       velm) && ok;
    else if (projectAfterKick)
        projectBody(start, end, bodyAtoms, shape, posq, posqCorrection, velm, false);
    if (noiseDecay != 1) {
        noiseGroup(start, end, 1, bodyAtoms, noiseDecay, noiseScale, random, randomIndex, velm);
        if (!resetFollows)
            projectBody(start, end, bodyAtoms, shape, posq, posqCorrection, velm, false);
    }
    if (projectAtEnd)
        projectBody(start, end, bodyAtoms, shape, posq, posqCorrection, velm, false);
    return ok;
}

/** A pass's arguments (CommonRigidBodyState::setKernelArguments), advanceGroups' and advanceLargeBodies'. */
#define ADVANCE_ARGUMENTS BODY_ARGUMENTS, int numClusters, int numFree, GLOBAL mixed4* RESTRICT bodyReference, \
        GLOBAL mixed* RESTRICT bodyOrientation, GLOBAL const int* RESTRICT clusterStart, \
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const mixed* RESTRICT constraintDistance, \
        GLOBAL const int* RESTRICT clusterAtomStart, GLOBAL const int* RESTRICT clusterAtoms, \
        GLOBAL const int* RESTRICT freeAtoms, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms, \
        GLOBAL mixed4* RESTRICT posDelta, BACKUP_ARGUMENTS, mixed kickTime, int projectAfterKick, mixed driftTime, \
        mixed tolerance, mixed noiseDecay, mixed noiseScale, GLOBAL const float4* RESTRICT random, \
        unsigned int randomIndex, int projectAtEnd, int resetFollows, GLOBAL int* RESTRICT failure, int stepIndex, \
        GLOBAL const mixed* RESTRICT velocityScale, int scaleVelocities

KERNEL void advanceGroups(ADVANCE_ARGUMENTS) {
    const int failed = failure[0];
    if (skipAfterFailure(failed, backupStepIndex))
        return;
    const bool onlyBackup = failed != 0;  // another group of this step failed: only its backup
    if (backupStepIndex >= 0)
        backupIntegratorArrays(integratorArrays, integratorBackup, integratorSize);
    const mixed kickScale = kickTime/(mixed) 0x100000000;
    const mixed velocityFactor = scaleVelocities ? velocityScale[0] : (mixed) 1;
    const int numGroups = numBodies + numClusters + numFree;
    for (int group = GLOBAL_ID; group < numGroups; group += GLOBAL_SIZE) {
        int kind, index, start, end;
        GLOBAL const int* RESTRICT atoms;
        if (group < numBodies) {
            kind = GROUP_BODY;
            index = group;
            start = bodyStart[index];
            end = bodyStart[index+1];
            atoms = bodyAtoms;
        }
        else if (group < numBodies + numClusters) {
            kind = GROUP_CLUSTER;
            index = group - numBodies;
            start = clusterAtomStart[index];
            end = clusterAtomStart[index+1];
            atoms = clusterAtoms;
        }
        else {
            kind = GROUP_FREE;
            index = group - numBodies - numClusters;
            start = index;
            end = index + 1;
            atoms = freeAtoms;
        }
        if (kind == GROUP_BODY && isLargeBody(start, end, bodyShape[index]))
            continue;  // advanceLargeBodies'
        if (onlyBackup) {
            backupAndKick(start, end, 1, atoms, true, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup,
                          1, 0, force, paddedNumAtoms);
            continue;
        }
        bool ok;
        if (kind == GROUP_BODY)
            ok = advanceBody(index, start, end, atoms, bodyShape[index], bodyReference, bodyOrientation, posq,
                             posqCorrection, velm, force, paddedNumAtoms, backupStepIndex >= 0, posqBackup,
                             correctionBackup, velmBackup, velocityFactor, kickScale, projectAfterKick != 0, driftTime,
                             noiseDecay, noiseScale, random, randomIndex, projectAtEnd != 0, resetFollows != 0);
        else {
            ok = backupAndKick(start, end, 1, atoms, backupStepIndex >= 0, posq, posqCorrection, velm, posqBackup,
                               correctionBackup, velmBackup, velocityFactor, kickScale, force, paddedNumAtoms);
            if (projectAfterKick)
                ok = projectCluster(kind, index, clusterStart, constraintAtoms, tolerance, posq, posqCorrection, velm) && ok;
            if (driftTime != 0) {
                if (kind == GROUP_CLUSTER)
                    ok = shakeCluster(clusterStart[index], clusterStart[index+1], constraintAtoms, constraintDistance,
                                      start, end, atoms, driftTime, tolerance, posq, posqCorrection, velm, posDelta) && ok;
                else
                    driftAtom(atoms[start], driftTime, posq, posqCorrection, velm);
            }
            if (noiseDecay != 1) {
                noiseGroup(start, end, 1, atoms, noiseDecay, noiseScale, random, randomIndex, velm);
                ok = projectCluster(kind, index, clusterStart, constraintAtoms, tolerance, posq, posqCorrection, velm) && ok;
            }
            if (projectAtEnd)
                ok = projectCluster(kind, index, clusterStart, constraintAtoms, tolerance, posq, posqCorrection, velm) && ok;
        }
        if (!ok)
            recordFailure(failure, stepIndex);
    }
}
