/*
 * Large bodies (isLargeBody: more than LARGE_BODY_ATOMS atoms, not linear), one work group of
 * LARGE_BODY_THREADS work items each: a pass's phases (advanceLargeBodies) and the projection
 * of velocities set from the host (projectLargeBodies) as advanceBody and projectBody do them,
 * with each loop over the atoms shared by the work group and the body's sums reduced in local
 * memory. advanceGroups and projectBodies leave these bodies alone. Each work item touches only
 * its own atoms but for the body's first atom (the origin of its sums), which every phase
 * reads after a barrier. Every barrier is reached by every work item whatever the pass asks
 * for (a phase not asked for sums nothing): a barrier under a condition makes pocl (OpenCL on
 * a CPU) copy the code after it for each path, and its compile time grows without bound.
 */

/** a += b: two shares of a body's sums (the shape errors: the larger). */
INLINE_DEVICE void addBodyAtomSums(BodyAtomSums* a, BodyAtomSums b) {
    a->mass += b.mass;
    a->moment += b.moment;
    a->momentum += b.momentum;
    a->angular += b.angular;
    a->J.m00 += b.J.m00; a->J.m01 += b.J.m01; a->J.m02 += b.J.m02;
    a->J.m10 += b.J.m10; a->J.m11 += b.J.m11; a->J.m12 += b.J.m12;
    a->J.m20 += b.J.m20; a->J.m21 += b.J.m21; a->J.m22 += b.J.m22;
    a->shapeError = max(a->shapeError, b.shapeError);
}

/** The work group's shares added up (one tree in local memory), returned to every item. */
INLINE_DEVICE BodyAtomSums sumOverWorkGroup(LOCAL_ARG BodyAtomSums* scratch, BodyAtomSums share) {
    scratch[LOCAL_ID] = share;
    SYNC_THREADS;
    for (int stride = LOCAL_SIZE/2; stride > 0; stride /= 2) {
        if (LOCAL_ID < stride) {
            BodyAtomSums sum = scratch[LOCAL_ID];
            addBodyAtomSums(&sum, scratch[LOCAL_ID+stride]);
            scratch[LOCAL_ID] = sum;
        }
        SYNC_THREADS;
    }
    const BodyAtomSums total = scratch[0];
    SYNC_THREADS;
    return total;
}

/**
 * gatherBody by the work group (each item sums its atoms, the group adds the sums); with
 * needed false, every item still takes part and the sums are of no atom.
 */
INLINE_DEVICE BodySums gatherLargeBody(LOCAL_ARG BodyAtomSums* scratch, bool needed, int start, int end,
        GLOBAL const int* RESTRICT bodyAtoms, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL const mixed4* RESTRICT velm, bool checkShape,
        GLOBAL const mixed4* RESTRICT reference, Matrix3 Q) {
    SYNC_THREADS;  // the first atom and its reference as the last phase left them
    const mixed3 origin = loadPosition(posq, posqCorrection, bodyAtoms[start]);
    const BodyAtomSums share = sumBodyAtoms(start + LOCAL_ID, (needed ? end : start), LOCAL_SIZE, origin, bodyAtoms,
                                            bodyAtoms, posq, posqCorrection, velm, checkShape, reference,
                                            firstReference(start, checkShape, reference), Q);
    return bodySumsAbout(sumOverWorkGroup(scratch, share), origin);
}

/** The largest of each work item's value (>= 0) over the work group, returned to every item. */
INLINE_DEVICE mixed maxOverWorkGroup(LOCAL_ARG mixed* scratch, mixed value) {
    scratch[LOCAL_ID] = value;
    SYNC_THREADS;
    for (int stride = LOCAL_SIZE/2; stride > 0; stride /= 2) {
        if (LOCAL_ID < stride)
            scratch[LOCAL_ID] = max(scratch[LOCAL_ID], scratch[LOCAL_ID+stride]);
        SYNC_THREADS;
    }
    const mixed largest = scratch[0];
    SYNC_THREADS;
    return largest;
}

/** The work group's phase of a projection (project false: sums only, nothing written). */
INLINE_DEVICE void projectLargeBody(LOCAL_ARG BodyAtomSums* scratch, bool project, int start, int end,
        GLOBAL const int* RESTRICT bodyAtoms, int shape, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    const BodySums sums = gatherLargeBody(scratch, project, start, end, bodyAtoms, posq, posqCorrection, velm, false,
                                          velm, zeroMatrix());
    if (project)
        setRigidVelocities(rigidMotionOf(sums, start, end, bodyAtoms, shape, posq, posqCorrection), start + LOCAL_ID,
                           end, LOCAL_SIZE, bodyAtoms, posq, posqCorrection, velm);
}

/**
 * advanceGroups' pass for the large bodies (largeBodies[i], body indices), one work group per
 * body: the phases of advanceBody, in its order, each with its barriers whether asked for or not.
 */
