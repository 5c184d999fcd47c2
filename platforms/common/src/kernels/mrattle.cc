/*
 * M-RATTLE on OpenMM's common compute platforms (OpenCL, CUDA): one work item per atom
 * for kicks and drifts, one per rigid body for the position reset and the velocity
 * projection, one per cluster of free-particle constraints for RATTLE. All integration
 * arithmetic is in 'mixed' precision (double in the mixed and double modes).
 *
 * failure[0] holds 0, or 1 + the step at which a reset or a constraint failed: every
 * kernel that would change the state then does nothing, so the state stays that from
 * before the failed step until the host reports the failure.
 */

// CHORD_CONVERGED: the rotation solve stops when its error estimate (step^2 / previous
// step) is below this fraction of the rotation: round-off of the precision in use.
#ifdef USE_DOUBLE_MIXED
#define CHORD_CONVERGED 1e-15
#define RIGID_TOLERANCE 1e-12
#else
#define CHORD_CONVERGED 1e-6
#define RIGID_TOLERANCE 1e-5
#endif
#define MAX_ROTATION_ITERATIONS 50
#define MAX_CONSTRAINT_ITERATIONS 1000

typedef struct {
    mixed m00, m01, m02, m10, m11, m12, m20, m21, m22;
} Matrix3;

DEVICE mixed3 loadPosition(GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, int atom) {
    real4 p = posq[atom];
#ifdef USE_MIXED_PRECISION
    real4 c = posqCorrection[atom];
    return make_mixed3(p.x + (mixed) c.x, p.y + (mixed) c.y, p.z + (mixed) c.z);
#else
    return make_mixed3(p.x, p.y, p.z);
#endif
}

DEVICE Matrix3 zeroMatrix() {
    Matrix3 m;
    m.m00 = m.m01 = m.m02 = m.m10 = m.m11 = m.m12 = m.m20 = m.m21 = m.m22 = 0;
    return m;
}

/** J += m a a^T */
DEVICE void addOuter(Matrix3* J, mixed m, mixed3 a) {
    J->m00 += m*a.x*a.x; J->m01 += m*a.x*a.y; J->m02 += m*a.x*a.z;
    J->m10 += m*a.y*a.x; J->m11 += m*a.y*a.y; J->m12 += m*a.y*a.z;
    J->m20 += m*a.z*a.x; J->m21 += m*a.z*a.y; J->m22 += m*a.z*a.z;
}

