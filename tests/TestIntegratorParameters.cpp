/*
 * A State's integrator parameters (Context::getState() with State::IntegratorParameters,
 * then setState()), for every platform and rigid-body integrator: what replica exchange on
 * one Context needs (issue 43: OpenMM 8.6's ReplicaExchangeSampler sets each replica's State
 * in turn).
 * - Set back, they restore the integrator's variables (a thermostat's heat bath) bit for
 *   bit, directly and through XML; a deterministic integrator then continues its run bit
 *   for bit. States without them still set.
 * - Replicas taking turns on one Context each run as they would alone, bit for bit, unless
 *   the integrator draws random numbers: its stream is the Context's, which a State does not
 *   carry (replicas must not draw the same numbers).
 * - Parameters of another integrator class are refused naming both; empty ones (OpenMM's
 *   own integrators write none) only an integrator without variables accepts; another chain
 *   length, another format and values that are not finite are refused.
 */
#include "MRattleNoseHooverIntegrator.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <memory>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

const int WithParameters = State::Positions | State::Velocities | State::IntegratorParameters;

/** A State through OpenMM's XML. */
string xmlOf(const State& state) {
    std::stringstream xml;
    XmlSerializer::serialize<State>(&state, "State", xml);
    return xml.str();
}
std::unique_ptr<State> stateOf(const string& xml) {
    std::istringstream stream(xml);
    return std::unique_ptr<State>(XmlSerializer::deserialize<State>(stream));
}

class IntegratorParameters : public RigidBodyTest {
protected:
    /** 8 rigid tetrahedral molecules in vacuum. */
    Cluster cluster = buildCluster(tetrahedral(), 2, 0.5, 4);
    /** This config's integrator's heat-bath energy (0 without a heat bath). */
    double heatBath(RigidBodyIntegrator& integrator) const {
        const auto& energy = GetParam().traits().heatBathEnergy;
        return energy ? energy(integrator) : 0.0;
    }
    /** A Context of the integrator at the cluster's positions, with velocities at the temperature from the seed. */
    std::unique_ptr<Context> start(RigidBodyIntegrator& integrator, double temperature, int seed) const {
        std::unique_ptr<Context> context = makeContext(*cluster.system, integrator);
        context->setPositions(cluster.positions);
        context->setVelocitiesToTemperature(temperature, seed);
        return context;
    }
    void expectSameRun(const State& expected, const State& actual) const {
        EXPECT_EQ(0.0, maxDeviation(expected.getPositions(), actual.getPositions()));
        EXPECT_EQ(0.0, maxDeviation(expected.getVelocities(), actual.getVelocities()));
    }
};

} // namespace

TEST_P(IntegratorParameters, SetStateRestoresTheIntegratorsVariablesBitForBit) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = start(*integrator, 200, 1);  // below the bath's 300 K: the bath moves
    integrator->step(20);
    const State saved = context->getState(WithParameters);
    const double savedBath = heatBath(*integrator);
    const std::unique_ptr<State> savedThroughXml = stateOf(xmlOf(saved));
    integrator->step(30);
    const State uninterrupted = context->getState(State::Positions | State::Velocities);
    const double bath = heatBath(*integrator);
    if (GetParam().traits().heatBathEnergy) {
        EXPECT_NE(0.0, savedBath);
        EXPECT_NE(savedBath, bath);
    }
    for (const State* state : {&saved, static_cast<const State*>(savedThroughXml.get())}) {
        context->setState(*state);
        EXPECT_EQ(savedBath, heatBath(*integrator));
        integrator->step(30);
        if (GetParam().traits().stochastic)
            continue;  // the Context's random stream has moved on: only the variables are the saved ones
        expectSameRun(uninterrupted, context->getState(State::Positions | State::Velocities));
        EXPECT_EQ(bath, heatBath(*integrator));
    }
    // A State without them sets as before and leaves the variables as they are.
    const double before = heatBath(*integrator);
    context->setState(context->getState(State::Positions | State::Velocities));
    EXPECT_EQ(before, heatBath(*integrator));
    integrator->step(5);
}

TEST_P(IntegratorParameters, ReplicasTakingTurnsOnOneContextRunAsTheyWouldAlone) {
    if (GetParam().traits().stochastic)
        GTEST_SKIP() << GetParam().integrator << " draws from the Context's random stream, which replicas sharing the "
                     << "Context share (a State does not carry it, so replicas never draw the same numbers): a "
                     << "replica's run differs from its run alone; SetStateRestoresTheIntegratorsVariablesBitForBit "
                     << "checks that its variables are carried";
    const int Turns = 3, StepsPerTurn = 10;
    // Two replicas of other velocities on one Context, as OpenMM 8.6's ReplicaExchangeSampler
    // runs them: set a replica's State, step, take its State back.
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = start(*integrator, 200, 1);
    vector<State> initial = {context->getState(WithParameters)};
    context->setVelocitiesToTemperature(400, 2);
    initial.push_back(context->getState(WithParameters));
    vector<State> replicas = initial;
    vector<double> baths(2);
    for (int turn = 0; turn < Turns; turn++)
        for (int r = 0; r < 2; r++) {
            context->setState(replicas[r]);
            integrator->step(StepsPerTurn);
            replicas[r] = context->getState(WithParameters);
            baths[r] = heatBath(*integrator);
        }
    if (GetParam().traits().heatBathEnergy)
        EXPECT_NE(baths[0], baths[1]);  // each replica's bath is its own
    for (int r = 0; r < 2; r++) {
        std::unique_ptr<RigidBodyIntegrator> alone = makeIntegrator(0.002);
        std::unique_ptr<Context> own = makeContext(*cluster.system, *alone);
        own->setState(initial[r]);
        alone->step(Turns * StepsPerTurn);
        expectSameRun(own->getState(State::Positions | State::Velocities), replicas[r]);
        EXPECT_EQ(heatBath(*alone), baths[r]) << "replica " << r;
    }
}

