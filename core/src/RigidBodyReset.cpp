// Drift and reset: a body's rotation solve and M-RATTLE's position reset, one body or four at a time.
#include "mrattle/RigidBodyMath.h"
#include "mrattle/Coordinates.h"
#include "mrattle/RigidBodyCoordinates.h"
#include "RigidBodyMathDetail.h"
#include "TorqueCondition.h"
#include <algorithm>
#include <cmath>

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace MRattlePlugin {
namespace RigidBodyMath {

namespace {

Vector3d vexOfSkewPart(const Matrix3d& A) {
    // vex(A - A^T)
    return Vector3d(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
}


/**
 * Linear body: the condition u x (j p - w) = 0 (u the old axis, p = P u the new one,
 * w = sum m_i s_i y_i, j = sum m_i s_i^2) has the closed form p = (w + lambda u) / j
 * with |p| = 1; spin about the axis is no degree of freedom, so P is the smallest
 * rotation taking u to p. displacement(atom) is y_i - a_i (positions about the centres).
 */
template <class Displacement>
RotationSolve solveLinearRotation(const BodyView& body, const double* oldPositions, const Vector3d& oldCenter,
                                  Displacement displacement) {
    RotationSolve result;
    Vector3d u = linearAxis(body, oldPositions, oldCenter);
    Vector3d w = Vector3d::Zero();
    double j = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        double m = body.masses[atom];
        Vector3d a = point(oldPositions, atom) - oldCenter;
        double s = a.dot(u);
        w += (m * s) * (a + displacement(atom));
        j += m * s * s;
    }
    result.iterations = 1;
    if (isPointExtent(j, body.totalMass)) {   // a point: nothing to rotate
        result.converged = true;
        return result;
    }
    double uw = u.dot(w);
    double discriminant = uw * uw - w.squaredNorm() + j * j;
    if (!(discriminant >= 0) || !std::isfinite(discriminant))
        return result;  // no rotation satisfies the condition (step far too large), or not finite
    Vector3d p = (w + (-uw + std::sqrt(discriminant)) * u) / j;
    p.normalize();
    double c = u.dot(p);
    if (c <= -1.0 + 1e-12)
        return result;
    // The smallest rotation taking u to p, less the identity: K + K^2/(1+c), K = [u x p].
    Matrix3d K = crossMatrix(u.cross(p));
    result.rotationMinusIdentity = K + K * K / (1.0 + c);
    result.rotation = Matrix3d::Identity() + result.rotationMinusIdentity;
    result.converged = true;
    return result;
}

/** exp([d]x) - 1, kept apart from the identity so that small rotations lose no digits. */
Matrix3d rotationMinusIdentity(const Vector3d& d) {
    double theta2 = d.squaredNorm();
    Matrix3d D = crossMatrix(d);
    double a, b;  // sin(t)/t and (1-cos(t))/t^2
    if (theta2 < 1e-8) {
        a = 1.0 - theta2 / 6.0 + theta2 * theta2 / 120.0;
        b = 0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0;
    } else {
        double theta = std::sqrt(theta2);
        a = std::sin(theta) / theta;
        b = (1.0 - std::cos(theta)) / theta2;
    }
    return a * D + b * D * D;
}

} // namespace

Matrix3d rotationFromVector(const Vector3d& d) {
    return Matrix3d::Identity() + rotationMinusIdentity(d);
}

RotationSolve solveResetRotation(const Matrix3d& J, const Matrix3d& Y) {
    return solveResetRotationForTorque(J, vexOfSkewPart(Y));
}

namespace {

/** P - 1 from the solve's Cayley vector w: c ([w]x + w w^T - |w|^2), c = 2 / (1 + |w|^2). */
void setRotationMinusIdentity(const TorqueCondition::Solution& solution, Matrix3d& D) {
    const double w0 = solution.w0, w1 = solution.w1, w2 = solution.w2;
    const double w2sum = w0 * w0 + w1 * w1 + w2 * w2, c = 2.0 / (1.0 + w2sum);
    D(0, 0) = c * (w0 * w0 - w2sum);
    D(1, 1) = c * (w1 * w1 - w2sum);
    D(2, 2) = c * (w2 * w2 - w2sum);
    D(0, 1) = c * (w0 * w1 - w2);
    D(1, 0) = c * (w0 * w1 + w2);
    D(0, 2) = c * (w0 * w2 + w1);
    D(2, 0) = c * (w0 * w2 - w1);
    D(1, 2) = c * (w1 * w2 - w0);
    D(2, 1) = c * (w1 * w2 + w0);
}

RotationSolve rotationSolveOf(const TorqueCondition::Solution& solution) {
    RotationSolve result;
    result.iterations = solution.iterations;
    result.converged = solution.converged;
    if (!solution.converged)
        return result;
    setRotationMinusIdentity(solution, result.rotationMinusIdentity);
    result.rotation = result.rotationMinusIdentity;
    result.rotation.diagonal().array() += 1.0;
    return result;
}

} // namespace

RotationSolve solveResetRotationForTorque(const Matrix3d& J, const Vector3d& target) {
    const TorqueCondition::Condition condition{J(0, 0), J(0, 1), J(0, 2), J(1, 1), J(1, 2), J(2, 2),
                                              target[0], target[1], target[2]};
    return rotationSolveOf(TorqueCondition::solve(condition, MaxRotationIterations));
}

namespace {

/**
 * One body's torque condition: J about the old centre and the target sum m a x (y - a),
 * from each atom's displacement y_i - a_i relative to the centres.
 */
template <class Displacement>
TorqueCondition::Condition torqueConditionOf(const BodyView& body, const double* oldPositions,
                                             const Vector3d& oldCenter, Displacement displacement) {
    // Torque target sum m a x y = sum m a x (y - a). Scalar sums of J's six entries: Eigen's
    // 3x3 outer products cost several times more here.
    const double o0 = oldCenter[0], o1 = oldCenter[1], o2 = oldCenter[2];
    double j00 = 0, j01 = 0, j02 = 0, j11 = 0, j12 = 0, j22 = 0, t0 = 0, t1 = 0, t2 = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double m = body.masses[atom];
        const double* x = oldPositions + 3 * atom;
        const double a0 = x[0] - o0, a1 = x[1] - o1, a2 = x[2] - o2;
        const double b0 = m * a0, b1 = m * a1, b2 = m * a2;
        j00 += b0 * a0; j01 += b0 * a1; j02 += b0 * a2;
        j11 += b1 * a1; j12 += b1 * a2; j22 += b2 * a2;
        const Vector3d d = displacement(atom);
        t0 += b1 * d[2] - b2 * d[1];
        t1 += b2 * d[0] - b0 * d[2];
        t2 += b0 * d[1] - b1 * d[0];
    }
    return TorqueCondition::Condition{j00, j01, j02, j11, j12, j22, t0, t1, t2};
}

/**
 * The rotation of one body's reset, given each atom's displacement y_i - a_i relative to
 * the centres (small: formed without the absolute positions, so no digits are lost).
 */
template <class Displacement>
RotationSolve solveBodyRotation(const BodyView& body, const double* oldPositions, const Vector3d& oldCenter,
                                Displacement displacement) {
    if (body.linear)
        return solveLinearRotation(body, oldPositions, oldCenter, displacement);
    return rotationSolveOf(TorqueCondition::solve(torqueConditionOf(body, oldPositions, oldCenter, displacement),
                                                  MaxRotationIterations));
}

} // namespace

RotationSolve resetBodyPositions(const BodyView& body, const double* oldPositions, double* newPositions) {
    const Vector3d oldCenter = centerOfMass(body, oldPositions);
    const Vector3d newCenter = centerOfMass(body, newPositions);
    RotationSolve solve = solveBodyRotation(body, oldPositions, oldCenter, [&](int atom) -> Vector3d {
        return (point(newPositions, atom) - newCenter) - (point(oldPositions, atom) - oldCenter);
    });
    if (!solve.converged)
        return solve;
    const Matrix3d& delta = solve.rotationMinusIdentity;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        Vector3d a = point(oldPositions, atom) - oldCenter;
        point(newPositions, atom) = newCenter + (a + delta * a);
    }
    return solve;
}

