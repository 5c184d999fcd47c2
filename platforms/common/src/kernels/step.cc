/*
 * The step: kicks, the drift, the bodies' position reset, writing the new state, and its backup.
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/**
 * Per atom: a kick over kickTime (0 for none) and a drift over h into newVelocity and posDelta (the state
 * itself is written only by applyPositionStep, once every body's reset has succeeded).
 */
KERNEL void kickAndDrift(int numAtoms, int paddedNumAtoms, mixed kickTime, mixed h,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, GLOBAL mixed4* RESTRICT posDelta,
        GLOBAL mixed4* RESTRICT newVelocity, GLOBAL int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    const mixed scale = kickTime/(mixed) 0x100000000;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        mixed4 velocity = velm[index];
        if (velocity.w != 0) {
            velocity = kicked(velocity, scale, force, index, paddedNumAtoms);
            posDelta[index] = make_mixed4(h*velocity.x, h*velocity.y, h*velocity.z, 0);
            if (!isFiniteVelocity(velocity))
                recordFailure(failure);  // not finite (NaN fails every comparison)
        }
        else
            posDelta[index] = make_mixed4(0, 0, 0, 0);
        newVelocity[index] = velocity;
    }
}

/**
 * M-RATTLE's position reset, one work item per body: the centre moves with the mean
 * velocity, the orientation is the rotation that makes the constraint displacement exert
 * zero torque about the old positions. Positions are taken relative to the body's first
 * atom so that a body far from the origin loses no digits.
 */
KERNEL void resetBodies(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const int* RESTRICT bodyShape, mixed h, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT posDelta,
        GLOBAL mixed4* RESTRICT newVelocity, GLOBAL int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        mixed3 origin, center, V;
        bodyCenterAndVelocity(start, end, bodyAtoms, posq, posqCorrection, newVelocity, &origin, &center, &V);
        if (!(dot(V, V) <= FINITE_BOUND && dot(center, center) <= FINITE_BOUND)) {  // inf or NaN
            recordFailure(failure);
            continue;
        }
        Matrix3 delta = zeroMatrix();
        const bool converged = bodyShape[body] == SHAPE_POINT || (bodyShape[body] == SHAPE_GENERAL ?
                solveBodyRotation(start, end, bodyAtoms, posq, posqCorrection, newVelocity, origin, center, V, h,
                                  &delta) :
                solveLinearBodyRotation(start, end, bodyAtoms, posq, posqCorrection, newVelocity, origin, center, V,
                                        h, &delta));
        if (!converged) {
            recordFailure(failure);
            continue;
        }
        const mixed3 shift = h*V;
        const mixed invH = 1/h;
        for (int k = start; k < end; k++) {
            const int atom = bodyAtoms[k];
            const mixed3 a = loadPosition(posq, posqCorrection, atom) - origin - center;
            const mixed3 turn = apply(delta, a);
            const mixed3 move = shift + turn;
            posDelta[atom] = make_mixed4(move.x, move.y, move.z, 0);
            const mixed4 v = newVelocity[atom];
            newVelocity[atom] = make_mixed4(V.x + turn.x*invH, V.y + turn.y*invH, V.z + turn.z*invH, v.w);
        }
    }
}

/** Write the step's positions and velocities, unless a reset or constraint failed. */
KERNEL void applyPositionStep(int numAtoms, GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mixed4* RESTRICT posDelta, GLOBAL const mixed4* RESTRICT newVelocity,
        GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        if (velm[index].w == 0)
            continue;
        const real4 p = posq[index];
        const mixed4 delta = posDelta[index];
        const mixed3 pos = loadPosition(posq, posqCorrection, index) + make_mixed3(delta.x, delta.y, delta.z);
#ifdef USE_MIXED_PRECISION
        posq[index] = make_real4((real) pos.x, (real) pos.y, (real) pos.z, p.w);
        posqCorrection[index] = make_real4(pos.x-(real) pos.x, pos.y-(real) pos.y, pos.z-(real) pos.z, 0);
#else
        posq[index] = make_real4(pos.x, pos.y, pos.z, p.w);
#endif
        velm[index] = newVelocity[index];
    }
}

/** Per atom: a kick over kickTime with the Context's forces; a velocity that is not finite is a failure. */
KERNEL void kickVelocities(int numAtoms, int paddedNumAtoms, mixed kickTime,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, GLOBAL int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    const mixed scale = kickTime/(mixed) 0x100000000;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        mixed4 velocity = velm[index];
        if (velocity.w != 0) {
            velocity = kicked(velocity, scale, force, index, paddedNumAtoms);
            velm[index] = velocity;
            if (!isFiniteVelocity(velocity))
                recordFailure(failure);  // the forces at the new positions are not finite
        }
    }
}

/**
 * Copy the state at the start of a step, and the step's index (since the host's last check)
 * into failure[1], unless a failure was recorded: the copy then keeps the state before the
 * failed step, and failure[1] its index.
 */
KERNEL void backupState(int numAtoms, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup, GLOBAL int* RESTRICT failure, int stepIndex) {
    if (failure[0] != 0)
        return;
    if (GLOBAL_ID == 0)
        failure[1] = stepIndex;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        posqBackup[index] = posq[index];
#ifdef USE_MIXED_PRECISION
        correctionBackup[index] = posqCorrection[index];
#endif
        velmBackup[index] = velm[index];
    }
}
