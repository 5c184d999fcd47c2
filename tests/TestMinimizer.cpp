/*
 * RigidBodyMinimizer: bodies keep their shapes, the energy goes down to a point where the
 * generalized force (net force and torque of each body, projected with unit masses) meets
 * LocalEnergyMinimizer's tolerance, dynamics continue rigidly after it, and it reaches an
 * energy no higher than LocalEnergyMinimizer with SETTLE on the same rigid-water System.
 * Linear bodies, far rotations, free particles with constraints, virtual sites, the
 * CompoundIntegrator, a non-finite energy and bad arguments are covered on Reference.
 */
#include "RigidBodyMinimizer.h"
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <cmath>
#include <random>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

Eigen::Vector3d eigen(const Vec3& v) {
    return Eigen::Vector3d(v[0], v[1], v[2]);
}

/**
 * The test's own RMS generalized force, per degree of freedom in units of a particle's force
 * (sqrt(3 sum / D), D: 3 per body plus its rotations, 3 per free particle; the minimizer's
 * test): per body |F|^2/n + tau . I^+ tau (torque about the centroid, unit-mass inertia,
 * pseudo-inverse for a linear body), per free particle |f|^2.
 */
double rmsGeneralizedForce(Context& context, const vector<vector<int> >& bodies, const vector<int>& freeParticles) {
    State state = context.getState(State::Positions | State::Forces);
    const vector<Vec3>& x = state.getPositions();
    const vector<Vec3>& f = state.getForces();
    double sum = 0;
    int freedoms = 3 * freeParticles.size();
    for (const vector<int>& body : bodies) {
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero(),
                        torque = Eigen::Vector3d::Zero();
        for (int i : body)
            centroid += eigen(x[i]) / body.size();
        Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
        for (int i : body) {
            const Eigen::Vector3d r = eigen(x[i]) - centroid;
            force += eigen(f[i]);
            torque += r.cross(eigen(f[i]));
            inertia += r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(inertia);
        for (int k = 0; k < 3; k++)
            if (principal.eigenvalues()[k] > 1e-9 * principal.eigenvalues()[2]) {
                sum += std::pow(principal.eigenvectors().col(k).dot(torque), 2) / principal.eigenvalues()[k];
                freedoms++;
            }
        sum += force.squaredNorm() / body.size();
        freedoms += 3;
    }
    for (int i : freeParticles)
        sum += f[i].dot(f[i]);
    return std::sqrt(3 * sum / freedoms);
}

/** Largest |d . (v_i - v_j)| over pairs of a body (d = x_i - x_j): zero for rigid motion. */
double maxRigidityRate(Context& context, const vector<vector<int> >& bodies) {
    State state = context.getState(State::Positions | State::Velocities);
    double worst = 0;
    for (const vector<int>& body : bodies)
        for (int i : body)
            for (int j : body)
                worst = std::max(worst, std::fabs((state.getPositions()[i] - state.getPositions()[j])
                                                      .dot(state.getVelocities()[i] - state.getVelocities()[j])));
    return worst;
}

double potentialEnergy(Context& context) {
    return context.getState(State::Energy).getPotentialEnergy();
}

vector<Vec3> positionsOf(Context& context) {
    return context.getState(State::Positions).getPositions();
}

/** Rigid TIP3P waters: the cluster with SETTLE's three constraints per water, as rigidWater=True gives. */
Cluster waterCluster(int n, double spacing, unsigned int seed) {
    Cluster cluster = buildCluster(water(), n, spacing, seed);
    for (const vector<int>& m : cluster.molecules) {
        const Vec3 oh = cluster.positions[m[1]] - cluster.positions[m[0]];
        const Vec3 hh = cluster.positions[m[2]] - cluster.positions[m[1]];
        cluster.system->addConstraint(m[0], m[1], std::sqrt(oh.dot(oh)));
        cluster.system->addConstraint(m[0], m[2], std::sqrt(oh.dot(oh)));
        cluster.system->addConstraint(m[1], m[2], std::sqrt(hh.dot(hh)));
    }
    return cluster;
}

class Minimizer : public RigidBodyTest {};

} // namespace

