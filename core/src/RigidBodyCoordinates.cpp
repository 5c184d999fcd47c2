#include "mrattle/RigidBodyCoordinates.h"
#include "mrattle/Coordinates.h"
#include "mrattle/RigidBodyMath.h"
#include <algorithm>
#include <cmath>

using Eigen::Matrix3d;
using Eigen::Vector3d;
using std::vector;

namespace MRattlePlugin {
namespace RigidBodyMath {

Matrix3d leftJacobian(const Vector3d& theta) {
    const double angle = theta.norm();
    const Matrix3d K = crossMatrix(theta);
    if (angle < 1e-4)  // series: the closed form loses digits to cancellation
        return Matrix3d::Identity() + K / 2 + K * K / 6;
    return Matrix3d::Identity() + (1 - std::cos(angle)) / (angle * angle) * K +
           (angle - std::sin(angle)) / (angle * angle * angle) * K * K;
}

Vector3d centroid(const double* positions, const vector<int>& atoms) {
    Vector3d sum = Vector3d::Zero();
    for (int i : atoms)
        sum += point(positions, i);
    return sum / atoms.size();
}

RigidBodyCoordinates::RigidBodyCoordinates(const vector<int>& atoms, const double* positions)
    : atoms(atoms), sqrtAtoms(std::sqrt((double) atoms.size())) {
    center = centroid(positions, atoms);
    for (int i : atoms)
        shape.push_back(point(positions, i) - center);
}

void RigidBodyCoordinates::restartAt(const double* positions, const double* masses, bool resetOrientation) {
    if (resetOrientation)
        base = Matrix3d::Identity();
    center = centroid(positions, atoms);
    // Rotations: the principal axes of the unit-mass inertia at orientation base; the
    // classification (linear, point) from the mass-weighted second moment, as the kernels do.
    Matrix3d inertia = Matrix3d::Zero(), secondMoment = Matrix3d::Zero();
    Vector3d centerOfMass = Vector3d::Zero();
    double mass = 0;
    for (size_t k = 0; k < atoms.size(); k++) {
        centerOfMass += masses[atoms[k]] * (base * shape[k]);
        mass += masses[atoms[k]];
    }
    centerOfMass /= mass;
    for (size_t k = 0; k < atoms.size(); k++) {
        const Vector3d r = base * shape[k];
        inertia += r.squaredNorm() * Matrix3d::Identity() - r * r.transpose();
        const Vector3d a = r - centerOfMass;
        secondMoment += masses[atoms[k]] * a * a.transpose();
    }
    const Shape kind = classifyShape(secondMoment, mass);
    const int rotations = degreesOfFreedom(kind) - 3;
    Eigen::SelfAdjointEigenSolver<Matrix3d> principal(inertia);  // eigenvalues ascending
    axes.resize(3, rotations);
    for (int k = 0; k < rotations; k++) {
        const int column = 3 - rotations + k;
        axes.col(k) = principal.eigenvectors().col(column) / std::sqrt(principal.eigenvalues()[column]);
    }
}

void RigidBodyCoordinates::foldRotation(const double* variables, double scale) {
    base = rotationFromVector(rotationVector(variables, scale)) * base;
}

Vector3d RigidBodyCoordinates::centroidAt(const double* variables, double scale) const {
    return center + scale * Vector3d(variables[0], variables[1], variables[2]) / sqrtAtoms;
}

Vector3d RigidBodyCoordinates::rotationVector(const double* variables, double scale) const {
    Vector3d theta = Vector3d::Zero();
    for (int k = 0; k < axes.cols(); k++)
        theta += axes.col(k) * (scale * variables[3 + k]);
    return theta;
}

void RigidBodyCoordinates::place(const double* variables, double scale, double* positions) const {
    const Vector3d at = centroidAt(variables, scale);
    const Matrix3d rotation = rotationFromVector(rotationVector(variables, scale)) * base;
    for (size_t k = 0; k < atoms.size(); k++)
        point(positions, atoms[k]) = at + rotation * shape[k];
}

void RigidBodyCoordinates::forceAndTorque(const double* variables, double scale, const double* positions,
                                          const double* forces, Vector3d& force, Vector3d& torque) const {
    const Vector3d at = centroidAt(variables, scale);
    force.setZero();
    torque.setZero();
    for (int i : atoms) {
        const Vector3d f = point(forces, i);
        force += f;
        torque += (point(positions, i) - at).cross(f);
    }
}

double RigidBodyCoordinates::gradient(const double* variables, double scale, const double* positions,
                                      const double* forces, double* gradient) const {
    const Vector3d theta = rotationVector(variables, scale);
    Vector3d force, torque;
    forceAndTorque(variables, scale, positions, forces, force, torque);
    // dE/du = -F/sqrt(n); dE/dv = -axes^T J(theta)^T tau, exact for the line search.
    const Vector3d translation = -force / sqrtAtoms;
    const Eigen::VectorXd rotation = -axes.transpose() * (leftJacobian(theta).transpose() * torque);
    for (int d = 0; d < 3; d++)
        gradient[d] = scale * translation[d];
    for (int k = 0; k < rotation.size(); k++)
        gradient[3 + k] = scale * rotation[k];
    // The force projected on rigid motion at this orientation: |F|^2/n + tau . I^-1 tau.
    const Eigen::VectorXd projected = axes.transpose() * (rotationFromVector(theta).transpose() * torque);
    return translation.squaredNorm() + projected.squaredNorm();
}

void RigidBodyCoordinates::projectForces(const double* variables, double scale, const double* positions,
                                         const double* forces, double* projected) const {
    const Matrix3d rotation = rotationFromVector(rotationVector(variables, scale));
    Vector3d force, torque;
    forceAndTorque(variables, scale, positions, forces, force, torque);
    // I^-1 at this orientation, over the body's rotations: R axes axes^T R^T.
    const Vector3d omega = rotation * (axes * (axes.transpose() * (rotation.transpose() * torque)));
    const Vector3d at = centroidAt(variables, scale);
    for (int i : atoms)
        point(projected, i) = force / atoms.size() + omega.cross(point(positions, i) - at);
}

} // namespace RigidBodyMath
} // namespace MRattlePlugin
