/*
 * RATTLE's velocity step for rigid bodies: the mass-weighted projection onto rigid-body
 * motion, one work item per body.
 */

/** A body's rigid-body motion: its centre (relative to its first atom, origin), V and w. */
typedef struct {
    mixed3 origin, center, V, omega;
} RigidMotion;

/**
 * The mass-weighted projection of a body's velocities onto rigid-body motion,
 * v_i = V + w x a_i with w = I^-1 L (in the plane normal to the axis for a linear body), from
 * what gatherBody summed of them.
 */
INLINE_DEVICE RigidMotion rigidMotionOf(BodySums sums, int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection) {
    RigidMotion motion;
    motion.origin = sums.origin;
    motion.center = sums.center;
    motion.V = sums.V;
    motion.omega = make_mixed3(0, 0, 0);
    const mixed j = sums.J.m00 + sums.J.m11 + sums.J.m22;
    if (shape == SHAPE_POINT) {
        // A point only translates.
    }
    else if (shape == SHAPE_LINEAR) {
        mixed3 u = make_mixed3(1, 0, 0);
        mixed farthest = -1;
        for (int k = start; k < end; k++) {
            const mixed3 a = loadPosition(posq, posqCorrection, bodyAtoms[k]) - motion.origin - motion.center;
            if (dot(a, a) > farthest) {
                farthest = dot(a, a);
                u = a;
            }
        }
        if (farthest > 0 && j > 0) {
            u *= 1/sqrt(farthest);
            motion.omega = (sums.L - dot(sums.L, u)*u)*(1/j);
        }
    }
    else
        solve3(inertiaOf(sums.J, j), sums.L, &motion.omega);
    return motion;
}

/** The rigid motion of a body's velocities. */
INLINE_DEVICE RigidMotion rigidMotion(int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    const BodySums sums = gatherBody(start, end, bodyAtoms, posq, posqCorrection, velm, false, velm, zeroMatrix());
    return rigidMotionOf(sums, start, end, bodyAtoms, shape, posq, posqCorrection);
}

/**
 * How far a body's velocities (of atoms first, first + stride, ... < end) are from their rigid
 * motion: *residual is the largest |v_i - rigid_i|^2, *scale the largest |rigid_i|^2.
 */
INLINE_DEVICE void rigidResidual(RigidMotion motion, int first, int end, int stride, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, mixed* residual, mixed* scale) {
    *scale = 0;
    *residual = 0;
    for (int k = first; k < end; k += stride) {
        const int atom = bodyAtoms[k];
        const mixed4 v = velm[atom];
        const mixed3 rigid = motion.V + cross(motion.omega, loadPosition(posq, posqCorrection, atom) - motion.origin - motion.center);
        const mixed3 difference = make_mixed3(v.x, v.y, v.z) - rigid;
        *scale = max(*scale, dot(rigid, rigid));
        *residual = max(*residual, dot(difference, difference));
    }
}

/** Replace a body's velocities (of atoms first, first + stride, ... < end) by its rigid motion. */
INLINE_DEVICE void setRigidVelocities(RigidMotion motion, int first, int end, int stride, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    for (int k = first; k < end; k += stride) {
        const int atom = bodyAtoms[k];
        const mixed4 v = velm[atom];
        const mixed3 rigid = motion.V + cross(motion.omega, loadPosition(posq, posqCorrection, atom) - motion.origin - motion.center);
        velm[atom] = make_mixed4(rigid.x, rigid.y, rigid.z, v.w);
    }
}

/**
 * Replace one body's velocities by their rigid-body projection. With onlyIfNotRigid,
 * velocities already rigid to round-off (RIGID_TOLERANCE) are left exactly as they are.
 */
INLINE_DEVICE void projectBody(int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm,
        bool onlyIfNotRigid) {
    const RigidMotion motion = rigidMotion(start, end, bodyAtoms, shape, posq, posqCorrection, velm);
    if (onlyIfNotRigid) {
        mixed residual, scale;
        rigidResidual(motion, start, end, 1, bodyAtoms, posq, posqCorrection, velm, &residual, &scale);
        if (residual <= RIGID_TOLERANCE*RIGID_TOLERANCE*scale)
            return;
    }
    setRigidVelocities(motion, start, end, 1, bodyAtoms, posq, posqCorrection, velm);
}

/** Every body's projection (velocities set from the host, Andersen collisions); large ones: projectLargeBodies. */
KERNEL void projectBodies(BODY_ARGUMENTS, int onlyIfNotRigid, GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE)
        if (!isLargeBody(bodyStart[body], bodyStart[body+1], bodyShape[body]))
            projectBody(bodyStart[body], bodyStart[body+1], bodyAtoms, bodyShape[body], posq, posqCorrection, velm,
                    onlyIfNotRigid != 0);
}

/**
 * Whether any velocity is not finite (or beyond LARGEST_SPEED): found[0] = 1 if so (never
 * cleared here). A screen for velocities set from the host; the host then checks them itself.
 */
KERNEL void findUnusableVelocities(int numAtoms, GLOBAL const mixed4* RESTRICT velm, GLOBAL int* RESTRICT found) {
    for (int atom = GLOBAL_ID; atom < numAtoms; atom += GLOBAL_SIZE)
        if (!isFiniteVelocity(velm[atom]))
            found[0] = 1;
}
