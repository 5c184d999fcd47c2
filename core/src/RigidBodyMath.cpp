#include "mrattle/RigidBodyMath.h"
#include "mrattle/Coordinates.h"
#include "mrattle/RigidBodyCoordinates.h"
#include "TorqueCondition.h"
#include <algorithm>
#include <cmath>
#include <limits>

using Eigen::Map;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace MRattlePlugin {
namespace RigidBodyMath {

namespace {

Vector3d vexOfSkewPart(const Matrix3d& A) {
    // vex(A - A^T)
    return Vector3d(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
}

/** Unit vector along a linear body: the direction of its atom farthest from the centre. */
Vector3d linearAxis(const BodyView& body, const double* positions, const Vector3d& center) {
    Vector3d farthest = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        Vector3d a = point(positions, body.atoms[k]) - center;
        if (a.squaredNorm() > farthest.squaredNorm())
            farthest = a;
    }
    double length = farthest.norm();
    return length > 0 ? Vector3d(farthest / length) : Vector3d(1, 0, 0);
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

} // namespace

Vector3d centerOfMass(const BodyView& body, const double* positions) {
    Vector3d sum = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++)
        sum += body.masses[body.atoms[k]] * point(positions, body.atoms[k]);
    return sum / body.totalMass;
}

Matrix3d secondMoment(const BodyView& body, const double* positions, const Vector3d& center) {
    Matrix3d J = Matrix3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        Vector3d a = point(positions, body.atoms[k]) - center;
        J.noalias() += body.masses[body.atoms[k]] * a * a.transpose();
    }
    return J;
}

bool isLinearShape(const Matrix3d& secondMoment) {
    Eigen::SelfAdjointEigenSolver<Matrix3d> solver(secondMoment, Eigen::EigenvaluesOnly);
    const Vector3d& ev = solver.eigenvalues();  // ascending
    // Principal moments tr(J) - ev: the smallest is ev(0) + ev(1), the largest ev(1) + ev(2).
    return ev(0) + ev(1) <= LinearMomentRatio * (ev(1) + ev(2));
}

Vector3d axisToStraighten(const Matrix3d& secondMoment, double totalMass) {
    if (classifyShape(secondMoment, totalMass) != Shape::Linear)
        return Vector3d::Zero();
    Eigen::SelfAdjointEigenSolver<Matrix3d> solver(secondMoment);
    const Vector3d& ev = solver.eigenvalues();
    // Within 1e-6 of its size of its axis (a single-precision platform's round-off) already:
    // leave the atoms bit for bit (the linear arithmetic is exact to that).
    if (ev(0) + ev(1) <= 1e-12 * ev(2))
        return Vector3d::Zero();
    return solver.eigenvectors().col(2);
}

namespace {

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

Shape classifyShape(const Matrix3d& secondMoment, double totalMass) {
    if (isPointExtent(secondMoment.trace(), totalMass))
        return Shape::Point;
    return isLinearShape(secondMoment) ? Shape::Linear : Shape::General;
}

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
 * An atom's velocity with a kick applied, as a separate pass would have stored it
 * (v + f * (time / m)); velocities as they are if there are no forces.
 */
class KickedVelocity {
public:
    KickedVelocity(const Kick& kick, const double* velocities) : kick(kick), velocities(velocities) {
    }
    Vector3d operator()(int atom) const {
        const double* v = velocities + 3 * atom;
        if (kick.forces == nullptr)
            return Vector3d(v[0], v[1], v[2]);
        const double* f = kick.forces + 3 * atom;
        const double scale = kick.time * kick.inverseMasses[atom];
        return Vector3d(v[0] + f[0] * scale, v[1] + f[1] * scale, v[2] + f[2] * scale);
    }

private:
    const Kick& kick;
    const double* velocities;
};

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

namespace {

/** The rigid-body motion nearest (mass-weighted) to a body's velocities: centre, V and w. */
struct RigidMotion {
    Vector3d center, velocity, omega;
};

/**
 * The sums of the nearest rigid motion: centre and centre velocity; for a general body J
 * (six entries) and L about the centre, whose I^-1 L is left to the caller; for a linear
 * body the angular velocity itself.
 */
struct MotionSums {
    RigidMotion motion;
    double j[6], L[3];
};

template <class Velocity>
void rigidMotionSums(const BodyView& body, const double* positions, Velocity velocity, MotionSums& sums) {
    // One pass, about the body's first atom (not the origin, so the sums lose no digits to
    // a body far from it): M c' = sum m a, p = sum m v, S = sum m a a^T, l = sum m a x v with
    // a = x - x_first; then J = S - M c' c'^T and L = l - c' x p about the centre.
    const double* origin = positions + 3 * body.atoms[0];
    const double o0 = origin[0], o1 = origin[1], o2 = origin[2];
    double ma0 = 0, ma1 = 0, ma2 = 0, p0 = 0, p1 = 0, p2 = 0, l0 = 0, l1 = 0, l2 = 0;
    double s00 = 0, s01 = 0, s02 = 0, s11 = 0, s12 = 0, s22 = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double m = body.masses[atom];
        const double* x = positions + 3 * atom;
        const Vector3d v = velocity(atom);
        const double a0 = x[0] - o0, a1 = x[1] - o1, a2 = x[2] - o2;
        const double b0 = m * a0, b1 = m * a1, b2 = m * a2;
        ma0 += b0; ma1 += b1; ma2 += b2;
        p0 += m * v[0]; p1 += m * v[1]; p2 += m * v[2];
        s00 += b0 * a0; s01 += b0 * a1; s02 += b0 * a2;
        s11 += b1 * a1; s12 += b1 * a2; s22 += b2 * a2;
        l0 += b1 * v[2] - b2 * v[1];
        l1 += b2 * v[0] - b0 * v[2];
        l2 += b0 * v[1] - b1 * v[0];
    }
    const double inverseMass = 1.0 / body.totalMass;
    const double c0 = ma0 * inverseMass, c1 = ma1 * inverseMass, c2 = ma2 * inverseMass;
    RigidMotion& motion = sums.motion;
    motion.center = Vector3d(o0 + c0, o1 + c1, o2 + c2);
    motion.velocity = Vector3d(p0 * inverseMass, p1 * inverseMass, p2 * inverseMass);
    const double j00 = s00 - ma0 * c0, j01 = s01 - ma0 * c1, j02 = s02 - ma0 * c2;
    const double j11 = s11 - ma1 * c1, j12 = s12 - ma1 * c2, j22 = s22 - ma2 * c2;
    const Vector3d L(l0 - (c1 * p2 - c2 * p1), l1 - (c2 * p0 - c0 * p2), l2 - (c0 * p1 - c1 * p0));
    if (body.linear) {
        // I = j (1 - u u^T): no spin about the axis.
        const double traceJ = j00 + j11 + j22;
        Vector3d u = linearAxis(body, positions, motion.center);
        motion.omega = isPointExtent(traceJ, body.totalMass) ? Vector3d::Zero()  // a point does not rotate
                                                             : Vector3d((L - L.dot(u) * u) / traceJ);
        return;
    }
    sums.j[0] = j00; sums.j[1] = j01; sums.j[2] = j02; sums.j[3] = j11; sums.j[4] = j12; sums.j[5] = j22;
    sums.L[0] = L[0]; sums.L[1] = L[1]; sums.L[2] = L[2];
}

template <class Velocity>
RigidMotion nearestRigidMotionWith(const BodyView& body, const double* positions, Velocity velocity) {
    MotionSums sums;
    rigidMotionSums(body, positions, velocity, sums);
    if (!body.linear)
        TorqueCondition::solveInertia(sums.j, sums.L, sums.motion.omega.data());
    return sums.motion;
}

RigidMotion nearestRigidMotion(const BodyView& body, const double* positions, const double* velocities) {
    return nearestRigidMotionWith(body, positions, [&](int atom) -> Vector3d { return point(velocities, atom); });
}

/** Replace the body's atom velocities by the rigid motion's. */
void setRigidVelocities(const BodyView& body, const RigidMotion& motion, const double* positions, double* velocities) {
    const double c0 = motion.center[0], c1 = motion.center[1], c2 = motion.center[2];
    const double u0 = motion.velocity[0], u1 = motion.velocity[1], u2 = motion.velocity[2];
    const double w0 = motion.omega[0], w1 = motion.omega[1], w2 = motion.omega[2];
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double* x = positions + 3 * atom;
        double* v = velocities + 3 * atom;
        const double a0 = x[0] - c0, a1 = x[1] - c1, a2 = x[2] - c2;
        v[0] = u0 + (w1 * a2 - w2 * a1);
        v[1] = u1 + (w2 * a0 - w0 * a2);
        v[2] = u2 + (w0 * a1 - w1 * a0);
    }
}

} // namespace