DEVICE Matrix3 multiply(Matrix3 A, Matrix3 B) {
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

DEVICE mixed3 apply(Matrix3 A, mixed3 v) {
    return make_mixed3(A.m00*v.x + A.m01*v.y + A.m02*v.z, A.m10*v.x + A.m11*v.y + A.m12*v.z,
                       A.m20*v.x + A.m21*v.y + A.m22*v.z);
}

/** A^-1 by the adjugate; returns false if A is singular. */
DEVICE bool inverse3(Matrix3 A, Matrix3* inverse) {
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
DEVICE bool solve3(Matrix3 A, mixed3 b, mixed3* x) {
    Matrix3 inverse;
    if (!inverse3(A, &inverse))
        return false;
    *x = apply(inverse, b);
    return true;
}

/** The inertia I = tr(J) - J of a second moment J whose trace is given. */
DEVICE Matrix3 inertiaOf(Matrix3 J, mixed traceJ) {
    Matrix3 I;
    I.m00 = traceJ - J.m00; I.m01 = -J.m01; I.m02 = -J.m02;
    I.m10 = -J.m10; I.m11 = traceJ - J.m11; I.m12 = -J.m12;
    I.m20 = -J.m20; I.m21 = -J.m21; I.m22 = traceJ - J.m22;
    return I;
}

/**
 * The reset rotation, as the core solves it (RigidBodyMath::solveResetRotationForTorque):
 * P is the Cayley rotation of w, P - 1 = c ([w]x + [w]x^2) with c = 2 / (1 + |w|^2), and the
 * condition vex(P J - J P^T) = target is the quadratic
 * F(w) = I w + (J w) x w - (1 + |w|^2) target / 2 = 0 with I = tr(J) - J. Newton from the
 * linearised answer I^-1 target / 2, keeping the Jacobian (chord steps) once the correction
 * is below 1e-3 of w. Returns true and P - 1 in *delta if it converged.
 */
DEVICE bool solveRotation(Matrix3 J, mixed3 target, Matrix3* delta) {
    const mixed traceJ = J.m00 + J.m11 + J.m22;
    const Matrix3 I = inertiaOf(J, traceJ);
    const mixed3 t = make_mixed3(0.5f*target.x, 0.5f*target.y, 0.5f*target.z);
    mixed3 w;
    if (!solve3(I, t, &w))
        return false;
    Matrix3 inverseJacobian;
    bool newJacobian = true, converged = false;
    mixed previousStep = sqrt(w.x*w.x + w.y*w.y + w.z*w.z);
    for (int iteration = 1; iteration < MAX_ROTATION_ITERATIONS && !converged; iteration++) {
        const mixed3 Jw = apply(J, w);
        const mixed scale = 1 + w.x*w.x + w.y*w.y + w.z*w.z;
        const mixed3 F = traceJ*w - Jw + cross(Jw, w) - scale*t;
        if (newJacobian) {
            // G = I - [w]x J + [J w]x - 2 t w^T
            Matrix3 G;
            G.m00 = I.m00 - (w.y*J.m20 - w.z*J.m10) - 2*t.x*w.x;
            G.m01 = I.m01 - (w.y*J.m21 - w.z*J.m11) - Jw.z - 2*t.x*w.y;
            G.m02 = I.m02 - (w.y*J.m22 - w.z*J.m12) + Jw.y - 2*t.x*w.z;
            G.m10 = I.m10 - (w.z*J.m00 - w.x*J.m20) + Jw.z - 2*t.y*w.x;
            G.m11 = I.m11 - (w.z*J.m01 - w.x*J.m21) - 2*t.y*w.y;
            G.m12 = I.m12 - (w.z*J.m02 - w.x*J.m22) - Jw.x - 2*t.y*w.z;
            G.m20 = I.m20 - (w.x*J.m10 - w.y*J.m00) - Jw.y - 2*t.z*w.x;
            G.m21 = I.m21 - (w.x*J.m11 - w.y*J.m01) + Jw.x - 2*t.z*w.y;
            G.m22 = I.m22 - (w.x*J.m12 - w.y*J.m02) - 2*t.z*w.z;
            if (!inverse3(G, &inverseJacobian))
                return false;
        }
        const mixed3 step = apply(inverseJacobian, F);
        w -= step;
        const mixed stepSize = sqrt(step.x*step.x + step.y*step.y + step.z*step.z);
        const mixed size = sqrt(w.x*w.x + w.y*w.y + w.z*w.z);
        if (!(size == size) || size > 1e30f)
            return false;  // not finite
        // The error left is about the step times the rate at which steps shrink.
        converged = (stepSize == 0 || stepSize*stepSize <= CHORD_CONVERGED*size*previousStep);
        newJacobian = !(stepSize <= 1e-3f*size);
        previousStep = stepSize;
    }
    if (!converged)
        return false;
    const mixed w2 = w.x*w.x + w.y*w.y + w.z*w.z, c = 2/(1 + w2);
    Matrix3 D;
    D.m00 = c*(w.x*w.x - w2); D.m11 = c*(w.y*w.y - w2); D.m22 = c*(w.z*w.z - w2);
    D.m01 = c*(w.x*w.y - w.z); D.m10 = c*(w.x*w.y + w.z);
    D.m02 = c*(w.x*w.z + w.y); D.m20 = c*(w.x*w.z - w.y);
    D.m12 = c*(w.y*w.z - w.x); D.m21 = c*(w.y*w.z + w.x);
    *delta = D;
    return true;
}

/** Every work item of one launch that fails writes the same value, so no atomic is needed. */
DEVICE void recordFailure(GLOBAL int* RESTRICT failure, int step) {
    failure[0] = 1+step;
}

/**
 * A body's centre of mass relative to its first atom (origin) and its mean velocity, from
 * velocities whose .w is the inverse mass. Positions relative to the first atom keep their
 * digits however far the body is from the origin.
 */
DEVICE void bodyCenterAndVelocity(int start, int end, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velocities, mixed3* origin, mixed3* center, mixed3* meanVelocity) {
    *origin = loadPosition(posq, posqCorrection, bodyAtoms[start]);
    mixed totalMass = 0;
    mixed3 weighted = make_mixed3(0, 0, 0), momentum = make_mixed3(0, 0, 0);
    for (int k = start; k < end; k++) {
        const int atom = bodyAtoms[k];
        const mixed4 v = velocities[atom];
        const mixed m = 1/v.w;
        totalMass += m;
        weighted += m*(loadPosition(posq, posqCorrection, atom) - *origin);
        momentum += m*make_mixed3(v.x, v.y, v.z);
    }
    *center = weighted*(1/totalMass);
    *meanVelocity = momentum*(1/totalMass);
}

/** velocity += scale f / m for one atom (scale: the kick's time over the force buffer's fixed-point unit). */
DEVICE mixed4 kicked(mixed4 velocity, mixed scale, GLOBAL const mm_long* RESTRICT force, int index, int paddedNumAtoms) {
    velocity.x += scale*force[index]*velocity.w;
    velocity.y += scale*force[index+paddedNumAtoms]*velocity.w;
    velocity.z += scale*force[index+paddedNumAtoms*2]*velocity.w;
    return velocity;
}

/**
 * Per atom: a kick over kickTime (0 for none) and a drift over h into newVelocity and posDelta (the state
 * itself is written only by applyPositionStep, once every body's reset has succeeded).
 */
KERNEL void kickAndDrift(int numAtoms, int paddedNumAtoms, mixed kickTime, mixed h,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, GLOBAL mixed4* RESTRICT posDelta,
        GLOBAL mixed4* RESTRICT newVelocity, GLOBAL int* RESTRICT failure, int step) {
    if (failure[0] != 0)
        return;
    const mixed scale = kickTime/(mixed) 0x100000000;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        mixed4 velocity = velm[index];
        if (velocity.w != 0) {
            velocity = kicked(velocity, scale, force, index, paddedNumAtoms);
            posDelta[index] = make_mixed4(h*velocity.x, h*velocity.y, h*velocity.z, 0);
            if (!(velocity.x*velocity.x + velocity.y*velocity.y + velocity.z*velocity.z <= 1e30f))
                recordFailure(failure, step);  // not finite (NaN fails every comparison)
        }
        else
            posDelta[index] = make_mixed4(0, 0, 0, 0);
        newVelocity[index] = velocity;
    }
}

/**
 * P - 1 of a body's reset: the torque condition's Newton solve. Each atom's drift relative to
 * the centres is h (v - V); its position about the centre is (x - origin) - center, the
 * centre taken relative to the first atom (origin) so that no digits are lost.
 */
DEVICE bool solveBodyRotation(int start, int end, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT newVelocity, mixed3 origin, mixed3 center, mixed3 V, mixed h, Matrix3* delta) {
    Matrix3 J = zeroMatrix();
    mixed3 target = make_mixed3(0, 0, 0);
    for (int k = start; k < end; k++) {
        const int atom = bodyAtoms[k];
        const mixed4 v = newVelocity[atom];
        const mixed m = 1/v.w;
        const mixed3 a = loadPosition(posq, posqCorrection, atom) - origin - center;
        addOuter(&J, m, a);
        target += m*cross(a, h*(make_mixed3(v.x, v.y, v.z) - V));
    }
    return solveRotation(J, target, delta);
}

/**
 * The same for a linear body, in closed form: u x (j p - w) = 0 with p = P u, spin about the
 * axis no degree of freedom, P the smallest rotation taking u to p.
 */
DEVICE bool solveLinearBodyRotation(int start, int end, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT newVelocity, mixed3 origin, mixed3 center, mixed3 V, mixed h, Matrix3* delta) {
    *delta = zeroMatrix();
    mixed3 u = make_mixed3(0, 0, 0);
    mixed farthest = -1;
    for (int k = start; k < end; k++) {
        const mixed3 a = loadPosition(posq, posqCorrection, bodyAtoms[k]) - origin - center;
        const mixed r2 = dot(a, a);
        if (r2 > farthest) {
            farthest = r2;
            u = a;
        }
    }
    const mixed length = sqrt(farthest);
    u = (length > 0 ? u*(1/length) : make_mixed3(1, 0, 0));
    mixed3 w = make_mixed3(0, 0, 0);
    mixed j = 0;
    for (int k = start; k < end; k++) {
        const int atom = bodyAtoms[k];
        const mixed4 v = newVelocity[atom];
        const mixed m = 1/v.w;
        const mixed3 a = loadPosition(posq, posqCorrection, atom) - origin - center;
        const mixed s = dot(a, u);
        w += (m*s)*(a + h*(make_mixed3(v.x, v.y, v.z) - V));
        j += m*s*s;
    }
    if (j == 0)
        return true;  // all atoms at the centre: nothing to rotate
    const mixed uw = dot(u, w);
    const mixed discriminant = uw*uw - dot(w, w) + j*j;
    if (!(discriminant >= 0))
        return false;  // no rotation satisfies the condition (step far too large), or not finite
    mixed3 p = (w + (-uw + sqrt(discriminant))*u)*(1/j);
    p *= 1/sqrt(dot(p, p));
    const mixed c = dot(u, p);
    if (!(c > -1 + 1e-6f))
        return false;
    // K + K^2/(1+c), K = [u x p]
    const mixed3 n = cross(u, p);
    Matrix3 K;
    K.m00 = 0; K.m01 = -n.z; K.m02 = n.y;
    K.m10 = n.z; K.m11 = 0; K.m12 = -n.x;
    K.m20 = -n.y; K.m21 = n.x; K.m22 = 0;
    const Matrix3 K2 = multiply(K, K);
    const mixed f = 1/(1 + c);
    delta->m00 = K.m00+f*K2.m00; delta->m01 = K.m01+f*K2.m01; delta->m02 = K.m02+f*K2.m02;
    delta->m10 = K.m10+f*K2.m10; delta->m11 = K.m11+f*K2.m11; delta->m12 = K.m12+f*K2.m12;
    delta->m20 = K.m20+f*K2.m20; delta->m21 = K.m21+f*K2.m21; delta->m22 = K.m22+f*K2.m22;
    return true;
}

/**
 * M-RATTLE's position reset, one work item per body: the centre moves with the mean
 * velocity, the orientation is the rotation that makes the constraint displacement exert
 * zero torque about the old positions. Positions are taken relative to the body's first
 * atom so that a body far from the origin loses no digits.
 */
KERNEL void resetBodies(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const int* RESTRICT bodyLinear, mixed h, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT posDelta,
        GLOBAL mixed4* RESTRICT newVelocity, GLOBAL int* RESTRICT failure, int step) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        mixed3 origin, center, V;
        bodyCenterAndVelocity(start, end, bodyAtoms, posq, posqCorrection, newVelocity, &origin, &center, &V);
        if (!(dot(V, V) <= 1e30f && dot(center, center) <= 1e30f)) {  // inf or NaN
            recordFailure(failure, step);
            continue;
        }
        Matrix3 delta;
        const bool converged = (bodyLinear[body] == 0 ?
                solveBodyRotation(start, end, bodyAtoms, posq, posqCorrection, newVelocity, origin, center, V, h,
                                  &delta) :
                solveLinearBodyRotation(start, end, bodyAtoms, posq, posqCorrection, newVelocity, origin, center, V,
                                        h, &delta));
        if (!converged) {
            recordFailure(failure, step);
            continue;
        }
        const mixed3 shift = h*V;
        const mixed invH = 1/h;
        for (int k = start; k < end; k++) {
            const int atom = bodyAtoms[k];
            const mixed3 a = loadPosition(posq, posqCorrection, atom) - origin - center;
            const mixed3 turn = apply(delta, a);
            const mixed3 move = shift + turn;
            posDelta[atom] = make_mixed4(move.x, move.y, move.z, 0);
            const mixed4 v = newVelocity[atom];
            newVelocity[atom] = make_mixed4(V.x + turn.x*invH, V.y + turn.y*invH, V.z + turn.z*invH, v.w);
        }
    }
}

