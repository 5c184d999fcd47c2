#ifndef MRATTLE_TORQUE_CONDITION_H_
#define MRATTLE_TORQUE_CONDITION_H_

/*
 * The rotation solve of M-RATTLE's position reset, for one body or four at once in the lanes
 * of SIMD registers. Internal to the core; plain doubles, no Eigen: the four-lane code is
 * compiled for AVX2 and must not instantiate inline code that other files share (its
 * templates are instantiated for its own vector type and always inlined).
 */
namespace MRattlePlugin {
namespace TorqueCondition {

/**
 * One body's condition: its second moment J = sum m a a^T about the centre (six entries)
 * and the torque target sum m a x (y - a).
 */
struct Condition {
    double j00, j01, j02, j11, j12, j22;
    double t0, t1, t2;
};

/** The rotation found: P - 1 = c ([w]x + [w]x^2), c = 2 / (1 + |w|^2), w the Cayley vector. */
struct Solution {
    double w0 = 0, w1 = 0, w2 = 0;
    int iterations = 0;   // the linear first solve and the Newton or chord steps after it
    bool converged = false;
};

#if defined(__GNUC__)
#define MRATTLE_INLINE inline __attribute__((always_inline))
#else
#define MRATTLE_INLINE inline
#endif

/**
 * x = I^-1 b for the inertia I = tr(J) - J of the second moment j (six entries), by I's
 * cofactors (I and its adjugate are symmetric). No pivoting: an inertia tensor needs none;
 * the result is not finite if I is singular.
 */
template <class Real>
MRATTLE_INLINE void inertiaSolve(const Real* j, Real b0, Real b1, Real b2, Real& x0, Real& x1, Real& x2) {
    const Real j00 = j[0], j01 = j[1], j02 = j[2], j11 = j[3], j12 = j[4], j22 = j[5];
    const Real traceJ = j00 + j11 + j22;
    const Real i00 = traceJ - j00, i11 = traceJ - j11, i22 = traceJ - j22;
    const Real c00 = i11 * i22 - j12 * j12, c01 = j01 * i22 + j12 * j02, c02 = j01 * j12 + i11 * j02;
    const Real c11 = i00 * i22 - j02 * j02, c12 = i00 * j12 + j01 * j02, c22 = i00 * i11 - j01 * j01;
    const Real inverseDet = 1.0 / (i00 * c00 - j01 * c01 - j02 * c02);
    x0 = (c00 * b0 + c01 * b1 + c02 * b2) * inverseDet;
    x1 = (c01 * b0 + c11 * b1 + c12 * b2) * inverseDet;
    x2 = (c02 * b0 + c12 * b1 + c22 * b2) * inverseDet;
}

/**
 * x = I^-1 b for the inertia I = tr(J) - J of a second moment j (j00, j01, j02, j11, j12,
 * j22): the solve's first iterate, and the velocity projection's angular velocity. Inline:
 * the projection calls it once per body.
 */
inline void solveInertia(const double* j, const double* b, double* x) {
    inertiaSolve(j, b[0], b[1], b[2], x[0], x[1], x[2]);
}

/** solveInertia for count (at most 4) bodies, j, b and x consecutive; in AVX2 lanes as solveUpToFour. */
void solveInertiaUpToFour(const double* j, const double* b, double* x, int count);

/** Solve one condition in at most maxIterations iterations. */
Solution solve(const Condition& condition, int maxIterations);

/**
 * Solve count (at most 4) conditions. Where the CPU has AVX2 and count > 1 they share the
 * lanes of AVX2 registers; each lane does the arithmetic of solve(), so every solution is
 * bit for bit solve()'s whichever path and whichever neighbours it had.
 */
void solveUpToFour(const Condition* conditions, int count, Solution* solutions, int maxIterations);


} // namespace TorqueCondition
} // namespace MRattlePlugin

#endif
