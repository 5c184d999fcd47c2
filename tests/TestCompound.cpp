/*
 * Rigid-body integrators inside OpenMM's CompoundIntegrator, for every platform and
 * integrator paired with each rigid-body integrator (both orders): the Context is
 * created, either member steps, switching keeps every body rigid and the motion smooth,
 * and a checkpoint of the compound restarts bit for bit.
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

struct CompoundConfig {
    string platform, first, second;
};

string compoundName(const ::testing::TestParamInfo<CompoundConfig>& info) {
    return info.param.platform + "_" + info.param.first + "_then_" + info.param.second;
}

void PrintTo(const CompoundConfig& config, std::ostream* out) {
    *out << config.platform << "/" << config.first << "+" << config.second;
}

/** Every ordered pair of rigid-body integrators that run on the same platform. */
vector<CompoundConfig> compoundConfigs() {
    vector<CompoundConfig> configs;
    vector<Config> all = allConfigs();
    for (const Config& first : all)
        for (const Config& second : all)
            if (first.platform == second.platform)
                configs.push_back({first.platform, first.integrator, second.integrator});
    return configs;
}

class Compound : public ::testing::TestWithParam<CompoundConfig> {
protected:
    /** The compound of the two integrators, bound to a Context on 8 tetrahedral molecules at 300 K. */
    void SetUp() override {
        MRATTLE_SKIP_IF_UNAVAILABLE(GetParam().platform);
        cluster = buildCluster(tetrahedral(), 2, 0.5, 12);
        compound.addIntegrator(makeIntegrator(GetParam().first, 0.001).release());
        compound.addIntegrator(makeIntegrator(GetParam().second, 0.001).release());
        context.reset(new Context(*cluster.system, compound, platform(GetParam().platform),
                                  platformProperties(GetParam().platform)));
        context->setPositions(cluster.positions);
        context->setVelocitiesToTemperature(300, 5);
    }
    RigidBodyIntegrator& member(int index) {
        return dynamic_cast<RigidBodyIntegrator&>(compound.getIntegrator(index));
    }
    double totalEnergy() {
        State state = context->getState(State::Energy);
        return state.getKineticEnergy() + state.getPotentialEnergy();
    }
    Cluster cluster;
    CompoundIntegrator compound;
    std::unique_ptr<Context> context;
};

} // namespace

TEST_P(Compound, EitherMemberStepsAndSwitchingKeepsBodiesRigid) {
    EXPECT_EQ(8, member(0).getNumBodiesInEffect());
    EXPECT_EQ(8, member(1).getNumBodiesInEffect());
    const double start = totalEnergy();
    vector<double> energies;
    for (int round = 0; round < 6; round++) {
        compound.setCurrentIntegrator(round % 2);
        compound.step(20);
        energies.push_back(totalEnergy());
    }
    State state = context->getState(State::Positions | State::Velocities);
    EXPECT_EQ(120, state.getStepCount());
    EXPECT_GT(maxDeviation(cluster.positions, state.getPositions()), 1e-3);  // it moved
    EXPECT_LT(maxDistanceChange(cluster.positions, state.getPositions(), cluster.molecules), 1e-10);
    // Both are second-order integrators of the same rigid dynamics: the energy stays put
    // (a Langevin member exchanges energy with its bath: rigidity is what is checked then).
    const bool nve = integratorTraits(GetParam().first).conservesEnergy &&
                     integratorTraits(GetParam().second).conservesEnergy;
    for (double energy : energies)
        if (nve)
            EXPECT_NEAR(start, energy, 2e-3 * std::fabs(start) + 0.05) << "after switching";
    // Velocities are rigid: every intra-body distance is constant to first order.
    const vector<Vec3>& x = state.getPositions();
    const vector<Vec3>& v = state.getVelocities();
    for (const vector<int>& body : cluster.molecules)
        for (int i : body)
            for (int j : body)
                EXPECT_NEAR(0.0, (x[i] - x[j]).dot(v[i] - v[j]), 1e-10);
}

TEST_P(Compound, VelocitiesSetWhileOneMemberIsCurrentAreRigidForTheOther) {
    compound.setCurrentIntegrator(0);
    compound.step(5);
    vector<Vec3> v = context->getState(State::Velocities).getVelocities();
    v[0] += Vec3(1.0, 0, 0);  // not rigid
    context->setVelocities(v);
    compound.setCurrentIntegrator(1);
    compound.step(20);
    State state = context->getState(State::Positions);
    EXPECT_LT(maxDistanceChange(cluster.positions, state.getPositions(), cluster.molecules), 1e-10);
}

TEST_P(Compound, CheckpointOfTheCompoundRestartsBitForBit) {
    compound.setCurrentIntegrator(1);
    compound.step(10);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    compound.setCurrentIntegrator(0);
    compound.step(10);
    compound.setCurrentIntegrator(1);
    compound.step(10);
    vector<Vec3> uninterrupted = context->getState(State::Positions).getPositions();
    context->loadCheckpoint(checkpoint);
    EXPECT_EQ(1, compound.getCurrentIntegrator());
    compound.setCurrentIntegrator(0);
    compound.step(10);
    compound.setCurrentIntegrator(1);
    compound.step(10);
    vector<Vec3> continued = context->getState(State::Positions).getPositions();
    for (size_t i = 0; i < continued.size(); i++)
        for (int d = 0; d < 3; d++)
            EXPECT_EQ(uninterrupted[i][d], continued[i][d]);
}

INSTANTIATE_TEST_SUITE_P(AllPairs, Compound, ::testing::ValuesIn(compoundConfigs()), compoundName);