void projectBodyVelocities(const BodyView& body, const double* positions, double* velocities) {
    setRigidVelocities(body, nearestRigidMotion(body, positions, velocities), positions, velocities);
}

void kickAndProjectBodyVelocities(const BodyView& body, const Kick& kick, const double* positions, double* velocities) {
    const RigidMotion motion = nearestRigidMotionWith(body, positions, KickedVelocity(kick, velocities));
    setRigidVelocities(body, motion, positions, velocities);
}

void kickAndProjectBodiesVelocities(const BodyView* bodies, int count, const Kick& kick, const double* positions,
                                    double* velocities) {
    const KickedVelocity velocity(kick, velocities);
    MotionSums sums[4];
    double j[24], L[12], omega[12];
    for (int first = 0; first < count; first += 4) {
        const int n = std::min(4, count - first);
        int general[4], numGeneral = 0;
        for (int i = 0; i < n; i++) {
            rigidMotionSums(bodies[first + i], positions, velocity, sums[i]);
            if (!bodies[first + i].linear) {
                std::copy(sums[i].j, sums[i].j + 6, j + 6 * numGeneral);
                std::copy(sums[i].L, sums[i].L + 3, L + 3 * numGeneral);
                general[numGeneral++] = i;
            }
        }
        TorqueCondition::solveInertiaUpToFour(j, L, omega, numGeneral);
        for (int g = 0; g < numGeneral; g++)
            sums[general[g]].motion.omega = Vector3d(omega[3 * g], omega[3 * g + 1], omega[3 * g + 2]);
        for (int i = 0; i < n; i++)
            setRigidVelocities(bodies[first + i], sums[i].motion, positions, velocities);
    }
}

double nonRigidVelocityFraction(const BodyView& body, const double* positions, const double* velocities) {
    const RigidMotion motion = nearestRigidMotion(body, positions, velocities);
    double scale = 0, residual = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        Vector3d rigid = motion.velocity + motion.omega.cross(point(positions, atom) - motion.center);
        scale = std::max(scale, rigid.norm());
        residual = std::max(residual, (point(velocities, atom) - rigid).norm());
    }
    if (residual == 0)
        return 0;
    return scale > 0 ? residual / scale : std::numeric_limits<double>::infinity();
}

bool projectNonRigidBodyVelocities(const BodyView& body, const double* positions, double* velocities,
                                   double relativeTolerance) {
    if (!(nonRigidVelocityFraction(body, positions, velocities) > relativeTolerance))
        return false;
    projectBodyVelocities(body, positions, velocities);
    return true;
}

} // namespace RigidBodyMath
} // namespace MRattlePlugin
