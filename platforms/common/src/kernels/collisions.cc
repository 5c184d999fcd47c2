/*
 * Andersen collisions of whole bodies: an AndersenThermostat re-draws single atoms; a
 * body whose velocities are then no longer rigid (COLLISION_THRESHOLD) gets fresh
 * Maxwell-Boltzmann velocities for all its atoms, which the projection then makes rigid
 * (projecting a body of which only some atoms are fresh does not keep the rigid-body
 * Boltzmann distribution). Compiled only for a System with an AndersenThermostat; large
 * bodies (isLargeBody) are collideLargeBodies', a work group each.
 */

/** Whether a body's largest departure from its rigid motion (rigidResidual) says an atom of it collided. */
INLINE_DEVICE bool collided(mixed residual, mixed scale) {
    return residual > COLLISION_THRESHOLD*COLLISION_THRESHOLD*scale || (scale == 0 && residual > 0);
}

/** Fresh Maxwell-Boltzmann velocities for a body's atoms first, first + stride, ... < end. */
INLINE_DEVICE void redrawVelocities(int first, int end, int stride, GLOBAL const int* RESTRICT bodyAtoms, mixed kT,
        GLOBAL const float4* RESTRICT random, unsigned int randomIndex, GLOBAL mixed4* RESTRICT velm) {
    for (int k = first; k < end; k += stride) {
        const int atom = bodyAtoms[k];
        const mixed4 v = velm[atom];
        const float4 g = random[randomIndex + atom];
        const mixed sigma = sqrt(kT*v.w);
        velm[atom] = make_mixed4(sigma*g.x, sigma*g.y, sigma*g.z, v.w);
    }
}

KERNEL void collideBodies(BODY_ARGUMENTS, mixed kT, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        if (isLargeBody(start, end, bodyShape[body]))
            continue;
        mixed residual, scale;
        const RigidMotion motion = rigidMotion(start, end, bodyAtoms, bodyShape[body], posq, posqCorrection, velm);
        rigidResidual(motion, start, end, 1, bodyAtoms, posq, posqCorrection, velm, &residual, &scale);
        if (collided(residual, scale))
            redrawVelocities(start, end, 1, bodyAtoms, kT, random, randomIndex, velm);
    }
}

/** collideBodies for the large bodies (largeBodies[i], body indices), one work group per body. */
KERNEL void collideLargeBodies(BODY_ARGUMENTS, mixed kT, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL const int* RESTRICT failure, GLOBAL const int* RESTRICT largeBodies, int numLargeBodies) {
    LOCAL BodyAtomSums scratch[LARGE_BODY_THREADS];
    LOCAL mixed maxima[LARGE_BODY_THREADS];
    const bool failed = failure[0] != 0;  // nothing writes the flag during this launch: one value for the group
    for (int i = GROUP_ID; i < numLargeBodies; i += NUM_GROUPS) {
        const int body = largeBodies[i], start = bodyStart[body], end = bodyStart[body+1], shape = bodyShape[body];
        const bool checks = !failed && isLargeBody(start, end, shape);
        mixed residual, scale;
        largeBodyMotion(scratch, maxima, checks, checks, start, end, bodyAtoms, shape, posq, posqCorrection, velm,
                        &residual, &scale);
        if (checks && collided(residual, scale))
            redrawVelocities(start + LOCAL_ID, end, LOCAL_SIZE, bodyAtoms, kT, random, randomIndex, velm);
    }
}
