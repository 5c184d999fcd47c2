/*
 * MRattleLangevinIntegrator on every platform it runs on: at zero friction its positions
 * are MRattleIntegrator's; bodies stay rigid under noise; it reaches the bath temperature
 * (kinetic, with the rigid-body degrees of freedom, within its statistical error); a seed
 * fixes the noise; checkpoints restore the random stream bit for bit; bad parameters are
 * refused; it serializes; it runs inside a CompoundIntegrator with MRattleIntegrator; at zero
 * temperature friction alone damps (OpenMM's single-bond test, free and rigid).
 */
#include "MRattleLangevinIntegrator.h"
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

class Langevin : public ::testing::TestWithParam<string> {
protected:
    void SetUp() override {
        MRATTLE_SKIP_IF_UNAVAILABLE(GetParam());
    }
    std::unique_ptr<Context> makeContext(const System& system, Integrator& integrator) const {
        return std::unique_ptr<Context>(
            new Context(system, integrator, platform(GetParam()), platformProperties(GetParam())));
    }
};

vector<string> langevinPlatforms() {
    vector<string> names;
    for (const Config& config : configsOf("MRattleLangevin"))
        names.push_back(config.platform);
    return names;
}

/** 8 tetrahedral molecules (bodies) with LJ and charges, plus 4 free particles held in pairs by constraints. */
Cluster mixedBodiesAndConstraints() {
    Cluster c = buildCluster(tetrahedral(), 2, 0.6, 8);
    NonbondedForce* nonbonded = nullptr;
    for (int f = 0; f < c.system->getNumForces(); f++)
        if (auto* force = dynamic_cast<NonbondedForce*>(&c.system->getForce(f)))
            nonbonded = force;
    for (int k = 0; k < 4; k++) {
        int p = c.system->addParticle(14.0);
        nonbonded->addParticle(0.0, 0.3, 0.5);
        c.positions.push_back(Vec3(1.5 + 0.12 * (k % 2), 0.4 * (k / 2), 0.0));
    }
    int n = c.system->getNumParticles();
    c.system->addConstraint(n - 4, n - 3, 0.12);
    c.system->addConstraint(n - 2, n - 1, 0.12);
    return c;
}

double kineticTemperature(Context& context, int dof) {
    const double temperature = 2 * context.getState(State::Energy).getKineticEnergy() / (dof * BOLTZ);
    // The integrator's own (what OpenMM 8's StateDataReporter reports) is the same number.
    RigidBodyIntegrator& integrator = dynamic_cast<RigidBodyIntegrator&>(context.getIntegrator());
    EXPECT_NEAR(temperature, integrator.computeSystemTemperature(), 1e-9 * temperature);
    return temperature;
}

} // namespace

TEST_P(Langevin, ZeroFrictionGivesMRattlePositions) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 3);
    vector<vector<Vec3> > positions;
    for (int kind = 0; kind < 2; kind++) {
        std::unique_ptr<RigidBodyIntegrator> integrator;
        if (kind == 0)
            integrator.reset(new MRattleIntegrator(0.002));
        else
            integrator.reset(new MRattleLangevinIntegrator(300, 0.0, 0.002));
        std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
        context->setPositions(c.positions);
        context->setVelocitiesToTemperature(300, 3);
        integrator->step(100);
        positions.push_back(context->getState(State::Positions).getPositions());
    }
    const double difference = maxDeviation(positions[0], positions[1]);
    std::cout << GetParam() << ": zero friction vs MRattleIntegrator after 100 steps: " << difference << " nm" << std::endl;
    EXPECT_GT(maxDeviation(c.positions, positions[0]), 1e-3);
    EXPECT_LT(difference, GetParam() == "Reference" ? 1e-12 : 1e-6);
}

TEST_P(Langevin, BodiesStayRigidAndFreeConstraintsHoldUnderNoise) {
    Cluster c = mixedBodiesAndConstraints();
    MRattleLangevinIntegrator integrator(300, 10.0, 0.002);
    for (const vector<int>& body : c.molecules)
        integrator.addRigidBody(body);
    std::unique_ptr<Context> context = makeContext(*c.system, integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 1);
    EXPECT_EQ(8 * 6 + 4 * 3 - 2, integrator.getNumDegreesOfFreedom());
    integrator.step(300);
    State state = context->getState(State::Positions | State::Velocities);
    EXPECT_LT(maxDistanceChange(c.positions, state.getPositions(), c.molecules), 1e-9);
    const int n = c.system->getNumParticles();
    for (int pair : {n - 4, n - 2}) {
        Vec3 d = state.getPositions()[pair + 1] - state.getPositions()[pair];
        EXPECT_NEAR(0.12, std::sqrt(d.dot(d)), 1e-5);
    }
}

