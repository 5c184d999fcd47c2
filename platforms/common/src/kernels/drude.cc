/*
 * The Drude integrators' kernels (CommonRigidBodyDrude.cpp; docs/ALGORITHM.md, "Drude
 * oscillators"), one work item per Drude group (a body with the Drude particles of its cores,
 * or a free core with its own) and per atom in no group. A group's velocities split into R,
 * its rigid motion with each Drude particle placed at its core (translation only for a free
 * pair: V + w x a with w = I^+ L about its centre of mass), and C = v - R, its Drude
 * particles' motion relative to their cores. Each mirrors
 * ReferenceRigidBodyDrude.cpp; each does nothing once a step has failed. The groups of a large
 * body (isLargeDrudeGroup) are the *LargeGroups kernels', a work group each, their sums
 * reduced in local memory as a large body's (largeBodies.cc).
 */

/** What the group kernels take after STATE_ARGUMENTS (CommonRigidBodyState::addDrudeGroupArguments). */
#define DRUDE_GROUP_ARGUMENTS int numGroups, GLOBAL const int* RESTRICT groupStart, \
        GLOBAL const int* RESTRICT groupAtoms, GLOBAL const int* RESTRICT groupPlaces, \
        GLOBAL const int* RESTRICT groupRotates, int numUngrouped, \
        GLOBAL const int* RESTRICT ungroupedAtoms, GLOBAL real4* RESTRICT posq, \
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm

/**
 * A rotating group is linear (its inertia's smallest eigenvalue at round-off of its largest,
 * Reference's pseudo-inverse) when det(I) is below this times tr(J)^3.
 */
#ifdef USE_DOUBLE_MIXED
#define DRUDE_LINEAR_DETERMINANT 1e-12
#else
#define DRUDE_LINEAR_DETERMINANT 1e-5f
#endif

/** Whether a Drude group is a large body's with its Drude particles: more than LARGE_BODY_ATOMS particles. */
INLINE_DEVICE bool isLargeDrudeGroup(int start, int end, int rotates) {
    return rotates != 0 && end - start > LARGE_BODY_ATOMS;
}

/** R from a group's sums (the places' inertia: linear below DRUDE_LINEAR_DETERMINANT; a free pair only translates). */
INLINE_DEVICE RigidMotion groupMotionOf(BodySums sums, int start, int end, GLOBAL const int* RESTRICT places,
        bool rotates, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection) {
    int shape = SHAPE_POINT;
    if (rotates) {
        const mixed j = sums.J.m00 + sums.J.m11 + sums.J.m22;
        const Matrix3 I = inertiaOf(sums.J, j);
        const mixed det = I.m00*(I.m11*I.m22 - I.m12*I.m21) - I.m01*(I.m10*I.m22 - I.m12*I.m20) +
                          I.m02*(I.m10*I.m21 - I.m11*I.m20);
        shape = (j <= 0 ? SHAPE_POINT : det <= DRUDE_LINEAR_DETERMINANT*j*j*j ? SHAPE_LINEAR : SHAPE_GENERAL);
    }
    return rigidMotionOf(sums, start, end, places, shape, posq, posqCorrection);
}

/**
 * The rigid motion R of a field of velocities (field[atom].w: the inverse mass) over a group,
 * groupAtoms[k] placed at the position of places[k].
 */
INLINE_DEVICE RigidMotion groupRigidMotion(int start, int end, GLOBAL const int* RESTRICT atoms,
        GLOBAL const int* RESTRICT places, bool rotates, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL const mixed4* RESTRICT field) {
    const mixed3 origin = loadPosition(posq, posqCorrection, places[start]);
    const BodySums sums = bodySumsAbout(sumBodyAtoms(start, end, 1, origin, atoms, places, posq, posqCorrection, field,
                                                     false, field, origin, zeroMatrix()), origin);
    return groupMotionOf(sums, start, end, places, rotates, posq, posqCorrection);
}

/** groupRigidMotion of a large body's group by the work group (after a barrier: the field as the last phase left it). */
INLINE_DEVICE RigidMotion largeGroupRigidMotion(LOCAL_ARG BodyAtomSums* scratch, int start, int end,
        GLOBAL const int* RESTRICT atoms, GLOBAL const int* RESTRICT places, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL const mixed4* RESTRICT field) {
    SYNC_THREADS;
    const mixed3 origin = loadPosition(posq, posqCorrection, places[start]);
    const BodyAtomSums share = sumBodyAtoms(start + LOCAL_ID, end, LOCAL_SIZE, origin, atoms, places, posq, posqCorrection,
                                            field, false, field, origin, zeroMatrix());
    return groupMotionOf(bodySumsAbout(sumOverWorkGroup(scratch, share), origin), start, end, places, true, posq,
                         posqCorrection);
}