TEST_P(Minimizer, BenzeneClusterLowersEnergyKeepsShapesAndStepsRigidly) {
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 3);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(*cluster.system, *integrator);
    context->setPositions(cluster.positions);
    context->setVelocitiesToTemperature(300, 7);
    const double start = potentialEnergy(*context);
    const double tolerance = 1.0;
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(*context, tolerance);

    EXPECT_NEAR(start, report.initialEnergy, 1e-9 * std::fabs(start));
    EXPECT_LT(report.finalEnergy, start - 1.0);
    EXPECT_NEAR(report.finalEnergy, potentialEnergy(*context), 1e-9 * std::fabs(start));
    EXPECT_GT(report.iterations, 0);
    EXPECT_GE(report.evaluations, report.iterations);
    const vector<Vec3> minimized = positionsOf(*context);
    EXPECT_LT(maxDistanceChange(cluster.positions, minimized, cluster.molecules), 1e-12);
    EXPECT_GT(maxDeviation(cluster.positions, minimized), 1e-3);  // it did move
    // Converged by the minimizer's test (rms per degree of freedom), measured independently of it.
    const double rms = rmsGeneralizedForce(*context, cluster.molecules, {});
    EXPECT_LE(rms, tolerance * (1 + 1e-9));
    EXPECT_NEAR(rms, report.rmsForce, 1e-6 * tolerance + 1e-6 * rms);
    // Velocities are rigid at the new positions, and dynamics go on with the same shapes.
    EXPECT_LT(maxRigidityRate(*context, cluster.molecules), 1e-10);
    integrator->step(20);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(*context), cluster.molecules), 1e-9);
    // From a minimum there is nothing to do: no iteration, the same energy.
    const double minimum = potentialEnergy(*context);
    RigidBodyMinimizationReport again = RigidBodyMinimizer::minimize(*context, 1e9);
    EXPECT_EQ(0, again.iterations);
    EXPECT_NEAR(minimum, again.finalEnergy, 1e-12 * std::fabs(minimum));
}

TEST_P(Minimizer, ClashingStartIsResolved) {
    // Two atoms of different molecules about 0.05 nm apart: forces of ~1e12 kJ/mol/nm, which
    // platforms that sum in fixed point clip (the minimizer then computes them on the CPU).
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 8);
    // Molecule 1 slides towards molecule 0 along the line of their centres until two atoms are 0.05 nm apart.
    auto closest = [&]() {
        double d = 1e9;
        for (int i : cluster.molecules[0])
            for (int j : cluster.molecules[1])
                d = std::min(d, std::sqrt((cluster.positions[i] - cluster.positions[j]).dot(cluster.positions[i] - cluster.positions[j])));
        return d;
    };
    const Vec3 towards = (cluster.positions[cluster.molecules[0][0]] - cluster.positions[cluster.molecules[1][0]]) * 1e-4;
    while (closest() > 0.05)
        for (int i : cluster.molecules[1])
            cluster.positions[i] += towards;
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(*cluster.system, *integrator);
    context->setPositions(cluster.positions);
    const double start = potentialEnergy(*context);
    ASSERT_GT(start, 1e8);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(*context, 10, 300);
    EXPECT_LT(report.finalEnergy, 0.0) << report.iterations << " iterations, " << report.evaluations << " evaluations, rms " << report.rmsForce;
    EXPECT_NEAR(report.finalEnergy, potentialEnergy(*context), 1e-6 * std::fabs(report.finalEnergy) + 1e-6);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(*context), cluster.molecules), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(AllPlatforms, Minimizer, ::testing::ValuesIn(configsOf("MRattle")), configName);

