/*
 * What is particular to the splitting baseline (RigidSplittingIntegrator): the rotor
 * step's order, conservation on a free asymmetric body, second-order energy error,
 * convergence to M-RATTLE as h -> 0, linear bodies, and an LJ cluster compared with
 * M-RATTLE.
 *
 * What it promises like every rigid-body integrator (body semantics, rigidity over long
 * runs, free-particle constraints, degrees of freedom and temperature, bad input such as a
 * zero step size, the CPU platform, checkpoints) is checked by the value-parameterised
 * suites (TestBodySemantics, TestBodyEnvironment, TestBadInput, TestPlatforms,
 * TestCheckpoint, TestCompound), which run for every config in allConfigs().
 */
#include "RigidSplittingIntegrator.h"
#include "TestSupport.h"
#include "mrattle/RigidBodyRotor.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

/** A non-planar, asymmetric 5-site body (three distinct principal moments), about its centre of mass. */
void asymmetricBody(vector<Vec3>& sites, vector<double>& masses) {
    sites = {Vec3(0, 0, 0), Vec3(0.10, 0, 0), Vec3(0, 0.12, 0), Vec3(0, 0, 0.09), Vec3(-0.07, -0.05, 0.03)};
    masses = {12.0, 1.0, 16.0, 14.0, 2.0};
    Vec3 center;
    double total = 0;
    for (size_t i = 0; i < sites.size(); i++) {
        center += sites[i] * masses[i];
        total += masses[i];
    }
    for (Vec3& s : sites)
        s -= center / total;
}

/**
 * Four asymmetric bodies (declared explicitly) at the corners of a tetrahedron, held
 * together by springs between atoms of different bodies, at rest length 1.3x their
 * initial distance (so they start out of equilibrium and the forces do work).
 */
struct SpringCluster {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > bodies;
};

SpringCluster springCluster() {
    SpringCluster c;
    vector<Vec3> sites;
    vector<double> masses;
    asymmetricBody(sites, masses);
    const Vec3 corners[4] = {Vec3(0.3, 0.3, 0.3), Vec3(0.3, -0.3, -0.3), Vec3(-0.3, 0.3, -0.3), Vec3(-0.3, -0.3, 0.3)};
    for (int b = 0; b < 4; b++) {
        vector<int> body;
        for (size_t i = 0; i < sites.size(); i++) {
            body.push_back(c.system.addParticle(masses[i]));
            // Rotate each copy differently so the bodies are not aligned.
            const Vec3& s = sites[i];
            Vec3 rotated = (b % 2 == 0 ? Vec3(s[1], s[2], s[0]) : Vec3(s[0], -s[2], s[1]));
            c.positions.push_back(corners[b] + (b < 2 ? rotated : s));
        }
        c.bodies.push_back(body);
    }
    HarmonicBondForce* springs = new HarmonicBondForce();
    for (int b1 = 0; b1 < 4; b1++)
        for (int b2 = b1 + 1; b2 < 4; b2++)
            for (int k = 0; k < 2; k++) {
                int i = c.bodies[b1][k + 1], j = c.bodies[b2][(k + b1 + b2) % 5];
                Vec3 d = c.positions[i] - c.positions[j];
                springs->addBond(i, j, 1.3 * std::sqrt(d.dot(d)), 300.0);
            }
    c.system.addForce(springs);
    return c;
}

template <class IntegratorType>
void addBodies(IntegratorType& integrator, const vector<vector<int> >& bodies) {
    for (const auto& body : bodies)
        integrator.addRigidBody(body);
}

/** Largest |E(t) - E(0)| of the total energy over a run of the given duration. */
double energyDeviation(double h, double duration) {
    SpringCluster c = springCluster();
    RigidSplittingIntegrator integrator(h);
    addBodies(integrator, c.bodies);
    Context context(c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 7);
    State s0 = context.getState(State::Energy);
    const double e0 = s0.getKineticEnergy() + s0.getPotentialEnergy();
    double worst = 0;
    const int steps = (int) std::lround(duration / h);
    for (int i = 0; i < steps; i++) {
        integrator.step(1);
        State s = context.getState(State::Energy);
        worst = std::max(worst, std::fabs(s.getKineticEnergy() + s.getPotentialEnergy() - e0));
    }
    return worst;
}

/** Positions of the cluster after the given time, from the same initial state, with either integrator. */
template <class IntegratorType>
vector<Vec3> clusterPositionsAfter(double h, double duration) {
    SpringCluster c = springCluster();
    IntegratorType integrator(h);
    addBodies(integrator, c.bodies);
    Context context(c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 11);
    integrator.step((int) std::lround(duration / h));
    return context.getState(State::Positions).getPositions();
}

