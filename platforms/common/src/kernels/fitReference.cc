/*
 * Positions set from the host, checked on the device against each body's reference geometry
 * (CommonRigidBodyState::updateShapes): a body that is its reference turned keeps it, and only
 * its orientation changes, so setPositions() and setState() need no download.
 */

/** The orthonormal frame (columns) of u and w's plane; for w = 0 (a linear body) any frame whose first axis is u. */
INLINE_DEVICE Matrix3 frameOf(mixed3 u, mixed3 w) {
    const mixed3 e1 = u*(1/sqrt(dot(u, u)));
    if (dot(w, w) == 0)  // the roll about a line is arbitrary: the axis least along it
        w = (fabs(e1.x) <= fabs(e1.y) && fabs(e1.x) <= fabs(e1.z) ? make_mixed3(1, 0, 0) :
             fabs(e1.y) <= fabs(e1.z) ? make_mixed3(0, 1, 0) : make_mixed3(0, 0, 1));
    mixed3 e2 = w - e1*dot(w, e1);
    e2 = e2*(1/sqrt(dot(e2, e2)));
    const mixed3 e3 = cross(e1, e2);
    Matrix3 F;
    F.m00 = e1.x; F.m01 = e2.x; F.m02 = e3.x;
    F.m10 = e1.y; F.m11 = e2.y; F.m12 = e3.y;
    F.m20 = e1.z; F.m21 = e2.z; F.m22 = e3.z;
    return F;
}

INLINE_DEVICE Matrix3 transpose(Matrix3 A) {
    Matrix3 T;
    T.m00 = A.m00; T.m01 = A.m10; T.m02 = A.m20;
    T.m10 = A.m01; T.m11 = A.m11; T.m12 = A.m21;
    T.m20 = A.m02; T.m21 = A.m12; T.m22 = A.m22;
    return T;
}

/**
 * Each body's turn Q from its reference to its positions, taken from three of its atoms
 * (bodyFrame: offsets i, j, k in the body, k < 0 for a linear body; .w = 0 for none), then
 * checked on every atom: |(x_k - x_0) - Q (ref_k - ref_0)| within FIT_TOLERANCE times the
 * round-off of the body's stored coordinates (in double precision, where nothing is rebuilt
 * from the reference, DOUBLE_FIT_DISTANCE for a body that is not linear). A body that fits
 * gets Q as its orientation (single and mixed precision); one that does not, or is not
 * finite, sets misfit[0] = 1, as does any atom's position (free ones too) that is not finite.
 */
KERNEL void fitBodiesToReference(int numAtoms, int numBodies, GLOBAL const int* RESTRICT bodyStart,
        GLOBAL const int* RESTRICT bodyAtoms, GLOBAL const int* RESTRICT bodyShape, GLOBAL const int4* RESTRICT bodyFrame,
        GLOBAL const mixed4* RESTRICT reference, GLOBAL mixed* RESTRICT orientation, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, mixed roundoff, mixed boxLength, GLOBAL int* RESTRICT misfit) {
    for (int atom = GLOBAL_ID; atom < numAtoms; atom += GLOBAL_SIZE) {
        const real4 p = posq[atom];
        if (!(fabs(p.x) <= FINITE_BOUND && fabs(p.y) <= FINITE_BOUND && fabs(p.z) <= FINITE_BOUND))
            misfit[0] = 1;  // the host names it
    }
    for (int body = GLOBAL_ID; body < numBodies; body += GLOBAL_SIZE) {
        if (bodyShape[body] == SHAPE_POINT)
            continue;
        const int4 frame = bodyFrame[body];
        if (frame.w == 0) {
            misfit[0] = 1;
            continue;
        }
        const int start = bodyStart[body], end = bodyStart[body+1];
        const mixed3 x0 = loadPosition(posq, posqCorrection, bodyAtoms[start]);
        const mixed4 q0 = reference[start];
        const mixed3 ref0 = make_mixed3(q0.x, q0.y, q0.z);
        const int third = (frame.z < 0 ? frame.x : frame.z);  // a linear body's frame: its line alone
        const mixed3 xi = loadPosition(posq, posqCorrection, bodyAtoms[start+frame.x]);
        const mixed4 ri = reference[start+frame.x], rj = reference[start+frame.y], rk = reference[start+third];
        const Matrix3 F = frameOf(loadPosition(posq, posqCorrection, bodyAtoms[start+frame.y]) - xi,
                                  loadPosition(posq, posqCorrection, bodyAtoms[start+third]) - xi);
        const Matrix3 G = frameOf(make_mixed3(rj.x-ri.x, rj.y-ri.y, rj.z-ri.z), make_mixed3(rk.x-ri.x, rk.y-ri.y, rk.z-ri.z));
        const Matrix3 Q = multiply(F, transpose(G));
        mixed largest = 0, error = 0;
        for (int k = start; k < end; k++) {
            const mixed3 x = loadPosition(posq, posqCorrection, bodyAtoms[k]);
            const mixed4 q = reference[k];
            const mixed3 d = (x - x0) - apply(Q, make_mixed3(q.x, q.y, q.z) - ref0);
            largest = max(largest, max(fabs(x.x), max(fabs(x.y), fabs(x.z))));
            const mixed squared = dot(d, d);
            if (!(squared <= error))  // NaN propagates (max() need not)
                error = squared;
        }
        mixed allowed = FIT_TOLERANCE*roundoff*(largest + boxLength);
#ifndef REBUILD_SHAPES
        if (frame.z >= 0)
            allowed = max(allowed, DOUBLE_FIT_DISTANCE);
#endif
        if (!(error <= allowed*allowed))
            misfit[0] = 1;
#ifdef REBUILD_SHAPES
        else
            storeOrientation(orientation, body, Q);
#endif
    }
}
