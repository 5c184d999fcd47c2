/*
 * The rigid minimizer's body coordinates on their own (core): the left Jacobian against
 * finite differences of the exponential map, centroids, placements that keep the shape,
 * the gradient against finite differences of an energy, and the projected forces.
 */
#include "mrattle/Coordinates.h"
#include "mrattle/RigidBodyCoordinates.h"
#include "mrattle/RigidBodyMath.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>
#include <vector>

using namespace MRattlePlugin;
using namespace MRattlePlugin::RigidBodyMath;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using std::vector;

namespace {

/** A 4-atom non-planar body (atoms 1..4 of a 6-particle array; 0 and 5 are not in it). */
struct Sample {
    vector<int> atoms{1, 2, 3, 4};
    vector<double> masses{1, 12, 1, 16, 14, 1};
    vector<double> x{9, 9, 9, 0.1, 0.0, 0.0, 0.0, 0.12, 0.01, -0.05, -0.02, 0.09, 0.03, 0.04, -0.11, 7, 7, 7};
};

/** A smooth energy of the positions: springs of each atom to a fixed point, and its forces. */
double energy(const vector<double>& x, vector<double>* forces = nullptr) {
    double e = 0;
    if (forces)
        forces->assign(x.size(), 0.0);
    for (size_t i = 0; i < x.size(); i++) {
        const double anchor = 0.05 * std::sin(1.0 + i), k = 100.0 + 10 * i;
        e += 0.5 * k * (x[i] - anchor) * (x[i] - anchor) * (1 + 0.1 * x[i]);
        if (forces)
            (*forces)[i] = -(k * (x[i] - anchor) * (1 + 0.1 * x[i]) + 0.05 * k * (x[i] - anchor) * (x[i] - anchor));
    }
    return e;
}

double distance(const vector<double>& x, int i, int j) {
    return (point(x.data(), i) - point(x.data(), j)).norm();
}

} // namespace

TEST(RigidBodyCoordinates, CrossMatrixIsTheCrossProduct) {
    const Vector3d w(0.3, -1.2, 2.5), v(-0.7, 0.4, 1.1);
    EXPECT_LT((crossMatrix(w) * v - w.cross(v)).norm(), 1e-15);
}

TEST(RigidBodyCoordinates, LeftJacobianIsTheDerivativeOfTheExponential) {
    // d/dt exp([theta + t d]x) exp([theta]x)^T = [J(theta) d]x, on both sides of the series switch.
    for (double angle : {1e-6, 3e-5, 0.5, 2.0, 3.0}) {
        const Vector3d theta = angle * Vector3d(0.48, -0.6, 0.64), d(0.2, 0.9, -0.4);
        const double h = 1e-6;
        const Matrix3d derivative = (rotationFromVector(theta + h * d) - rotationFromVector(theta - h * d)) / (2 * h);
        const Matrix3d skew = derivative * rotationFromVector(theta).transpose();
        EXPECT_LT((skew - crossMatrix(leftJacobian(theta) * d)).norm(), 1e-8) << "angle " << angle;
    }
}

TEST(RigidBodyCoordinates, CentroidOfTheListedAtoms) {
    Sample s;
    const Vector3d expected = (point(s.x.data(), 1) + point(s.x.data(), 2) + point(s.x.data(), 3) +
                               point(s.x.data(), 4)) / 4;
    EXPECT_LT((centroid(s.x.data(), s.atoms) - expected).norm(), 1e-16);
}

TEST(RigidBodyCoordinates, PlacementsKeepTheShapeAndOtherParticles) {
    Sample s;
    RigidBodyCoordinates body(s.atoms, s.x.data());
    body.restartAt(s.x.data(), s.masses.data(), true);
    ASSERT_EQ(body.numVariables(), 6);
    vector<double> variables{0, 0, 0, 0, 0, 0}, placed = s.x;
    body.place(variables.data(), 1.0, placed.data());
    for (size_t i = 0; i < s.x.size(); i++)
        EXPECT_NEAR(placed[i], s.x[i], 1e-15);
    variables = {0.3, -0.2, 0.1, 0.4, 0.7, -0.5};
    body.place(variables.data(), 1.0, placed.data());
    for (int i : s.atoms)
        for (int j : s.atoms)
            EXPECT_NEAR(distance(placed, i, j), distance(s.x, i, j), 1e-14);
    EXPECT_EQ(placed[0], 9.0);
    EXPECT_EQ(placed[17], 7.0);
    // The centroid moves by scale u / sqrt(n).
    EXPECT_LT((centroid(placed.data(), s.atoms) - centroid(s.x.data(), s.atoms) -
               Vector3d(0.3, -0.2, 0.1) / 2).norm(), 1e-14);
    // Folding the rotation in and restarting there describes the same placement at v = 0.
    body.foldRotation(variables.data(), 1.0);
    body.restartAt(placed.data(), s.masses.data(), false);
    vector<double> zero(6, 0.0), again = s.x;
    body.place(zero.data(), 1.0, again.data());
    for (int i : s.atoms)
        EXPECT_LT((point(again.data(), i) - point(placed.data(), i)).norm(), 1e-14);
}

