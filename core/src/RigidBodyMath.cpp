#include "mrattle/RigidBodyMath.h"
#include "mrattle/Coordinates.h"
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

Matrix3d crossMatrix(const Vector3d& w) {
    Matrix3d m;
    m << 0, -w.z(), w.y(),
         w.z(), 0, -w.x(),
         -w.y(), w.x(), 0;
    return m;
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
    if (j == 0) {   // all atoms at the centre: nothing to rotate
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
    return ev(1) <= 1e-12 * ev(2);
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

/** cay(d) - 1 = (1 - [d]/2)^-1 (1 + [d]/2) - 1 = 2 ([w]x + [w]x^2) / (1 + |w|^2), w = d/2. */
Matrix3d cayleyMinusIdentity(const Vector3d& d) {
    Matrix3d W = crossMatrix(0.5 * d);
    return (2.0 / (1.0 + 0.25 * d.squaredNorm())) * (W + W * W);
}

} // namespace

Shape classifyShape(const Matrix3d& secondMoment, double totalMass) {
    if (!(secondMoment.trace() > 1e-20 * totalMass))
        return Shape::Point;
    return isLinearShape(secondMoment) ? Shape::Linear : Shape::General;
}

Matrix3d rotationFromVector(const Vector3d& d) {
    return Matrix3d::Identity() + rotationMinusIdentity(d);
}

RotationSolve solveResetRotation(const Matrix3d& J, const Matrix3d& Y) {
    return solveResetRotationForTorque(J, vexOfSkewPart(Y));
}

RotationSolve solveResetRotationForTorque(const Matrix3d& J, const Vector3d& target) {
    // The rotation of one step is small, so P = 1 + Delta is carried as Delta: the residual
    // vex(P J - J P^T) = vex(Delta J - J Delta^T) (J symmetric) then has round-off relative
    // to the rotation itself, not to J, and the torque condition holds to that precision.
    // Updates are Cayley rotations, orthogonal to round-off without trigonometry; they
    // agree with exp([d]x) to first order, so Newton still converges quadratically.
    RotationSolve result;
    result.iterations = MaxRotationIterations;
    Matrix3d delta = Matrix3d::Zero();
    for (int iteration = 0; iteration < MaxRotationIterations; iteration++) {
        Matrix3d deltaJ = delta * J;
        Vector3d r = vexOfSkewPart(deltaJ) - target;
        if (r.isZero(0.0)) {
            result.iterations = iteration;
            result.converged = true;
            break;
        }
        Matrix3d PJ = J + deltaJ;
        Matrix3d K = PJ.trace() * Matrix3d::Identity() - PJ;
        Vector3d d = -K.inverse() * r;
        if (!d.allFinite())
            break;
        Matrix3d E = cayleyMinusIdentity(d);
        delta += E + E * delta;
        // Quadratic convergence: after a correction of relative size e the error is about
        // e^2, so a correction below 1e-7 of the rotation leaves it at round-off.
        if (d.squaredNorm() <= 1e-14 * delta.squaredNorm()) {
            result.iterations = iteration + 1;
            result.converged = true;
            break;
        }
    }
    result.rotation = Matrix3d::Identity() + delta;
    result.rotationMinusIdentity = delta;
    return result;
}

namespace {

/**
 * The rotation of one body's reset, given each atom's displacement y_i - a_i relative to
 * the centres (small: formed without the absolute positions, so no digits are lost).
 */
template <class Displacement>
RotationSolve solveBodyRotation(const BodyView& body, const double* oldPositions, const Vector3d& oldCenter,
                                Displacement displacement) {
    if (body.linear)
        return solveLinearRotation(body, oldPositions, oldCenter, displacement);
    // Torque target sum m a x y = sum m a x (y - a).
    Matrix3d J = Matrix3d::Zero();
    Vector3d target = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        double m = body.masses[atom];
        Vector3d ma = m * (point(oldPositions, atom) - oldCenter);
        J.noalias() += ma * (point(oldPositions, atom) - oldCenter).transpose();
        target += ma.cross(displacement(atom));
    }
    return solveResetRotationForTorque(J, target);
}

} // namespace

RotationSolve resetBodyPositions(const BodyView& body, const double* oldPositions, double* newPositions) {
    const Vector3d oldCenter = centerOfMass(body, oldPositions);
    const Vector3d newCenter = centerOfMass(body, newPositions);
    RotationSolve solve = solveBodyRotation(body, oldPositions, oldCenter, [&](int atom) -> Vector3d {
        return (point(newPositions, atom) - newCenter) - (point(oldPositions, atom) - oldCenter);
    });
    const Matrix3d& delta = solve.rotationMinusIdentity;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        Vector3d a = point(oldPositions, atom) - oldCenter;
        point(newPositions, atom) = newCenter + (a + delta * a);
    }
    return solve;
}

RotationSolve driftAndResetBody(const BodyView& body, double stepSize, const double* positions, double* velocities,
                                double* newPositions) {
    const Vector3d center = centerOfMass(body, positions);
    Vector3d momentum = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++)
        momentum += body.masses[body.atoms[k]] * point(velocities, body.atoms[k]);
    const Vector3d V = momentum / body.totalMass;
    if (!V.allFinite() || !center.allFinite())
        return RotationSolve();  // not converged: nothing is written
    // The drift moves atom i by h v_i; relative to the centres that is h (v_i - V).
    RotationSolve solve = solveBodyRotation(body, positions, center, [&](int atom) -> Vector3d {
        return stepSize * (point(velocities, atom) - V);
    });
    if (!solve.converged)
        return solve;
    const Matrix3d& delta = solve.rotationMinusIdentity;
    const Vector3d shift = stepSize * V;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        Vector3d turn = delta * (point(positions, atom) - center);
        point(newPositions, atom) = point(positions, atom) + (shift + turn);
        point(velocities, atom) = V + turn / stepSize;
    }
    return solve;
}

namespace {

/** The rigid-body motion nearest (mass-weighted) to a body's velocities: centre, V and w. */
struct RigidMotion {
    Vector3d center, velocity, omega;
};

RigidMotion nearestRigidMotion(const BodyView& body, const double* positions, const double* velocities) {
    Vector3d massPosition = Vector3d::Zero();
    Vector3d momentum = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        double m = body.masses[atom];
        massPosition += m * point(positions, atom);
        momentum += m * point(velocities, atom);
    }
    RigidMotion motion;
    motion.center = massPosition / body.totalMass;
    motion.velocity = momentum / body.totalMass;
    // L about the centre; sum m_i a_i = 0, so using v_i instead of v_i - V is exact.
    Matrix3d J = Matrix3d::Zero();
    Vector3d L = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        double m = body.masses[atom];
        Vector3d a = point(positions, atom) - motion.center;
        J.noalias() += (m * a) * a.transpose();
        L += m * a.cross(point(velocities, atom));
    }
    if (body.linear) {
        // I = j (1 - u u^T): no spin about the axis.
        Vector3d u = linearAxis(body, positions, motion.center);
        double j = J.trace();
        motion.omega = j > 0 ? Vector3d((L - L.dot(u) * u) / j) : Vector3d::Zero();
    } else {
        Matrix3d inertia = J.trace() * Matrix3d::Identity() - J;
        motion.omega = inertia.inverse() * L;
    }
    return motion;
}

} // namespace

void projectBodyVelocities(const BodyView& body, const double* positions, double* velocities) {
    const RigidMotion motion = nearestRigidMotion(body, positions, velocities);
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        point(velocities, atom) = motion.velocity + motion.omega.cross(point(positions, atom) - motion.center);
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
