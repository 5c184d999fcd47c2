/*
 * Andersen collisions of whole bodies: an AndersenThermostat re-draws single atoms; a
 * body whose velocities are then no longer rigid (COLLISION_THRESHOLD) gets fresh
 * Maxwell-Boltzmann velocities for all its atoms, which the projection then makes rigid
 * (projecting a body of which only some atoms are fresh does not keep the rigid-body
 * Boltzmann distribution). Compiled only for a System with an AndersenThermostat.
 */
KERNEL void collideBodies(BODY_ARGUMENTS, mixed kT, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        mixed residual, scale;
        const RigidMotion motion = rigidMotion(start, end, bodyAtoms, bodyShape[body], posq, posqCorrection, velm);
        rigidResidual(motion, start, end, 1, bodyAtoms, posq, posqCorrection, velm, &residual, &scale);
        if (!(residual > COLLISION_THRESHOLD*COLLISION_THRESHOLD*scale || (scale == 0 && residual > 0)))
            continue;  // still rigid: no atom of it collided
        for (int k = start; k < end; k++) {
            const int atom = bodyAtoms[k];
            const mixed4 v = velm[atom];
            const float4 g = random[randomIndex + atom];
            const mixed sigma = sqrt(kT*v.w);
            velm[atom] = make_mixed4(sigma*g.x, sigma*g.y, sigma*g.z, v.w);
        }
    }
}