TEST(RigidBodyCoordinates, GradientIsTheDerivativeOfTheEnergy) {
    Sample s;
    RigidBodyCoordinates body(s.atoms, s.x.data());
    body.restartAt(s.x.data(), s.masses.data(), true);
    const double scale = 0.05;
    const vector<double> at{0.2, -0.4, 0.3, 1.5, -2.0, 0.8};  // a far rotation: J(theta) matters
    auto energyAt = [&](const vector<double>& variables) {
        vector<double> placed = s.x;
        body.place(variables.data(), scale, placed.data());
        return energy(placed);
    };
    vector<double> placed = s.x, forces, gradient(6);
    body.place(at.data(), scale, placed.data());
    energy(placed, &forces);
    const double projectedNorm2 = body.gradient(at.data(), scale, placed.data(), forces.data(), gradient.data());
    for (int k = 0; k < 6; k++) {
        vector<double> plus = at, minus = at;
        plus[k] += 1e-5;
        minus[k] -= 1e-5;
        EXPECT_NEAR(gradient[k], (energyAt(plus) - energyAt(minus)) / 2e-5, 1e-6 * (1 + std::fabs(gradient[k])))
            << "variable " << k;
    }
    // The projected forces: rigid motion of the body, with the squared norm gradient() returns.
    vector<double> projected(s.x.size(), 0.0);
    body.projectForces(at.data(), scale, placed.data(), forces.data(), projected.data());
    double norm2 = 0;
    for (int i : s.atoms)
        norm2 += point(projected.data(), i).squaredNorm();
    EXPECT_NEAR(norm2, projectedNorm2, 1e-10 * projectedNorm2);
    const Vector3d c = centroid(placed.data(), s.atoms);
    for (int i : s.atoms)
        for (int j : s.atoms) {
            // Rigid: no relative velocity along the line between two atoms.
            const Vector3d d = point(placed.data(), i) - point(placed.data(), j);
            EXPECT_NEAR(d.dot(point(projected.data(), i) - point(projected.data(), j)), 0, 1e-9);
        }
    // It has the net force and the torque of the forces it projects.
    Vector3d force = Vector3d::Zero(), torque = Vector3d::Zero(), projectedTorque = Vector3d::Zero();
    Vector3d projectedForce = Vector3d::Zero();
    for (int i : s.atoms) {
        force += point(forces.data(), i);
        projectedForce += point(projected.data(), i);
        torque += (point(placed.data(), i) - c).cross(point(forces.data(), i));
        projectedTorque += (point(placed.data(), i) - c).cross(point(projected.data(), i));
    }
    EXPECT_LT((force - projectedForce).norm(), 1e-10 * force.norm());
    EXPECT_LT((torque - projectedTorque).norm(), 1e-10 * torque.norm());
}

TEST(RigidBodyCoordinates, LinearBodyHasTwoRotationsAndPointNone) {
    vector<double> x{0, 0, 0, 0.1, 0, 0, 0.2, 0, 0}, masses{1, 1, 1};
    RigidBodyCoordinates linear({0, 1, 2}, x.data());
    linear.restartAt(x.data(), masses.data(), true);
    EXPECT_EQ(linear.numVariables(), 5);
    vector<double> tiny{0, 0, 0, 1e-5, 0, 0};
    RigidBodyCoordinates pointBody({0, 1}, tiny.data());
    pointBody.restartAt(tiny.data(), masses.data(), true);
    EXPECT_EQ(pointBody.numVariables(), 3);
}
