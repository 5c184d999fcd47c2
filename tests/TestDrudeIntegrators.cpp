/*
 * Both Drude integrators on every platform that runs them: setVelocitiesToTemperature() draws
 * the bodies at the temperature and the Drude particles' relative motion at the Drude
 * temperature; a DrudeForce added to the System (or given more pairs) after the Context was
 * created, which the Context does not see, makes the next step fail naming the integrator,
 * with positions and velocities as they were; after Context::reinitialize() it steps.
 */
#include "DrudeTestSystem.h"
#include "TestSupport.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "openmm/DrudeForce.h"
#include <cmath>
#include <gtest/gtest.h>

using namespace OpenMM;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

namespace {

class DrudeIntegrators : public ::testing::TestWithParam<Config> {};

void expectSame(const vector<Vec3>& before, const vector<Vec3>& after) {
    for (size_t i = 0; i < before.size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(before[i][k], after[i][k]) << "particle " << i;
}

TEST_P(DrudeIntegrators, ADrudeForceAddedAfterTheContextFailsTheStepUntilReinitialize) {
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

TEST_P(DrudeIntegrators, VelocitiesForTemperatureDrawTheDrudeParticlesAtTheDrudeTemperature) {
    MRATTLE_SKIP_IF_UNAVAILABLE(GetParam().platform);
    // No force at the start (no NonbondedForce, each Drude particle on its core): the shift by
    // half a step of the forces that setVelocitiesToTemperature() gives a leapfrog integrator
    // (OpenMM's, MRattleDrudeLangevin's) is then zero, and what is measured is the draw.
    Drude::DrudeSystem d = Drude::drudeWaters(27, 0, 0.4);
    d.system.removeForce(0);
    for (const auto& pair : d.pairs)
        d.positions[pair.first] = d.positions[pair.second];
    std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> integrator = makeIntegrator(GetParam().integrator, 0.001);
    for (const vector<int>& body : d.bodies)
        integrator->addRigidBody(body);
    Context context(d.system, *integrator, Platform::getPlatformByName(GetParam().platform),
                    platformProperties(GetParam().platform));
    context.setPositions(d.positions);
    auto* langevin = dynamic_cast<MRattlePlugin::MRattleDrudeLangevinIntegrator*>(integrator.get());
    auto* noseHoover = dynamic_cast<MRattlePlugin::MRattleDrudeNoseHooverIntegrator*>(integrator.get());
    ASSERT_TRUE(langevin || noseHoover);
    const double drudeTarget = 5.0;
    langevin ? langevin->setDrudeTemperature(drudeTarget) : noseHoover->setDrudeTemperature(drudeTarget);
    // Ten draws: 81 relative and 159 other degrees of freedom each, so each mean has a relative
    // standard error of about sqrt(2/810) = 5% (Drude) and 4% (bodies); allowed 4 of them.
    double drude = 0, body = 0;
    const int draws = 10;
    for (int seed = 1; seed <= draws; seed++) {
        context.setVelocitiesToTemperature(300, seed);
        drude += (langevin ? langevin->computeDrudeTemperature() : noseHoover->computeDrudeTemperature()) / draws;
        body += (langevin ? langevin->computeBodyTemperature() : noseHoover->computeBodyTemperature()) / draws;
    }
    EXPECT_NEAR(drudeTarget, drude, 4 * std::sqrt(2.0 / (81 * draws)) * drudeTarget);
    EXPECT_NEAR(300, body, 4 * std::sqrt(2.0 / (159 * draws)) * 300);
}

vector<Config> drudeConfigs() {
    vector<Config> configs;
    for (const string name : {"MRattleDrudeLangevin", "MRattleDrudeNoseHoover"})
        for (const Config& config : configsOf(name))
            configs.push_back(config);
    return configs;
}

INSTANTIATE_TEST_SUITE_P(Drude, DrudeIntegrators, ::testing::ValuesIn(drudeConfigs()), configName);

} // namespace

#endif // MRATTLE_HAVE_DRUDE