double maxDifference(const vector<Vec3>& a, const vector<Vec3>& b) {
    double worst = 0;
    for (size_t i = 0; i < a.size(); i++) {
        Vec3 d = a[i] - b[i];
        worst = std::max(worst, std::sqrt(d.dot(d)));
    }
    return worst;
}

/** Angular momentum about the centre of mass (free of the round-off of a drifting centre). */
Vec3 angularMomentum(const System& system, const vector<Vec3>& x, const vector<Vec3>& v) {
    Vec3 center, velocity;
    double total = 0;
    for (int i = 0; i < system.getNumParticles(); i++) {
        double m = system.getParticleMass(i);
        center += x[i] * m;
        velocity += v[i] * m;
        total += m;
    }
    center /= total;
    velocity /= total;
    Vec3 l;
    for (int i = 0; i < system.getNumParticles(); i++)
        l += (x[i] - center).cross(v[i] - velocity) * system.getParticleMass(i);
    return l;
}

} // namespace

TEST(RigidSplitting, RotorStepHasThirdOrderLocalErrorAndConservesAngularMomentum) {
    // Spherical top: the exact free rotation over h is by h * Pi / I about Pi, with Pi
    // fixed in the body. The splitting's sub-rotations do not commute, so one step is
    // off by O(h^3): halving h divides the error by 8.
    Eigen::Vector3d moments(2.0, 2.0, 2.0), pi(0.3, -0.4, 1.2);
    double errors[2];
    for (int k = 0; k < 2; k++) {
        double h = 0.2 / (1 << k);
        Eigen::Vector3d advanced = pi;
        Eigen::Matrix3d R = RigidBodyRotor::freeRotorStep(moments, advanced, h, false);
        errors[k] = (R - RigidBodyMath::rotationFromVector(h * pi / 2.0)).norm();
    }
    EXPECT_GT(errors[0] / errors[1], 7.0);
    EXPECT_LT(errors[0] / errors[1], 9.0);
    // Asymmetric top: the space-frame angular momentum Q Pi is kept exactly (Q = 1 here).
    Eigen::Vector3d asymmetric(1.0, 2.0, 3.5), pi2 = pi;
    Eigen::Matrix3d R2 = RigidBodyRotor::freeRotorStep(asymmetric, pi2, 0.1, false);
    EXPECT_LT((R2 * pi2 - pi).norm(), 1e-14);
    EXPECT_LT((R2.transpose() * R2 - Eigen::Matrix3d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(1.0, R2.determinant(), 1e-14);
}

TEST(RigidSplitting, FreeAsymmetricBodyConservesAngularMomentumAndStaysRigid) {
    vector<Vec3> sites;
    vector<double> masses;
    asymmetricBody(sites, masses);
    System system;
    for (double m : masses)
        system.addParticle(m);
    RigidSplittingIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1, 2, 3, 4});
    Context context(system, integrator, platform("Reference"));
    context.setPositions(sites);
    // A tumbling motion about all three axes, plus drift.
    vector<Vec3> velocities;
    const Vec3 omega(4.0, -7.0, 10.0), drift(0.3, 0.1, -0.2);
    for (const Vec3& s : sites)
        velocities.push_back(drift + omega.cross(s));
    context.setVelocities(velocities);
    State s0 = context.getState(State::Positions | State::Velocities | State::Energy);
    const Vec3 l0 = angularMomentum(system, s0.getPositions(), s0.getVelocities());
    const double e0 = s0.getKineticEnergy();
    double worstEnergy = 0, firstHalfWorst = 0;
    const int steps = 10000;
    for (int i = 0; i < steps; i++) {
        integrator.step(1);
        double e = context.getState(State::Energy).getKineticEnergy();
        worstEnergy = std::max(worstEnergy, std::fabs(e - e0));
        if (i < steps / 2)
            firstHalfWorst = worstEnergy;
    }
    State s = context.getState(State::Positions | State::Velocities | State::Energy);
    Vec3 dl = angularMomentum(system, s.getPositions(), s.getVelocities()) - l0;
    // Each step keeps it to round-off (~1e-15 relative); 10^4 steps accumulate at most ~1e-11.
    EXPECT_LT(std::sqrt(dl.dot(dl)), 1e-11 * std::sqrt(l0.dot(l0)));
    EXPECT_LT(maxDistanceChange(sites, s.getPositions(), integrator.getBodiesInEffect()), 1e-10);
    // The splitting does not conserve the rotor energy exactly: it oscillates at O((h w)^2)
    // (here h|w| ~ 0.025) with no drift, so the second half adds nothing to the worst error.
    EXPECT_LT(worstEnergy, 1e-3 * e0);
    EXPECT_GT(worstEnergy, 0.0);
    EXPECT_LT(worstEnergy, 1.5 * firstHalfWorst) << worstEnergy / e0 << " " << firstHalfWorst / e0;
    // Centre of mass moves uniformly.
    Vec3 center;
    double totalMass = 0;
    for (int i = 0; i < 5; i++) {
        center += s.getPositions()[i] * masses[i];
        totalMass += masses[i];
    }
    center /= totalMass;
    Vec3 expected = drift * (steps * 0.002);
    EXPECT_NEAR(expected[0], center[0], 1e-10);
    EXPECT_NEAR(expected[1], center[1], 1e-10);
    EXPECT_NEAR(expected[2], center[2], 1e-10);
}

