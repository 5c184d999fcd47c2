/*
 * The numerical core on its own: the rotation solve of the position reset (convergence,
 * orthogonality, the zero-torque condition it stands for), the velocity projection
 * (idempotent, momentum-preserving, rigid) and linear bodies.
 */
#include "mrattle/Coordinates.h"
#include "mrattle/RigidBodyMath.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

using namespace MRattlePlugin::RigidBodyMath;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using std::vector;

namespace {

/** A body's data: atoms 0..n-1 with their masses, positions and velocities as 3N arrays. */
struct SampleBody {
    vector<int> atoms;
    vector<double> masses, x, v;
    double total = 0;
    BodyView view(bool linear = false) const {
        return BodyView{atoms.data(), (int) atoms.size(), masses.data(), total, linear};
    }
    Vector3d position(int i) const { return Vector3d(x[3 * i], x[3 * i + 1], x[3 * i + 2]); }
    Vector3d velocity(int i) const { return Vector3d(v[3 * i], v[3 * i + 1], v[3 * i + 2]); }
};

SampleBody makeBody(const vector<Vector3d>& sites, const vector<double>& masses, const Vector3d& offset) {
    SampleBody b;
    b.masses = masses;
    for (size_t i = 0; i < sites.size(); i++) {
        b.atoms.push_back(i);
        b.total += masses[i];
        for (int k = 0; k < 3; k++) {
            b.x.push_back(sites[i][k] + offset[k]);
            b.v.push_back(0);
        }
    }
    return b;
}

/** Non-planar, asymmetric: five sites, distinct masses. */
SampleBody asymmetricBody() {
    return makeBody({Vector3d(0, 0, 0), Vector3d(0.10, 0, 0), Vector3d(0, 0.12, 0), Vector3d(0, 0, 0.09), Vector3d(-0.07, -0.05, 0.03)},
                    {12.0, 1.0, 16.0, 14.0, 2.0}, Vector3d(1.3, -0.4, 2.2));
}

SampleBody linearBody() {
    return makeBody({Vector3d(-0.116, 0, 0), Vector3d(0, 0, 0), Vector3d(0.156, 0, 0)}, {16.0, 12.0, 32.0},
                    Vector3d(0.5, 0.5, 0.5));
}

/** Random velocities (not rigid) and a random drift displacement of the given size. */
void randomize(SampleBody& b, unsigned seed, double size, vector<double>& drifted) {
    std::mt19937 generator(seed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    drifted = b.x;
    for (size_t k = 0; k < b.x.size(); k++) {
        b.v[k] = gaussian(generator);
        drifted[k] += size * gaussian(generator);
    }
}

Vector3d momentum(const SampleBody& b) {
    Vector3d p = Vector3d::Zero();
    for (int i : b.atoms)
        p += b.masses[i] * b.velocity(i);
    return p;
}

Vector3d angularMomentum(const SampleBody& b) {
    Vector3d l = Vector3d::Zero();
    for (int i : b.atoms)
        l += b.masses[i] * b.position(i).cross(b.velocity(i));
    return l;
}

double maxStretchRate(const SampleBody& b) {
    double worst = 0;
    for (int i : b.atoms)
        for (int j : b.atoms)
            if (i < j) {
                Vector3d d = b.position(i) - b.position(j);
                worst = std::max(worst, std::fabs((b.velocity(i) - b.velocity(j)).dot(d)) / d.norm());
            }
    return worst;
}

} // namespace

TEST(CoreMath, RotationSolveConvergesToAProperRotation) {
    SampleBody b = asymmetricBody();
    for (double size : {1e-4, 1e-3, 1e-2, 3e-2}) {
        vector<double> drifted;
        randomize(b, 7, size, drifted);
        BodyView body = b.view();
        Vector3d oldCenter = centerOfMass(body, b.x.data()), newCenter = centerOfMass(body, drifted.data());
        Matrix3d J = secondMoment(body, b.x.data(), oldCenter);
        Matrix3d Y = Matrix3d::Zero();
        for (int i : b.atoms)
            Y += b.masses[i] * (Vector3d(drifted[3 * i], drifted[3 * i + 1], drifted[3 * i + 2]) - newCenter) *
                 (b.position(i) - oldCenter).transpose();
        RotationSolve solve = solveResetRotation(J, Y);
        ASSERT_TRUE(solve.converged) << "displacement " << size;
        std::cout << "drift " << size << " nm: " << solve.iterations << " Newton iterations" << std::endl;
        EXPECT_LE(solve.iterations, size < 2e-2 ? 4 : 6) << "displacement " << size;
        const Matrix3d& P = solve.rotation;
        EXPECT_LT((P.transpose() * P - Matrix3d::Identity()).norm(), 1e-14);
        EXPECT_NEAR(1.0, P.determinant(), 1e-14);
        // The condition itself: zero torque of (P a_i - y_i) about the old body vectors.
        Vector3d torque = Vector3d::Zero();
        for (int i : b.atoms) {
            Vector3d a = b.position(i) - oldCenter;
            Vector3d y = Vector3d(drifted[3 * i], drifted[3 * i + 1], drifted[3 * i + 2]) - newCenter;
            torque += b.masses[i] * a.cross(P * a - y);
        }
        EXPECT_LT(torque.norm(), 1e-13 * J.trace()) << "displacement " << size;
    }
}

TEST(CoreMath, RotationSolveRecoversAnExactRotation) {
    // If the drift is itself a rotation R of the body, P = R solves the condition.
    SampleBody b = asymmetricBody();
    BodyView body = b.view();
    Vector3d center = centerOfMass(body, b.x.data());
    Matrix3d J = secondMoment(body, b.x.data(), center);
    Matrix3d R = rotationFromVector(Vector3d(0.3, -0.2, 0.5));
    Matrix3d Y = R * J;  // sum m (R a) a^T
    RotationSolve solve = solveResetRotation(J, Y);
    ASSERT_TRUE(solve.converged);
    EXPECT_LT((solve.rotation - R).norm(), 1e-13);
    // The whole reset: positions become c_new + R a exactly, so every distance is kept.
    vector<double> moved = b.x;
    for (int i : b.atoms) {
        Vector3d y = center + Vector3d(0.01, 0.02, -0.03) + R * (b.position(i) - center);
        for (int k = 0; k < 3; k++)
            moved[3 * i + k] = y[k];
    }
    vector<double> reset = moved;
    ASSERT_TRUE(resetBodyPositions(body, b.x.data(), reset.data()).converged);
    for (size_t k = 0; k < reset.size(); k++)
        EXPECT_NEAR(moved[k], reset[k], 1e-14);
}

TEST(CoreMath, ResetKeepsDistancesAndCenter) {
    SampleBody b = asymmetricBody();
    vector<double> drifted;
    randomize(b, 3, 5e-3, drifted);
    BodyView body = b.view();
    Vector3d driftedCenter = centerOfMass(body, drifted.data());
    vector<double> reset = drifted;
    ASSERT_TRUE(resetBodyPositions(body, b.x.data(), reset.data()).converged);
    EXPECT_LT((centerOfMass(body, reset.data()) - driftedCenter).norm(), 1e-15);
    for (int i : b.atoms)
        for (int j : b.atoms) {
            Vector3d before = b.position(i) - b.position(j);
            Vector3d after(reset[3 * i] - reset[3 * j], reset[3 * i + 1] - reset[3 * j + 1], reset[3 * i + 2] - reset[3 * j + 2]);
            EXPECT_NEAR(before.norm(), after.norm(), 1e-15);
        }
}

TEST(CoreMath, ProjectionIsIdempotentAndKeepsMomenta) {
    SampleBody b = asymmetricBody();
    vector<double> unused;
    randomize(b, 11, 0, unused);
    Vector3d p0 = momentum(b), l0 = angularMomentum(b);
    EXPECT_GT(maxStretchRate(b), 0.1);  // not rigid before
    projectBodyVelocities(b.view(), b.x.data(), b.v.data());
    EXPECT_LT((momentum(b) - p0).norm(), 1e-13 * p0.norm());
    EXPECT_LT((angularMomentum(b) - l0).norm(), 1e-13 * l0.norm());
    EXPECT_LT(maxStretchRate(b), 1e-14);
    vector<double> once = b.v;
    projectBodyVelocities(b.view(), b.x.data(), b.v.data());
    for (size_t k = 0; k < once.size(); k++)
        EXPECT_NEAR(once[k], b.v[k], 1e-14);
}

TEST(CoreMath, ShapeClassification) {
    SampleBody linear = linearBody(), asymmetric = asymmetricBody();
    BodyView lv = linear.view(), av = asymmetric.view();
    EXPECT_TRUE(isLinearShape(secondMoment(lv, linear.x.data(), centerOfMass(lv, linear.x.data()))));
    EXPECT_FALSE(isLinearShape(secondMoment(av, asymmetric.x.data(), centerOfMass(av, asymmetric.x.data()))));
    // Planar (a triangle) is not linear; a 1e-2 nm kink in a 0.27 nm rod is not linear either
    // (one of 1e-3 nm is: LinearMomentRatio, tested in TestFaults).
    SampleBody triangle = makeBody({Vector3d(0, 0, 0), Vector3d(0.1, 0, 0), Vector3d(0, 0.1, 0)}, {1, 1, 1}, Vector3d(0, 0, 0));
    BodyView tv = triangle.view();
    EXPECT_FALSE(isLinearShape(secondMoment(tv, triangle.x.data(), centerOfMass(tv, triangle.x.data()))));
    SampleBody kinked = makeBody({Vector3d(-0.116, 0, 0), Vector3d(0, 1e-2, 0), Vector3d(0.156, 0, 0)}, {16, 12, 32}, Vector3d(0, 0, 0));
    BodyView kv = kinked.view();
    EXPECT_FALSE(isLinearShape(secondMoment(kv, kinked.x.data(), centerOfMass(kv, kinked.x.data()))));
}

TEST(CoreMath, ShapeClassificationAgreesWithTheEigensolverAtEveryBend) {
    // isLinearShape() decides bodies far from linear without the eigensolver: it must give
    // the eigensolver's answer for every bend, the threshold's neighbourhood included.
    std::mt19937 random(42);
    std::uniform_real_distribution<double> uniform(-1, 1);
    int linear = 0, general = 0;
    for (int trial = 0; trial < 20000; trial++) {
        const double bend = std::pow(10.0, -8 + 8 * (0.5 + 0.5 * uniform(random)));  // 1e-8 to 1 nm
        vector<Vector3d> sites;
        for (int i = 0; i < 3 + trial % 3; i++)
            sites.push_back(Vector3d(0.1 * i + 0.01 * uniform(random), bend * uniform(random), bend * uniform(random)));
        SampleBody body = makeBody(sites, vector<double>(sites.size(), 1 + 15 * (0.5 + 0.5 * uniform(random))),
                                   Vector3d(uniform(random), uniform(random), uniform(random)));
        const BodyView view = body.view();
        const Matrix3d J = secondMoment(view, body.x.data(), centerOfMass(view, body.x.data()));
        Eigen::SelfAdjointEigenSolver<Matrix3d> solver(J, Eigen::EigenvaluesOnly);
        const Vector3d& ev = solver.eigenvalues();
        const bool expected = ev(0) + ev(1) <= LinearMomentRatio * (ev(1) + ev(2));
        ASSERT_EQ(expected, isLinearShape(J)) << "bend " << bend;
        (expected ? linear : general)++;
    }
    EXPECT_GT(linear, 1000);
    EXPECT_GT(general, 1000);
}

TEST(CoreMath, LinearBodyResetAndProjection) {
    SampleBody b = linearBody();
    vector<double> drifted;
    randomize(b, 5, 5e-3, drifted);
    BodyView body = b.view(true);
    vector<double> reset = drifted;
    RotationSolve solve = resetBodyPositions(body, b.x.data(), reset.data());
    ASSERT_TRUE(solve.converged);
    // Still collinear, distances kept, centre where the drift put it.
    Vector3d x0(reset[0], reset[1], reset[2]), x1(reset[3], reset[4], reset[5]), x2(reset[6], reset[7], reset[8]);
    EXPECT_LT((x2 - x0).cross(x1 - x0).norm() / ((x2 - x0).norm() * (x1 - x0).norm()), 1e-14);
    EXPECT_NEAR(0.116, (x1 - x0).norm(), 1e-15);
    EXPECT_NEAR(0.156, (x2 - x1).norm(), 1e-15);
    EXPECT_LT((centerOfMass(body, reset.data()) - centerOfMass(body, drifted.data())).norm(), 1e-15);
    // The axis turned (the drift was not along it), and the zero-torque condition holds in
    // the plane normal to the old axis (the only torque a linear body can take).
    Vector3d u = (b.position(2) - b.position(0)).normalized();
    EXPECT_GT((x2 - x0).normalized().cross(u).norm(), 1e-3);
    Vector3d oldCenter = centerOfMass(body, b.x.data()), newCenter = centerOfMass(body, drifted.data());
    Vector3d torque = Vector3d::Zero();
    for (int i : b.atoms) {
        Vector3d a = b.position(i) - oldCenter;
        Vector3d moved = Vector3d(reset[3 * i], reset[3 * i + 1], reset[3 * i + 2]) - newCenter;
        Vector3d y = Vector3d(drifted[3 * i], drifted[3 * i + 1], drifted[3 * i + 2]) - newCenter;
        torque += b.masses[i] * a.cross(moved - y);
    }
    EXPECT_LT(torque.norm(), 1e-15);
    // Projection: rigid, no spin about the axis, momenta kept.
    b.x = reset;
    Vector3d p0 = momentum(b), l0 = angularMomentum(b);
    projectBodyVelocities(body, b.x.data(), b.v.data());
    EXPECT_LT(maxStretchRate(b), 1e-14);
    EXPECT_LT((momentum(b) - p0).norm(), 1e-13 * p0.norm());
    Vector3d axis = (x2 - x0).normalized(), center = centerOfMass(body, b.x.data());
    double spin = 0;
    for (int i : b.atoms)
        spin += b.masses[i] * (b.position(i) - center).cross(b.velocity(i)).dot(axis);
    EXPECT_NEAR(0.0, spin, 1e-15);
    // Angular momentum normal to the axis is kept (the axial part cannot be carried).
    Vector3d dl = angularMomentum(b) - l0;
    EXPECT_LT((dl - dl.dot(axis) * axis).norm(), 1e-13 * l0.norm());
}

TEST(CoreMath, RotationFromVector) {
    for (const Vector3d& d : {Vector3d(1e-9, 2e-9, -1e-9), Vector3d(1e-5, 0, 2e-5), Vector3d(0.4, -1.0, 2.0)}) {
        Matrix3d R = rotationFromVector(d);
        EXPECT_LT((R.transpose() * R - Matrix3d::Identity()).norm(), 1e-14);
        EXPECT_NEAR(1.0, R.determinant(), 1e-14);
        EXPECT_LT((R * d - d).norm(), 1e-15 * (1 + d.norm()));  // the axis is fixed
        Eigen::AngleAxisd expected(d.norm(), d.normalized());
        EXPECT_LT((R - expected.toRotationMatrix()).norm(), 1e-14);
    }
}

TEST(CoreMath, FoldedKicksEqualASeparateKickPass) {
    // Kick passes folded into the reset's and the projection's passes give bit for bit what
    // a kick pass of its own followed by driftAndResetBody / projectBodyVelocities gives.
    for (bool linear : {false, true}) {
        SampleBody b = linear ? linearBody() : asymmetricBody();
        vector<double> unused;
        randomize(b, 17, 0, unused);
        projectBodyVelocities(b.view(linear), b.x.data(), b.v.data());  // a rigid start
        std::mt19937 generator(3);
        std::normal_distribution<double> gaussian(0.0, 1.0);
        vector<double> forces(b.x.size()), inverseMasses;
        for (double& f : forces)
            f = 500 * gaussian(generator);
        for (double m : b.masses)
            inverseMasses.push_back(1.0 / m);
        Kick kick;
        kick.forces = forces.data();
        kick.inverseMasses = inverseMasses.data();
        kick.time = 0.001;
        auto kickedSeparately = [&](vector<double> v) {
            for (int i : b.atoms)
                for (int d = 0; d < 3; d++)
                    v[3 * i + d] = v[3 * i + d] + forces[3 * i + d] * (kick.time * inverseMasses[i]);
            return v;
        };
        BodyView body = b.view(linear);
        // Kick, drift and reset.
        vector<double> separateV = kickedSeparately(b.v), separateX(b.x.size()), foldedV(b.v.size()), foldedX(b.x.size());
        ASSERT_TRUE(driftAndResetBody(body, 0.002, b.x.data(), separateV.data(), separateX.data()).converged);
        ASSERT_TRUE(kickDriftAndResetBody(body, kick, 0.002, b.x.data(), b.v.data(), foldedX.data(), foldedV.data()).converged);
        EXPECT_EQ(separateX, foldedX) << linear;
        EXPECT_EQ(separateV, foldedV) << linear;
        EXPECT_NE(separateV, b.v);  // the kick and the step changed them
        // Kick and projection.
        vector<double> projected = kickedSeparately(b.v), folded = b.v;
        projectBodyVelocities(body, b.x.data(), projected.data());
        kickAndProjectBodyVelocities(body, kick, b.x.data(), folded.data());
        EXPECT_EQ(projected, folded) << linear;
        // No forces: no kick.
        vector<double> still = b.v, unkicked(b.v.size()), positions(b.x.size()), reference = b.v;
        ASSERT_TRUE(kickDriftAndResetBody(body, Kick(), 0.002, b.x.data(), still.data(), positions.data(), unkicked.data()).converged);
        ASSERT_TRUE(driftAndResetBody(body, 0.002, b.x.data(), reference.data(), separateX.data()).converged);
        EXPECT_EQ(reference, unkicked) << linear;
        EXPECT_EQ(still, b.v);  // the input velocities are not written
    }
}

TEST(CoreMath, BodiesSolvedTogetherEqualBodiesSolvedAlone) {
    // kickDriftAndResetBodies solves four bodies' rotations at a time (in SIMD lanes where the
    // CPU has AVX2); every body must come out bit for bit as kickDriftAndResetBody leaves it,
    // whatever its neighbours, and the first failing body must be the one reported. (On a
    // CPU without AVX2 both paths are the scalar code and the test checks only the blocks.)
    const int numBodies = 11;   // blocks of 4, 4 and 3
    SampleBody shape = asymmetricBody(), rod = linearBody();
    vector<int> atoms;
    vector<double> masses, x, v;
    vector<BodyView> views;
    vector<vector<int> > members;
    std::mt19937 generator(9);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    for (int b = 0; b < numBodies; b++) {
        const SampleBody& s = (b == 5 ? rod : shape);   // one linear body among them
        vector<int> body;
        for (size_t i = 0; i < s.atoms.size(); i++) {
            body.push_back(masses.size());
            masses.push_back(s.masses[i]);
            for (int d = 0; d < 3; d++) {
                x.push_back(s.x[3 * i + d] + 0.7 * b);
                v.push_back((b % 3 + 1) * gaussian(generator));   // different rotations per body
            }
        }
        members.push_back(body);
    }
    for (int b = 0; b < numBodies; b++) {
        const SampleBody& s = (b == 5 ? rod : shape);
        views.push_back(BodyView{members[b].data(), (int) members[b].size(), masses.data(), s.total, b == 5});
    }
    vector<double> forces(x.size()), inverseMasses;
    for (double& f : forces)
        f = 300 * gaussian(generator);
    for (double m : masses)
        inverseMasses.push_back(1.0 / m);
    Kick kick;
    kick.forces = forces.data();
    kick.inverseMasses = inverseMasses.data();
    kick.time = 0.001;
    for (int failing : {-1, 6, 10}) {   // none, then a body in the second and in the last block
        vector<double> velocities = v;
        if (failing >= 0) {   // 200 rad/ps about z through its first atom: 2 rad in a 0.01 ps step
            const Vector3d pivot = MRattlePlugin::point(x.data(), members[failing][0]);
            for (int atom : members[failing])
                MRattlePlugin::point(velocities.data(), atom) = Vector3d(0, 0, 200).cross(MRattlePlugin::point(x.data(), atom) - pivot);
        }
        const double h = failing >= 0 ? 0.01 : 0.002;
        vector<double> alonePositions(x.size(), 0.0), aloneVelocities(x.size(), 0.0);
        int aloneFailure = numBodies;
        for (int b = 0; b < numBodies && aloneFailure == numBodies; b++)
            if (!kickDriftAndResetBody(views[b], kick, h, x.data(), velocities.data(), alonePositions.data(),
                                       aloneVelocities.data()).converged)
                aloneFailure = b;
        vector<double> togetherPositions(x.size(), 0.0), togetherVelocities(x.size(), 0.0);
        const int togetherFailure = kickDriftAndResetBodies(views.data(), numBodies, kick, h, x.data(), velocities.data(),
                                                            togetherPositions.data(), togetherVelocities.data());
        EXPECT_EQ(failing >= 0 ? failing : numBodies, aloneFailure);
        EXPECT_EQ(aloneFailure, togetherFailure);
        // Every body before the failure is written the same way, bit for bit.
        for (int b = 0; b < aloneFailure; b++)
            for (int atom : members[b])
                for (int d = 0; d < 3; d++) {
                    EXPECT_EQ(alonePositions[3 * atom + d], togetherPositions[3 * atom + d]) << b;
                    EXPECT_EQ(aloneVelocities[3 * atom + d], togetherVelocities[3 * atom + d]) << b;
                }
        EXPECT_NE(alonePositions[3 * members[0][0]], 0.0);   // written
    }
    // The same for the kick and projection, whose inertia solves share lanes too.
    vector<double> projectedAlone = v, projectedTogether = v;
    for (int b = 0; b < numBodies; b++)
        kickAndProjectBodyVelocities(views[b], kick, x.data(), projectedAlone.data());
    kickAndProjectBodiesVelocities(views.data(), numBodies, kick, x.data(), projectedTogether.data());
    EXPECT_EQ(projectedAlone, projectedTogether);
    EXPECT_NE(projectedAlone, v);
}
