/*
 * Small 3x3 algebra, positions, failures, body centres and kicks: what every other file uses.
 *
 * The step's device code on OpenMM's common compute platforms (OpenCL, CUDA), one program in
 * the order bodyMath, rotation, step, freeConstraints, projection, advance, reduction, then an
 * integrator's own (collisions, thermostats). Integration arithmetic is 'mixed' (double in
 * the mixed and double modes); the host's constants come as defines.
 *
 * failure[0] holds 0, or 1 + the index of the step (since the host's last check) in which a
 * reset, a constraint or a velocity failed: every kernel that would change the state then does
 * nothing, but for the step's backup by that same step's first launch (so the backup is of one
 * time), until the host finds it and puts back the state from before that step.
 */

/** What every per-body kernel takes first (CommonRigidBodyState::addBodyArguments). */
#define BODY_ARGUMENTS int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms, \
        GLOBAL const int* RESTRICT bodyShape, GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, \
        GLOBAL mixed4* RESTRICT velm

/**
 * What an integrator's own kernel takes first (CommonRigidBodyState::integratorArguments): the
 * failure flag and what it records, the integrator's declared arrays, the velocity factor of
 * the next scaleVelocities phase, and the kinetic energy's partial sums (addPartialSums).
 */
#define STATE_ARGUMENTS GLOBAL int* RESTRICT failure, int stepIndex, GLOBAL mixed* RESTRICT integratorArrays, \
        GLOBAL mixed* RESTRICT velocityScale, GLOBAL const mixed* RESTRICT partials, \
        GLOBAL const int* RESTRICT partialCount

/** What the step's first launch takes to back up the state: atoms and the integrator's arrays. */
#define BACKUP_ARGUMENTS GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup, \
        GLOBAL mixed4* RESTRICT velmBackup, GLOBAL const mixed* RESTRICT integratorArrays, \
        GLOBAL mixed* RESTRICT integratorBackup, int integratorSize, int backupStepIndex

/* SHAPE_* (bodyShape[body]), FINITE_BOUND and the other constants are the host's, as defines. */

/* Every helper is inlined: pocl (OpenCL on a CPU) would pass 3x3 matrices through the stack. */
#if defined(__OPENCL_VERSION__) && defined(__clang__)
#define INLINE_DEVICE static inline __attribute__((always_inline))
#else
#define INLINE_DEVICE DEVICE
#endif

typedef struct {
    mixed m00, m01, m02, m10, m11, m12, m20, m21, m22;
} Matrix3;

INLINE_DEVICE mixed3 loadPosition(GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, int atom) {
    real4 p = posq[atom];
#ifdef USE_MIXED_PRECISION
    real4 c = posqCorrection[atom];
    return make_mixed3(p.x + (mixed) c.x, p.y + (mixed) c.y, p.z + (mixed) c.z);
#else
    return make_mixed3(p.x, p.y, p.z);
#endif
}

INLINE_DEVICE Matrix3 zeroMatrix() {
    Matrix3 m;
    m.m00 = m.m01 = m.m02 = m.m10 = m.m11 = m.m12 = m.m20 = m.m21 = m.m22 = 0;
    return m;
}

/** J += m a a^T */
INLINE_DEVICE void addOuter(Matrix3* J, mixed m, mixed3 a) {
    J->m00 += m*a.x*a.x; J->m01 += m*a.x*a.y; J->m02 += m*a.x*a.z;
    J->m10 += m*a.y*a.x; J->m11 += m*a.y*a.y; J->m12 += m*a.y*a.z;
    J->m20 += m*a.z*a.x; J->m21 += m*a.z*a.y; J->m22 += m*a.z*a.z;
}

INLINE_DEVICE Matrix3 multiply(Matrix3 A, Matrix3 B) {
    Matrix3 C;
    C.m00 = A.m00*B.m00 + A.m01*B.m10 + A.m02*B.m20;
    C.m01 = A.m00*B.m01 + A.m01*B.m11 + A.m02*B.m21;
    C.m02 = A.m00*B.m02 + A.m01*B.m12 + A.m02*B.m22;
    C.m10 = A.m10*B.m00 + A.m11*B.m10 + A.m12*B.m20;
    C.m11 = A.m10*B.m01 + A.m11*B.m11 + A.m12*B.m21;
    C.m12 = A.m10*B.m02 + A.m11*B.m12 + A.m12*B.m22;
    C.m20 = A.m20*B.m00 + A.m21*B.m10 + A.m22*B.m20;
    C.m21 = A.m20*B.m01 + A.m21*B.m11 + A.m22*B.m21;
    C.m22 = A.m20*B.m02 + A.m21*B.m12 + A.m22*B.m22;
    return C;
}