TEST(RigidSplitting, EnergyErrorIsSecondOrder) {
    const double duration = 0.4;
    double coarse = energyDeviation(0.002, duration);
    double fine = energyDeviation(0.001, duration);
    EXPECT_GT(coarse, 0.0);
    double ratio = coarse / fine;
    EXPECT_GT(ratio, 3.0) << "coarse " << coarse << " fine " << fine;
    EXPECT_LT(ratio, 5.0) << "coarse " << coarse << " fine " << fine;
}

TEST(RigidSplitting, ConvergesToMRattleAsStepShrinks) {
    // Both are second order, so after a fixed time their difference shrinks like h^2.
    const double duration = 0.2;
    double previous = 0;
    for (double h : {0.004, 0.002, 0.001}) {
        double difference = maxDifference(clusterPositionsAfter<RigidSplittingIntegrator>(h, duration),
                                          clusterPositionsAfter<MRattleIntegrator>(h, duration));
        EXPECT_GT(difference, 0.0);
        EXPECT_LT(difference, 1e-3);
        if (previous > 0) {
            EXPECT_GT(previous / difference, 3.0) << "h " << h;
            EXPECT_LT(previous / difference, 5.0) << "h " << h;
        }
        previous = difference;
    }
}

TEST(RigidSplitting, LinearBodyHasFiveDegreesOfFreedomAndStaysOnItsLine) {
    // A CO2-like linear body tumbling freely, and an asymmetric body it is tied to by a spring.
    System system;
    vector<Vec3> positions = {Vec3(-0.116, 0, 0), Vec3(0, 0, 0), Vec3(0.116, 0, 0)};
    for (double m : {16.0, 12.0, 16.0})
        system.addParticle(m);
    vector<Vec3> sites;
    vector<double> masses;
    asymmetricBody(sites, masses);
    for (size_t i = 0; i < sites.size(); i++) {
        system.addParticle(masses[i]);
        positions.push_back(sites[i] + Vec3(0.5, 0.1, 0));
    }
    HarmonicBondForce* spring = new HarmonicBondForce();
    spring->addBond(2, 4, 0.45, 200.0);
    system.addForce(spring);
    RigidSplittingIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1, 2});
    integrator.addRigidBody({3, 4, 5, 6, 7});
    Context context(system, integrator, platform("Reference"));
    context.setPositions(positions);
    EXPECT_TRUE(integrator.isBodyLinear(0));
    EXPECT_FALSE(integrator.isBodyLinear(1));
    EXPECT_EQ(11, integrator.getNumDegreesOfFreedom());
    // Spin about the axis is removed by the projection: only tumbling remains.
    vector<Vec3> velocities(8);
    velocities[0] = Vec3(0, 1.0, 0.5);
    velocities[2] = Vec3(0.2, -1.0, 0.5);
    velocities[5] = Vec3(0.3, 0, 0);
    context.setVelocities(velocities);
    State s0 = context.getState(State::Energy);
    const double e0 = s0.getKineticEnergy() + s0.getPotentialEnergy();
    double worst = 0;
    for (int i = 0; i < 500; i++) {
        integrator.step(4);
        State s = context.getState(State::Energy);
        worst = std::max(worst, std::fabs(s.getKineticEnergy() + s.getPotentialEnergy() - e0));
    }
    State s = context.getState(State::Positions | State::Velocities);
    const vector<Vec3>& x = s.getPositions();
    EXPECT_LT(maxDistanceChange(positions, x, integrator.getBodiesInEffect()), 1e-10);
    Vec3 axis = x[2] - x[0];
    Vec3 offCentre = (x[1] - x[0]).cross(axis);
    EXPECT_LT(std::sqrt(offCentre.dot(offCentre)), 1e-12);
    // No spin about the axis: the atoms' velocities relative to the centre are normal to it.
    const vector<Vec3>& v = s.getVelocities();
    EXPECT_LT(std::fabs((v[2] - v[1]).dot(axis)), 1e-9);
    EXPECT_LT(worst, 1e-2 * std::fabs(e0) + 0.05);
    EXPECT_GT(worst, 0.0);
}

