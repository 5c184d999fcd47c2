/*
 * Reliability (issue 13): every bad input and numerical fault is refused with a clear
 * OpenMMException, nothing is silently wrong. Generic over platforms and integrators where
 * the behaviour is the same; a failed step leaves positions and velocities as they were.
 */
#include "MRattleXml.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <cmath>
#include <limits>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

class Reliability : public RigidBodyTest {};

/** A diatomic (linear body) and a benzene; an external force "k*x" on atom 0 with global k. */
struct FaultySystem {
    System system;
    vector<Vec3> positions;
};

FaultySystem faultySystem() {
    FaultySystem f;
    f.system.addParticle(12.0);
    f.system.addParticle(16.0);
    f.positions = {Vec3(0, 0, 0), Vec3(0.113, 0, 0)};
    HarmonicBondForce* bonds = new HarmonicBondForce();
    bonds->addBond(0, 1, 0.113, 0.0);
    Molecule b = benzene();
    for (size_t i = 0; i < b.sites.size(); i++) {
        f.system.addParticle(b.masses[i]);
        f.positions.push_back(b.sites[i] + Vec3(1.0, 0, 0));
    }
    for (auto& bond : b.bonds)
        bonds->addBond(2 + bond.first, 2 + bond.second, 0.14, 0.0);
    f.system.addForce(bonds);
    CustomExternalForce* push = new CustomExternalForce("k*x");
    push->addGlobalParameter("k", 0.0);
    push->addParticle(0);
    push->addParticle(2);
    f.system.addForce(push);
    return f;
}

} // namespace

TEST_P(Reliability, NonFiniteForcesAreRefusedAndTheStateKept) {
    if (isDevicePlatform(GetParam().platform))
        GTEST_SKIP() << "OpenMM's device force buffer is fixed point: a force that is not finite reaches the "
                        "integrator as a large finite one (infinity; NaN too through pocl, 0 on CUDA), found by the speed "
                        "it gives (DevicePlatform.AnInfiniteForceIsFoundByTheSpeedItGives), not as 'not finite'";
    for (double k : {std::numeric_limits<double>::infinity(), std::nan("")}) {
        FaultySystem f = faultySystem();
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
        std::unique_ptr<Context> context = makeContext(f.system, *integrator);
        context->setPositions(f.positions);
        context->setVelocitiesToTemperature(300, 2);
        ASSERT_TRUE(integrator->isBodyLinear(0));
        integrator->step(3);
        State before = context->getState(State::Positions | State::Velocities);
        context->setParameter("k", k);
        string message = messageOf([&] { integrator->step(1); });
        EXPECT_NE(string::npos, message.find("not finite")) << k << ": " << message;
        State after = context->getState(State::Positions | State::Velocities);
        EXPECT_EQ(before.getStepCount(), after.getStepCount());
        EXPECT_EQ(0.0, maxDeviation(before.getPositions(), after.getPositions())) << k;
        EXPECT_EQ(0.0, maxDeviation(before.getVelocities(), after.getVelocities())) << k;
        context->setParameter("k", 0.0);
        integrator->step(2);  // usable again
        EXPECT_EQ(before.getStepCount() + 2, context->getState(State::Positions).getStepCount());
    }
}

TEST_P(Reliability, AStepTooLargeForTheRotationIsRefused) {
    if (GetParam().traits().rescalesVelocities)
        GTEST_SKIP() << GetParam().integrator << " scales the velocities before the drift: its thermostat slows a "
                        "spin this far from its temperature first (the reset's refusal is checked without it)";
    // A benzene spinning at 20 rad/ps with a 0.1 ps step turns by 2 rad in a step.
    Molecule b = benzene();
    System system;
    vector<Vec3> velocities;
    for (size_t i = 0; i < b.sites.size(); i++) {
        system.addParticle(b.masses[i]);
        velocities.push_back(Vec3(0, 0, 20).cross(b.sites[i]));
    }
    HarmonicBondForce* bonds = new HarmonicBondForce();
    for (auto& bond : b.bonds)
        bonds->addBond(bond.first, bond.second, 0.14, 0.0);
    system.addForce(bonds);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.1);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions(b.sites);
    context->setVelocities(velocities);
    string message = messageOf([&] {
        integrator->step(1);
        context->getState(State::Energy);  // on a device platform the failure is reported here
    });
    EXPECT_FALSE(message.empty());
    EXPECT_TRUE(message.find("too large") != string::npos || message.find("no rotation") != string::npos) << message;
    State state = context->getState(State::Positions);
    EXPECT_EQ(0, state.getStepCount());
    EXPECT_LT(maxDeviation(b.sites, state.getPositions()), 1e-12);
}