INLINE_DEVICE mixed3 rigidVelocityAt(RigidMotion motion, mixed3 x) {
    return motion.V + cross(motion.omega, x - motion.origin - motion.center);
}

/** u = M^-1/2 g for a group's atoms first, first + stride, ... < end (0 without draws). */
INLINE_DEVICE void drawGroupNoise(int first, int end, int stride, GLOBAL const int* RESTRICT groupAtoms, bool draws,
        GLOBAL const float4* RESTRICT random, unsigned int randomIndex, GLOBAL const mixed4* RESTRICT velm,
        GLOBAL mixed4* RESTRICT noise) {
    for (int k = first; k < end; k += stride) {
        const int atom = groupAtoms[k];
        const mixed w = velm[atom].w;
        const float4 g = (draws ? random[randomIndex + atom] : make_float4(0, 0, 0, 0));
        const mixed s = sqrt(w);
        noise[atom] = make_mixed4(s*g.x, s*g.y, s*g.z, w);
    }
}

/** v' = a R + aDrude C + scale R(u) + drudeScale (u - R(u)) for a group's atoms first, first + stride, ... < end. */
INLINE_DEVICE void applyGroupNoise(int first, int end, int stride, GLOBAL const int* RESTRICT groupAtoms,
        GLOBAL const int* RESTRICT groupPlaces, RigidMotion motion, RigidMotion noiseMotion, mixed a, mixed scale,
        mixed aDrude, mixed drudeScale, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mixed4* RESTRICT noise) {
    for (int k = first; k < end; k += stride) {
        const int atom = groupAtoms[k];
        const mixed3 x = loadPosition(posq, posqCorrection, groupPlaces[k]);
        const mixed4 v4 = velm[atom], u4 = noise[atom];
        const mixed3 v = make_mixed3(v4.x, v4.y, v4.z), u = make_mixed3(u4.x, u4.y, u4.z);
        const mixed3 vR = rigidVelocityAt(motion, x), uR = rigidVelocityAt(noiseMotion, x);
        const mixed3 next = a*vR + aDrude*(v - vR) + scale*uR + drudeScale*(u - uR);
        velm[atom] = make_mixed4(next.x, next.y, next.z, v4.w);
    }
}

/**
 * Langevin's step over h with the split: v' = a R + aDrude C + scale R(u) + drudeScale (u - R(u)),
 * u = M^-1/2 g (g: OpenMM's Gaussian numbers, one float4 per atom), noise a scratch field for
 * u; every other atom as noiseAtom. A projection follows (it takes u - R(u) to C(u)).
 */
KERNEL void drudeNoise(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS, GLOBAL mixed4* RESTRICT noise, mixed a, mixed scale,
        mixed aDrude, mixed drudeScale, GLOBAL const float4* RESTRICT random, unsigned int randomIndex) {
    if (failure[0] != 0)
        return;
    const bool draws = scale != 0 || drudeScale != 0;
    for (int item = GLOBAL_ID; item < numGroups + numUngrouped; item += GLOBAL_SIZE) {
        if (item >= numGroups) {
            noiseAtom(ungroupedAtoms[item-numGroups], a, scale, random, randomIndex, velm);
            continue;
        }
        const int start = groupStart[item], end = groupStart[item+1];
        const bool rotates = groupRotates[item] != 0;
        if (isLargeDrudeGroup(start, end, groupRotates[item]))
            continue;
        drawGroupNoise(start, end, 1, groupAtoms, draws, random, randomIndex, velm, noise);
        const RigidMotion motion = groupRigidMotion(start, end, groupAtoms, groupPlaces, rotates, posq, posqCorrection, velm);
        const RigidMotion noiseMotion = groupRigidMotion(start, end, groupAtoms, groupPlaces, rotates, posq, posqCorrection, noise);
        applyGroupNoise(start, end, 1, groupAtoms, groupPlaces, motion, noiseMotion, a, scale, aDrude, drudeScale, posq,
                        posqCorrection, velm, noise);
    }
}