TEST_P(Minimizer, HugeForcesAreResolvedOrRefusedByName) {
    // OpenMM's TestLocalEnergyMinimizer::testLargeForces: ten charged particles within 1e-10 nm
    // (energy ~1e120 kJ/mol); here also as five rigid dimers, 0.1 nm long, on top of each other.
    for (bool dimers : {false, true}) {
        System system;
        NonbondedForce* nonbonded = new NonbondedForce();
        system.addForce(nonbonded);
        std::mt19937 generator(0);
        std::uniform_real_distribution<double> uniform(0.0, 1.0);
        vector<Vec3> positions;
        for (int i = 0; i < 10; i++) {
            system.addParticle(1.0);
            nonbonded->addParticle(1.0, 0.2, 1.0);
            positions.push_back(Vec3(uniform(generator), uniform(generator), uniform(generator)) * 1e-10);
        }
        vector<vector<int> > bodies;
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.01);
        if (dimers)
            for (int b = 0; b < 5; b++) {
                positions[b + 5] = positions[b] + Vec3(0.1, 0, 0);
                nonbonded->addException(b, b + 5, 0, 1, 0);
                bodies.push_back({b, b + 5});
                integrator->addRigidBody(bodies.back());
            }
        std::unique_ptr<Context> context = makeContext(system, *integrator);
        context->setPositions(positions);
        const double start = potentialEnergy(*context);
        const std::string why = dimers ? "dimers" : "free particles";
        try {
            RigidBodyMinimizer::minimize(*context, 1.0);
        } catch (const OpenMMException& e) {
            // Where the platform cannot compute the start (CPU's and OpenCL's single-precision
            // nonbonded kernels overflow), it says so, as OpenMM's own minimizer does there.
            EXPECT_NE("Reference", GetParam().platform) << "Reference computes this start: it must minimize";
            EXPECT_FALSE(std::isfinite(start)) << why << ": " << e.what();
            EXPECT_NE(std::string::npos, std::string(e.what()).find("not finite")) << e.what();
            continue;
        }
        ASSERT_TRUE(std::isfinite(start)) << why;
        const double end = potentialEnergy(*context);
        EXPECT_LT(end, 1e-100 * start) << why;
        double farthest = 0;
        for (const Vec3& r : positionsOf(*context))
            farthest = std::max(farthest, std::sqrt(r.dot(r)));
        EXPECT_GT(farthest, 0.1) << why;
        EXPECT_LT(farthest, 100.0) << why;
        EXPECT_LT(maxDistanceChange(positions, positionsOf(*context), bodies), 1e-9) << why;
    }
}

TEST(MinimizerReference, RigidWaterMinimumIsLocalEnergyMinimizersWithSettle) {
    // 8 rigid TIP3P waters: each minimizer, started from the other's minimum, finds nothing
    // more to gain. (From one start the two searches can reach different minima of the
    // cluster: neither is then wrong; the benchmark compares them on OpenMM's tip3p.pdb.)
    Cluster cluster = waterCluster(2, 0.31, 5);
    const double tolerance = 0.1;
    MRattleIntegrator integrator(0.001);
    Context rigid(*cluster.system, integrator, platform("Reference"));
    rigid.setPositions(cluster.positions);
    const double start = potentialEnergy(rigid);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(rigid, tolerance);
    EXPECT_LT(report.finalEnergy, start - 10);
    EXPECT_LE(rmsGeneralizedForce(rigid, cluster.molecules, {}), 1.05 * tolerance);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(rigid), cluster.molecules), 1e-12);

    VerletIntegrator verlet(0.001);
    verlet.setConstraintTolerance(1e-8);
    Context settle(*cluster.system, verlet, platform("Reference"));
    settle.setPositions(positionsOf(rigid));
    const double rigidMinimum = potentialEnergy(settle);
    LocalEnergyMinimizer::minimize(settle, tolerance);
    EXPECT_GT(potentialEnergy(settle), rigidMinimum - 1e-2);

    // From a start of OpenMM's, LocalEnergyMinimizer's minimum, the other way round.
    settle.setPositions(cluster.positions);
    LocalEnergyMinimizer::minimize(settle, tolerance);
    rigid.setPositions(positionsOf(settle));
    const double openmmMinimum = potentialEnergy(rigid);
    EXPECT_LT(openmmMinimum, start - 10);
    report = RigidBodyMinimizer::minimize(rigid, tolerance);
    // No higher, to round-off: with no iteration to make (OpenMM 8.1.2's minimum passes the
    // test) the search's energy of the same positions, rebuilt from its coordinates, differs
    // from the State's in the last digits (1e-13 kJ/mol measured).
    EXPECT_LE(report.finalEnergy, openmmMinimum + 1e-12 * std::fabs(openmmMinimum));
    EXPECT_GT(report.finalEnergy, openmmMinimum - 1e-2);
}

