/*
 * Every bad input raises an OpenMMException whose message names what is wrong: the body
 * (by the index addRigidBody() returned) and the particle. A value-parameterised suite:
 * every platform and rigid-body integrator (allConfigs()) refuses the same inputs with the
 * same messages.
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <functional>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

/** Six particles: two bonded pairs and two free atoms, particle 4 massless. */
System* smallSystem() {
    System* system = new System();
    for (double mass : {12.0, 1.0, 16.0, 1.0, 0.0, 40.0})
        system->addParticle(mass);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    bonds->addBond(0, 1, 0.1, 1000);
    bonds->addBond(2, 3, 0.1, 1000);
    system->addForce(bonds);
    return system;
}

const vector<Vec3> SmallSystemPositions = {Vec3(0, 0, 0),   Vec3(0.1, 0, 0), Vec3(0.5, 0, 0),
                                          Vec3(0.6, 0, 0), Vec3(1, 0, 0),   Vec3(0, 1, 0)};

class BadInput : public RigidBodyTest {
protected:
    /** The message of binding this config's integrator with the given bodies to smallSystem() (or the given System). */
    string bindingMessage(const vector<vector<int> >& bodies, System* system = nullptr) {
        std::unique_ptr<System> owned(system != nullptr ? system : smallSystem());
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
        for (const vector<int>& body : bodies)
            integrator->addRigidBody(body);
        return messageOf([&] { makeContext(*owned, *integrator); });
    }
};

void expectContains(const string& message, const vector<string>& parts) {
    for (const string& part : parts)
        EXPECT_NE(string::npos, message.find(part)) << "'" << part << "' is missing from: " << message;
}

} // namespace

TEST_P(BadInput, ParticleIndexOutOfRange) {
    expectContains(bindingMessage({{0, 1}, {2, 99}}), {"Rigid body 1", "particle 99", "only 6 particles"});
}

TEST_P(BadInput, ParticleInTwoBodies) {
    expectContains(bindingMessage({{0, 1}, {2, 3}, {3, 5}}), {"Particle 3", "rigid bodies 1 and 2"});
}

TEST_P(BadInput, EmptyBody) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    integrator->addRigidBody({0, 1});
    expectContains(messageOf([&] { integrator->addRigidBody({}); }), {"Rigid body 1", "empty"});
    EXPECT_EQ(1, integrator->getNumRigidBodies());  // the bad body was not added
}

TEST_P(BadInput, NegativeIndex) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    expectContains(messageOf([&] { integrator->addRigidBody({0, -2}); }), {"Rigid body 0", "particle -2", "negative"});
}

TEST_P(BadInput, DuplicateWithinBody) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    expectContains(messageOf([&] { integrator->addRigidBody({2, 3, 2}); }), {"Rigid body 0", "particle 2", "twice"});
}

TEST_P(BadInput, MasslessMember) {
    expectContains(bindingMessage({{0, 1}, {3, 4}}), {"Rigid body 1", "particle 4", "zero mass"});
}

TEST_P(BadInput, VirtualSiteMember) {
    System* system = smallSystem();
    system->setParticleMass(4, 0.0);
    system->setVirtualSite(4, new TwoParticleAverageSite(0, 1, 0.5, 0.5));
    expectContains(bindingMessage({{0, 1, 4}}, system), {"Rigid body 0", "particle 4", "virtual site"});
}

TEST_P(BadInput, ConstraintCrossingABody) {
    System* system = smallSystem();
    system->addConstraint(2, 3, 0.1);  // inside body 1: fine
    system->addConstraint(1, 5, 0.2);  // from body 0 to a free particle
    expectContains(bindingMessage({{0, 1}, {2, 3}}, system),
                   {"Constraint 1", "particle 1", "rigid body 0", "particle 5", "outside"});
    // Between two bodies.
    System* twoBodies = smallSystem();
    twoBodies->addConstraint(0, 1, 0.1);
    twoBodies->addConstraint(3, 0, 0.2);
    expectContains(bindingMessage({{0, 1}, {2, 3}}, twoBodies), {"Constraint 1", "particle 3", "rigid body 1", "particle 0"});
}

TEST_P(BadInput, AddRigidBodyAfterBinding) {
    std::unique_ptr<System> system(smallSystem());
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    integrator->addRigidBody({0, 1});
    std::unique_ptr<Context> context = makeContext(*system, *integrator);
    expectContains(messageOf([&] { integrator->addRigidBody({2, 3}); }), {"addRigidBody", "bound"});
    EXPECT_EQ(1, integrator->getNumRigidBodies());
}

TEST_P(BadInput, ZeroStepSize) {
    std::unique_ptr<System> system(smallSystem());
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    std::unique_ptr<Context> context = makeContext(*system, *integrator);
    context->setPositions(SmallSystemPositions);
    integrator->setStepSize(0);
    expectContains(messageOf([&] { integrator->step(1); }), {"step size", "0"});
    // Nothing moved.
    EXPECT_EQ(0.0, context->getState(State::Positions).getTime());
    // Constructed with a zero step size: the Context is created, the first step refused.
    std::unique_ptr<RigidBodyIntegrator> zero = makeIntegrator(0.0);
    zero->addRigidBody({0, 1});
    std::unique_ptr<Context> zeroContext = makeContext(*system, *zero);
    zeroContext->setPositions(SmallSystemPositions);
    zeroContext->setVelocitiesToTemperature(300, 1);
    expectContains(messageOf([&] { zero->step(1); }), {"step size", "0"});
    EXPECT_EQ(SmallSystemPositions, zeroContext->getState(State::Positions).getPositions());
}

TEST_P(BadInput, SteppingWhileUnbound) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    expectContains(messageOf([&] { integrator->step(1); }), {"not bound"});
    expectContains(messageOf([&] { integrator->getNumDegreesOfFreedom(); }), {"not bound"});
}

TEST_P(BadInput, QueriesOutOfRange) {
    std::unique_ptr<System> system(smallSystem());
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    integrator->addRigidBody({0, 1});
    expectContains(messageOf([&] { integrator->getRigidBodyParticles(1); }), {"body index 1", "out of range"});
    std::unique_ptr<Context> context = makeContext(*system, *integrator);
    context->setPositions(SmallSystemPositions);
    expectContains(messageOf([&] { integrator->isBodyLinear(-1); }), {"body index -1", "out of range"});
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, BadInput, ::testing::ValuesIn(allConfigs()), configName);
