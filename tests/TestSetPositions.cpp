/*
 * The positions a user sets are the positions used, as with OpenMM's own integrators, on
 * every platform and integrator: OpenMM's TestVirtualSites pattern (many configurations of a
 * body with a LocalCoordinatesSite set, each checked, then a step) steps from the last one.
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

class SetPositions : public RigidBodyTest {};

Vec3 unit(const Vec3& v) {
    return v / std::sqrt(v.dot(v));
}

} // namespace

TEST_P(SetPositions, ManyConfigurationsWithAVirtualSiteThenAStep) {
    // A body of three particles and a LocalCoordinatesSite on them, pulled by an external force.
    System system;
    for (int i = 0; i < 3; i++)
        system.addParticle(12.0 + 2 * i);
    system.addParticle(0.0);
    const Vec3 originWeights(0.2, 0.3, 0.5), xWeights(-1.0, 0.5, 0.5), yWeights(0.0, -1.0, 1.0), local(0.4, 0.3, 0.2);
    system.setVirtualSite(3, new LocalCoordinatesSite(0, 1, 2, originWeights, xWeights, yWeights, local));
    CustomExternalForce* pull = new CustomExternalForce("2*x - 3*y + z");
    pull->addParticle(3, {});
    system.addForce(pull);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    integrator->addRigidBody({0, 1, 2});
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    std::mt19937 generator(3);
    std::uniform_real_distribution<double> uniform(-0.5, 0.5);
    vector<Vec3> positions(4);
    for (int configuration = 0; configuration < 100; configuration++) {
        // Each configuration a new shape of the body.
        for (int i = 0; i < 3; i++)
            positions[i] = Vec3(uniform(generator), uniform(generator), uniform(generator));
        context->setPositions(positions);
        context->computeVirtualSites();
        const State state = context->getState(State::Positions | State::Forces);
        const vector<Vec3>& x = state.getPositions();
        Vec3 origin, xAxis, yAxis;
        for (int i = 0; i < 3; i++) {
            origin += x[i] * originWeights[i];
            xAxis += x[i] * xWeights[i];
            yAxis += x[i] * yWeights[i];
        }
        const Vec3 zAxis = unit(xAxis.cross(yAxis));
        xAxis = unit(xAxis);
        yAxis = zAxis.cross(xAxis);
        const Vec3 site = origin + xAxis * local[0] + yAxis * local[1] + zAxis * local[2];
        for (int d = 0; d < 3; d++) {
            ASSERT_NEAR(positions[0][d], x[0][d], 1e-12) << "configuration " << configuration;
            ASSERT_NEAR(site[d], x[3][d], 1e-9) << "configuration " << configuration;
        }
        // The site's force went to the body's particles.
        const Vec3 total = state.getForces()[0] + state.getForces()[1] + state.getForces()[2];
        ASSERT_NEAR(0, (total - Vec3(-2, 3, -1)).dot(total - Vec3(-2, 3, -1)), 1e-12) << "configuration " << configuration;
    }
    // The step starts from the configuration set last: its shape is the body's.
    integrator->step(5);
    EXPECT_LT(maxDistanceChange(positions, context->getState(State::Positions).getPositions(), {{0, 1, 2}}), 1e-9);
    EXPECT_EQ(5, context->getStepCount());
}

TEST_P(SetPositions, PositionsSetAgainAfterAStepChangeTheShapes) {
    // Set, step, set a deformed copy and a rigid move of it: each step keeps what was set last.
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 3);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    std::unique_ptr<Context> context = makeContext(*cluster.system, *integrator);
    context->setPositions(cluster.positions);
    integrator->step(1);
    vector<Vec3> deformed = context->getState(State::Positions).getPositions();
    deformed[cluster.molecules[0][1]] += Vec3(2e-3, -1e-3, 0);
    context->setPositions(deformed);
    for (Vec3& r : deformed)
        r += Vec3(0.01, -0.02, 0.03);
    context->setPositions(deformed);
    integrator->step(2);
    EXPECT_LT(maxDistanceChange(deformed, context->getState(State::Positions).getPositions(), cluster.molecules), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, SetPositions, ::testing::ValuesIn(allConfigs()), configName);