namespace {

/**
 * A body's reset after its first passes: the centre and its velocity, then either the turn
 * P - 1 (a linear body, solved in closed form) or the torque condition still to solve.
 */
struct ResetSetup {
    Vector3d center, V;
    bool finite = false, converged = false;
    TorqueCondition::Condition condition;
    Matrix3d rotationMinusIdentity;
    int iterations = 0;
};

/** The passes before the solve, with each atom's velocity from velocity(atom). */
template <class Velocity>
void setUpReset(const BodyView& body, double stepSize, const double* positions, Velocity velocity, ResetSetup& setup) {
    // Centre and centre-of-mass velocity in one pass (the same sums as centerOfMass's).
    Vector3d massPosition = Vector3d::Zero(), momentum = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        const double m = body.masses[body.atoms[k]];
        massPosition += m * point(positions, body.atoms[k]);
        momentum += m * velocity(body.atoms[k]);
    }
    setup.center = massPosition / body.totalMass;
    setup.V = momentum / body.totalMass;
    setup.finite = setup.V.allFinite() && setup.center.allFinite();
    setup.converged = false;
    if (!setup.finite)
        return;  // not converged: nothing will be written
    // The drift moves atom i by h v_i; relative to the centres that is h (v_i - V).
    const Vector3d V = setup.V;
    auto displacement = [&](int atom) -> Vector3d { return stepSize * (velocity(atom) - V); };
    if (body.linear) {
        const RotationSolve solve = solveLinearRotation(body, positions, setup.center, displacement);
        setup.converged = solve.converged;
        setup.iterations = solve.iterations;
        setup.rotationMinusIdentity = solve.rotationMinusIdentity;
    }
    else
        setup.condition = torqueConditionOf(body, positions, setup.center, displacement);
}

/** Take a general body's solved condition. */
void takeSolution(const TorqueCondition::Solution& solution, ResetSetup& setup) {
    setup.converged = solution.converged;
    setup.iterations = solution.iterations;
    if (solution.converged)
        setRotationMinusIdentity(solution, setup.rotationMinusIdentity);
}

