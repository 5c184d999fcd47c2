/*
 * M-RATTLE's position reset rotation: the torque condition's Newton solve, and its closed form for linear bodies.
 */

/**
 * The reset rotation, as the core solves it (RigidBodyMath::solveResetRotationForTorque):
 * P is the Cayley rotation of w, P - 1 = c ([w]x + [w]x^2) with c = 2 / (1 + |w|^2), and the
 * condition vex(P J - J P^T) = target is the quadratic
 * F(w) = I w + (J w) x w - (1 + |w|^2) target / 2 = 0 with I = tr(J) - J. Newton from the
 * linearised answer I^-1 target / 2, keeping the Jacobian (chord steps) once the correction
 * is below CHORD_SWITCH of w. Returns true and P - 1 in *delta if it converged.
 */
INLINE_DEVICE bool solveRotation(Matrix3 J, mixed3 target, Matrix3* delta) {
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
        if (!(size <= FINITE_BOUND))
            return false;  // not finite
        // The error left is about the step times the rate at which steps shrink.
        converged = (stepSize == 0 || stepSize*stepSize <= CHORD_CONVERGED*size*previousStep);
        newJacobian = !(stepSize <= CHORD_SWITCH*size);
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

/**
 * P - 1 of a linear body's reset, in closed form: u x (j p - w) = 0 with p = P u, spin about the
 * axis no degree of freedom, P the smallest rotation taking u to p.
 */
INLINE_DEVICE bool solveLinearBodyRotation(int start, int end, GLOBAL const int* RESTRICT bodyAtoms,
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

