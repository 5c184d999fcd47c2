/*
 * RATTLE for constraints between free particles: SHAKE's position iterations and the velocity step, one work item per cluster.
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/**
 * RATTLE's position step for the free-particle constraints, one work item per cluster of
 * constraints (a connected group, e.g. the bonds to hydrogens of one heavy atom): SHAKE
 * iterations along the old bond vectors, then velocities from the constrained displacement.
 */
KERNEL void constrainFreePositions(int numClusters, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const mixed* RESTRICT constraintDistance,
        mixed h, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL mixed4* RESTRICT posDelta, GLOBAL mixed4* RESTRICT newVelocity, mixed tolerance,
        GLOBAL int* RESTRICT failure) {
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
            recordFailure(failure);
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

/**
 * RATTLE's velocity step for the free-particle constraints, one work item per cluster:
 * remove the relative velocity along each bond until every bond's rate of change is below
 * the tolerance (relative to its length).
 */
KERNEL void constrainFreeVelocities(int numClusters, GLOBAL const int* RESTRICT clusterStart,
        GLOBAL const int2* RESTRICT constraintAtoms, GLOBAL const real4* RESTRICT posq,
        GLOBAL const real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm, mixed tolerance,
        GLOBAL int* RESTRICT failure) {
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
            recordFailure(failure);
    }
}