KERNEL void advanceLargeBodies(ADVANCE_ARGUMENTS, GLOBAL const int* RESTRICT largeBodies, int numLargeBodies) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    LOCAL int failedAtStart;
    if (LOCAL_ID == 0)
        failedAtStart = failure[0];
    SYNC_THREADS;
    const int failed = failedAtStart;  // one value for the whole work group
    const bool skip = skipAfterFailure(failed, backupStepIndex), onlyBackup = failed != 0;
    const mixed kickScale = kickTime/(mixed) 0x100000000;
    const mixed velocityFactor = scaleVelocities ? velocityScale[0] : (mixed) 1;
    for (int i = GROUP_ID; i < numLargeBodies; i += NUM_GROUPS) {
        const int body = largeBodies[i], start = bodyStart[body], end = bodyStart[body+1], shape = bodyShape[body];
        const bool moves = !skip && isLargeBody(start, end, shape);  // a body linear now is advanceGroups'
        const bool advances = moves && !onlyBackup;
        const int first = start + LOCAL_ID;
        bool ok = true;
        if (moves)
            ok = backupAndKick(first, end, LOCAL_SIZE, bodyAtoms, backupStepIndex >= 0, posq, posqCorrection, velm,
                               posqBackup, correctionBackup, velmBackup, (advances ? velocityFactor : 1),
                               (advances ? kickScale : 0), force, paddedNumAtoms);
        // The reset (no projection before it: advanceGroups), or the projection after the kick.
        const bool resets = advances && driftTime != 0;
        const bool fitted = fittedShape(shape);
        const Matrix3 oldOrientation = (fitted ? loadOrientation(bodyOrientation, body) : zeroMatrix());
        const BodySums sums = gatherLargeBody(scratch, advances && (resets || projectAfterKick), start, end, bodyAtoms,
                                              posq, posqCorrection, velm, resets && fitted, bodyReference,
                                              oldOrientation);
        if (resets)
            ok = finishReset(body, start, end, first, LOCAL_SIZE, sums, oldOrientation, bodyAtoms, bodyReference,
                             bodyOrientation, shape, driftTime, posq, posqCorrection, velm) && ok;
        else if (advances && projectAfterKick)
            setRigidVelocities(rigidMotionOf(sums, start, end, bodyAtoms, shape, posq, posqCorrection), first, end,
                               LOCAL_SIZE, bodyAtoms, posq, posqCorrection, velm);
        // Langevin's noise and its projection, then the projection at the end.
        const bool noise = advances && noiseDecay != 1;
        if (noise)
            noiseGroup(first, end, LOCAL_SIZE, bodyAtoms, noiseDecay, noiseScale, random, randomIndex, velm);
        projectLargeBody(scratch, noise && !resetFollows, start, end, bodyAtoms, shape, posq, posqCorrection, velm);
        projectLargeBody(scratch, advances && projectAtEnd, start, end, bodyAtoms, shape, posq, posqCorrection, velm);
        if (!ok)
            recordFailure(failure, stepIndex);
    }
}

/**
 * A large body's rigid motion (if needed) and, if measured, the largest departures from it
 * over the work group (rigidResidual's residual and scale; 0 if not). Every item takes part.
 */
INLINE_DEVICE RigidMotion largeBodyMotion(LOCAL_ARG BodyAtomSums* scratch, LOCAL_ARG mixed* maxima, bool needed,
        bool measured, int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, mixed* residual, mixed* scale) {
    const BodySums sums = gatherLargeBody(scratch, needed, start, end, bodyAtoms, posq, posqCorrection, velm, false,
                                          velm, zeroMatrix());
    RigidMotion motion;
    if (needed)
        motion = rigidMotionOf(sums, start, end, bodyAtoms, shape, posq, posqCorrection);
    *residual = *scale = 0;
    if (measured)
        rigidResidual(motion, start + LOCAL_ID, end, LOCAL_SIZE, bodyAtoms, posq, posqCorrection, velm, residual, scale);
    *residual = maxOverWorkGroup(maxima, *residual);
    *scale = maxOverWorkGroup(maxima, *scale);
    return motion;
}

/**
 * projectBodies for the large bodies, one work group per body: velocities already rigid to
 * round-off (RIGID_TOLERANCE) are left as they are with onlyIfNotRigid.
 */
KERNEL void projectLargeBodies(BODY_ARGUMENTS, int onlyIfNotRigid, GLOBAL const int* RESTRICT failure,
        GLOBAL const int* RESTRICT largeBodies, int numLargeBodies) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    LOCAL mixed maxima[LARGE_BODY_THREADS];
    const bool failed = failure[0] != 0;  // nothing writes the flag during this launch: one value for the group
    for (int i = GROUP_ID; i < numLargeBodies; i += NUM_GROUPS) {
        const int body = largeBodies[i], start = bodyStart[body], end = bodyStart[body+1], shape = bodyShape[body];
        const bool moves = !failed && isLargeBody(start, end, shape);
        mixed residual, scale;
        const RigidMotion motion = largeBodyMotion(scratch, maxima, moves, moves && onlyIfNotRigid, start, end,
                                                   bodyAtoms, shape, posq, posqCorrection, velm, &residual, &scale);
        if (moves && (!onlyIfNotRigid || !(residual <= RIGID_TOLERANCE*RIGID_TOLERANCE*scale)))
            setRigidVelocities(motion, start + LOCAL_ID, end, LOCAL_SIZE, bodyAtoms, posq, posqCorrection, velm);
    }
}