/**
 * RATTLE's position step for the free-particle constraints, one work item per cluster of
 * constraints (a connected group, e.g. the bonds to hydrogens of one heavy atom): SHAKE
 * iterations along the old bond vectors, then velocities from the constrained displacement.
 */
KERNEL void constrainFreePositions(int numClusters, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const mixed* RESTRICT constraintDistance,
        mixed h, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL mixed4* RESTRICT posDelta, GLOBAL mixed4* RESTRICT newVelocity, mixed tolerance,
        GLOBAL int* RESTRICT failure, int step) {
    if (failure[0] != 0)
        return;
    const mixed invH = 1/h;
    for (int cluster = GLOBAL_ID; cluster < numClusters; cluster += GLOBAL_SIZE) {
        const int start = clusterStart[cluster], end = clusterStart[cluster+1];
        bool converged = false;
        for (int iteration = 0; iteration < MAX_CONSTRAINT_ITERATIONS && !converged; iteration++) {
            converged = true;
            for (int c = start; c < end; c++) {
                const int2 atoms = constraintAtoms[c];
                const mixed d = constraintDistance[c];
                const mixed3 oldR = loadPosition(posq, posqCorrection, atoms.x) - loadPosition(posq, posqCorrection, atoms.y);
                const mixed4 di = posDelta[atoms.x], dj = posDelta[atoms.y];
                const mixed3 newR = oldR + make_mixed3(di.x - dj.x, di.y - dj.y, di.z - dj.z);
                const mixed diff = d*d - dot(newR, newR);
                if (fabs(diff) > 2*tolerance*d*d) {
                    converged = false;
                    const mixed wi = newVelocity[atoms.x].w, wj = newVelocity[atoms.y].w;
                    const mixed g = diff/(2*dot(newR, oldR)*(wi + wj));
                    posDelta[atoms.x] = make_mixed4(di.x + g*wi*oldR.x, di.y + g*wi*oldR.y, di.z + g*wi*oldR.z, 0);
                    posDelta[atoms.y] = make_mixed4(dj.x - g*wj*oldR.x, dj.y - g*wj*oldR.y, dj.z - g*wj*oldR.z, 0);
                }
            }
        }
        if (!converged) {
            recordFailure(failure, step);
            continue;
        }
        for (int c = start; c < end; c++) {
            const int2 atoms = constraintAtoms[c];
            mixed4 d = posDelta[atoms.x], v = newVelocity[atoms.x];
            newVelocity[atoms.x] = make_mixed4(d.x*invH, d.y*invH, d.z*invH, v.w);
            d = posDelta[atoms.y];
            v = newVelocity[atoms.y];
            newVelocity[atoms.y] = make_mixed4(d.x*invH, d.y*invH, d.z*invH, v.w);
        }
    }
}