TEST_P(Langevin, ReachesTheBathTemperature) {
    // 27 tetrahedral molecules held together by LJ, friction 20/ps: after 4 ps the kinetic
    // temperature with the rigid-body degrees of freedom, averaged over 20 blocks of 0.4 ps
    // (each longer than the velocity correlation time 1/(2 friction)), is within 3 standard
    // errors of the bath's. The seed is fixed, so the test is repeatable.
    Cluster c = buildCluster(tetrahedral(), 3, 0.45, 5);
    MRattleLangevinIntegrator integrator(250, 20.0, 0.002);
    integrator.setRandomNumberSeed(11);
    std::unique_ptr<Context> context = makeContext(*c.system, integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(400, 2);  // start hot
    integrator.step(2000);
    const int dof = integrator.getNumDegreesOfFreedom();
    vector<double> blocks;
    for (int b = 0; b < 20; b++) {
        double sum = 0;
        for (int s = 0; s < 20; s++) {
            integrator.step(10);
            sum += kineticTemperature(*context, dof);
        }
        blocks.push_back(sum / 20);
    }
    const double meanT = mean(blocks), error = standardDeviation(blocks) / std::sqrt(blocks.size() - 1.0);
    std::cout << GetParam() << ": kinetic temperature " << meanT << " +- " << error << " K (bath 250 K)" << std::endl;
    EXPECT_GT(error, 0.0);
    EXPECT_LT(std::fabs(meanT - 250), 3 * error);
    EXPECT_LT(error, 5.0);  // the test resolves a few percent
}

TEST_P(Langevin, ASeedFixesTheNoiseAndACheckpointRestoresIt) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 4);
    auto run = [&](int seed, int steps) {
        MRattleLangevinIntegrator integrator(300, 5.0, 0.002);
        integrator.setRandomNumberSeed(seed);
        std::unique_ptr<Context> context = makeContext(*c.system, integrator);
        context->setPositions(c.positions);
        context->setVelocitiesToTemperature(300, 1);
        integrator.step(steps);
        return context->getState(State::Positions).getPositions();
    };
    EXPECT_EQ(0.0, maxDeviation(run(5, 50), run(5, 50)));
    EXPECT_GT(maxDeviation(run(5, 50), run(6, 50)), 1e-6);

    // Seed 0 (a new stream each Context): a checkpoint still continues bit for bit, in the same Context and a new one.
    MRattleLangevinIntegrator integrator(300, 5.0, 0.002);
    std::unique_ptr<Context> context = makeContext(*c.system, integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 1);
    integrator.step(20);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    integrator.step(40);
    State uninterrupted = context->getState(State::Positions | State::Velocities);
    std::istringstream again(checkpoint.str());
    context->loadCheckpoint(again);
    integrator.step(40);
    State continued = context->getState(State::Positions | State::Velocities);
    MRattleLangevinIntegrator restartedIntegrator(300, 5.0, 0.002);
    std::unique_ptr<Context> restarted = makeContext(*c.system, restartedIntegrator);
    std::istringstream fresh(checkpoint.str());
    restarted->loadCheckpoint(fresh);
    restartedIntegrator.step(40);
    for (const State& state : {continued, restarted->getState(State::Positions | State::Velocities)}) {
        EXPECT_EQ(0.0, maxDeviation(uninterrupted.getPositions(), state.getPositions()));
        EXPECT_EQ(0.0, maxDeviation(uninterrupted.getVelocities(), state.getVelocities()));
    }
}

TEST_P(Langevin, RunsInACompoundIntegratorWithMRattle) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 9);
    CompoundIntegrator compound;
    compound.addIntegrator(new MRattleLangevinIntegrator(300, 5.0, 0.001));
    compound.addIntegrator(new MRattleIntegrator(0.001));
    std::unique_ptr<Context> context = makeContext(*c.system, compound);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 2);
    for (int round = 0; round < 4; round++) {
        compound.setCurrentIntegrator(round % 2);
        compound.step(25);
    }
    EXPECT_LT(maxDistanceChange(c.positions, context->getState(State::Positions).getPositions(), c.molecules), 1e-10);
}