/** The last pass: new positions x + h V + (P - 1) a and velocities V + (P - 1) a / h. */
void applyReset(const BodyView& body, const ResetSetup& setup, double stepSize, const double* positions,
                double* newPositions, double* newVelocities) {
    const Matrix3d& D = setup.rotationMinusIdentity;
    const Vector3d& V = setup.V;
    const double c0 = setup.center[0], c1 = setup.center[1], c2 = setup.center[2];
    const double s0 = stepSize * V[0], s1 = stepSize * V[1], s2 = stepSize * V[2];
    const double inverseStep = 1.0 / stepSize;
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double* x = positions + 3 * atom;
        const double a0 = x[0] - c0, a1 = x[1] - c1, a2 = x[2] - c2;
        const double r0 = D(0, 0) * a0 + D(0, 1) * a1 + D(0, 2) * a2;   // the turn (P - 1) a
        const double r1 = D(1, 0) * a0 + D(1, 1) * a1 + D(1, 2) * a2;
        const double r2 = D(2, 0) * a0 + D(2, 1) * a1 + D(2, 2) * a2;
        double* y = newPositions + 3 * atom;
        y[0] = x[0] + (s0 + r0);
        y[1] = x[1] + (s1 + r1);
        y[2] = x[2] + (s2 + r2);
        double* v = newVelocities + 3 * atom;
        v[0] = V[0] + r0 * inverseStep;
        v[1] = V[1] + r1 * inverseStep;
        v[2] = V[2] + r2 * inverseStep;
    }
}

/** driftAndResetBody with each atom's velocity from velocity(atom); writes newVelocities. */
template <class Velocity>
RotationSolve driftAndResetWith(const BodyView& body, double stepSize, const double* positions, Velocity velocity,
                                double* newPositions, double* newVelocities) {
    ResetSetup setup;
    setUpReset(body, stepSize, positions, velocity, setup);
    if (!setup.finite)
        return RotationSolve();
    if (!body.linear)
        takeSolution(TorqueCondition::solve(setup.condition, MaxRotationIterations), setup);
    RotationSolve result;
    result.converged = setup.converged;
    result.iterations = setup.iterations;
    if (!setup.converged)
        return result;
    applyReset(body, setup, stepSize, positions, newPositions, newVelocities);
    result.rotationMinusIdentity = setup.rotationMinusIdentity;
    result.rotation = setup.rotationMinusIdentity;
    result.rotation.diagonal().array() += 1.0;
    return result;
}

/**
 * The same for several bodies, four at a time: their first passes, the rotation solves of
 * the general ones together (TorqueCondition::solveUpToFour), their last passes. Returns
 * the index of the first body whose reset failed, or count.
 */
template <class Velocity>
int driftAndResetBodiesWith(const BodyView* bodies, int count, double stepSize, const double* positions,
                            Velocity velocity, double* newPositions, double* newVelocities) {
    ResetSetup setups[4];
    TorqueCondition::Condition conditions[4];
    TorqueCondition::Solution solutions[4];
    for (int first = 0; first < count; first += 4) {
        const int n = std::min(4, count - first);
        int general[4], numGeneral = 0;
        for (int i = 0; i < n; i++) {
            setUpReset(bodies[first + i], stepSize, positions, velocity, setups[i]);
            if (setups[i].finite && !bodies[first + i].linear) {
                conditions[numGeneral] = setups[i].condition;
                general[numGeneral++] = i;
            }
        }
        TorqueCondition::solveUpToFour(conditions, numGeneral, solutions, MaxRotationIterations);
        for (int g = 0; g < numGeneral; g++)
            takeSolution(solutions[g], setups[general[g]]);
        for (int i = 0; i < n; i++) {
            if (!setups[i].converged)
                return first + i;
            applyReset(bodies[first + i], setups[i], stepSize, positions, newPositions, newVelocities);
        }
    }
    return count;
}

} // namespace

RotationSolve driftAndResetBody(const BodyView& body, double stepSize, const double* positions, double* velocities,
                                double* newPositions) {
    // In place: the last pass, which writes velocities, no longer reads them.
    return driftAndResetWith(body, stepSize, positions, [&](int atom) -> Vector3d { return point(velocities, atom); },
                             newPositions, velocities);
}

RotationSolve kickDriftAndResetBody(const BodyView& body, const Kick& kick, double stepSize, const double* positions,
                                    const double* velocities, double* newPositions, double* newVelocities) {
    return driftAndResetWith(body, stepSize, positions, KickedVelocity(kick, velocities), newPositions, newVelocities);
}

int kickDriftAndResetBodies(const BodyView* bodies, int count, const Kick& kick, double stepSize,
                            const double* positions, const double* velocities, double* newPositions,
                            double* newVelocities) {
    return driftAndResetBodiesWith(bodies, count, stepSize, positions, KickedVelocity(kick, velocities), newPositions,
                                   newVelocities);
}


} // namespace RigidBodyMath
} // namespace MRattlePlugin
