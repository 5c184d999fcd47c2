/*
 * Every bad input raises an OpenMMException whose message names what is wrong: the body
 * (by the index addRigidBody() returned) and the particle.
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

/** The message of binding an integrator with the given bodies to smallSystem() (or the given System). */
string bindingMessage(const vector<vector<int> >& bodies, System* system = nullptr) {
    std::unique_ptr<System> owned(system != nullptr ? system : smallSystem());
    MRattleIntegrator integrator(0.001);
    for (const vector<int>& body : bodies)
        integrator.addRigidBody(body);
    return messageOf([&] { Context context(*owned, integrator, platform("Reference")); });
}

void expectContains(const string& message, const vector<string>& parts) {
    for (const string& part : parts)
        EXPECT_NE(string::npos, message.find(part)) << "'" << part << "' is missing from: " << message;
}

} // namespace

TEST(BadInput, ParticleIndexOutOfRange) {
    expectContains(bindingMessage({{0, 1}, {2, 99}}), {"Rigid body 1", "particle 99", "only 6 particles"});
}

TEST(BadInput, ParticleInTwoBodies) {
    expectContains(bindingMessage({{0, 1}, {2, 3}, {3, 5}}), {"Particle 3", "rigid bodies 1 and 2"});
}

TEST(BadInput, EmptyBody) {
    MRattleIntegrator integrator(0.001);
    integrator.addRigidBody({0, 1});
    expectContains(messageOf([&] { integrator.addRigidBody({}); }), {"Rigid body 1", "empty"});
    EXPECT_EQ(1, integrator.getNumRigidBodies());  // the bad body was not added
}

TEST(BadInput, NegativeIndex) {
    MRattleIntegrator integrator(0.001);
    expectContains(messageOf([&] { integrator.addRigidBody({0, -2}); }), {"Rigid body 0", "particle -2", "negative"});
}

TEST(BadInput, DuplicateWithinBody) {
    MRattleIntegrator integrator(0.001);
    expectContains(messageOf([&] { integrator.addRigidBody({2, 3, 2}); }), {"Rigid body 0", "particle 2", "twice"});
}

TEST(BadInput, MasslessMember) {
    expectContains(bindingMessage({{0, 1}, {3, 4}}), {"Rigid body 1", "particle 4", "zero mass"});
}

TEST(BadInput, VirtualSiteMember) {
    System* system = smallSystem();
    system->setParticleMass(4, 0.0);
    system->setVirtualSite(4, new TwoParticleAverageSite(0, 1, 0.5, 0.5));
    expectContains(bindingMessage({{0, 1, 4}}, system), {"Rigid body 0", "particle 4", "virtual site"});
}

TEST(BadInput, ConstraintCrossingABody) {
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

TEST(BadInput, AddRigidBodyAfterBinding) {
    std::unique_ptr<System> system(smallSystem());
    MRattleIntegrator integrator(0.001);
    integrator.addRigidBody({0, 1});
    Context context(*system, integrator, platform("Reference"));
    expectContains(messageOf([&] { integrator.addRigidBody({2, 3}); }), {"addRigidBody", "bound"});
    EXPECT_EQ(1, integrator.getNumRigidBodies());
}

TEST(BadInput, ZeroStepSize) {
    std::unique_ptr<System> system(smallSystem());
    MRattleIntegrator integrator(0.001);
    Context context(*system, integrator, platform("Reference"));
    context.setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.5, 0, 0), Vec3(0.6, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
    integrator.setStepSize(0);
    expectContains(messageOf([&] { integrator.step(1); }), {"step size", "0"});
    // Nothing moved.
    EXPECT_EQ(0.0, context.getState(State::Positions).getTime());
}

TEST(BadInput, SteppingWhileUnbound) {
    MRattleIntegrator integrator(0.001);
    expectContains(messageOf([&] { integrator.step(1); }), {"not bound"});
    expectContains(messageOf([&] { integrator.getNumDegreesOfFreedom(); }), {"not bound"});
}

TEST(BadInput, QueriesOutOfRange) {
    std::unique_ptr<System> system(smallSystem());
    MRattleIntegrator integrator(0.001);
    integrator.addRigidBody({0, 1});
    expectContains(messageOf([&] { integrator.getRigidBodyParticles(1); }), {"body index 1", "out of range"});
    Context context(*system, integrator, platform("Reference"));
    context.setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.5, 0, 0), Vec3(0.6, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
    expectContains(messageOf([&] { integrator.isBodyLinear(-1); }), {"body index -1", "out of range"});
}
