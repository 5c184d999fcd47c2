/*
 * Sums across the whole device in two launches, nothing read by the host: the state's
 * kineticEnergyPartialSums leaves one partial sum per work group, and an integrator's kernel
 * of one work group of REDUCTION_THREADS adds them up (addPartialSums) and acts on the total
 * (the thermostats, thermostats.cc).
 */

/** Sum an array of the work group (one value per work item) into its first element. */
DEVICE void sumOverGroup(LOCAL_ARG mixed* sums) {
    SYNC_THREADS;
    for (int stride = LOCAL_SIZE/2; stride > 0; stride /= 2) {
        if (LOCAL_ID < stride)
            sums[LOCAL_ID] += sums[LOCAL_ID+stride];
        SYNC_THREADS;
    }
}

/** Sum two arrays of the work group (one value per work item) into their first elements. */
DEVICE void sumTwoOverGroup(LOCAL_ARG mixed* sums, LOCAL_ARG mixed* sums2) {
    SYNC_THREADS;
    for (int stride = LOCAL_SIZE/2; stride > 0; stride /= 2) {
        if (LOCAL_ID < stride) {
            sums[LOCAL_ID] += sums[LOCAL_ID+stride];
            sums2[LOCAL_ID] += sums2[LOCAL_ID+stride];
        }
        SYNC_THREADS;
    }
}

/**
 * Twice the kinetic energy of the massive atoms, each work group's share into partials;
 * partialCount[0] = the number of work groups. The step's first launch (backupStepIndex >= 0)
 * also backs up the state, as advanceGroups would.
 */
KERNEL void kineticEnergyPartialSums(int numAtoms, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL const mixed4* RESTRICT velm, GLOBAL mixed* RESTRICT partials,
        GLOBAL int* RESTRICT partialCount, BACKUP_ARGUMENTS, GLOBAL const int* RESTRICT failure) {
    LOCAL mixed sums[REDUCTION_THREADS];
    const bool backup = backupStepIndex >= 0 && !skipAfterFailure(failure[0], backupStepIndex);
    if (backup)
        backupIntegratorArrays(integratorArrays, integratorBackup, integratorSize);
    mixed sum = 0;
    for (int atom = GLOBAL_ID; atom < numAtoms; atom += GLOBAL_SIZE) {
        if (backup)
            backupAtom(atom, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup);
        const mixed4 v = velm[atom];
        if (v.w != 0)
            sum += (v.x*v.x + v.y*v.y + v.z*v.z)/v.w;
    }
    sums[LOCAL_ID] = sum;
    sumOverGroup(sums);
    if (LOCAL_ID == 0)
        partials[GROUP_ID] = sums[0];
    if (GLOBAL_ID == 0)
        partialCount[0] = NUM_GROUPS;
}

/** The partial sums added up by one work group, into sums[0]. */
DEVICE void addPartialSums(GLOBAL const mixed* RESTRICT partials, GLOBAL const int* RESTRICT partialCount,
        LOCAL_ARG mixed* sums) {
    mixed sum = 0;
    const int count = partialCount[0];
    for (int g = LOCAL_ID; g < count; g += LOCAL_SIZE)
        sum += partials[g];
    sums[LOCAL_ID] = sum;
    sumOverGroup(sums);
}
