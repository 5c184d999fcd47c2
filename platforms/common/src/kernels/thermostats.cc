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
    LOCAL mixed unused[REDUCTION_THREADS];
    addPartialSums(partials, partialCount, sums, unused);
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
        sum += partials[2*g];
    const int relativeGroups = relativeCount[0];
    for (int g = LOCAL_ID; g < relativeGroups; g += LOCAL_SIZE)
        relativeSum += relative[g];
    sums[LOCAL_ID] = sum;
    relativeSums[LOCAL_ID] = relativeSum;
    sumOverGroup(sums, relativeSums);
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
 * Half a step of stochastic velocity rescaling (Bussi, Donadio and Parrinello 2007): the new
 * kinetic energy drawn exactly, with R_1 (gaussian[0]) and the dof - 1 other squared standard
 * normals (their sum, from the partial sums) from OpenMM's device Gaussian numbers;
 * c = exp(-frequency * halfStep). Adds the change of kinetic energy to the work
 * (integratorArrays[workOffset]); the factor into velocityScale[0]. One work group.
 */
KERNEL void stochasticRescalingHalfStep(STATE_ARGUMENTS, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        int dof, mixed kT, mixed c, int workOffset) {
    LOCAL mixed sums[REDUCTION_THREADS];
    LOCAL mixed squares[REDUCTION_THREADS];
    addPartialSums(partials, partialCount, sums, squares);
    if (LOCAL_ID != 0 || failure[0] != 0)
        return;
    GLOBAL mixed* work = integratorArrays + workOffset;
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
    setVelocityScale(alpha, 0, velocityScale, failure, stepIndex);
}
