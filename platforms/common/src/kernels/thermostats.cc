/*
 * The thermostats that scale every velocity by one factor (MRattleNoseHooverIntegrator,
 * MRattleBussiIntegrator), with nothing read by the host. A half step is:
 *
 *   thermostatPartialSums  every work group of the device sums its atoms' share of twice the
 *                          kinetic energy (and, for CSVR, of the squared Gaussian numbers)
 *                          into partials[2 GROUP_ID], [2 GROUP_ID + 1];
 *   noseHooverChainHalfStep or stochasticRescalingHalfStep
 *                          one work group of THERMOSTAT_THREADS (defined by the host) adds
 *                          the partial sums, and its first work item turns them into the
 *                          factor (velocityScale[0]), no work per atom;
 *   the scaling            in the step's first pass for the first half step (advance.cc,
 *                          which also makes the step's backup), scaleVelocities for the second.
 *
 * The maths is RigidBodyThermostats' (openmmapi/src/RigidBodyThermostats.cpp), which the
 * tests hold it to.
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/** Sum two arrays of the work group (one value per work item) into their first elements. */
DEVICE void sumOverGroup(LOCAL_ARG mixed* sums, LOCAL_ARG mixed* sums2) {
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
 * Twice the kinetic energy of the massive atoms and the sum of gaussian[k]^2 for
 * 1 <= k < numGaussians (gaussian: OpenMM's random numbers from randomIndex), each work
 * group's share into partials; partialCount[0] = the number of work groups.
 */
KERNEL void thermostatPartialSums(int numAtoms, GLOBAL const mixed4* RESTRICT velm, GLOBAL const float4* RESTRICT random,
        unsigned int randomIndex, int numGaussians, GLOBAL mixed* RESTRICT partials, GLOBAL int* RESTRICT partialCount) {
    LOCAL mixed sums[THERMOSTAT_THREADS];
    LOCAL mixed squares[THERMOSTAT_THREADS];
    mixed sum = 0;
    for (int atom = GLOBAL_ID; atom < numAtoms; atom += GLOBAL_SIZE) {
        const mixed4 v = velm[atom];
        if (v.w != 0)
            sum += (v.x*v.x + v.y*v.y + v.z*v.z)/v.w;
    }
    GLOBAL const float* gaussian = (GLOBAL const float*) (random + randomIndex);
    mixed square = 0;
    for (int k = 1 + GLOBAL_ID; k < numGaussians; k += GLOBAL_SIZE)
        square += (mixed) gaussian[k]*gaussian[k];
    sums[LOCAL_ID] = sum;
    squares[LOCAL_ID] = square;
    sumOverGroup(sums, squares);
    if (LOCAL_ID == 0) {
        partials[2*GROUP_ID] = sums[0];
        partials[2*GROUP_ID+1] = squares[0];
    }
    if (GLOBAL_ID == 0)
        partialCount[0] = NUM_GROUPS;
}

/** thermostatPartialSums' partial sums added up by one work group, into sums[0] and squares[0]. */
DEVICE void addPartialSums(GLOBAL const mixed* RESTRICT partials, GLOBAL const int* RESTRICT partialCount,
        LOCAL_ARG mixed* sums, LOCAL_ARG mixed* squares) {
    mixed sum = 0, square = 0;
    const int count = partialCount[0];
    for (int g = LOCAL_ID; g < count; g += LOCAL_SIZE) {
        sum += partials[2*g];
        square += partials[2*g+1];
    }
    sums[LOCAL_ID] = sum;
    squares[LOCAL_ID] = square;
    sumOverGroup(sums, squares);
}

/**
 * The factor for every velocity; one that is not finite (from a kinetic energy that is not)
 * is a failure of the step, which the host then undoes.
 */
DEVICE void setVelocityScale(mixed factor, GLOBAL mixed* RESTRICT velocityScale, GLOBAL int* RESTRICT failure,
        int stepIndex) {
    if (factor*factor <= 1e30f)
        velocityScale[0] = factor;
    else
        recordFailure(failure, stepIndex);
}

/** Every velocity times velocityScale[0] (the second half step; the first is applied in the step's first pass). */
KERNEL void scaleVelocities(int numAtoms, GLOBAL mixed4* RESTRICT velm, GLOBAL const mixed* RESTRICT velocityScale,
        GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    const mixed factor = velocityScale[0];
    for (int atom = GLOBAL_ID; atom < numAtoms; atom += GLOBAL_SIZE) {
        const mixed4 v = velm[atom];
        velm[atom] = make_mixed4(factor*v.x, factor*v.y, factor*v.z, v.w);
    }
}

/** The chain's acceleration G_j with its mass divided out (RigidBodyThermostats::NoseHooverChain::propagate). */
DEVICE mixed chainAcceleration(int j, mixed twiceKinetic, GLOBAL const mixed* RESTRICT chainVelocity, mixed dof,
        mixed kT, mixed w2) {
    if (j == 0)
        return (twiceKinetic - dof*kT)*w2/(dof*kT);
    const mixed previous = chainVelocity[j-1];
    return (j == 1 ? dof : (mixed) 1)*previous*previous - w2;
}

DEVICE void chainHalfUpdate(int j, mixed s, int chainLength, mixed twiceKinetic, GLOBAL mixed* RESTRICT chainVelocity,
        mixed dof, mixed kT, mixed w2) {
    const mixed g = chainAcceleration(j, twiceKinetic, chainVelocity, dof, kT, w2);
    if (j == chainLength-1)
        chainVelocity[j] += 0.5f*s*g;
    else {
        const mixed e = exp(-0.25f*s*chainVelocity[j+1]);
        chainVelocity[j] = e*(e*chainVelocity[j] + 0.5f*s*g);
    }
}

/**
 * Half a step of the Nose-Hoover chain (numMTS sub-steps, each a Yoshida-Suzuki composition
 * with the given weights) from the kinetic energy's partial sums: the factor of every
 * velocity into velocityScale[0]. One work group. The first half step of a step
 * (backupStepIndex >= 0) backs up the chain first, even when a failure of this same step is
 * already recorded (the step's backup is of one time).
 */
KERNEL void noseHooverChainHalfStep(GLOBAL const mixed* RESTRICT partials, GLOBAL const int* RESTRICT partialCount,
        int chainLength, GLOBAL mixed* RESTRICT chainPosition, GLOBAL mixed* RESTRICT chainVelocity,
        GLOBAL const mixed* RESTRICT weights, int numWeights, int numMTS, mixed dof, mixed kT, mixed frequency,
        mixed halfStep, GLOBAL mixed* RESTRICT velocityScale, GLOBAL int* RESTRICT failure, int backupStepIndex,
        GLOBAL mixed* RESTRICT chainPositionBackup, GLOBAL mixed* RESTRICT chainVelocityBackup, int stepIndex) {
    LOCAL mixed sums[THERMOSTAT_THREADS];
    LOCAL mixed unused[THERMOSTAT_THREADS];
    addPartialSums(partials, partialCount, sums, unused);
    if (LOCAL_ID != 0)
        return;
    const int failed = failure[0];
    if (skipAfterFailure(failed, backupStepIndex))
        return;
    if (backupStepIndex >= 0)  // the chain before the step
        for (int j = 0; j < chainLength; j++) {
            chainPositionBackup[j] = chainPosition[j];
            chainVelocityBackup[j] = chainVelocity[j];
        }
    if (failed != 0)
        return;
    const mixed w2 = frequency*frequency;
    mixed twiceKinetic = sums[0], scale = 1;
    for (int mts = 0; mts < numMTS; mts++)
        for (int k = 0; k < numWeights; k++) {
            const mixed s = weights[k]*halfStep/numMTS;
            for (int j = chainLength-1; j >= 0; j--)
                chainHalfUpdate(j, s, chainLength, twiceKinetic, chainVelocity, dof, kT, w2);
            const mixed f = exp(-s*chainVelocity[0]);
            scale *= f;
            twiceKinetic *= f*f;
            for (int j = 0; j < chainLength; j++)
                chainPosition[j] += s*chainVelocity[j];
            for (int j = 0; j < chainLength; j++)
                chainHalfUpdate(j, s, chainLength, twiceKinetic, chainVelocity, dof, kT, w2);
        }
    setVelocityScale(scale, velocityScale, failure, stepIndex);
}

/**
 * Half a step of stochastic velocity rescaling (Bussi, Donadio and Parrinello 2007): the new
 * kinetic energy drawn exactly, with R_1 (gaussian[0]) and the dof - 1 other squared standard
 * normals (their sum, the paper's chi-squared variable, from the partial sums) from OpenMM's
 * device Gaussian numbers; c = exp(-frequency * halfStep). Adds the change of kinetic energy
 * to work[0]; the factor into velocityScale[0]. One work group; the first half step of a
 * step backs up the work as the chain's does.
 */
KERNEL void stochasticRescalingHalfStep(GLOBAL const mixed* RESTRICT partials, GLOBAL const int* RESTRICT partialCount,
        GLOBAL const float4* RESTRICT random, unsigned int randomIndex, int dof, mixed kT, mixed c,
        GLOBAL mixed* RESTRICT work, GLOBAL mixed* RESTRICT velocityScale, GLOBAL int* RESTRICT failure,
        int backupStepIndex, GLOBAL mixed* RESTRICT workBackup, int stepIndex) {
    LOCAL mixed sums[THERMOSTAT_THREADS];
    LOCAL mixed squares[THERMOSTAT_THREADS];
    addPartialSums(partials, partialCount, sums, squares);
    if (LOCAL_ID != 0)
        return;
    const int failed = failure[0];
    if (skipAfterFailure(failed, backupStepIndex))
        return;
    if (backupStepIndex >= 0)  // the work before the step
        workBackup[0] = work[0];
    if (failed != 0)
        return;
    const mixed kinetic = 0.5f*sums[0], meanKinetic = 0.5f*dof*kT;
    mixed alpha = 1;
    if (kinetic > 0 && dof > 0) {
        const mixed r1 = ((GLOBAL const float*) (random + randomIndex))[0];
        const mixed along = sqrt(c*kinetic) + r1*sqrt((1-c)*meanKinetic/dof);
        const mixed newKinetic = along*along + (1-c)*meanKinetic*squares[0]/dof;
        alpha = sqrt(newKinetic/kinetic);
        if (along < 0)
            alpha = -alpha;
        work[0] += newKinetic - kinetic;
    }
    setVelocityScale(alpha, velocityScale, failure, stepIndex);
}
