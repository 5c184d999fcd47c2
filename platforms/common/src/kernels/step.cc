/*
 * A step's work on single atoms and on one body: its backup, kicks, drifts, the bodies'
 * position reset, Langevin's noise. The kernel that sequences them per group of atoms is
 * advanceGroups (advance.cc).
 */

/** Write a position in the storage's precision (mixed: a float and its correction). */
INLINE_DEVICE void storePosition(GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, int atom, mixed3 pos) {
    const real4 p = posq[atom];
#ifdef USE_MIXED_PRECISION
    posq[atom] = make_real4((real) pos.x, (real) pos.y, (real) pos.z, p.w);
    posqCorrection[atom] = make_real4(pos.x-(real) pos.x, pos.y-(real) pos.y, pos.z-(real) pos.z, 0);
#else
    posq[atom] = make_real4(pos.x, pos.y, pos.z, p.w);
#endif
}

/** Copy an atom's state into the step's backup (put back if the step fails). */
INLINE_DEVICE void backupAtom(int atom, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup) {
    posqBackup[atom] = posq[atom];
#ifdef USE_MIXED_PRECISION
    correctionBackup[atom] = posqCorrection[atom];
#endif
    velmBackup[atom] = velm[atom];
}

/** The integrator's declared arrays into their backup (the step's first launch), across the launch's work items. */
INLINE_DEVICE void backupIntegratorArrays(GLOBAL const mixed* RESTRICT integratorArrays,
        GLOBAL mixed* RESTRICT integratorBackup, int integratorSize) {
    for (int i = GLOBAL_ID; i < integratorSize; i += GLOBAL_SIZE)
        integratorBackup[i] = integratorArrays[i];
}

/** A kick of one atom's velocity with the Context's forces; false if the velocity is then not finite. */
INLINE_DEVICE bool kickAtom(int atom, mixed scale, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms,
        GLOBAL mixed4* RESTRICT velm) {
    mixed4 velocity = velm[atom];
    if (velocity.w == 0)
        return true;
    velocity = kicked(velocity, scale, force, atom, paddedNumAtoms);
    velm[atom] = velocity;
    return isFiniteVelocity(velocity);  // not finite: the forces are not (NaN fails every comparison)
}

/** A free atom's drift over h. */
INLINE_DEVICE void driftAtom(int atom, mixed h, GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm) {
    const mixed4 v = velm[atom];
    if (v.w == 0)
        return;
    const mixed4 delta = make_mixed4(h*v.x, h*v.y, h*v.z, 0);
    storePosition(posq, posqCorrection, atom, loadPosition(posq, posqCorrection, atom) + make_mixed3(delta.x, delta.y, delta.z));
}

/** Langevin's Ornstein-Uhlenbeck step of one atom: v = a v + sqrt((1 - a^2) kT / m) g (noiseScale = sqrt((1 - a^2) kT)). */
INLINE_DEVICE void noiseAtom(int atom, mixed a, mixed noiseScale, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL mixed4* RESTRICT velm) {
    const mixed4 v = velm[atom];
    if (v.w == 0)
        return;
    if (noiseScale == 0) {  // zero temperature: friction alone, no random numbers drawn
        velm[atom] = make_mixed4(a*v.x, a*v.y, a*v.z, v.w);
        return;
    }
    const float4 g = random[randomIndex + atom];
    const mixed sigma = noiseScale*sqrt(v.w);
    velm[atom] = make_mixed4(a*v.x + sigma*g.x, a*v.y + sigma*g.y, a*v.z + sigma*g.z, v.w);
}

/** (R + R^-T) / 2: a step of Newton's iteration for the polar factor (the nearest rotation) of R. */
INLINE_DEVICE Matrix3 polarStep(Matrix3 R) {
    Matrix3 inverse;
    if (!inverse3(R, &inverse))
        return R;
    Matrix3 next;
    next.m00 = 0.5f*(R.m00 + inverse.m00); next.m01 = 0.5f*(R.m01 + inverse.m10); next.m02 = 0.5f*(R.m02 + inverse.m20);
    next.m10 = 0.5f*(R.m10 + inverse.m01); next.m11 = 0.5f*(R.m11 + inverse.m11); next.m12 = 0.5f*(R.m12 + inverse.m21);
    next.m20 = 0.5f*(R.m20 + inverse.m02); next.m21 = 0.5f*(R.m21 + inverse.m12); next.m22 = 0.5f*(R.m22 + inverse.m22);
    return next;
}

/** A body's orientation (9 numbers from orientation[9*body]). */
INLINE_DEVICE Matrix3 loadOrientation(GLOBAL const mixed* RESTRICT orientation, int body) {
    GLOBAL const mixed* q = orientation + 9*body;
    Matrix3 Q;
    Q.m00 = q[0]; Q.m01 = q[1]; Q.m02 = q[2];
    Q.m10 = q[3]; Q.m11 = q[4]; Q.m12 = q[5];
    Q.m20 = q[6]; Q.m21 = q[7]; Q.m22 = q[8];
    return Q;
}

INLINE_DEVICE void storeOrientation(GLOBAL mixed* RESTRICT orientation, int body, Matrix3 Q) {
    GLOBAL mixed* q = orientation + 9*body;
    q[0] = Q.m00; q[1] = Q.m01; q[2] = Q.m02;
    q[3] = Q.m10; q[4] = Q.m11; q[5] = Q.m12;
    q[6] = Q.m20; q[7] = Q.m21; q[8] = Q.m22;
}

