#include "mrattle/RigidBodyRotor.h"
#include "mrattle/Coordinates.h"
#include <cmath>

using Eigen::Map;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace MRattlePlugin {
namespace RigidBodyRotor {

PrincipalFrame principalFrame(const Matrix3d& secondMoment) {
    // Eigenvalues of J ascend, so the inertia moments tr(J) - lambda descend: reverse.
    Eigen::SelfAdjointEigenSolver<Matrix3d> solver(secondMoment);
    const double trace = secondMoment.trace();
    PrincipalFrame frame;
    for (int k = 0; k < 3; k++) {
        frame.axes.col(k) = solver.eigenvectors().col(2 - k);
        frame.moments(k) = trace - solver.eigenvalues()(2 - k);
    }
    // Angular momentum is an axial vector: the body frame must be right-handed.
    if (frame.axes.determinant() < 0)
        frame.axes.col(2) = -frame.axes.col(2);
    return frame;
}

PrincipalFrame principalFrame(const Matrix3d& secondMoment, const RigidBodyMath::BodyView& body, const double* positions,
                              const Vector3d& center) {
    PrincipalFrame frame = principalFrame(secondMoment);
    // Equal moments leave the eigensolver free to pick any basis of their plane (it follows
    // round-off), which makes the splitting irreversible. Take the basis from the body's own
    // atoms instead: it then turns with the body, and a step back undoes a step forward.
    const double scale = frame.moments.cwiseAbs().maxCoeff();
    const double degenerate = 1e-10 * scale;
    auto atomDirection = [&](const Vector3d& normal) -> Vector3d {
        // The unit direction of the first atom (in body order) with a component off the unit
        // `normal` (any component if normal is zero), that component only; zero if none has.
        for (int k = 0; k < body.numAtoms; k++) {
            Vector3d a = point(positions, body.atoms[k]) - center;
            if (normal.squaredNorm() > 0)
                a -= a.dot(normal) * normal;
            if (a.norm() > 1e-6 * std::sqrt(scale / body.totalMass))
                return a.normalized();
        }
        return Vector3d::Zero();
    };
    if (scale <= 0 || body.linear)
        return frame;
    const bool equal01 = std::fabs(frame.moments(0) - frame.moments(1)) <= degenerate;
    const bool equal12 = std::fabs(frame.moments(1) - frame.moments(2)) <= degenerate;
    if (equal01 && equal12) {  // a spherical top: two atoms' directions
        const Vector3d e0 = atomDirection(Vector3d::Zero());
        const Vector3d e1 = atomDirection(e0);   // orthogonal to e0, so e0 x e1 is a unit vector
        if (e0.squaredNorm() > 0 && e1.squaredNorm() > 0) {
            frame.axes.col(0) = e0;
            frame.axes.col(1) = e1;
            frame.axes.col(2) = e0.cross(e1);
        }
    }
    else if (equal01 || equal12) {  // a symmetric top: the unique axis, and an atom in the plane
        const int unique = equal01 ? 2 : 0, first = equal01 ? 0 : 1, second = first + 1;
        const Vector3d normal = frame.axes.col(unique);
        const Vector3d e = atomDirection(normal);
        if (e.squaredNorm() > 0) {
            frame.axes.col(first) = e;
            frame.axes.col(second) = normal.cross(e);   // right-handed: (e, n x e, n) and (n, e, n x e)
        }
    }
    return frame;
}

Matrix3d axisRotation(int axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;
    Matrix3d R = Matrix3d::Identity();
    R(i, i) = c;
    R(j, j) = c;
    R(i, j) = -s;
    R(j, i) = s;
    return R;
}

Matrix3d freeRotorStep(const Vector3d& moments, Vector3d& bodyMomentum, double h, bool linear) {
    static const int axes[5] = {0, 1, 2, 1, 0};
    static const double fractions[5] = {0.5, 0.5, 1.0, 0.5, 0.5};
    Matrix3d rotation = Matrix3d::Identity();
    if (linear)
        bodyMomentum(0) = 0;
    for (int s = 0; s < 5; s++) {
        const int k = axes[s];
        if (moments(k) <= 0 || (linear && k == 0))
            continue;  // no rotational degree of freedom about this axis
        Matrix3d R = axisRotation(k, fractions[s] * h * bodyMomentum(k) / moments(k));
        rotation = rotation * R;
        bodyMomentum = R.transpose() * bodyMomentum;
    }
    return rotation;
}

bool positionStep(const RigidBodyMath::BodyView& body, const double* positions, const double* velocities,
                  const double* forces, double h, double* newPositions, double* newVelocities) {
    // One pass for the centre and total momentum/force, one for J, L and the torque.
    Vector3d massPosition = Vector3d::Zero(), momentum = Vector3d::Zero(), force = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double m = body.masses[atom];
        massPosition += m * point(positions, atom);
        momentum += m * point(velocities, atom);
        force += point(forces, atom);
    }
    const Vector3d center = massPosition / body.totalMass;
    Matrix3d J = Matrix3d::Zero();
    Vector3d angularMomentum = Vector3d::Zero(), torque = Vector3d::Zero();
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double m = body.masses[atom];
        const Vector3d a = point(positions, atom) - center;
        J.noalias() += (m * a) * a.transpose();
        angularMomentum += m * a.cross(point(velocities, atom));  // sum m_i a_i = 0: V drops out
        torque += a.cross(point(forces, atom));
    }
    // Half kick, drift of the centre.
    momentum += (0.5 * h) * force;
    angularMomentum += (0.5 * h) * torque;
    const Vector3d centerVelocity = momentum / body.totalMass;
    const Vector3d newCenter = center + h * centerVelocity;

    // A point (all atoms at the centre) has no rotation: it only translates.
    if (RigidBodyMath::classifyShape(J, body.totalMass) == RigidBodyMath::Shape::Point) {
        if (!newCenter.allFinite() || !centerVelocity.allFinite())
            return false;
        for (int k = 0; k < body.numAtoms; k++) {
            const int atom = body.atoms[k];
            point(newPositions, atom) = newCenter + (point(positions, atom) - center);
            point(newVelocities, atom) = centerVelocity;
        }
        return true;
    }
    // Free rotor in the principal frame Q: Pi = Q^T L, Q -> Q R, so a_i -> S a_i with S = Q R Q^T.
    const PrincipalFrame frame = principalFrame(J, body, positions, center);
    Vector3d bodyMomentum = frame.axes.transpose() * angularMomentum;
    const Matrix3d rotation = freeRotorStep(frame.moments, bodyMomentum, h, body.linear);
    const Matrix3d newAxes = frame.axes * rotation;
    const Matrix3d spaceRotation = newAxes * frame.axes.transpose();
    Vector3d bodyOmega = Vector3d::Zero();
    for (int k = 0; k < 3; k++)
        if (frame.moments(k) > 0 && !(body.linear && k == 0))
            bodyOmega(k) = bodyMomentum(k) / frame.moments(k);
    const Vector3d omega = newAxes * bodyOmega;
    // Refuse what the exact rotations would integrate without complaint but wrongly: values
    // that are not finite, and a turn of more than a quarter in one step.
    if (!newCenter.allFinite() || !omega.allFinite() || !spaceRotation.allFinite() ||
        std::fabs(h) * omega.norm() > MaxRotationPerStep)
        return false;
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const Vector3d a = spaceRotation * (point(positions, atom) - center);
        point(newPositions, atom) = newCenter + a;
        point(newVelocities, atom) = centerVelocity + omega.cross(a);
    }
    return true;
}

} // namespace RigidBodyRotor
} // namespace MRattlePlugin