TEST(MinimizerReference, FirstStepIsTakenWithoutBacktracking) {
    // liblbfgs's unit first step, 1 nm in all, was halved at least once on every benchmark
    // system; the minimizer's scale makes it 0.003 nm rms, which the line search accepts.
    Cluster cluster = waterCluster(3, 0.31, 11);
    MRattleIntegrator integrator(0.001);
    Context context(*cluster.system, integrator, platform("Reference"));
    context.setPositions(cluster.positions);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 1e-6, 1);
    EXPECT_EQ(1, report.iterations);
    EXPECT_EQ(2, report.evaluations);  // the start and one trial point
    EXPECT_LT(report.finalEnergy, report.initialEnergy);
    // The rest of the search keeps L-BFGS's own steps: about one evaluation per iteration.
    context.setPositions(cluster.positions);
    report = RigidBodyMinimizer::minimize(context, 1.0);
    EXPECT_GT(report.iterations, 10);
    EXPECT_LT(report.evaluations, 1.2 * report.iterations + 2) << report.iterations << " iterations";
}

TEST(MinimizerReference, LinearBodyFarRotationFreeConstraintsAndVirtualSites) {
    // A linear 3-site body, a water turned nearly upside down in a field that flips it, a
    // free diatomic with a constraint, and a virtual site on the water.
    System system;
    vector<Vec3> positions;
    auto add = [&](double mass, const Vec3& r) {
        positions.push_back(r);
        return system.addParticle(mass);
    };
    const double angle = 170 * M_PI / 180;  // bisector of the water from +x
    const Vec3 axis(std::cos(angle), std::sin(angle), 0), side(-std::sin(angle), std::cos(angle), 0);
    const double oh = 0.09572, half = 104.52 / 2 * M_PI / 180;
    const int o = add(16, Vec3(0, 0, 0));
    const int h1 = add(1, axis * (oh * std::cos(half)) + side * (oh * std::sin(half)));
    const int h2 = add(1, axis * (oh * std::cos(half)) - side * (oh * std::sin(half)));
    const int c = add(12, Vec3(1.0, 0.2, 0.1));
    const int o1 = add(16, Vec3(1.0 + 0.116, 0.2, 0.1 + 0.01));
    const int o2 = add(16, Vec3(1.0 - 0.116, 0.2, 0.1 - 0.01));
    const int a = add(14, Vec3(-1.0, 0.5, 0));
    const int b = add(14, Vec3(-1.0, 0.5 + 0.13, 0.02));
    const int site = add(0, Vec3(0, 0, 0));
    system.setVirtualSite(site, new TwoParticleAverageSite(h1, h2, 0.5, 0.5));
    system.addConstraint(a, b, 0.11);
    // The field pulls hydrogens to +x and the oxygen to -x (no net force); a well holds
    // the rest: springs to the origin of the line's centre and of the diatomic.
    CustomExternalForce* field = new CustomExternalForce("q*x");
    field->addPerParticleParameter("q");
    field->addParticle(o, {100.0});
    field->addParticle(h1, {-50.0});
    field->addParticle(h2, {-50.0});
    system.addForce(field);
    CustomExternalForce* well = new CustomExternalForce("k*((x-x0)^2+(y-y0)^2+(z-z0)^2)");
    for (const char* name : {"k", "x0", "y0", "z0"})
        well->addPerParticleParameter(name);
    well->addParticle(o1, {50.0, 1.3, 0.2, 0.1});  // turns the line towards x
    well->addParticle(a, {50.0, -1.0, 0.5, 0.0});
    well->addParticle(b, {50.0, -1.0, 0.8, 0.0});  // pulls on the constraint
    well->addParticle(site, {200.0, 0.5, 0.0, 0.0});  // its force goes to the hydrogens
    system.addForce(well);
    MRattleIntegrator integrator(0.001);
    integrator.addRigidBody({o, h1, h2});
    integrator.addRigidBody({c, o1, o2});
    Context context(system, integrator, platform("Reference"));
    context.setPositions(positions);
    context.computeVirtualSites();
    ASSERT_TRUE(integrator.isBodyLinear(1));
    const double start = potentialEnergy(context);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 1e-3);
    EXPECT_LT(report.finalEnergy, start);
    const vector<Vec3> x = positionsOf(context);
    EXPECT_LT(maxDistanceChange(positions, x, integrator.getBodiesInEffect()), 1e-12);
    // The water turned ~170 degrees: its bisector now points along the field's pull, +x.
    const Vec3 bisector = (x[h1] + x[h2]) * 0.5 - x[o];
    EXPECT_GT(bisector[0] / std::sqrt(bisector.dot(bisector)), std::cos(0.01));
    // The line turned into x (the linear body has only its two rotations).
    const Vec3 line = x[o1] - x[o2];
    EXPECT_GT(line[0] / std::sqrt(line.dot(line)), 0.99);
    // The free constraint holds to the integrator's tolerance, the virtual site follows.
    const Vec3 ab = x[b] - x[a];
    EXPECT_NEAR(0.11, std::sqrt(ab.dot(ab)), 0.11 * 1e-4);
    EXPECT_GT(x[b][1], 0.5 + 0.11 * 0.9);  // the diatomic turned to the well along y
    const Vec3 average = (x[h1] + x[h2]) * 0.5;
    EXPECT_LT(std::sqrt((x[site] - average).dot(x[site] - average)), 1e-12);
    EXPECT_LE(rmsGeneralizedForce(context, integrator.getBodiesInEffect(), {}), 1.0);  // bodies: converged
}