/** Write the step's positions and velocities, unless a reset or constraint failed. */
KERNEL void applyPositionStep(int numAtoms, GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mixed4* RESTRICT posDelta, GLOBAL const mixed4* RESTRICT newVelocity,
        GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        if (velm[index].w == 0)
            continue;
        const real4 p = posq[index];
        const mixed4 delta = posDelta[index];
        const mixed3 pos = loadPosition(posq, posqCorrection, index) + make_mixed3(delta.x, delta.y, delta.z);
#ifdef USE_MIXED_PRECISION
        posq[index] = make_real4((real) pos.x, (real) pos.y, (real) pos.z, p.w);
        posqCorrection[index] = make_real4(pos.x-(real) pos.x, pos.y-(real) pos.y, pos.z-(real) pos.z, 0);
#else
        posq[index] = make_real4(pos.x, pos.y, pos.z, p.w);
#endif
        velm[index] = newVelocity[index];
    }
}

/** Per atom: a kick over kickTime with the Context's forces. */
KERNEL void kickVelocities(int numAtoms, int paddedNumAtoms, mixed kickTime,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    const mixed scale = kickTime/(mixed) 0x100000000;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        mixed4 velocity = velm[index];
        if (velocity.w != 0)
            velm[index] = kicked(velocity, scale, force, index, paddedNumAtoms);
    }
}

