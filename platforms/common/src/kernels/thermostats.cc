/*
 * The thermostats that scale every velocity by one factor (MRattleNoseHooverIntegrator,
 * MRattleBussiIntegrator), nothing read by the host. A half step is the state's
 * sumKineticEnergy (reduction.cc), then one of these kernels, one work group that adds the
 * partial sums and turns them into the factor (velocityScale[0]), then the state's
 * scaleVelocities phase. The maths is RigidBodyThermostats' (openmmapi), which the tests
 * hold it to. The chain and the work are declared arrays: the state backs them up.
 */

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
 * velocity into velocityScale[0]. One work group.
 */
KERNEL void noseHooverChainHalfStep(STATE_ARGUMENTS, int chainLength, int positionOffset, int velocityOffset,
        GLOBAL const mixed* RESTRICT weights, int numWeights, int numMTS, mixed dof, mixed kT, mixed frequency,
        mixed halfStep) {
    LOCAL mixed sums[REDUCTION_THREADS];
    LOCAL mixed unused[REDUCTION_THREADS];
    addPartialSums(partials, partialCount, sums, unused);
    if (LOCAL_ID != 0 || failure[0] != 0)
        return;
    GLOBAL mixed* chainPosition = integratorArrays + positionOffset;
    GLOBAL mixed* chainVelocity = integratorArrays + velocityOffset;
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
    setVelocityScale(alpha, velocityScale, failure, stepIndex);
}
