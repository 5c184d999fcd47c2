/*
 * The kinetic energy of each rigid body split into its centre-of-mass translation and its
 * rotation (CommonRigidBodyState::computeKineticEnergies), in 'mixed' precision:
 * energy[3*body] = M V^2 / 2, energy[3*body + 1] = sum m |v - V|^2 / 2 over its atoms,
 * energy[3*body + 2] = sum m v^2 / 2 over its atoms (V its centre-of-mass velocity, M its mass).
 * One work item per body; bodies of more than LARGE_BODY_ATOMS atoms a work group each.
 */

/** A body's centre-of-mass velocity from its mass and momentum. */
INLINE_DEVICE mixed3 centerVelocity(mixed mass, mixed3 momentum) {
    return make_mixed3(momentum.x/mass, momentum.y/mass, momentum.z/mass);
}

/** The energies of a body from its mass, momentum and the two sums over its atoms. */
INLINE_DEVICE void storeBodyEnergies(GLOBAL mixed* RESTRICT energy, int body, mixed mass, mixed3 momentum,
        mixed rotational, mixed total) {
    const mixed3 center = centerVelocity(mass, momentum);
    energy[3*body] = 0.5f*mass*dot(center, center);
    energy[3*body+1] = 0.5f*rotational;
    energy[3*body+2] = 0.5f*total;
}

/** The mass and momentum of a body's atoms first, first + stride, ... < end. */
INLINE_DEVICE void massAndMomentum(int first, int end, int stride, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const mixed4* RESTRICT velm, mixed* mass, mixed3* momentum) {
    *mass = 0;
    *momentum = make_mixed3(0, 0, 0);
    for (int k = first; k < end; k += stride) {
        const mixed4 v = velm[bodyAtoms[k]];
        const mixed m = 1/v.w;  // body members are massive
        *mass += m;
        *momentum += make_mixed3(m*v.x, m*v.y, m*v.z);
    }
}

/** Over a body's atoms first, first + stride, ... < end: sum m |v - V|^2 and sum m v^2. */
INLINE_DEVICE void kineticSums(int first, int end, int stride, mixed3 center, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const mixed4* RESTRICT velm, mixed* rotational, mixed* total) {
    *rotational = *total = 0;
    for (int k = first; k < end; k += stride) {
        const mixed4 v = velm[bodyAtoms[k]];
        const mixed m = 1/v.w;
        const mixed3 velocity = make_mixed3(v.x, v.y, v.z);
        const mixed3 relative = velocity - center;
        *rotational += m*dot(relative, relative);
        *total += m*dot(velocity, velocity);
    }
}

KERNEL void bodyKineticEnergy(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL mixed* RESTRICT energy) {
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        if (end - start > LARGE_BODY_ATOMS)
            continue;
        mixed mass, rotational, total;
        mixed3 momentum;
        massAndMomentum(start, end, 1, bodyAtoms, velm, &mass, &momentum);
        kineticSums(start, end, 1, centerVelocity(mass, momentum), bodyAtoms, velm, &rotational, &total);
        storeBodyEnergies(energy, body, mass, momentum, rotational, total);
    }
}

/** bodyKineticEnergy for the bodies of more than LARGE_BODY_ATOMS atoms (largeBodies[i]), a work group each. */
KERNEL void largeBodyKineticEnergy(GLOBAL const int* RESTRICT largeBodies, int numLargeBodies,
        GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms, GLOBAL const mixed4* RESTRICT velm,
        GLOBAL mixed* RESTRICT energy) {
    LOCAL mixed mass[LARGE_BODY_THREADS], px[LARGE_BODY_THREADS], py[LARGE_BODY_THREADS], pz[LARGE_BODY_THREADS];
    LOCAL mixed rotational[LARGE_BODY_THREADS], total[LARGE_BODY_THREADS];
    for (int i = GROUP_ID; i < numLargeBodies; i += NUM_GROUPS) {
        const int body = largeBodies[i], start = bodyStart[body], end = bodyStart[body+1];
        mixed m, r, t;
        mixed3 p;
        massAndMomentum(start + LOCAL_ID, end, LOCAL_SIZE, bodyAtoms, velm, &m, &p);
        mass[LOCAL_ID] = m;
        px[LOCAL_ID] = p.x;
        py[LOCAL_ID] = p.y;
        pz[LOCAL_ID] = p.z;
        sumTwoOverGroup(mass, px);
        sumTwoOverGroup(py, pz);
        const mixed3 momentum = make_mixed3(px[0], py[0], pz[0]);
        kineticSums(start + LOCAL_ID, end, LOCAL_SIZE, centerVelocity(mass[0], momentum), bodyAtoms, velm, &r, &t);
        rotational[LOCAL_ID] = r;
        total[LOCAL_ID] = t;
        sumTwoOverGroup(rotational, total);
        if (LOCAL_ID == 0)
            storeBodyEnergies(energy, body, mass[0], momentum, rotational[0], total[0]);
        SYNC_THREADS;  // every item has read this body's sums before the next body's are written
    }
}
