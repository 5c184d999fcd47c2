/*
 * Langevin's Ornstein-Uhlenbeck step (MRattleLangevinIntegrator).
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/**
 * Langevin's Ornstein-Uhlenbeck step, per atom: v = a v + sqrt((1 - a^2) kT / m) g with
 * OpenMM's device Gaussian numbers; the projection onto rigid-body motion follows.
 */
KERNEL void langevinNoise(int numAtoms, GLOBAL mixed4* RESTRICT velm, mixed a, mixed noiseScale,
        GLOBAL const float4* RESTRICT random, unsigned int randomIndex, GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        mixed4 v = velm[index];
        if (v.w != 0) {
            const float4 g = random[randomIndex + index];
            const mixed sigma = noiseScale*sqrt(v.w);
            velm[index] = make_mixed4(a*v.x + sigma*g.x, a*v.y + sigma*g.y, a*v.z + sigma*g.z, v.w);
        }
    }
}

