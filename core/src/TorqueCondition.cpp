#include "TorqueCondition.h"
#include "mrattle/RigidBodyMath.h"
#include <cmath>

namespace MRattlePlugin {
namespace TorqueCondition {

namespace {

/*
 * The solve is written once, over "lanes": a double (one body) or a GCC vector of four
 * doubles (four bodies). Every operation is lane by lane and in the same order, and the
 * core is built without floating-point contraction, so a lane's result does not depend on
 * the width or on its neighbours. Per-lane decisions (a new Jacobian, convergence) are
 * masks; a lane that has converged or failed is frozen while the others go on.
 */
struct ScalarLanes {
    typedef double Real;
    typedef bool Mask;
    static MRATTLE_INLINE Real select(Mask m, Real a, Real b) { return m ? a : b; }
    static MRATTLE_INLINE Real squareRoot(Real x) { return std::sqrt(x); }
    static MRATTLE_INLINE bool any(Mask m) { return m; }
    static MRATTLE_INLINE Mask finite(Real x) { return x - x == 0; }  // false for inf and NaN
    static MRATTLE_INLINE Mask all() { return true; }
    static MRATTLE_INLINE Mask none() { return false; }
    static MRATTLE_INLINE Mask andNot(Mask a, Mask b) { return a && !b; }
    static MRATTLE_INLINE Mask negate(Mask a) { return !a; }
};

// GCC on x86-64 (its vector extensions, including ?: on vectors, and __builtin_cpu_supports).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MRATTLE_HAVE_AVX2_LANES 1
typedef double Double4 __attribute__((vector_size(32)));
typedef long long Mask4 __attribute__((vector_size(32)));

struct Avx2Lanes {
    typedef Double4 Real;
    typedef Mask4 Mask;
    static MRATTLE_INLINE Real select(Mask m, Real a, Real b) { return m ? a : b; }
    static MRATTLE_INLINE Real squareRoot(Real x) {
        return Real{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
    }
    static MRATTLE_INLINE bool any(Mask m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }
    static MRATTLE_INLINE Mask finite(Real x) { return x - x == 0; }
    static MRATTLE_INLINE Mask all() { return Mask{-1, -1, -1, -1}; }
    static MRATTLE_INLINE Mask none() { return Mask{0, 0, 0, 0}; }
    static MRATTLE_INLINE Mask andNot(Mask a, Mask b) { return a & ~b; }
    static MRATTLE_INLINE Mask negate(Mask a) { return ~a; }
};
#endif

/**
 * P is parametrised by its half Gibbs vector w (tan of half the angle along the axis):
 * P - 1 = c ([w]x + [w]x^2), c = 2 / (1 + |w|^2), orthogonal to round-off for any w and
 * formed without the identity, so a small rotation keeps its digits. With I = tr(J) - J,
 * vex(D J - J D^T) = c (I w + (J w) x w) for D = P - 1, and the condition times 1/c is the
 * quadratic F(w) = I w + (J w) x w - (1 + |w|^2) target / 2 = 0: Newton from the linearised
 * answer, then chord steps (the Jacobian kept) once the correction is below 1e-3 of w, whose
 * error shrinks by about the previous correction's relative size. Closed-form 3x3 inverses.
 * iterations: per lane, as a Real (exact for small integers). Masks combine with & and |
 * (bitwise on vector lanes, on bools as 0/1), negations only through L.
 */
template <class L>
MRATTLE_INLINE void solveLanes(const typename L::Real* j, const typename L::Real* target, typename L::Real* w,
                               typename L::Real& iterations, typename L::Mask& converged, int maxIterations) {
    typedef typename L::Real Real;
    typedef typename L::Mask Mask;
    const Real j00 = j[0], j01 = j[1], j02 = j[2], j11 = j[3], j12 = j[4], j22 = j[5];
    const Real traceJ = j00 + j11 + j22;
    const Real i00 = traceJ - j00, i11 = traceJ - j11, i22 = traceJ - j22;   // I = tr(J) - J
    const Real t0 = 0.5 * target[0], t1 = 0.5 * target[1], t2 = 0.5 * target[2];
    // At w = 0 the Jacobian is the inertia: the first iterate is the linearised answer I^-1 t.
    Real w0, w1, w2;
    inertiaSolve(j, t0, t1, t2, w0, w1, w2);
    Real g0 = Real{}, g1 = g0, g2 = g0, g3 = g0, g4 = g0, g5 = g0, g6 = g0, g7 = g0, g8 = g0;  // G^-1, row-major
    Mask active = L::all(), newJacobian = L::all();
    converged = L::none();
    iterations = Real{} + maxIterations;
    Real previousStep = L::squareRoot(w0 * w0 + w1 * w1 + w2 * w2);
    for (int iteration = 1; iteration < maxIterations && L::any(active); iteration++) {
        const Real jw0 = j00 * w0 + j01 * w1 + j02 * w2;
        const Real jw1 = j01 * w0 + j11 * w1 + j12 * w2;
        const Real jw2 = j02 * w0 + j12 * w1 + j22 * w2;
        const Real scale = 1.0 + w0 * w0 + w1 * w1 + w2 * w2;
        // F = I w + (J w) x w - (1 + |w|^2) target / 2, with I w = tr(J) w - J w.
        const Real f0 = traceJ * w0 - jw0 + (jw1 * w2 - jw2 * w1) - scale * t0;
        const Real f1 = traceJ * w1 - jw1 + (jw2 * w0 - jw0 * w2) - scale * t1;
        const Real f2 = traceJ * w2 - jw2 + (jw0 * w1 - jw1 * w0) - scale * t2;
        const Mask refresh = newJacobian & active;
        if (L::any(refresh)) {
            // G = dF/dw = I - [w]x J + [J w]x - 2 t w^T (t = target / 2); ([w]x J)(r,c) = (w x J_c)_r.
            const Real a00 = i00 - (w1 * j02 - w2 * j01) - 2 * t0 * w0;
            const Real a01 = -j01 - (w1 * j12 - w2 * j11) - jw2 - 2 * t0 * w1;
            const Real a02 = -j02 - (w1 * j22 - w2 * j12) + jw1 - 2 * t0 * w2;
            const Real a10 = -j01 - (w2 * j00 - w0 * j02) + jw2 - 2 * t1 * w0;
            const Real a11 = i11 - (w2 * j01 - w0 * j12) - 2 * t1 * w1;
            const Real a12 = -j12 - (w2 * j02 - w0 * j22) - jw0 - 2 * t1 * w2;
            const Real a20 = -j02 - (w0 * j01 - w1 * j00) - jw1 - 2 * t2 * w0;
            const Real a21 = -j12 - (w0 * j11 - w1 * j01) + jw0 - 2 * t2 * w1;
            const Real a22 = i22 - (w0 * j12 - w1 * j02) - 2 * t2 * w2;
            const Real b00 = a11 * a22 - a12 * a21, b01 = a02 * a21 - a01 * a22, b02 = a01 * a12 - a02 * a11;
            const Real b10 = a12 * a20 - a10 * a22, b11 = a00 * a22 - a02 * a20, b12 = a02 * a10 - a00 * a12;
            const Real b20 = a10 * a21 - a11 * a20, b21 = a01 * a20 - a00 * a21, b22 = a00 * a11 - a01 * a10;
            const Real inverseDet = 1.0 / (a00 * b00 + a01 * b10 + a02 * b20);
            g0 = L::select(refresh, b00 * inverseDet, g0);
            g1 = L::select(refresh, b01 * inverseDet, g1);
            g2 = L::select(refresh, b02 * inverseDet, g2);
            g3 = L::select(refresh, b10 * inverseDet, g3);
            g4 = L::select(refresh, b11 * inverseDet, g4);
            g5 = L::select(refresh, b12 * inverseDet, g5);
            g6 = L::select(refresh, b20 * inverseDet, g6);
            g7 = L::select(refresh, b21 * inverseDet, g7);
            g8 = L::select(refresh, b22 * inverseDet, g8);
        }
        const Real s0 = g0 * f0 + g1 * f1 + g2 * f2;
        const Real s1 = g3 * f0 + g4 * f1 + g5 * f2;
        const Real s2 = g6 * f0 + g7 * f1 + g8 * f2;
        w0 = L::select(active, w0 - s0, w0);
        w1 = L::select(active, w1 - s1, w1);
        w2 = L::select(active, w2 - s2, w2);
        const Real stepSize = L::squareRoot(s0 * s0 + s1 * s1 + s2 * s2);
        const Real size = L::squareRoot(w0 * w0 + w1 * w1 + w2 * w2);
        active = active & L::finite(size);   // a lane whose w is not finite has failed
        // The error left is about the step times the rate at which steps shrink.
        const Mask done = active & (stepSize * stepSize <= RigidBodyMath::ChordConvergence * size * previousStep);
        converged = converged | done;
        iterations = L::select(done, Real{} + (iteration + 1), iterations);
        active = L::andNot(active, done);
        newJacobian = L::negate(stepSize <= RigidBodyMath::ChordSwitch * size);
        previousStep = L::select(active, stepSize, previousStep);
    }
    w[0] = w0;
    w[1] = w1;
    w[2] = w2;
}

#ifdef MRATTLE_HAVE_AVX2_LANES
__attribute__((target("avx2"))) void solveInertiaFourLanes(const double* j, const double* b, double* x, int count) {
    Double4 jLanes[6], bLanes[3], xLanes[3];
    for (int lane = 0; lane < 4; lane++) {
        const int from = lane < count ? lane : 0;   // spare lanes repeat the first
        for (int k = 0; k < 6; k++)
            jLanes[k][lane] = j[6 * from + k];
        for (int k = 0; k < 3; k++)
            bLanes[k][lane] = b[3 * from + k];
    }
    inertiaSolve(jLanes, bLanes[0], bLanes[1], bLanes[2], xLanes[0], xLanes[1], xLanes[2]);
    for (int lane = 0; lane < count; lane++)
        for (int k = 0; k < 3; k++)
            x[3 * lane + k] = xLanes[k][lane];
}

__attribute__((target("avx2"))) void solveFourLanes(const Condition* conditions, int count, Solution* solutions,
                                                     int maxIterations) {
    Double4 j[6], target[3], w[3], iterations;
    Mask4 converged;
    for (int lane = 0; lane < 4; lane++) {
        const Condition& c = conditions[lane < count ? lane : 0];   // spare lanes repeat the first
        j[0][lane] = c.j00; j[1][lane] = c.j01; j[2][lane] = c.j02;
        j[3][lane] = c.j11; j[4][lane] = c.j12; j[5][lane] = c.j22;
        target[0][lane] = c.t0; target[1][lane] = c.t1; target[2][lane] = c.t2;
    }
    solveLanes<Avx2Lanes>(j, target, w, iterations, converged, maxIterations);
    for (int lane = 0; lane < count; lane++) {
        solutions[lane].w0 = w[0][lane];
        solutions[lane].w1 = w[1][lane];
        solutions[lane].w2 = w[2][lane];
        solutions[lane].iterations = (int) iterations[lane];
        solutions[lane].converged = converged[lane] != 0;
    }
}
#endif

/** Whether the four-lane functions run (AVX2 on this CPU), checked once. */
bool usesSimdLanes() {
#ifdef MRATTLE_HAVE_AVX2_LANES
    static const bool avx2 = __builtin_cpu_supports("avx2");
    return avx2;
#else
    return false;
#endif
}

} // namespace

Solution solve(const Condition& c, int maxIterations) {
    const double j[6] = {c.j00, c.j01, c.j02, c.j11, c.j12, c.j22}, target[3] = {c.t0, c.t1, c.t2};
    double w[3], iterations;
    bool converged;
    solveLanes<ScalarLanes>(j, target, w, iterations, converged, maxIterations);
    Solution solution;
    solution.w0 = w[0];
    solution.w1 = w[1];
    solution.w2 = w[2];
    solution.iterations = (int) iterations;
    solution.converged = converged;
    return solution;
}

void solveInertiaUpToFour(const double* j, const double* b, double* x, int count) {
#ifdef MRATTLE_HAVE_AVX2_LANES
    if (count > 1 && usesSimdLanes()) {
        solveInertiaFourLanes(j, b, x, count);
        return;
    }
#endif
    for (int i = 0; i < count; i++)
        solveInertia(j + 6 * i, b + 3 * i, x + 3 * i);
}

void solveUpToFour(const Condition* conditions, int count, Solution* solutions, int maxIterations) {
#ifdef MRATTLE_HAVE_AVX2_LANES
    // One body alone is cheaper in scalar code (the lanes cost the same as four bodies).
    if (count > 1 && usesSimdLanes()) {
        solveFourLanes(conditions, count, solutions, maxIterations);
        return;
    }
#endif
    for (int i = 0; i < count; i++)
        solutions[i] = solve(conditions[i], maxIterations);
}

} // namespace TorqueCondition
} // namespace MRattlePlugin