TEST(RigidSplitting, LennardJonesClusterConservesEnergyLikeMRattle) {
    // 8 non-planar molecules with LJ and charges (molecules are the bodies): both
    // second-order integrators conserve energy to a similar, small fluctuation, and each
    // run's drift over 1 ps, with 3 error bars from block means, stays below 1e-4 of the
    // kinetic energy (1.3e-3 kJ/mol of 51 measured); the two drifts agree within 4 combined errors.
    double fluctuation[2];
    Drift drifts[2];
    for (int method = 0; method < 2; method++) {
        MRattleTest::Cluster c = buildCluster(tetrahedral(), 2, 0.5, 21);
        std::unique_ptr<RigidBodyIntegrator> integrator;
        if (method == 0)
            integrator.reset(new RigidSplittingIntegrator(0.001));
        else
            integrator.reset(new MRattleIntegrator(0.001));
        Context context(*c.system, *integrator, platform("Reference"));
        context.setPositions(c.positions);
        context.setVelocitiesToTemperature(200, 13);
        EXPECT_EQ(8, integrator->getNumBodiesInEffect());
        vector<double> energies;
        for (int i = 0; i < 200; i++) {
            integrator->step(5);
            State s = context.getState(State::Energy);
            energies.push_back(s.getKineticEnergy() + s.getPotentialEnergy());
        }
        vector<Vec3> x = context.getState(State::Positions).getPositions();
        EXPECT_LT(maxDistanceChange(c.positions, x, c.molecules), 1e-10);
        fluctuation[method] = standardDeviation(energies);
        double kinetic = context.getState(State::Energy).getKineticEnergy();
        EXPECT_LT(fluctuation[method], 1e-3 * kinetic) << "method " << method;
        drifts[method] = driftOfBlockMeans(energies);
        std::cout << "method " << method << ": energy rms " << fluctuation[method] << ", drift " << drifts[method].change
                  << " +- " << drifts[method].error << " kJ/mol, kinetic " << kinetic << std::endl;
        EXPECT_LT(std::fabs(drifts[method].change) + 3 * drifts[method].error, 1e-4 * kinetic) << "drift, method " << method;
    }
    EXPECT_LT(std::fabs(drifts[0].change - drifts[1].change), 4 * std::hypot(drifts[0].error, drifts[1].error));
    EXPECT_GT(fluctuation[0], 0.0);
    EXPECT_LT(fluctuation[0], 10 * fluctuation[1]);
    EXPECT_LT(fluctuation[1], 10 * fluctuation[0]);
}

TEST(RigidSplitting, AStepForwardAndBackReturnsForSymmetricAndAsymmetricBodies) {
    // Benzene is a symmetric top (two equal moments); with the degenerate plane's basis
    // taken from its atoms the splitting is time-reversible like M-RATTLE: a step, the
    // velocities negated, a step and negated again return to round-off. The 5-site body
    // has three distinct moments.
    for (const bool symmetric : {true, false}) {
        Cluster c = buildCluster(symmetric ? benzene() : tetrahedral(), 2, symmetric ? 0.7 : 0.5, 3);
        RigidSplittingIntegrator integrator(0.004);
        Context context(*c.system, integrator, platform("Reference"));
        context.setPositions(c.positions);
        context.setVelocitiesToTemperature(300, 2);
        integrator.step(20);
        State before = context.getState(State::Positions | State::Velocities);
        // Reversibility: a step, the velocities negated, a step, negated again.
        integrator.step(1);
        vector<Vec3> v = context.getState(State::Velocities).getVelocities();
        for (Vec3& vi : v)
            vi = -vi;
        context.setVelocities(v);
        integrator.step(1);
        v = context.getState(State::Velocities).getVelocities();
        for (Vec3& vi : v)
            vi = -vi;
        context.setVelocities(v);
        State after = context.getState(State::Positions | State::Velocities);
        const double back = maxDeviation(before.getPositions(), after.getPositions());
        std::cout << (symmetric ? "benzene" : "5-site") << ": forward and back misses by " << back << " nm" << std::endl;
        EXPECT_LT(back, 1e-13);
        EXPECT_LT(maxDeviation(before.getVelocities(), after.getVelocities()), 1e-10);
    }
}