/** drudeNoise for the large bodies' groups (largeGroups[i], group indices), a work group each. */
KERNEL void drudeNoiseLargeGroups(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS, GLOBAL mixed4* RESTRICT noise, mixed a,
        mixed scale, mixed aDrude, mixed drudeScale, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL const int* RESTRICT largeGroups, int numLargeGroups) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    if (failure[0] != 0)
        return;  // nothing writes the flag during this launch: one value for the work group
    const bool draws = scale != 0 || drudeScale != 0;
    for (int i = GROUP_ID; i < numLargeGroups; i += NUM_GROUPS) {
        const int group = largeGroups[i], start = groupStart[group], end = groupStart[group+1];
        drawGroupNoise(start + LOCAL_ID, end, LOCAL_SIZE, groupAtoms, draws, random, randomIndex, velm, noise);
        const RigidMotion motion = largeGroupRigidMotion(scratch, start, end, groupAtoms, groupPlaces, posq,
                                                         posqCorrection, velm);
        const RigidMotion noiseMotion = largeGroupRigidMotion(scratch, start, end, groupAtoms, groupPlaces, posq,
                                                              posqCorrection, noise);
        applyGroupNoise(start + LOCAL_ID, end, LOCAL_SIZE, groupAtoms, groupPlaces, motion, noiseMotion, a, scale, aDrude,
                        drudeScale, posq, posqCorrection, velm, noise);
    }
}

/**
 * OpenMM's hard wall for one pair, after the drift: a Drude particle farther than maxDistance
 * from its core bounces back with a speed sqrt(kT_d / m_d) along the bond, relative to its
 * core (in a body: the Drude particle alone moves) or to the pair's centre of mass (a free
 * core: both move). False beyond twice the distance (the step fails).
 */
INLINE_DEVICE bool bounceDrude(int drude, int core, bool coreInBody, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed maxDistance, mixed kTDrude,
        mixed h) {
    const mixed3 xd = loadPosition(posq, posqCorrection, drude), xc = loadPosition(posq, posqCorrection, core);
    const mixed3 delta = xd - xc;
    const mixed r = sqrt(dot(delta, delta));
    if (!(r > maxDistance))
        return true;
    if (!(r <= 2*maxDistance))
        return false;
    const mixed3 direction = delta*(1/r);
    const mixed beyond = r - maxDistance;
    const mixed4 vd4 = velm[drude], vc4 = velm[core];
    const mixed3 vd = make_mixed3(vd4.x, vd4.y, vd4.z), vc = make_mixed3(vc4.x, vc4.y, vc4.z);
    if (coreInBody) {
        const mixed relative = dot(vd - vc, direction);
        const mixed time = (relative != 0 ? min(beyond/fabs(relative), h) : h);
        const mixed bounced = -sqrt(kTDrude*vd4.w);
        storePosition(posq, posqCorrection, drude, xd + direction*(-beyond + time*bounced));
        const mixed3 v = vd + direction*(bounced - relative);
        velm[drude] = make_mixed4(v.x, v.y, v.z, vd4.w);
        return true;
    }
    const mixed m1 = 1/vd4.w, m2 = 1/vc4.w, inverseTotal = 1/(m1 + m2);
    mixed along1 = dot(vd, direction), along2 = dot(vc, direction);
    const mixed3 across1 = vd - direction*along1, across2 = vc - direction*along2;
    const mixed centre = (m1*along1 + m2*along2)*inverseTotal;
    along1 -= centre;
    along2 -= centre;
    const mixed time = (along1 != along2 ? min(beyond/fabs(along1 - along2), h) : h);
    const mixed speed = sqrt(kTDrude*vd4.w);
    const mixed sign = (along1 - along2 < 0 ? (mixed) -1 : (mixed) 1);  // outwards (or at rest): inwards after
    along1 = -sign*speed*m2*inverseTotal;
    along2 = sign*speed*m1*inverseTotal;
    storePosition(posq, posqCorrection, drude, xd + direction*(-beyond*m2*inverseTotal + time*along1));
    storePosition(posq, posqCorrection, core, xc + direction*(beyond*m1*inverseTotal + time*along2));
    const mixed3 v1 = across1 + direction*(along1 + centre), v2 = across2 + direction*(along2 + centre);
    velm[drude] = make_mixed4(v1.x, v1.y, v1.z, vd4.w);
    velm[core] = make_mixed4(v2.x, v2.y, v2.z, vc4.w);
    return true;
}

/** The wall for a group's pairs first, first + stride, ... < end; a failing one recorded (drudeHardWall). */
INLINE_DEVICE void bounceGroup(int first, int end, int stride, GLOBAL const int* RESTRICT pairAtoms, bool coreInBody,
        GLOBAL int* RESTRICT failure, int stepIndex, GLOBAL int* RESTRICT failedPair, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed maxDistance, mixed kTDrude, mixed h) {
    for (int k = first; k < end; k += stride)
        if (!bounceDrude(pairAtoms[2*k], pairAtoms[2*k+1], coreInBody, posq, posqCorrection, velm, maxDistance, kTDrude, h)) {
            failedPair[0] = k + 1;
            recordFailure(failure, stepIndex);
        }
}