/**
 * The body's orientation after its reset rotation P = 1 + delta: Q = P Q, made orthonormal
 * again (one step of Newton's polar iteration, from a matrix orthonormal to round-off). Its
 * reference geometry (reference[k] for bodyAtoms[k], about its centre of mass) turned by Q
 * is then the body's shape, exact to round-off however many steps it takes. If the body's
 * shape is not Q ref (stale: something else moved it, e.g. another integrator of a
 * CompoundIntegrator), its positions a about its centre become its reference, Q = 1. The
 * atoms first, first + stride, ... < end are this work item's; the leader stores Q.
 */
INLINE_DEVICE Matrix3 turnOrientation(int body, int first, int end, int stride, bool leader,
        GLOBAL const int* RESTRICT bodyAtoms, GLOBAL mixed4* RESTRICT reference, GLOBAL mixed* RESTRICT orientation,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, Matrix3 Q, bool stale,
        mixed3 origin, mixed3 center, Matrix3 delta) {
    if (stale) {
        for (int k = first; k < end; k += stride) {
            const mixed3 a = loadPosition(posq, posqCorrection, bodyAtoms[k]) - origin - center;
            reference[k] = make_mixed4(a.x, a.y, a.z, 0);
        }
        Q = zeroMatrix();
        Q.m00 = Q.m11 = Q.m22 = 1;
    }
    Matrix3 P = delta;
    P.m00 += 1; P.m11 += 1; P.m22 += 1;
    Q = polarStep(multiply(P, Q));
    if (leader)
        storeOrientation(orientation, body, Q);
    return Q;
}

/** Whether a body's shape is rebuilt from its reference and orientation (single and mixed precision). */
INLINE_DEVICE bool fittedShape(int shape) {
#ifdef REBUILD_SHAPES
    return shape != SHAPE_POINT;
#else
    return false;  // double precision: no round-off worth rebuilding from
#endif
}

/**
 * The reset of a body from its sums (gathered before anything was written): the rotation,
 * then the new positions and velocities of the atoms first, first + stride, ... < end (the
 * leader stores the orientation). A linear body's rotation reads every atom, so only a
 * single work item (stride 1) resets one. Returns false if no rotation was found.
 */
INLINE_DEVICE bool finishReset(int body, int start, int end, int first, int stride, BodySums sums,
        Matrix3 oldOrientation, GLOBAL const int* RESTRICT bodyAtoms, GLOBAL mixed4* RESTRICT reference,
        GLOBAL mixed* RESTRICT orientation, int shape, mixed h, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    const bool fitted = fittedShape(shape);
    const mixed3 origin = sums.origin, center = sums.center, V = sums.V;
    if (!(dot(V, V) <= FINITE_BOUND && dot(center, center) <= FINITE_BOUND))
        return false;  // inf or NaN
    Matrix3 delta = zeroMatrix();
    const bool converged = shape == SHAPE_POINT || (shape == SHAPE_GENERAL ?
            solveRotation(sums.J, h*sums.L, &delta) :
            solveLinearBodyRotation(start, end, bodyAtoms, posq, posqCorrection, velm, origin, center, V, h, &delta));
    if (!converged)
        return false;
    const bool stale = !(sums.shapeError <= STALE_REFERENCE*STALE_REFERENCE);
    const Matrix3 rotation = (fitted ? turnOrientation(body, first, end, stride, first == start, bodyAtoms, reference,
                                                       orientation, posq, posqCorrection, oldOrientation, stale, origin,
                                                       center, delta) : delta);
    const mixed3 shift = h*V;
    const mixed3 newCenter = origin + (center + shift);
    const mixed invH = 1/h;
    for (int k = first; k < end; k += stride) {
        const int atom = bodyAtoms[k];
        const mixed3 x = loadPosition(posq, posqCorrection, atom);
        const mixed3 turn = apply(delta, x - origin - center);
        if (fitted) {
            const mixed4 q = reference[k];
            const mixed3 ref = make_mixed3(q.x, q.y, q.z);
            storePosition(posq, posqCorrection, atom, newCenter + apply(rotation, ref));
        }
        else
            storePosition(posq, posqCorrection, atom, x + (shift + turn));
        const mixed4 v = velm[atom];
        velm[atom] = make_mixed4(V.x + turn.x*invH, V.y + turn.y*invH, V.z + turn.z*invH, v.w);
    }
    return true;
}

/**
 * M-RATTLE's drift and position reset of one body over h, from its positions and velocities:
 * the centre moves with the mean velocity, the orientation is the rotation that makes the
 * constraint displacement exert zero torque about the old positions; the new velocities are
 * the displacement's over h. The torque condition reads of the velocities only the angular
 * momentum about the centre, so one loop (gatherBody) reads the body before its positions
 * and velocities are written. The new positions are the body's reference geometry in its
 * orientation (turnOrientation), so the shape is re-imposed every step as SETTLE does and
 * float round-off cannot random-walk it. Returns false if no rotation was found.
 */
INLINE_DEVICE bool resetBody(int body, int start, int end, GLOBAL const int* RESTRICT bodyAtoms, GLOBAL mixed4* RESTRICT reference,
        GLOBAL mixed* RESTRICT orientation, int shape, mixed h, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    const bool fitted = fittedShape(shape);
    const Matrix3 oldOrientation = (fitted ? loadOrientation(orientation, body) : zeroMatrix());
    const BodySums sums = gatherBody(start, end, bodyAtoms, posq, posqCorrection, velm, fitted, reference, oldOrientation);
    return finishReset(body, start, end, start, 1, sums, oldOrientation, bodyAtoms, reference, orientation, shape, h,
                       posq, posqCorrection, velm);
}