TEST_P(IntegratorParameters, RefusesTheParametersOfAnotherIntegratorClass) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = start(*integrator, 300, 1);
    const string self = GetParam().integrator + "Integrator";
    for (const IntegratorTraits& other : integrators()) {
        if (other.name == GetParam().integrator)
            continue;
        std::unique_ptr<RigidBodyIntegrator> otherIntegrator(other.make(0.002));
        Context otherContext(*cluster.system, *otherIntegrator, platform("Reference"));
        otherContext.setPositions(cluster.positions);
        const State foreign = otherContext.getState(WithParameters);
        const string message = messageOf([&] { context->setState(foreign); });
        EXPECT_NE(string::npos, message.find(self + ": the State's integrator parameters are those of a " + other.name +
                                             "Integrator, not of a " + self))
            << message;
    }
    // OpenMM's VerletIntegrator writes none: only an integrator without variables takes that.
    VerletIntegrator verlet(0.002);
    Context verletContext(*cluster.system, verlet, platform("Reference"));
    verletContext.setPositions(cluster.positions);
    const State empty = verletContext.getState(WithParameters);
    if (GetParam().traits().heatBathEnergy) {
        const string message = messageOf([&] { context->setState(empty); });
        EXPECT_NE(string::npos, message.find("integrator parameters are empty")) << message;
    } else
        EXPECT_NO_THROW(context->setState(empty));
    // OpenMM's NoseHooverIntegrator writes a chain of its own format.
    NoseHooverIntegrator noseHoover(300, 1, 0.002);
    Context noseHooverContext(*cluster.system, noseHoover, platform("Reference"));
    noseHooverContext.setPositions(cluster.positions);
    const State openmmChain = noseHooverContext.getState(WithParameters);
    const string message = messageOf([&] { context->setState(openmmChain); });
    EXPECT_NE(string::npos, message.find("were not written by one of this plugin's integrators")) << message;
    integrator->step(2);  // a refusal leaves the integrator usable
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, IntegratorParameters, ::testing::ValuesIn(allConfigs()), configName);

namespace {
/** The XML with the first `original` after `after` replaced (a test failure if either is missing). */
string replacedAfter(const string& xml, const string& after, const string& original, const string& replacement) {
    const size_t start = xml.find(after);
    const size_t at = start == string::npos ? string::npos : xml.find(original, start);
    EXPECT_NE(string::npos, at) << "'" << original << "' after '" << after << "' not in the XML";
    if (at == string::npos)
        return xml;
    return xml.substr(0, at) + replacement + xml.substr(at + original.size());
}
} // namespace

TEST(IntegratorParametersFormat, RefusesAnotherChainLengthFormatOrValuesThatAreNotFinite) {
    loadPlugins();
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 4);
    MRattleNoseHooverIntegrator three(300, 10, 0.002, 3), five(300, 10, 0.002, 5);
    Context context(*c.system, three, platform("Reference")), other(*c.system, five, platform("Reference"));
    for (Context* each : {&context, &other}) {
        each->setPositions(c.positions);
        each->setVelocitiesToTemperature(200, 1);
        each->getIntegrator().step(10);
    }
    const State longer = other.getState(WithParameters);
    string message = messageOf([&] { context.setState(longer); });
    EXPECT_NE(string::npos, message.find("hold 5 values of chainPositions; this MRattleNoseHooverIntegrator has 3"))
        << message;

    const string xml = xmlOf(context.getState(WithParameters));
    const std::unique_ptr<State> laterVersion = stateOf(replacedAfter(xml, "<IntegratorParameters", "version=\"1\"",
                                                                      "version=\"2\""));
    message = messageOf([&] { context.setState(*laterVersion); });
    EXPECT_NE(string::npos, message.find("have format version 2; this build reads version 1")) << message;
    const std::unique_ptr<State> infinite = stateOf(replacedAfter(xml, "<chainVelocities", "v=\"", "v=\"1e999"));
    message = messageOf([&] { context.setState(*infinite); });
    EXPECT_NE(string::npos, message.find("hold a value of chainVelocities that is not finite")) << message;
    const std::unique_ptr<State> renamed = stateOf(replacedAfter(xml, "<chainVelocities", "chainVelocities",
                                                                 "chainMomenta"));
    message = messageOf([&] { context.setState(*renamed); });
    EXPECT_NE(string::npos, message.find("hold 'chainMomenta', which a MRattleNoseHooverIntegrator does not have"))
        << message;
    // The refusals changed nothing: the State as written still restores the chain.
    const double bath = three.computeHeatBathEnergy();
    context.setState(*stateOf(xml));
    EXPECT_EQ(bath, three.computeHeatBathEnergy());
}
