/*
 * Both Drude integrators on every platform that runs them: a DrudeForce added to the System
 * (or given more pairs) after the Context was created, which the Context does not see, makes
 * the next step fail naming the integrator, with positions and velocities as they were; after
 * Context::reinitialize() the same integrator steps.
 */
#include "DrudeTestSystem.h"
#include "TestSupport.h"
#include "openmm/DrudeForce.h"
#include <gtest/gtest.h>

using namespace OpenMM;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

namespace {

class DrudeSystemChanges : public ::testing::TestWithParam<Config> {};

void expectSame(const vector<Vec3>& before, const vector<Vec3>& after) {
    for (size_t i = 0; i < before.size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(before[i][k], after[i][k]) << "particle " << i;
}

TEST_P(DrudeSystemChanges, ADrudeForceAddedAfterTheContextFailsTheStepUntilReinitialize) {
    MRATTLE_SKIP_IF_UNAVAILABLE(GetParam().platform);
    Drude::DrudeSystem d = Drude::drudeWaters(2, 1, 0.4);
    d.system.removeForce(1);   // the DrudeForce: the Context starts without one
    std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> integrator = makeIntegrator(GetParam().integrator, 0.001);
    for (const vector<int>& body : d.bodies)
        integrator->addRigidBody(body);
    Context context(d.system, *integrator, Platform::getPlatformByName(GetParam().platform),
                    platformProperties(GetParam().platform));
    context.setPositions(d.positions);
    integrator->step(2);
    DrudeForce* drude = new DrudeForce();
    for (const auto& pair : d.pairs)
        drude->addParticle(pair.first, pair.second, -1, -1, -1, -1.2, 0.001, 1.0, 1.0);
    d.system.addForce(drude);
    const State before = context.getState(State::Positions | State::Velocities);
    const string message = messageOf([&] { integrator->step(3); });
    EXPECT_NE(string::npos, message.find(GetParam().integrator)) << message;
    EXPECT_NE(string::npos, message.find("reinitialize")) << message;
    const State after = context.getState(State::Positions | State::Velocities);
    expectSame(before.getPositions(), after.getPositions());
    expectSame(before.getVelocities(), after.getVelocities());
    // More pairs in the same force: refused too; reinitialize() then sees them.
    context.reinitialize(true);
    integrator->step(2);
    drude->addParticle(d.bodies[0][1], d.bodies[0][0], -1, -1, -1, -0.1, 0.0001, 1.0, 1.0);
    EXPECT_NE(string::npos, messageOf([&] { integrator->step(1); }).find("reinitialize"));
}

vector<Config> drudeConfigs() {
    vector<Config> configs;
    for (const string name : {"MRattleDrudeLangevin", "MRattleDrudeNoseHoover"})
        for (const Config& config : configsOf(name))
            configs.push_back(config);
    return configs;
}

INSTANTIATE_TEST_SUITE_P(Drude, DrudeSystemChanges, ::testing::ValuesIn(drudeConfigs()), configName);

} // namespace

#endif // MRATTLE_HAVE_DRUDE