/**
 * RATTLE's velocity step for a rigid body, one work item per body: the mass-weighted
 * projection onto rigid-body motion v_i = V + w x a_i, w = I^-1 L. With onlyIfNotRigid,
 * velocities already rigid to round-off are left exactly as they are. With collide (an
 * Andersen thermostat), a body whose velocities are not rigid -- an atom collided -- first
 * gets fresh Maxwell-Boltzmann velocities for all its atoms.
 */
KERNEL void projectBodies(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyAtoms,
        GLOBAL const int* RESTRICT bodyLinear, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, int onlyIfNotRigid,
        GLOBAL const int* RESTRICT failure, int collide, mixed kT, GLOBAL const float4* RESTRICT random,
        unsigned int randomIndex) {
    if (failure[0] != 0)
        return;
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        const int start = bodyStart[body], end = bodyStart[body+1];
        for (int pass = (collide ? 0 : 1); pass < 2; pass++) {
            mixed3 origin, center, V;
            bodyCenterAndVelocity(start, end, bodyAtoms, posq, posqCorrection, velm, &origin, &center, &V);
            Matrix3 J = zeroMatrix();
            mixed3 L = make_mixed3(0, 0, 0), u = make_mixed3(1, 0, 0);
            mixed farthest = -1;
            for (int k = start; k < end; k++) {
                const int atom = bodyAtoms[k];
                const mixed4 v = velm[atom];
                const mixed m = 1/v.w;
                const mixed3 a = loadPosition(posq, posqCorrection, atom) - origin - center;
                addOuter(&J, m, a);
                L += m*cross(a, make_mixed3(v.x, v.y, v.z));
                if (dot(a, a) > farthest) {
                    farthest = dot(a, a);
                    u = a;
                }
            }
            mixed3 omega = make_mixed3(0, 0, 0);
            const mixed j = J.m00 + J.m11 + J.m22;
            if (bodyLinear[body] != 0) {
                if (farthest > 0 && j > 0) {
                    u *= 1/sqrt(farthest);
                    omega = (L - dot(L, u)*u)*(1/j);
                }
            }
            else
                solve3(inertiaOf(J, j), L, &omega);
            mixed scale = 0, residual = 0;
            for (int k = start; k < end; k++) {
                const int atom = bodyAtoms[k];
                const mixed4 v = velm[atom];
                const mixed3 rigid = V + cross(omega, loadPosition(posq, posqCorrection, atom) - origin - center);
                const mixed3 difference = make_mixed3(v.x, v.y, v.z) - rigid;
                scale = max(scale, dot(rigid, rigid));
                residual = max(residual, dot(difference, difference));
            }
            if (pass == 0) {
                // Collision detection (Andersen): not rigid to 1e-8 means an atom was re-drawn.
                if (residual > 1e-16f*scale || (scale == 0 && residual > 0)) {
                    for (int k = start; k < end; k++) {
                        const int atom = bodyAtoms[k];
                        const mixed4 v = velm[atom];
                        const float4 g = random[randomIndex + atom];
                        const mixed sigma = sqrt(kT*v.w);
                        velm[atom] = make_mixed4(sigma*g.x, sigma*g.y, sigma*g.z, v.w);
                    }
                }
                continue;
            }
            if (onlyIfNotRigid && residual <= RIGID_TOLERANCE*RIGID_TOLERANCE*scale)
                continue;
            for (int k = start; k < end; k++) {
                const int atom = bodyAtoms[k];
                const mixed4 v = velm[atom];
                const mixed3 rigid = V + cross(omega, loadPosition(posq, posqCorrection, atom) - origin - center);
                velm[atom] = make_mixed4(rigid.x, rigid.y, rigid.z, v.w);
            }
        }
    }
}

