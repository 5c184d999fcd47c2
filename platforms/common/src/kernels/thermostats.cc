/*
 * The thermostats that scale every velocity by one factor (MRattleNoseHooverIntegrator,
 * MRattleBussiIntegrator), with nothing read by the host: one work group of
 * THERMOSTAT_THREADS (defined by the host) sums the kinetic energy, its first work item
 * turns it into the factor, and the group scales every velocity. The maths is
 * RigidBodyThermostats' (openmmapi/src/RigidBodyThermostats.cpp), which the tests hold it to.
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/**
 * The step's backup of the atoms (backupStepIndex >= 0: this is the step's first kernel that
 * changes the state), as the step's first pass would make it (advance.cc).
 */
DEVICE void backupAtoms(int numAtoms, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup, int backupStepIndex) {
    if (backupStepIndex < 0)
        return;
    for (int atom = LOCAL_ID; atom < numAtoms; atom += LOCAL_SIZE)
        backupAtom(atom, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup);
}

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

/** This work item's share of twice the kinetic energy of the massive atoms. */
DEVICE mixed twiceKineticOfAtoms(int numAtoms, GLOBAL const mixed4* RESTRICT velm) {
    mixed sum = 0;
    for (int index = LOCAL_ID; index < numAtoms; index += LOCAL_SIZE) {
        const mixed4 v = velm[index];
        if (v.w != 0)
            sum += (v.x*v.x + v.y*v.y + v.z*v.z)/v.w;
    }
    return sum;
}

/**
 * Scale every velocity by the factor; a factor that is not finite (from a kinetic energy that
 * is not) is a failure of the step, which the host then undoes, and scales nothing.
 */
DEVICE void scaleAllVelocities(int numAtoms, GLOBAL mixed4* RESTRICT velm, mixed factor, GLOBAL int* RESTRICT failure,
        int stepIndex) {
    if (!(factor*factor <= 1e30f)) {
        if (LOCAL_ID == 0)
            recordFailure(failure, stepIndex);
        return;
    }
    for (int index = LOCAL_ID; index < numAtoms; index += LOCAL_SIZE) {
        const mixed4 v = velm[index];
        velm[index] = make_mixed4(factor*v.x, factor*v.y, factor*v.z, v.w);
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
 * with the given weights) on the current velocities, which it scales. One work group.
 */
KERNEL void noseHooverChainHalfStep(int numAtoms, GLOBAL mixed4* RESTRICT velm, int chainLength,
        GLOBAL mixed* RESTRICT chainPosition, GLOBAL mixed* RESTRICT chainVelocity, GLOBAL const mixed* RESTRICT weights,
        int numWeights, int numMTS, mixed dof, mixed kT, mixed frequency, mixed halfStep,
        GLOBAL int* RESTRICT failure, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup, GLOBAL mixed4* RESTRICT velmBackup,
        int backupStepIndex, GLOBAL mixed* RESTRICT chainPositionBackup, GLOBAL mixed* RESTRICT chainVelocityBackup,
        int stepIndex) {
    const int failed = failure[0];
    if (skipAfterFailure(failed, backupStepIndex))
        return;
    backupAtoms(numAtoms, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup, backupStepIndex);
    if (failed != 0) {  // this step failed already: its backup only
        if (LOCAL_ID == 0)
            for (int j = 0; j < chainLength; j++) {
                chainPositionBackup[j] = chainPosition[j];
                chainVelocityBackup[j] = chainVelocity[j];
            }
        return;
    }
    LOCAL mixed sums[THERMOSTAT_THREADS];
    LOCAL mixed unused[THERMOSTAT_THREADS];
    LOCAL mixed factor;
    sums[LOCAL_ID] = twiceKineticOfAtoms(numAtoms, velm);
    unused[LOCAL_ID] = 0;
    sumOverGroup(sums, unused);
    if (LOCAL_ID == 0) {
        if (backupStepIndex >= 0)  // the chain before the step
            for (int j = 0; j < chainLength; j++) {
                chainPositionBackup[j] = chainPosition[j];
                chainVelocityBackup[j] = chainVelocity[j];
            }
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
        factor = scale;
    }
    SYNC_THREADS;
    scaleAllVelocities(numAtoms, velm, factor, failure, stepIndex);
}

/**
 * Half a step of stochastic velocity rescaling (Bussi, Donadio and Parrinello 2007): the new
 * kinetic energy drawn exactly, with R_1 and the dof - 1 other squared standard normals taken
 * from OpenMM's device Gaussian numbers (their sum is the paper's chi-squared variable);
 * c = exp(-frequency * halfStep). Adds the change of kinetic energy to work[0]. One work group.
 */
KERNEL void stochasticRescalingHalfStep(int numAtoms, GLOBAL mixed4* RESTRICT velm, GLOBAL const float4* RESTRICT random,
        unsigned int randomIndex, int dof, mixed kT, mixed c, GLOBAL mixed* RESTRICT work,
        GLOBAL int* RESTRICT failure, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup, GLOBAL mixed4* RESTRICT velmBackup,
        int backupStepIndex, GLOBAL mixed* RESTRICT workBackup, int stepIndex) {
    const int failed = failure[0];
    if (skipAfterFailure(failed, backupStepIndex))
        return;
    backupAtoms(numAtoms, posq, posqCorrection, velm, posqBackup, correctionBackup, velmBackup, backupStepIndex);
    if (failed != 0) {  // this step failed already: its backup only
        if (LOCAL_ID == 0)
            workBackup[0] = work[0];
        return;
    }
    LOCAL mixed sums[THERMOSTAT_THREADS];
    LOCAL mixed squares[THERMOSTAT_THREADS];
    LOCAL mixed factor;
    sums[LOCAL_ID] = twiceKineticOfAtoms(numAtoms, velm);
    GLOBAL const float* gaussian = (GLOBAL const float*) (random + randomIndex);
    mixed sum = 0;
    for (int k = 1 + LOCAL_ID; k < dof; k += LOCAL_SIZE)
        sum += (mixed) gaussian[k]*gaussian[k];
    squares[LOCAL_ID] = sum;
    sumOverGroup(sums, squares);
    if (LOCAL_ID == 0) {
        if (backupStepIndex >= 0)  // the work before the step
            workBackup[0] = work[0];
        const mixed kinetic = 0.5f*sums[0], meanKinetic = 0.5f*dof*kT;
        mixed alpha = 1;
        if (kinetic > 0 && dof > 0) {
            const mixed r1 = gaussian[0];
            const mixed along = sqrt(c*kinetic) + r1*sqrt((1-c)*meanKinetic/dof);
            const mixed newKinetic = along*along + (1-c)*meanKinetic*squares[0]/dof;
            alpha = sqrt(newKinetic/kinetic);
            if (along < 0)
                alpha = -alpha;
            work[0] += newKinetic - kinetic;
        }
        factor = alpha;
    }
    SYNC_THREADS;
    scaleAllVelocities(numAtoms, velm, factor, failure, stepIndex);
}