TEST_P(Reliability, SettersRefuseValuesThatAreNotFinite) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    EXPECT_NE(string::npos, messageOf([&] { integrator->setConstraintTolerance(std::nan("")); }).find("finite positive"));
    EXPECT_NE(string::npos, messageOf([&] { integrator->setConstraintTolerance(-1e-5); }).find("finite positive"));
    EXPECT_NE(string::npos, messageOf([&] { integrator->setConstraintTolerance(INFINITY); }).find("finite positive"));
    EXPECT_NE(string::npos, messageOf([&] { integrator->setStepSize(INFINITY); }).find("finite"));
    EXPECT_NE(string::npos, messageOf([&] { integrator->setStepSize(std::nan("")); }).find("finite"));
    // Through OpenMM's base class too: the setters are virtual.
    Integrator& base = *integrator;
    EXPECT_THROW(base.setStepSize(std::nan("")), OpenMMException);
    EXPECT_EQ(0.002, integrator->getStepSize());
    EXPECT_EQ(1e-5, integrator->getConstraintTolerance());
}

TEST_P(Reliability, DegreesOfFreedomOfPointBodiesAndMasslessConstraints) {
    // Two massive particles at one place, declared a body: a point, 3 degrees of freedom,
    // and its translation gets exactly the requested temperature.
    System system;
    system.addParticle(10.0);
    system.addParticle(10.0);
    system.addParticle(0.0);
    system.addParticle(0.0);
    system.addConstraint(2, 3, 0.1);  // between massless particles: OpenMM ignores it
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    integrator->addRigidBody({0, 1});
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions({Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0.5, 0.5), Vec3(0, 0, 0), Vec3(0.1, 0, 0)});
    EXPECT_EQ(3, integrator->getNumDegreesOfFreedom());
    EXPECT_FALSE(integrator->isBodyLinear(0));
    EXPECT_EQ(1, integrator->getTopology().getNumMasslessConstraints());
    context->setVelocitiesToTemperature(300, 5);
    const double kinetic = context->getState(State::Energy).getKineticEnergy();
    EXPECT_NEAR(1.5 * 0.0083144626 * 300, kinetic, 1e-6);
    integrator->step(10);
    vector<Vec3> x = context->getState(State::Positions).getPositions();
    EXPECT_LT(maxDeviation({x[0]}, {x[1]}), 1e-12);
}

TEST(Reliability, OnlyMasslessParticlesHaveNoDegreesOfFreedom) {
    System system;
    system.addParticle(0.0);
    system.addParticle(0.0);
    system.addConstraint(0, 1, 0.1);
    MRattleIntegrator integrator(0.002);
    Context context(system, integrator, platform("Reference"));
    EXPECT_EQ(0, integrator.getNumDegreesOfFreedom());
}

TEST(Reliability, SerializedIntegratorsAreReadStrictly) {
    MRattleIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1, 2});
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", stream);
    const string xml = stream.str();
    auto refused = [](const string& document) {
        return messageOf([&] { delete deserializeIntegratorXml(document); });
    };
    auto replaced = [&](const string& from, const string& to) {
        string document = xml;
        size_t at = document.find(from);
        EXPECT_NE(string::npos, at) << from;
        return document.replace(at, from.size(), to);
    };
    // A duplicated <RigidBodies> element.
    size_t start = xml.find("<RigidBodies"), end = xml.find("</RigidBodies>") + string("</RigidBodies>").size();
    string duplicated = xml;
    duplicated.insert(end, xml.substr(start, end - start));
    EXPECT_NE(string::npos, refused(duplicated).find("2 <RigidBodies> elements")) << refused(duplicated);
    // Step sizes of zero, in hexadecimal, infinite; no message names the root element "<>".
    for (const string bad : {"0", "0x10", "inf", "nan", "1e999"}) {
        string message = refused(replaced("stepSize=\".002\"", "stepSize=\"" + bad + "\""));
        EXPECT_NE(string::npos, message.find(bad == "0" ? "must be nonzero" : "finite decimal number")) << bad << ": " << message;
        EXPECT_EQ(string::npos, message.find("<>")) << message;
    }
    // A duplicated attribute (OpenMM's reader would keep the last).
    EXPECT_NE(string::npos, refused(replaced("stepSize=\".002\"", "stepSize=\".002\" stepSize=\".004\"")).find("appears twice"));
    // The document cut at every point before its end: refused, never a crash.
    int refusals = 0;
    for (size_t cut = 0; cut + 1 < xml.size(); cut++)
        refusals += !refused(xml.substr(0, cut)).empty();
    EXPECT_EQ((int) xml.size() - 1, refusals);
    // The whole document is read.
    std::unique_ptr<Integrator> copy(deserializeIntegratorXml(xml));
    ASSERT_NE(nullptr, dynamic_cast<MRattleIntegrator*>(copy.get()));
    EXPECT_EQ(1, dynamic_cast<MRattleIntegrator&>(*copy).getNumRigidBodies());
}

