/*
 * The kinetic energy of each rigid body split into its centre-of-mass translation and its
 * rotation (CommonRigidBodyState::computeKineticEnergies): one work item per body, in 'mixed' precision.
 * energy[3*body] = M V^2 / 2, energy[3*body + 1] = sum m |v - V|^2 / 2 over its atoms,
 * energy[3*body + 2] = sum m v^2 / 2 over its atoms (V its centre-of-mass velocity, M its mass).
 */
KERNEL void bodyKineticEnergy(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL mixed* RESTRICT energy) {
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        mixed mass = 0;
        mixed3 momentum = make_mixed3(0, 0, 0);
        for (int k = start; k < end; k++) {
            const mixed4 v = velm[bodyAtoms[k]];
            const mixed m = 1/v.w;  // body members are massive
            mass += m;
            momentum += make_mixed3(m*v.x, m*v.y, m*v.z);
        }
        const mixed3 center = make_mixed3(momentum.x/mass, momentum.y/mass, momentum.z/mass);
        mixed rotational = 0, total = 0;
        for (int k = start; k < end; k++) {
            const mixed4 v = velm[bodyAtoms[k]];
            const mixed m = 1/v.w;
            const mixed3 velocity = make_mixed3(v.x, v.y, v.z);
            const mixed3 relative = velocity - center;
            rotational += m*dot(relative, relative);
            total += m*dot(velocity, velocity);
        }
        energy[3*body] = 0.5f*mass*dot(center, center);
        energy[3*body+1] = 0.5f*rotational;
        energy[3*body+2] = 0.5f*total;
    }
}