INLINE_DEVICE mixed3 apply(Matrix3 A, mixed3 v) {
    return make_mixed3(A.m00*v.x + A.m01*v.y + A.m02*v.z, A.m10*v.x + A.m11*v.y + A.m12*v.z,
                       A.m20*v.x + A.m21*v.y + A.m22*v.z);
}

/** A^-1 by the adjugate; returns false if A is singular. */
INLINE_DEVICE bool inverse3(Matrix3 A, Matrix3* inverse) {
    Matrix3 C;
    C.m00 = A.m11*A.m22 - A.m12*A.m21; C.m01 = A.m02*A.m21 - A.m01*A.m22; C.m02 = A.m01*A.m12 - A.m02*A.m11;
    C.m10 = A.m12*A.m20 - A.m10*A.m22; C.m11 = A.m00*A.m22 - A.m02*A.m20; C.m12 = A.m02*A.m10 - A.m00*A.m12;
    C.m20 = A.m10*A.m21 - A.m11*A.m20; C.m21 = A.m01*A.m20 - A.m00*A.m21; C.m22 = A.m00*A.m11 - A.m01*A.m10;
    mixed det = A.m00*C.m00 + A.m01*C.m10 + A.m02*C.m20;
    if (det == 0)
        return false;
    mixed inv = 1/det;
    C.m00 *= inv; C.m01 *= inv; C.m02 *= inv;
    C.m10 *= inv; C.m11 *= inv; C.m12 *= inv;
    C.m20 *= inv; C.m21 *= inv; C.m22 *= inv;
    *inverse = C;
    return true;
}

/** Solve A x = b by A's adjugate; returns false if A is singular. */
INLINE_DEVICE bool solve3(Matrix3 A, mixed3 b, mixed3* x) {
    Matrix3 inverse;
    if (!inverse3(A, &inverse))
        return false;
    *x = apply(inverse, b);
    return true;
}

/** The inertia I = tr(J) - J of a second moment J whose trace is given. */
INLINE_DEVICE Matrix3 inertiaOf(Matrix3 J, mixed traceJ) {
    Matrix3 I;
    I.m00 = traceJ - J.m00; I.m01 = -J.m01; I.m02 = -J.m02;
    I.m10 = -J.m10; I.m11 = traceJ - J.m11; I.m12 = -J.m12;
    I.m20 = -J.m20; I.m21 = -J.m21; I.m22 = traceJ - J.m22;
    return I;
}

/**
 * A velocity that is finite and below LARGEST_SPEED (NaN fails every comparison): OpenMM
 * sums device forces in fixed point, where an infinite force becomes the largest number it
 * holds (about 2e9 kJ/mol/nm), which kicks any atom far beyond that speed.
 */
INLINE_DEVICE bool isFiniteVelocity(mixed4 v) {
    return v.x*v.x + v.y*v.y + v.z*v.z <= LARGEST_SPEED*LARGEST_SPEED;
}

/** Every work item of one launch that fails writes the same value (its step's), so no atomic is needed. */
INLINE_DEVICE void recordFailure(GLOBAL int* RESTRICT failure, int stepIndex) {
    failure[0] = stepIndex + 1;
}

/**
 * Whether a work item does nothing, from failure[0] as it read it once: a step failed, unless
 * this launch makes the backup of that very step (backupStepIndex >= 0), which it then still makes.
 */
INLINE_DEVICE bool skipAfterFailure(int failed, int backupStepIndex) {
    return failed != 0 && failed != backupStepIndex + 1;
}

/** velocity += scale f / m for one atom (scale: the kick's time over the force buffer's fixed-point unit). */
INLINE_DEVICE mixed4 kicked(mixed4 velocity, mixed scale, GLOBAL const mm_long* RESTRICT force, int index, int paddedNumAtoms) {
    velocity.x += scale*force[index]*velocity.w;
    velocity.y += scale*force[index+paddedNumAtoms]*velocity.w;
    velocity.z += scale*force[index+paddedNumAtoms*2]*velocity.w;
    return velocity;
}

/**
 * Whether a body is moved by a work group of its own (largeBodies.cc) rather than by one work
 * item: more than LARGE_BODY_ATOMS atoms, and not linear (a linear body's rotation reads every atom).
 */