/**
 * The hard wall, one work item per group, its pairs in the DrudeForce's order (pairAtoms: Drude,
 * core). A pair beyond twice the wall fails the step and writes 1 + its index (the same in every
 * atom order) to failedPair[0], which the host reads only once it has found the failure, to name
 * the particle; of several failing pairs, one's index stays.
 */
KERNEL void drudeHardWall(STATE_ARGUMENTS, int numGroups, GLOBAL const int* RESTRICT groupStart, GLOBAL const int* RESTRICT pairStart,
        GLOBAL const int* RESTRICT pairAtoms, GLOBAL const int* RESTRICT groupRotates, GLOBAL int* RESTRICT failedPair,
        GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm,
        mixed maxDistance, mixed kTDrude, mixed h) {
    if (failure[0] != 0)
        return;
    for (int group = GLOBAL_ID; group < numGroups; group += GLOBAL_SIZE)
        if (!isLargeDrudeGroup(groupStart[group], groupStart[group+1], groupRotates[group]))
            bounceGroup(pairStart[group], pairStart[group+1], 1, pairAtoms, groupRotates[group] != 0, failure, stepIndex,
                        failedPair, posq, posqCorrection, velm, maxDistance, kTDrude, h);
}

/**
 * drudeHardWall for the large bodies' groups (largeGroups[i]), a work group each, its items
 * taking the pairs in turn: each moves its Drude particle alone (its core is in the body).
 */
KERNEL void drudeHardWallLargeGroups(STATE_ARGUMENTS, GLOBAL const int* RESTRICT pairStart,
        GLOBAL const int* RESTRICT pairAtoms, GLOBAL int* RESTRICT failedPair, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed maxDistance, mixed kTDrude, mixed h,
        GLOBAL const int* RESTRICT largeGroups, int numLargeGroups) {
    if (failure[0] != 0)
        return;
    for (int i = GROUP_ID; i < numLargeGroups; i += NUM_GROUPS) {
        const int group = largeGroups[i];
        bounceGroup(pairStart[group] + LOCAL_ID, pairStart[group+1], LOCAL_SIZE, pairAtoms, true, failure, stepIndex,
                    failedPair, posq, posqCorrection, velm, maxDistance, kTDrude, h);
    }
}

/** Twice KE_C, sum m |v - R|^2, over a group's atoms first, first + stride, ... < end. */
INLINE_DEVICE mixed relativeEnergy(int first, int end, int stride, GLOBAL const int* RESTRICT groupAtoms,
        GLOBAL const int* RESTRICT groupPlaces, RigidMotion motion, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL const mixed4* RESTRICT velm) {
    mixed sum = 0;
    for (int k = first; k < end; k += stride) {
        const mixed4 v = velm[groupAtoms[k]];
        const mixed3 c = make_mixed3(v.x, v.y, v.z) - rigidVelocityAt(motion, loadPosition(posq, posqCorrection, groupPlaces[k]));
        sum += dot(c, c)/v.w;
    }
    return sum;
}

/** Twice each large body's group's KE_C into largeRelative[i] (largeGroups[i]), a work group each. */
KERNEL void drudeRelativeEnergiesLargeGroups(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS, GLOBAL mixed* RESTRICT largeRelative,
        GLOBAL const int* RESTRICT largeGroups, int numLargeGroups) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    LOCAL mixed sums[LARGE_BODY_THREADS];
    for (int i = GROUP_ID; i < numLargeGroups; i += NUM_GROUPS) {
        const int group = largeGroups[i], start = groupStart[group], end = groupStart[group+1];
        const RigidMotion motion = largeGroupRigidMotion(scratch, start, end, groupAtoms, groupPlaces, posq,
                                                         posqCorrection, velm);
        sums[LOCAL_ID] = relativeEnergy(start + LOCAL_ID, end, LOCAL_SIZE, groupAtoms, groupPlaces, motion, posq,
                                        posqCorrection, velm);
        sumOverGroup(sums);
        if (LOCAL_ID == 0)
            largeRelative[i] = sums[0];
    }
}

/**
 * Twice the Drude groups' KE_C, sum m |v - R|^2, summed by each work group (of REDUCTION_THREADS)
 * into relative[GROUP_ID] (the large bodies' groups from largeRelative, which
 * drudeRelativeEnergiesLargeGroups wrote before); relativeCount[0] = the number of work groups.
 */