TEST_P(Langevin, ZeroTemperatureDampsAFreeOscillatorAsOpenMMsSingleBondTest) {
    // OpenMM's TestLangevinMiddleIntegrator::testSingleBond: two free particles (each its own
    // one-particle body) on a harmonic bond at T = 0 are a damped oscillator; friction alone acts.
    System system;
    system.addParticle(2.0);
    system.addParticle(2.0);
    HarmonicBondForce* bond = new HarmonicBondForce();
    bond->addBond(0, 1, 1.5, 1);
    system.addForce(bond);
    MRattleLangevinIntegrator integrator(0, 0.1, 0.01);
    integrator.addRigidBody({0});
    integrator.addRigidBody({1});
    std::unique_ptr<Context> context = makeContext(system, integrator);
    context->setPositions({Vec3(-1, 0, 0), Vec3(1, 0, 0)});
    const double freq = std::sqrt(1 - 0.05 * 0.05);
    for (int i = 0; i < 1000; i++) {
        const State state = context->getState(State::Positions | State::Velocities);
        const double t = state.getTime();
        const double distance = 1.5 + 0.5 * std::exp(-0.05 * t) * std::cos(freq * t);
        const double speed = -0.5 * std::exp(-0.05 * t) * (0.05 * std::cos(freq * t) + freq * std::sin(freq * t));
        ASSERT_NEAR(-0.5 * distance, state.getPositions()[0][0], 0.02) << "t = " << t;
        ASSERT_NEAR(0.5 * distance, state.getPositions()[1][0], 0.02) << "t = " << t;
        ASSERT_NEAR(-0.5 * speed, state.getVelocities()[0][0], 0.02) << "t = " << t;
        ASSERT_NEAR(0.5 * speed, state.getVelocities()[1][0], 0.02) << "t = " << t;
        integrator.step(1);
    }
    // The figure: particle 0's velocity after 100 steps is the same on every platform.
    MRattleLangevinIntegrator reference(0, 0.1, 0.01);
    reference.addRigidBody({0});
    reference.addRigidBody({1});
    Context onReference(system, reference, platform("Reference"));
    onReference.setPositions({Vec3(-1, 0, 0), Vec3(1, 0, 0)});
    context->setPositions({Vec3(-1, 0, 0), Vec3(1, 0, 0)});
    context->setVelocities({Vec3(), Vec3()});
    integrator.step(100);
    reference.step(100);
    EXPECT_NEAR(onReference.getState(State::Velocities).getVelocities()[0][0],
                context->getState(State::Velocities).getVelocities()[0][0], 1e-9);
}

TEST_P(Langevin, ZeroTemperatureDampsASpinningRigidRotor) {
    // The same test's rigid form: a rigid dimer spinning and drifting with no force loses its
    // angular and linear momentum as exp(-friction t), each step's factor exp(-friction h).
    System system;
    system.addParticle(2.0);
    system.addParticle(2.0);
    const double friction = 0.1, h = 0.01;
    MRattleLangevinIntegrator integrator(0, friction, h);
    integrator.addRigidBody({0, 1});
    std::unique_ptr<Context> context = makeContext(system, integrator);
    context->setPositions({Vec3(-0.75, 0, 0), Vec3(0.75, 0, 0)});
    context->setVelocities({Vec3(0.1, -0.5, 0), Vec3(0.1, 0.5, 0)});
    const int steps = 500;
    integrator.step(steps);
    const State state = context->getState(State::Positions | State::Velocities);
    const vector<double> m = masses(system);
    const double decay = std::exp(-friction * h * steps);
    const Vec3 p = totalMomentum(m, state.getVelocities());
    const Vec3 center = (state.getPositions()[0] + state.getPositions()[1]) * 0.5;
    vector<Vec3> relative = {state.getPositions()[0] - center, state.getPositions()[1] - center};
    const Vec3 l = angularMomentum(m, relative, state.getVelocities());
    EXPECT_NEAR(0.4 * decay, p[0], 1e-9);
    EXPECT_NEAR(0, p[1], 1e-9);
    EXPECT_NEAR(2 * 2.0 * 0.75 * 0.5 * decay, l[2], 1e-9);
    EXPECT_NEAR(1.5, std::sqrt((state.getPositions()[1] - state.getPositions()[0]).dot(
                                   state.getPositions()[1] - state.getPositions()[0])), 1e-9);
}

TEST(LangevinApi, RefusesBadParametersAndSerializes) {
    EXPECT_NE(string::npos, messageOf([] { MRattleLangevinIntegrator(-1, 1, 0.002); }).find("temperature"));
    EXPECT_NE(string::npos, messageOf([] { MRattleLangevinIntegrator(300, std::nan(""), 0.002); }).find("friction"));
    MRattleLangevinIntegrator integrator(310, 2.5, 0.003);
    EXPECT_NE(string::npos, messageOf([&] { integrator.setFriction(-2); }).find("friction"));
    EXPECT_NE(string::npos, messageOf([&] { integrator.setTemperature(INFINITY); }).find("temperature"));
    integrator.setRandomNumberSeed(77);
    integrator.addRigidBody({0, 1, 2});
    const string xml = toXml(integrator);
    std::unique_ptr<Integrator> copy = fromXml(xml);
    MRattleLangevinIntegrator& read = dynamic_cast<MRattleLangevinIntegrator&>(*copy);
    EXPECT_EQ(310, read.getTemperature());
    EXPECT_EQ(2.5, read.getFriction());
    EXPECT_EQ(0.003, read.getStepSize());
    EXPECT_EQ(77, read.getRandomNumberSeed());
    EXPECT_EQ(1, read.getNumRigidBodies());
    EXPECT_NE(string::npos, messageOfXmlWith(xml, "friction=\"2.5\"", "friction=\"-1\"").find("friction"));
}

// Named by platform ("Platforms/Langevin.X/CUDA"), so that a platform's cases can be selected.
INSTANTIATE_TEST_SUITE_P(Platforms, Langevin, ::testing::ValuesIn(langevinPlatforms()),
                         [](const ::testing::TestParamInfo<string>& info) { return info.param; });
