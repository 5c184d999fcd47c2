/*
 * RATTLE for constraints between free particles, one cluster of constraints at a time (a
 * connected group, e.g. the bonds to hydrogens of one heavy atom): SHAKE's position
 * iterations and the velocity step. A cluster lists its constraints (clusterStart into
 * constraintAtoms) and, once each, its atoms.
 */

/**
 * RATTLE's position step over h: each atom's displacement (in posDelta, scratch) starts as
 * h v, SHAKE iterates along the old bond vectors, then positions and velocities are written
 * from the constrained displacement. Returns false if it did not converge.
 */
INLINE_DEVICE bool shakeCluster(int constraintStart, int constraintEnd, GLOBAL const int2* RESTRICT constraintAtoms,
        GLOBAL const mixed* RESTRICT constraintDistance, int atomStart, int atomEnd,
        GLOBAL const int* RESTRICT clusterAtoms, mixed h, mixed tolerance, GLOBAL real4* RESTRICT posq,
        GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, GLOBAL mixed4* RESTRICT posDelta) {
    for (int k = atomStart; k < atomEnd; k++) {
        const int atom = clusterAtoms[k];
        const mixed4 v = velm[atom];
        posDelta[atom] = make_mixed4(h*v.x, h*v.y, h*v.z, 0);
    }
    bool converged = false;
    for (int iteration = 0; iteration < MAX_CONSTRAINT_ITERATIONS && !converged; iteration++) {
        converged = true;
        for (int c = constraintStart; c < constraintEnd; c++) {
            const int2 atoms = constraintAtoms[c];
            const mixed d = constraintDistance[c];
            const mixed3 oldR = loadPosition(posq, posqCorrection, atoms.x) - loadPosition(posq, posqCorrection, atoms.y);
            const mixed4 di = posDelta[atoms.x], dj = posDelta[atoms.y];
            const mixed3 newR = oldR + make_mixed3(di.x - dj.x, di.y - dj.y, di.z - dj.z);
            const mixed diff = d*d - dot(newR, newR);
            if (fabs(diff) > 2*tolerance*d*d) {
                converged = false;
                const mixed wi = velm[atoms.x].w, wj = velm[atoms.y].w;
                const mixed g = diff/(2*dot(newR, oldR)*(wi + wj));
                posDelta[atoms.x] = make_mixed4(di.x + g*wi*oldR.x, di.y + g*wi*oldR.y, di.z + g*wi*oldR.z, 0);
                posDelta[atoms.y] = make_mixed4(dj.x - g*wj*oldR.x, dj.y - g*wj*oldR.y, dj.z - g*wj*oldR.z, 0);
            }
        }
    }
    if (!converged)
        return false;
    const mixed invH = 1/h;
    for (int k = atomStart; k < atomEnd; k++) {
        const int atom = clusterAtoms[k];
        const mixed4 d = posDelta[atom], v = velm[atom];
        storePosition(posq, posqCorrection, atom, loadPosition(posq, posqCorrection, atom) + make_mixed3(d.x, d.y, d.z));
        velm[atom] = make_mixed4(d.x*invH, d.y*invH, d.z*invH, v.w);
    }
    return true;
}

/**
 * RATTLE's velocity step: remove the relative velocity along each bond until every bond's
 * rate of change is below the tolerance (relative to its length). Returns false if it did
 * not converge.
 */
INLINE_DEVICE bool rattleCluster(int constraintStart, int constraintEnd, GLOBAL const int2* RESTRICT constraintAtoms,
        GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm,
        mixed tolerance) {
    bool converged = false;
    for (int iteration = 0; iteration < MAX_CONSTRAINT_ITERATIONS && !converged; iteration++) {
        converged = true;
        for (int c = constraintStart; c < constraintEnd; c++) {
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
    return converged;
}

/** The velocity step for every cluster (velocities set from the host, Andersen collisions). */
KERNEL void constrainFreeVelocities(int numClusters, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed tolerance,
        GLOBAL int* RESTRICT failure, int stepIndex) {
    if (failure[0] != 0)
        return;
    for (int cluster = GLOBAL_ID; cluster < numClusters; cluster += GLOBAL_SIZE)
        if (!rattleCluster(clusterStart[cluster], clusterStart[cluster+1], constraintAtoms, posq, posqCorrection, velm,
                           tolerance))
            recordFailure(failure, stepIndex);
}