TEST(Reliability, ACheckpointWithADamagedIntegratorNameIsRefusedWithAReadableMessage) {
    Cluster c = buildCluster(benzene(), 1, 0.7, 1);
    MRattleIntegrator integrator(0.002);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    std::stringstream stream;
    context.createCheckpoint(stream);
    string checkpoint = stream.str();
    size_t offset = checkpoint.rfind("MRattleC") + 16;  // magic, version, name length
    for (char damage : {'\0', '\x80', '\x01'}) {
        string damaged = checkpoint;
        damaged[offset] = damage;
        std::istringstream in(damaged);
        string message = messageOf([&] { context.loadCheckpoint(in); });
        EXPECT_NE(string::npos, message.find("kernel '\\x")) << message;
        EXPECT_NE(string::npos, message.find("this one uses 'IntegrateMRattleStep'")) << message;
    }
}


TEST(Reliability, DamageAnywhereInTheIntegratorsCheckpointDataIsRefused) {
    // Every byte of the integrator's part (header, kernel state, checksum) flipped in turn:
    // each damaged checkpoint is refused, none is loaded as if it were whole.
    Cluster c = buildCluster(benzene(), 1, 0.7, 1);
    c.system->addForce(new AndersenThermostat(300, 5.0));  // the kernel then has a random state to save
    MRattleIntegrator integrator(0.002);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 1);
    integrator.step(3);
    std::stringstream stream;
    context.createCheckpoint(stream);
    const string checkpoint = stream.str();
    const size_t start = checkpoint.rfind("MRattleC");
    ASSERT_GT(checkpoint.size() - start, 100u);  // header, a few kB of random state, checksum
    int refused = 0, tried = 0;
    for (size_t at = start; at < checkpoint.size(); at += 7, tried++) {
        string damaged = checkpoint;
        damaged[at] ^= 0x04;
        std::istringstream in(damaged);
        refused += !messageOf([&] { context.loadCheckpoint(in); }).empty();
    }
    EXPECT_EQ(tried, refused);
    std::istringstream whole(checkpoint);
    context.loadCheckpoint(whole);
    integrator.step(1);
}

TEST_P(Reliability, ABodySpanningMoleculesIsRefusedWithABarostat) {
    // Two waters declared one body: fine without a barostat, refused with one (it would
    // scale the molecules apart inside the body).
    for (bool barostat : {false, true}) {
        Cluster c = buildCluster(water(), 2, 0.5, 3, [] {
            ClusterOptions options;
            options.method = NonbondedForce::PME;
            options.cutoff = 0.45;
            return options;
        }());
        if (barostat)
            c.system->addForce(new MonteCarloBarostat(1.0, 300.0, 1));
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
        vector<int> joined = c.molecules[0];
        joined.insert(joined.end(), c.molecules[1].begin(), c.molecules[1].end());
        integrator->addRigidBody(joined);
        string message = barostat ? messageOf([&] { makeContext(*c.system, *integrator); }) : "";
        if (barostat) {
            EXPECT_NE(string::npos, message.find("two different molecules")) << message;
            EXPECT_NE(string::npos, message.find("MonteCarloBarostat")) << message;
        }
        else
            EXPECT_NO_THROW(makeContext(*c.system, *integrator));
    }
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, Reliability, ::testing::ValuesIn(allConfigs()), configName);