KERNEL void drudeRelativeEnergies(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS, GLOBAL mixed* RESTRICT relative,
        GLOBAL int* RESTRICT relativeCount, GLOBAL const mixed* RESTRICT largeRelative, int numLargeGroups) {
    LOCAL mixed sums[REDUCTION_THREADS];
    mixed sum = 0;
    for (int group = GLOBAL_ID; group < numGroups; group += GLOBAL_SIZE) {
        const int start = groupStart[group], end = groupStart[group+1];
        if (isLargeDrudeGroup(start, end, groupRotates[group]))
            continue;
        const RigidMotion motion = groupRigidMotion(start, end, groupAtoms, groupPlaces, groupRotates[group] != 0, posq,
                                                    posqCorrection, velm);
        sum += relativeEnergy(start, end, 1, groupAtoms, groupPlaces, motion, posq, posqCorrection, velm);
    }
    for (int i = GLOBAL_ID; i < numLargeGroups; i += GLOBAL_SIZE)
        sum += largeRelative[i];
    sums[LOCAL_ID] = sum;
    sumOverGroup(sums);
    if (LOCAL_ID == 0)
        relative[GROUP_ID] = sums[0];
    if (GLOBAL_ID == 0)
        relativeCount[0] = NUM_GROUPS;
}

/** R times factor and C times drudeFactor for a group's atoms first, first + stride, ... < end. */
INLINE_DEVICE void scaleGroup(int first, int end, int stride, GLOBAL const int* RESTRICT groupAtoms,
        GLOBAL const int* RESTRICT groupPlaces, RigidMotion motion, mixed factor, mixed drudeFactor,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    for (int k = first; k < end; k += stride) {
        const int atom = groupAtoms[k];
        const mixed4 v4 = velm[atom];
        const mixed3 v = make_mixed3(v4.x, v4.y, v4.z);
        const mixed3 vR = rigidVelocityAt(motion, loadPosition(posq, posqCorrection, groupPlaces[k]));
        const mixed3 next = factor*vR + drudeFactor*(v - vR);
        velm[atom] = make_mixed4(next.x, next.y, next.z, v4.w);
    }
}

/** Each group's R times velocityScale[0] and C times velocityScale[1]; every other atom times velocityScale[0]. */
KERNEL void scaleDrudeVelocities(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS) {
    const mixed factor = velocityScale[0], drudeFactor = velocityScale[1];
    if (failure[0] != 0 || (factor == 1 && drudeFactor == 1))
        return;  // chains at rest: the velocities as they are, bit for bit
    for (int item = GLOBAL_ID; item < numGroups + numUngrouped; item += GLOBAL_SIZE) {
        if (item >= numGroups) {
            const int atom = ungroupedAtoms[item-numGroups];
            const mixed4 v = velm[atom];
            velm[atom] = make_mixed4(factor*v.x, factor*v.y, factor*v.z, v.w);
            continue;
        }
        const int start = groupStart[item], end = groupStart[item+1];
        if (isLargeDrudeGroup(start, end, groupRotates[item]))
            continue;
        const RigidMotion motion = groupRigidMotion(start, end, groupAtoms, groupPlaces, groupRotates[item] != 0, posq,
                                                    posqCorrection, velm);
        scaleGroup(start, end, 1, groupAtoms, groupPlaces, motion, factor, drudeFactor, posq, posqCorrection, velm);
    }
}

/** scaleDrudeVelocities for the large bodies' groups (largeGroups[i]), a work group each. */
KERNEL void scaleDrudeVelocitiesLargeGroups(STATE_ARGUMENTS, DRUDE_GROUP_ARGUMENTS, GLOBAL const int* RESTRICT largeGroups,
        int numLargeGroups) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    const mixed factor = velocityScale[0], drudeFactor = velocityScale[1];
    if (failure[0] != 0 || (factor == 1 && drudeFactor == 1))
        return;  // the same for every work item: nothing writes them during this launch
    for (int i = GROUP_ID; i < numLargeGroups; i += NUM_GROUPS) {
        const int group = largeGroups[i], start = groupStart[group], end = groupStart[group+1];
        const RigidMotion motion = largeGroupRigidMotion(scratch, start, end, groupAtoms, groupPlaces, posq,
                                                         posqCorrection, velm);
        scaleGroup(start + LOCAL_ID, end, LOCAL_SIZE, groupAtoms, groupPlaces, motion, factor, drudeFactor, posq,
                   posqCorrection, velm);
    }
}