INLINE_DEVICE bool isLargeBody(int start, int end, int shape) {
    return end - start > LARGE_BODY_ATOMS && shape != SHAPE_LINEAR;
}

/** A body's motion as one loop over its atoms gathers it (gatherBody). */
typedef struct {
    mixed3 origin;  // the body's first atom: positions are taken relative to it, so no digits are lost far from the origin
    mixed3 center;  // the centre of mass, relative to origin
    mixed3 V;       // the centre-of-mass velocity
    Matrix3 J;      // the second moment about the centre, sum m a a^T (a = x - origin - center)
    mixed3 L;       // the angular momentum about the centre, sum m a x v
    mixed shapeError;  // with a reference: the largest |(x_k - x_0) - Q (ref_k - ref_0)|^2
} BodySums;

/** What a share of a body's atoms adds to BodySums (its sums about the body's first atom). */
typedef struct {
    mixed mass;
    mixed3 moment, momentum, angular;
    Matrix3 J;
    mixed shapeError;
} BodyAtomSums;

/**
 * The sums over a body's atoms first, first + stride, ... < end (velocities' .w the inverse
 * mass) about origin, atom bodyAtoms[k] placed at the position of places[k] (the same array
 * for a body; a Drude group places a Drude particle at its core); with checkShape, also how
 * far the body's shape, seen from origin, is from its reference geometry turned by Q.
 */
INLINE_DEVICE BodyAtomSums sumBodyAtoms(int first, int end, int stride, mixed3 origin, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const int* RESTRICT places, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, bool checkShape, GLOBAL const mixed4* RESTRICT reference, mixed3 ref0,
        Matrix3 Q) {
    BodyAtomSums s;
    s.mass = 0;
    s.moment = s.momentum = s.angular = make_mixed3(0, 0, 0);
    s.J = zeroMatrix();
    s.shapeError = 0;
    for (int k = first; k < end; k += stride) {
        const int atom = bodyAtoms[k];
        const mixed4 v = velm[atom];
        const mixed m = 1/v.w;  // body members are massive
        const mixed3 a = loadPosition(posq, posqCorrection, places[k]) - origin;
        const mixed3 velocity = make_mixed3(v.x, v.y, v.z);
        s.mass += m;
        s.moment += m*a;
        s.momentum += m*velocity;
        s.angular += m*cross(a, velocity);
        addOuter(&s.J, m, a);
        if (checkShape) {
            const mixed4 q = reference[k];
            const mixed3 d = a - apply(Q, make_mixed3(q.x, q.y, q.z) - ref0);
            s.shapeError = max(s.shapeError, dot(d, d));
        }
    }
    return s;
}

/** A body's sums about its first atom moved to its centre: J_c = J_0 - M c c^T, L_c = L_0 - M c x V. */
INLINE_DEVICE BodySums bodySumsAbout(BodyAtomSums s, mixed3 origin) {
    BodySums sums;
    sums.origin = origin;
    const mixed inverseMass = 1/s.mass;
    sums.center = s.moment*inverseMass;
    sums.V = s.momentum*inverseMass;
    addOuter(&s.J, -s.mass, sums.center);
    sums.J = s.J;
    sums.L = s.angular - s.mass*cross(sums.center, sums.V);
    sums.shapeError = s.shapeError;
    return sums;
}

/** The reference geometry's first atom, from which bodyAtoms' shape is compared (checkShape). */
INLINE_DEVICE mixed3 firstReference(int start, bool checkShape, GLOBAL const mixed4* RESTRICT reference) {
    if (!checkShape)
        return make_mixed3(0, 0, 0);
    const mixed4 q = reference[start];
    return make_mixed3(q.x, q.y, q.z);
}

/**
 * One loop over a body's atoms: its centre, mean velocity, second moment and angular momentum
 * (sumBodyAtoms, bodySumsAbout), so the reset and the projection read the atoms once before
 * they write them.
 */
INLINE_DEVICE BodySums gatherBody(int start, int end, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, bool checkShape, GLOBAL const mixed4* RESTRICT reference, Matrix3 Q) {
    const mixed3 origin = loadPosition(posq, posqCorrection, bodyAtoms[start]);
    const BodyAtomSums s = sumBodyAtoms(start, end, 1, origin, bodyAtoms, bodyAtoms, posq, posqCorrection, velm, checkShape,
                                        reference, firstReference(start, checkShape, reference), Q);
    return bodySumsAbout(s, origin);
}