TEST(MinimizerReference, BodyTurnsFarAboutOneAxis) {
    // A triangle about the origin whose first atom is pulled round the z axis by a smooth
    // field of its angle t, -k cos(t + s cos t) (s < 1: one minimum, at t + s cos t = 0, and
    // one maximum, at t + s cos t = pi, 4.42 rad apart the long way round). From just past
    // the maximum on that side the body turns 4.27 rad, beyond pi: the search restarts about
    // a new frame on the way. A well on every atom holds the centroid, with no torque about it.
    const double s = 0.8;
    auto solve = [&](double target, double t) {  // Newton: t + s cos t = target
        for (int k = 0; k < 50; k++)
            t -= (t + s * std::cos(t) - target) / (1 - s * std::sin(t));
        return t;
    };
    const double minimum = solve(0, 0), maximum = solve(M_PI, 3);
    ASSERT_NEAR(4.4239, maximum - minimum, 1e-4);
    System system;
    vector<Vec3> positions;
    const double radius = 0.1, startAngle = maximum - 0.15;
    CustomExternalForce* field = new CustomExternalForce("-10*cos(t + 0.8*cos(t)); t = atan2(y, x)");
    CustomExternalForce* well = new CustomExternalForce("1000*(x^2+y^2+z^2)");
    for (int k = 0; k < 3; k++) {
        const double a = startAngle + 2 * M_PI * k / 3;
        positions.push_back(Vec3(radius * std::cos(a), radius * std::sin(a), 0));
        well->addParticle(system.addParticle(12), {});
    }
    field->addParticle(0, {});
    system.addForce(field);
    system.addForce(well);
    MRattleIntegrator integrator(0.001);
    integrator.addRigidBody({0, 1, 2});
    Context context(system, integrator, platform("Reference"));
    context.setPositions(positions);
    context.setVelocitiesToTemperature(300, 3);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 1e-3);
    const vector<Vec3> x = positionsOf(context);
    EXPECT_LT(maxDistanceChange(positions, x, integrator.getBodiesInEffect()), 1e-12);
    EXPECT_NEAR(minimum, std::atan2(x[0][1], x[0][0]), 1e-3) << report.iterations << " iterations";
    EXPECT_NEAR(-10 + 1000 * 3 * radius * radius, report.finalEnergy, 1e-3);
    EXPECT_LT(maxRigidityRate(context, integrator.getBodiesInEffect()), 1e-10);
}

