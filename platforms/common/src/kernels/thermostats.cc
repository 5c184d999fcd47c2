/*
 * The thermostats that scale every velocity by one factor (MRattleNoseHooverIntegrator,
 * MRattleBussiIntegrator), nothing read by the host. A half step is the state's
 * sumKineticEnergy (reduction.cc), then one of these kernels, one work group that adds the
 * partial sums and turns them into the factor (velocityScale[0]), then the state's
 * scaleVelocities phase. The maths is RigidBodyThermostats' (openmmapi), which the tests
 * hold it to. The chain and the work are declared arrays: the state backs them up. The Drude
 * integrator's two chains (MRattleDrudeNoseHooverIntegrator) scale two parts of the velocities
 * by two factors (the state's scaleDrudeVelocities, kernels/drude.cc).
 */

/**
 * A factor of the next scaling (velocityScale[index]); one that is not finite (from a kinetic
 * energy that is not) is a failure of the step, which the host then undoes.
 */
DEVICE void setVelocityScale(mixed factor, int index, GLOBAL mixed* RESTRICT velocityScale,
        GLOBAL int* RESTRICT failure, int stepIndex) {
    if (factor*factor <= 1e30f)
        velocityScale[index] = factor;
    else
        recordFailure(failure, stepIndex);
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
 * Half a step of a Nose-Hoover chain (numMTS sub-steps, each a Yoshida-Suzuki composition with
 * the given weights) on twice the kinetic energy of dof degrees of freedom: returns the factor
 * of their velocities.
 */
DEVICE mixed propagateChain(GLOBAL mixed* RESTRICT chainPosition, GLOBAL mixed* RESTRICT chainVelocity, int chainLength,
        mixed twiceKinetic, GLOBAL const mixed* RESTRICT weights, int numWeights, int numMTS, mixed dof, mixed kT,
        mixed frequency, mixed halfStep) {
    const mixed w2 = frequency*frequency;
    mixed scale = 1;
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
    return scale;
}

/**
 * Half a step of the Nose-Hoover chain from the kinetic energy's partial sums: the factor of
 * every velocity into velocityScale[0]. One work group.
 */
KERNEL void noseHooverChainHalfStep(STATE_ARGUMENTS, int chainLength, int positionOffset, int velocityOffset,
        GLOBAL const mixed* RESTRICT weights, int numWeights, int numMTS, mixed dof, mixed kT, mixed frequency,
        mixed halfStep) {
    LOCAL mixed sums[REDUCTION_THREADS];
    addPartialSums(partials, partialCount, sums);
    if (LOCAL_ID != 0 || failure[0] != 0)
        return;
    const mixed scale = propagateChain(integratorArrays + positionOffset, integratorArrays + velocityOffset, chainLength,
                                       sums[0], weights, numWeights, numMTS, dof, kT, frequency, halfStep);
    setVelocityScale(scale, 0, velocityScale, failure, stepIndex);
}

/**
 * Half a step of MRattleDrudeNoseHooverIntegrator's two chains: the first on KE_R = KE - KE_C
 * (dof), the Drude chain on KE_C (drudeDof), twice KE from the partial sums and twice KE_C
 * from the Drude groups' relative energies' partial sums (CommonRigidBodyState::
 * sumDrudeKineticEnergies); their factors into velocityScale[0] and [1] (a chain without
 * degrees of freedom: 1). One work group.
 */
KERNEL void drudeNoseHooverChainsHalfStep(STATE_ARGUMENTS, GLOBAL const mixed* RESTRICT relative,
        GLOBAL const int* RESTRICT relativeCount,
        int chainLength, int positionOffset, int velocityOffset, int drudePositionOffset, int drudeVelocityOffset,
        GLOBAL const mixed* RESTRICT weights, int numWeights, int numMTS, mixed dof, mixed kT, mixed frequency,
        mixed drudeDof, mixed drudeKT, mixed drudeFrequency, mixed halfStep) {
    LOCAL mixed sums[REDUCTION_THREADS];
    LOCAL mixed relativeSums[REDUCTION_THREADS];
    mixed sum = 0, relativeSum = 0;
    const int count = partialCount[0];
    for (int g = LOCAL_ID; g < count; g += LOCAL_SIZE)
        sum += partials[g];
    const int relativeGroups = relativeCount[0];
    for (int g = LOCAL_ID; g < relativeGroups; g += LOCAL_SIZE)
        relativeSum += relative[g];
    sums[LOCAL_ID] = sum;
    relativeSums[LOCAL_ID] = relativeSum;
    sumTwoOverGroup(sums, relativeSums);
    if (LOCAL_ID != 0 || failure[0] != 0)
        return;
    mixed factor = 1, drudeFactor = 1;
    if (dof > 0)
        factor = propagateChain(integratorArrays + positionOffset, integratorArrays + velocityOffset, chainLength,
                                sums[0] - relativeSums[0], weights, numWeights, numMTS, dof, kT, frequency, halfStep);
    if (drudeDof > 0)
        drudeFactor = propagateChain(integratorArrays + drudePositionOffset, integratorArrays + drudeVelocityOffset,
                                     chainLength, relativeSums[0], weights, numWeights, numMTS, drudeDof, drudeKT,
                                     drudeFrequency, halfStep);
    setVelocityScale(factor, 0, velocityScale, failure, stepIndex);
    setVelocityScale(drudeFactor, 1, velocityScale, failure, stepIndex);
}

/**
 * The sum of n squared standard normals from the Gaussian numbers g[0 .. count): 2 Gamma(n/2, 1)
 * for even n, one g^2 more for odd n (csvrScale's 2 Gamma(n/2, 1) in distribution), the Gamma
 * variable by Marsaglia and Tsang's rejection (ACM TOMS 26, 363, 2000), two numbers a try (the
 * second made uniform), each accepted with probability above 0.95. Should every try fail (below
 * 1e-30 with 62 numbers), n, its mean.
 */
DEVICE mixed chiSquared(int n, GLOBAL const float* RESTRICT g, int count) {
    mixed sum = 0;
    int next = 0;
    if (n % 2 == 1) {
        sum = (mixed) g[0]*g[0];
        next = 1;
        n--;
    }
    if (n == 0)
        return sum;
    const mixed d = 0.5f*n - (mixed) 1/3, c = 1/sqrt(9*d);
    for (; next + 1 < count; next += 2) {
        const mixed x = g[next], t = c*x;
        if (t <= -1)
            continue;
        const mixed u = 0.5f*erfc(-g[next+1]*0.70710678f), v = (1 + t)*(1 + t)*(1 + t);
        // log(v) - v + 1 with its leading terms cancelled exactly: -3t - 3t^2 - t^3 + 3 log1p(t).
        if (u < 1 - 0.0331f*x*x*x*x || log(u) < 0.5f*x*x + d*(3*(log1p(t) - t) - 3*t*t - t*t*t))
            return sum + 2*d*v;
    }
    return sum + n;
}

/**
 * Half a step of stochastic velocity rescaling (Bussi, Donadio and Parrinello 2007): the new
 * kinetic energy drawn exactly, with R_1 (gaussian[0]) and the sum of the dof - 1 other squared
 * standard normals (chiSquared) from numGaussians of OpenMM's device Gaussian numbers at
 * randomIndex; c = exp(-frequency * halfStep). Adds the change of kinetic energy to the work
 * (integratorArrays[workOffset]); the factor into velocityScale[0]. One work group.
 */
KERNEL void stochasticRescalingHalfStep(STATE_ARGUMENTS, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        int numGaussians, int dof, mixed kT, mixed c, int workOffset) {
    LOCAL mixed sums[REDUCTION_THREADS];
    addPartialSums(partials, partialCount, sums);
    if (LOCAL_ID != 0 || failure[0] != 0)
        return;
    GLOBAL mixed* work = integratorArrays + workOffset;
    const mixed kinetic = 0.5f*sums[0], meanKinetic = 0.5f*dof*kT;
    mixed alpha = 1;
    if (kinetic > 0 && dof > 0) {
        GLOBAL const float* gaussian = (GLOBAL const float*) (random + randomIndex);
        const mixed r1 = gaussian[0];
        const mixed others = chiSquared(dof - 1, gaussian + 1, numGaussians - 1);
        const mixed along = sqrt(c*kinetic) + r1*sqrt((1-c)*meanKinetic/dof);
        const mixed newKinetic = along*along + (1-c)*meanKinetic*others/dof;
        alpha = sqrt(newKinetic/kinetic);
        if (along < 0)
            alpha = -alpha;
        work[0] += newKinetic - kinetic;
    }
    setVelocityScale(alpha, 0, velocityScale, failure, stepIndex);
}
