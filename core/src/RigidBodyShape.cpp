// A body's shape and axis: centre, second moment, linear or a point, the axis to straighten.
#include "mrattle/RigidBodyMath.h"
#include "mrattle/Coordinates.h"
#include "RigidBodyMathDetail.h"
#include <cmath>

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace MRattlePlugin {
namespace RigidBodyMath {

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
    // A body far from linear needs no eigensolver (positions set at 100k atoms classify every
    // body): with s = e0 + e1, c2 = e0 e1 + e2 s <= 1.25 tr(J) s, so c2 > 2 r tr(J)^2 gives
    // s > 1.6 r tr(J) >= 1.6 r (e1 + e2), far beyond the solver's round-off. Lower triangle, as the solver reads it.
    const Matrix3d& J = secondMoment;
    const double trace = J.trace();
    const double minors = J(0, 0) * J(1, 1) - J(1, 0) * J(1, 0) + J(0, 0) * J(2, 2) - J(2, 0) * J(2, 0) +
                          J(1, 1) * J(2, 2) - J(2, 1) * J(2, 1);
    if (trace > 0 && minors > 2 * LinearMomentRatio * trace * trace)
        return false;
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

Shape classifyShape(const Matrix3d& secondMoment, double totalMass) {
    if (isPointExtent(secondMoment.trace(), totalMass))
        return Shape::Point;
    return isLinearShape(secondMoment) ? Shape::Linear : Shape::General;
}

} // namespace RigidBodyMath
} // namespace MRattlePlugin