TEST(MinimizerReference, CompoundIntegratorUsesItsRigidMember) {
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 4);
    CompoundIntegrator compound;
    compound.addIntegrator(new VerletIntegrator(0.001));
    compound.addIntegrator(new MRattleIntegrator(0.001));
    compound.setCurrentIntegrator(0);
    Context context(*cluster.system, compound, platform("Reference"));
    context.setPositions(cluster.positions);
    EXPECT_TRUE(RigidBodyMinimizer::appliesTo(context));
    const double start = potentialEnergy(context);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 5.0);
    EXPECT_LT(report.finalEnergy, start);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(context), cluster.molecules), 1e-12);
}

TEST(MinimizerReference, NonFiniteEnergyIsNamedAndLeavesTheBestPoint) {
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 5);
    // A constant pull on the first molecule towards +x, into a region where the energy is NaN.
    CustomExternalForce* pull = new CustomExternalForce("-100*x + 1e-6*sqrt(2-x)");
    for (int i : cluster.molecules[0])
        pull->addParticle(i, {});
    cluster.system->addForce(pull);
    MRattleIntegrator integrator(0.001);
    Context context(*cluster.system, integrator, platform("Reference"));
    context.setPositions(cluster.positions);
    context.setVelocitiesToTemperature(300, 5);
    const double start = potentialEnergy(context);
    const std::string message = messageOf([&] { RigidBodyMinimizer::minimize(context, 1e-3); });
    EXPECT_NE(std::string::npos, message.find("potential energy is not finite")) << message;
    EXPECT_NE(std::string::npos, message.find("best point")) << message;
    const double left = potentialEnergy(context);
    EXPECT_TRUE(std::isfinite(left));
    EXPECT_LT(left, start);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(context), cluster.molecules), 1e-12);
    // The integrator saw the positions left: velocities rigid at them, and it steps.
    EXPECT_LT(maxRigidityRate(context, cluster.molecules), 1e-10);
    integrator.step(5);
    EXPECT_LT(maxDistanceChange(cluster.positions, positionsOf(context), cluster.molecules), 1e-9);
}

TEST(MinimizerReference, BadArgumentsAndIterationLimit) {
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 6);
    MRattleIntegrator integrator(0.001);
    Context context(*cluster.system, integrator, platform("Reference"));
    EXPECT_NE(std::string::npos, messageOf([&] { RigidBodyMinimizer::minimize(context); }).find("positions"));
    context.setPositions(cluster.positions);
    EXPECT_NE(std::string::npos, messageOf([&] { RigidBodyMinimizer::minimize(context, -1); }).find("tolerance"));
    EXPECT_NE(std::string::npos, messageOf([&] { RigidBodyMinimizer::minimize(context, NAN); }).find("tolerance"));
    EXPECT_NE(std::string::npos, messageOf([&] { RigidBodyMinimizer::minimize(context, 1, -1); }).find("maxIterations"));
    VerletIntegrator verlet(0.001);
    Context flexible(*cluster.system, verlet, platform("Reference"));
    flexible.setPositions(cluster.positions);
    EXPECT_FALSE(RigidBodyMinimizer::appliesTo(flexible));
    EXPECT_NE(std::string::npos,
              messageOf([&] { RigidBodyMinimizer::minimize(flexible); }).find("LocalEnergyMinimizer"));
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 1e-6, 3);
    EXPECT_EQ(3, report.iterations);
    EXPECT_LT(report.finalEnergy, report.initialEnergy);
}
