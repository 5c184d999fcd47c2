/*
 * Every platform runs the same physics as Reference, with every rigid-body integrator.
 * The CPU platform's nonbonded forces are single precision, so trajectories part at
 * round-off and drift apart; the test holds the integrator's CPU-vs-Reference difference
 * to what OpenMM's own VerletIntegrator shows on the same System from the same start.
 *
 * PlatformAgreement runs for every config whose platform is not Reference (each compared
 * with Reference, with the same integrator); Platforms for every config (allConfigs()).
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <iostream>
#include <map>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

/** Positions after the steps from the given start, on one platform. */
vector<Vec3> finalPositions(const Cluster& c, Integrator& integrator, const std::string& platformName,
                            const State& start, int steps) {
    Context context(*c.system, integrator, platform(platformName), platformProperties(platformName));
    context.setPositions(start.getPositions());
    context.setVelocities(start.getVelocities());
    integrator.step(steps);
    return context.getState(State::Positions).getPositions();
}

/** Every config but those on Reference: each is compared with Reference. */
vector<Config> nonReferenceConfigs() {
    vector<Config> configs;
    for (const Config& config : allConfigs())
        if (config.platform != "Reference")
            configs.push_back(config);
    return configs;
}

class PlatformAgreement : public RigidBodyTest {};
class Platforms : public RigidBodyTest {};

} // namespace

TEST_P(PlatformAgreement, AgreesWithReferenceAsVerletDoes) {
    const std::string name = GetParam().platform;
    Cluster c = buildCluster(benzene(), 2, 0.65, 4);
    const double stepSize = 0.001;
    const int steps = 200;
    // One rigid start for everything.
    std::unique_ptr<RigidBodyIntegrator> setup = makeIntegrator(stepSize);
    Context setupContext(*c.system, *setup, platform("Reference"));
    setupContext.setPositions(c.positions);
    setupContext.setVelocitiesToTemperature(300, 2);
    State start = setupContext.getState(State::Positions | State::Velocities);

    std::unique_ptr<RigidBodyIntegrator> rigidReference = makeIntegrator(stepSize), rigidOther = makeIntegrator(stepSize);
    // A device draws noise from OpenMM's device generator, Reference and CPU from the
    // kernel's own: compare the deterministic part there, without the noise.
    if (isDevicePlatform(name) && GetParam().traits().stochastic)
        for (RigidBodyIntegrator* integrator : {rigidReference.get(), rigidOther.get()})
            GetParam().traits().removeNoise(*integrator);
    vector<Vec3> a = finalPositions(c, *rigidReference, "Reference", start, steps);
    vector<Vec3> b = finalPositions(c, *rigidOther, name, start, steps);
    VerletIntegrator verletReference(stepSize), verletOther(stepSize);
    vector<Vec3> va = finalPositions(c, verletReference, "Reference", start, steps);
    vector<Vec3> vb = finalPositions(c, verletOther, name, start, steps);
    const double rigid = maxDeviation(a, b), verlet = maxDeviation(va, vb);
    std::cout << name << " vs Reference after " << steps << " steps: " << GetParam().integrator << " " << rigid
              << " nm, VerletIntegrator " << verlet << " nm; rigidity on " << name << " "
              << maxDistanceChange(start.getPositions(), b, c.molecules) << " nm" << std::endl;
    EXPECT_GT(maxDeviation(start.getPositions(), a), 1e-2);  // the molecules moved
    EXPECT_GT(rigid, 0.0);  // the platform's own forces were used
    EXPECT_LT(rigid, 5 * verlet);
    EXPECT_LT(rigid, 1e-4);
    EXPECT_LT(maxDistanceChange(start.getPositions(), b, c.molecules), 1e-12);
}

TEST_P(Platforms, BodySemanticsMatchReference) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.45, 5);
    c.system->addForce(new CMMotionRemover());
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 3);
    EXPECT_EQ(c.molecules, integrator->getBodiesInEffect());
    EXPECT_EQ(8 * 6 - 3, integrator->getNumDegreesOfFreedom());
    integrator->step(100);
    EXPECT_LT(maxDistanceChange(c.positions, context->getState(State::Positions).getPositions(), c.molecules), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, Platforms, ::testing::ValuesIn(allConfigs()), configName);
INSTANTIATE_TEST_SUITE_P(NonReference, PlatformAgreement, ::testing::ValuesIn(nonReferenceConfigs()), configName);