/**
 * RATTLE's velocity step for the free-particle constraints, one work item per cluster:
 * remove the relative velocity along each bond until every bond's rate of change is below
 * the tolerance (relative to its length).
 */
KERNEL void constrainFreeVelocities(int numClusters, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed tolerance,
        GLOBAL int* RESTRICT failure, int step) {
    if (failure[0] != 0)
        return;
    for (int cluster = GLOBAL_ID; cluster < numClusters; cluster += GLOBAL_SIZE) {
        const int start = clusterStart[cluster], end = clusterStart[cluster+1];
        bool converged = false;
        for (int iteration = 0; iteration < MAX_CONSTRAINT_ITERATIONS && !converged; iteration++) {
            converged = true;
            for (int c = start; c < end; c++) {
                const int2 atoms = constraintAtoms[c];
                const mixed3 r = loadPosition(posq, posqCorrection, atoms.x) - loadPosition(posq, posqCorrection, atoms.y);
                const mixed4 vi = velm[atoms.x], vj = velm[atoms.y];
                const mixed3 relative = make_mixed3(vi.x - vj.x, vi.y - vj.y, vi.z - vj.z);
                const mixed rate = dot(r, relative);
                const mixed r2 = dot(r, r);
                if (fabs(rate) > tolerance*r2) {
                    converged = false;
                    const mixed g = -rate/(r2*(vi.w + vj.w));
                    velm[atoms.x] = make_mixed4(vi.x + g*vi.w*r.x, vi.y + g*vi.w*r.y, vi.z + g*vi.w*r.z, vi.w);
                    velm[atoms.y] = make_mixed4(vj.x - g*vj.w*r.x, vj.y - g*vj.w*r.y, vj.z - g*vj.w*r.z, vj.w);
                }
            }
        }
        if (!converged)
            recordFailure(failure, step);
    }
}

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

/** Copy the state at the start of a step, unless a failure was recorded (the copy then keeps the state before it). */
KERNEL void backupState(int numAtoms, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup, GLOBAL const int* RESTRICT failure) {
    if (failure[0] != 0)
        return;
    for (int index = GLOBAL_ID; index < numAtoms; index += GLOBAL_SIZE) {
        posqBackup[index] = posq[index];
#ifdef USE_MIXED_PRECISION
        correctionBackup[index] = posqCorrection[index];
#endif
        velmBackup[index] = velm[index];
    }
}
