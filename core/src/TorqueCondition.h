#ifndef MRATTLE_TORQUE_CONDITION_H_
#define MRATTLE_TORQUE_CONDITION_H_

/*
 * The rotation solve of M-RATTLE's position reset, for one body or four at once in the lanes
 * of SIMD registers. Internal to the core; plain doubles, no Eigen (the four-lane code is
 * compiled for AVX2 and must not instantiate shared inline code).
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

/**
 * x = I^-1 b for the inertia I = tr(J) - J of a second moment j (j00, j01, j02, j11, j12,
 * j22): the solve's first iterate, and the velocity projection's angular velocity.
 */
void solveInertia(const double* j, const double* b, double* x);

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

/** Whether solveUpToFour uses AVX2 lanes on this CPU. */
bool usesSimdLanes();

} // namespace TorqueCondition
} // namespace MRattlePlugin

#endif
