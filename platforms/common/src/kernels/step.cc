/*
 * A step's work on single atoms and on one body: its backup, kicks, drifts, the bodies'
 * position reset, Langevin's noise. The kernel that sequences them per group of atoms is
 * advanceGroups (advance.cc).
 *
 * (See bodyMath.cc for the program's layout and the failure flag.)
 */

/** Write a position in the storage's precision (mixed: a float and its correction). */
DEVICE void storePosition(GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, int atom, mixed3 pos) {
    const real4 p = posq[atom];
#ifdef USE_MIXED_PRECISION
    posq[atom] = make_real4((real) pos.x, (real) pos.y, (real) pos.z, p.w);
    posqCorrection[atom] = make_real4(pos.x-(real) pos.x, pos.y-(real) pos.y, pos.z-(real) pos.z, 0);
#else
    posq[atom] = make_real4(pos.x, pos.y, pos.z, p.w);
#endif
}

/** Copy an atom's state into the step's backup (put back if the step fails). */
DEVICE void backupAtom(int atom, GLOBAL const real4* RESTRICT posq, GLOBAL const real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL real4* RESTRICT posqBackup, GLOBAL real4* RESTRICT correctionBackup,
        GLOBAL mixed4* RESTRICT velmBackup) {
    posqBackup[atom] = posq[atom];
#ifdef USE_MIXED_PRECISION
    correctionBackup[atom] = posqCorrection[atom];
#endif
    velmBackup[atom] = velm[atom];
}

/** A kick of one atom's velocity with the Context's forces; false if the velocity is then not finite. */
DEVICE bool kickAtom(int atom, mixed scale, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms,
        GLOBAL mixed4* RESTRICT velm) {
    mixed4 velocity = velm[atom];
    if (velocity.w == 0)
        return true;
    velocity = kicked(velocity, scale, force, atom, paddedNumAtoms);
    velm[atom] = velocity;
    return isFiniteVelocity(velocity);  // not finite: the forces are not (NaN fails every comparison)
}

/** A free atom's drift over h. */
DEVICE void driftAtom(int atom, mixed h, GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection,
        GLOBAL const mixed4* RESTRICT velm) {
    const mixed4 v = velm[atom];
    if (v.w == 0)
        return;
    const mixed4 delta = make_mixed4(h*v.x, h*v.y, h*v.z, 0);
    storePosition(posq, posqCorrection, atom, loadPosition(posq, posqCorrection, atom) + make_mixed3(delta.x, delta.y, delta.z));
}

/** Langevin's Ornstein-Uhlenbeck step of one atom: v = a v + sqrt((1 - a^2) kT / m) g (noiseScale = sqrt((1 - a^2) kT)). */
DEVICE void noiseAtom(int atom, mixed a, mixed noiseScale, GLOBAL const float4* RESTRICT random, unsigned int randomIndex,
        GLOBAL mixed4* RESTRICT velm) {
    const mixed4 v = velm[atom];
    if (v.w == 0)
        return;
    const float4 g = random[randomIndex + atom];
    const mixed sigma = noiseScale*sqrt(v.w);
    velm[atom] = make_mixed4(a*v.x + sigma*g.x, a*v.y + sigma*g.y, a*v.z + sigma*g.z, v.w);
}

/**
 * M-RATTLE's drift and position reset of one body over h, from its positions and velocities:
 * the centre moves with the mean velocity, the orientation is the rotation that makes the
 * constraint displacement exert zero torque about the old positions; the new velocities are
 * the displacement's over h. Positions are taken relative to the body's first atom so that
 * a body far from the origin loses no digits. Returns false if no rotation was found.
 */
DEVICE bool resetBody(int start, int end, GLOBAL const int* RESTRICT bodyAtoms, int shape, mixed h,
        GLOBAL real4* RESTRICT posq, GLOBAL real4* RESTRICT posqCorrection, GLOBAL mixed4* RESTRICT velm) {
    mixed3 origin, center, V;
    bodyCenterAndVelocity(start, end, bodyAtoms, posq, posqCorrection, velm, &origin, &center, &V);
    if (!(dot(V, V) <= FINITE_BOUND && dot(center, center) <= FINITE_BOUND))
        return false;  // inf or NaN
    Matrix3 delta = zeroMatrix();
    const bool converged = shape == SHAPE_POINT || (shape == SHAPE_GENERAL ?
            solveBodyRotation(start, end, bodyAtoms, posq, posqCorrection, velm, origin, center, V, h, &delta) :
            solveLinearBodyRotation(start, end, bodyAtoms, posq, posqCorrection, velm, origin, center, V, h, &delta));
    if (!converged)
        return false;
    const mixed3 shift = h*V;
    const mixed invH = 1/h;
    for (int k = start; k < end; k++) {
        const int atom = bodyAtoms[k];
        const mixed3 x = loadPosition(posq, posqCorrection, atom);
        const mixed3 turn = apply(delta, x - origin - center);
        storePosition(posq, posqCorrection, atom, x + (shift + turn));
        const mixed4 v = velm[atom];
        velm[atom] = make_mixed4(V.x + turn.x*invH, V.y + turn.y*invH, V.z + turn.z*invH, v.w);
    }
    return true;
}
