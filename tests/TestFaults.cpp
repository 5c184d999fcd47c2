/*
 * The faults an independent fuzz run found (issue 22), one regression test each: a step
 * that returns has produced a finite state that keeps every constraint, and a refused one
 * leaves the state as it was; a refused checkpoint is recovered from safely; negative
 * masses are refused; errors name the call that raised them; near-linear and tiny bodies
 * step at 2 fs; the shape rule is the same on every platform; integrator XML is checked
 * for depth and stray children. Generic over platforms and all three integrators.
 */
#include "MRattleLangevinIntegrator.h"
#include "MRattleXml.h"
#include "openmm/serialization/XmlSerializer.h"
#include "TestSupport.h"
#include "mrattle/RigidBodyMath.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>
#include <set>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

/** Every platform and integrator (allConfigs()). */
class Faults : public RigidBodyTest {};

struct Snapshot {
    vector<Vec3> positions, velocities;
    double time;
    long long steps;
};

Snapshot snapshot(Context& context) {
    State s = context.getState(State::Positions | State::Velocities);
    return {s.getPositions(), s.getVelocities(), s.getTime(), s.getStepCount()};
}

bool allFinite(const vector<Vec3>& values) {
    for (const Vec3& v : values)
        if (!std::isfinite(v[0] + v[1] + v[2]))
            return false;
    return true;
}

void expectSame(const Snapshot& a, const Snapshot& b, const string& what) {
    EXPECT_EQ(a.steps, b.steps) << what;
    EXPECT_EQ(a.time, b.time) << what;
    EXPECT_EQ(0.0, maxDeviation(a.positions, b.positions)) << what;
    EXPECT_EQ(0.0, maxDeviation(a.velocities, b.velocities)) << what;
}

/**
 * Step one at a time until a step is refused: every step that returns leaves finite
 * positions and velocities, and the refused one leaves the state exactly as before it.
 * Returns the refusal's message ("" if none came in maxSteps).
 */
string stepUntilRefused(Context& context, Integrator& integrator, int maxSteps) {
    for (int i = 0; i < maxSteps; i++) {
        Snapshot before = snapshot(context);
        try {
            integrator.step(1);
        } catch (const OpenMMException& e) {
            expectSame(before, snapshot(context), string("refused step: ") + e.what());
            return e.what();
        }
        Snapshot after = snapshot(context);
        if (!allFinite(after.positions) || !allFinite(after.velocities)) {
            ADD_FAILURE() << "step " << i << " returned with positions or velocities that are not finite";
            return "";
        }
    }
    return "";
}

/** Three atoms (16, 1, 1) held together by bonds, in sqrt(1.1 - x): its force is not finite past x = 1.1. */
System wallSystem() {
    System system;
    for (double m : {16.0, 1.0, 1.0})
        system.addParticle(m);
    CustomExternalForce* wall = new CustomExternalForce("sqrt(1.1-x)");
    for (int i = 0; i < 3; i++)
        wall->addParticle(i, {});
    system.addForce(wall);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    bonds->addBond(0, 1, 0.1, 1);
    bonds->addBond(0, 2, 0.1, 1);
    system.addForce(bonds);
    return system;
}

} // namespace

// Item 1.
TEST_P(Faults, ForcesThatAreNotFiniteAtTheNewPositionsAreRefused) {
    System system = wallSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.01);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions({Vec3(1, 0, 0), Vec3(1.05, 0.08, 0), Vec3(0.95, 0, 0.1)});
    context->setVelocities({Vec3(5, 0, 0), Vec3(5, 0, 0), Vec3(5, 0, 0)});
    const string message = stepUntilRefused(*context, *integrator, 200);
    EXPECT_NE(string::npos, message.find("not finite")) << message;
    // Trying again keeps to the same rule (Langevin noise may take it elsewhere).
    stepUntilRefused(*context, *integrator, 3);
}

TEST_P(Faults, AStepSizeWhoseInverseIsNotFiniteIsRefused) {
    System system = wallSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions({Vec3(0, 0, 0), Vec3(0.05, 0.08, 0), Vec3(-0.05, 0, 0.1)});
    context->setVelocities({Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0)});
    integrator->setStepSize(1e-320);
    Snapshot before = snapshot(*context);
    const string message = messageOf([&] { integrator->step(1); });
    EXPECT_NE(string::npos, message.find("too small")) << message;
    expectSame(before, snapshot(*context), "tiny step");
}

// Item 2.
TEST_P(Faults, AFreeConstraintThatDoesNotConvergeIsRefused) {
    System system;
    for (double m : {12.0, 12.0, 16.0, 1.0, 1.0})
        system.addParticle(m);
    system.addConstraint(0, 1, 0.1);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.01);
    integrator->addRigidBody({2, 3, 4});
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(1, 1, 1), Vec3(1.1, 1, 1), Vec3(1, 1.1, 1)});
    context->setVelocities({Vec3(0, -300, 0), Vec3(0, 300, 0), Vec3(), Vec3(), Vec3()});
    for (int i = 0; i < 5; i++) {
        Snapshot before = snapshot(*context);
        try {
            integrator->step(1);
        } catch (const OpenMMException& e) {
            expectSame(before, snapshot(*context), e.what());
            EXPECT_NE(string::npos, string(e.what()).find("did not converge")) << e.what();
            return;
        }
        vector<Vec3> x = snapshot(*context).positions;
        const double distance = std::sqrt((x[1] - x[0]).dot(x[1] - x[0]));
        EXPECT_NEAR(0.1, distance, 2 * integrator->getConstraintTolerance() * 0.1) << "step " << i;
    }
}

// Item 3: after a refused checkpoint the documented recovery is safe, and stepping waits for it.
TEST_P(Faults, ARefusedCheckpointIsRecoveredByReinitializeAndNothingCrashesMeanwhile) {
    System system = wallSystem();
    system.addForce(new AndersenThermostat(300, 10));
    const vector<Vec3> positions = {Vec3(0, 0, 0), Vec3(0.05, 0.08, 0), Vec3(-0.05, 0, 0.1)};
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions(positions);
    context->setVelocitiesToTemperature(300, 5);
    integrator->step(3);
    const State saved = context->getState(State::Positions | State::Velocities | State::Parameters);
    std::stringstream stream;
    context->createCheckpoint(stream);
    const string good = stream.str();
    const size_t ours = good.rfind("MRattleC");
    ASSERT_NE(string::npos, ours);
    // A System with OpenMM's own integrator and thermostat in the same process: OpenMM's
    // Reference and CPU platforms share its random generator with the damaged Context.
    System verletSystem = wallSystem();
    verletSystem.addForce(new AndersenThermostat(300, 10));
    VerletIntegrator verlet(0.001);
    std::unique_ptr<Context> verletContext = makeContext(verletSystem, verlet);
    verletContext->setPositions(positions);
    // 4 bytes inserted into OpenMM's part, most of them in its random state at its end.
    vector<size_t> offsets;
    for (size_t back = 4; back < std::min<size_t>(ours, 2600); back += 37)
        offsets.push_back(ours - back);
    int exercised = 0;  // damages that reached the checks below
    for (size_t offset : offsets) {
        string damaged = good;
        damaged.insert(offset, "junk");
        std::istringstream in(damaged);
        string message;
        try {
            context->loadCheckpoint(in);
            continue;  // OpenMM's own check refused nothing and ours accepted: not a damage we can see
        } catch (const OpenMMException& e) {
            message = e.what();
        }
        if (message.find("OpenMM had already loaded") == string::npos)
            continue;  // OpenMM's own checks refused it, before overwriting anything
        EXPECT_NE(string::npos, message.find("call Context::reinitialize()")) << message;
        exercised++;
        context->setState(saved);
        const string refusal = messageOf([&] { integrator->step(5); });
        EXPECT_NE(string::npos, refusal.find("reinitialize()")) << refusal;
        // OpenMM's own integrator draws its collisions from the generator the damaged load
        // overwrote: it may refuse to go on (a NaN coordinate), but it must not crash.
        try {
            verlet.step(5);
        } catch (const OpenMMException&) {
            verletContext->setPositions(positions);
        }
        context->reinitialize();
        context->setState(saved);
        integrator->step(5);
        EXPECT_TRUE(allFinite(snapshot(*context).velocities)) << offset;
    }
    EXPECT_GT(exercised, 0) << "no damage reached the refusal this test is about";
}

// Item 5.
TEST_P(Faults, NegativeMassesAreRefused) {
    System system;
    system.addParticle(-2.0);
    system.addParticle(1.0);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    integrator->addRigidBody({0, 1});
    const string message = messageOf([&] { makeContext(system, *integrator); });
    EXPECT_NE(string::npos, message.find("Particle 0 has mass -2")) << message;
}

// Item 7: an error names what is wrong with the call that raised it.
TEST_P(Faults, AValidSetPositionsIsNotBlamedForRefusedVelocities) {
    System system = wallSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    const vector<Vec3> positions = {Vec3(0, 0, 0), Vec3(0.05, 0.08, 0), Vec3(-0.05, 0, 0.1)};
    context->setPositions(positions);
    const string refused = messageOf([&] { context->setVelocities({Vec3(std::nan(""), 0, 0), Vec3(), Vec3()}); });
    EXPECT_EQ(0u, refused.find("setVelocities")) << refused;
    EXPECT_NO_THROW(context->setPositions(positions));
    const string step = messageOf([&] { integrator->step(1); });
    EXPECT_NE(string::npos, step.find("velocities are not finite")) << step;
    context->setVelocities({Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0)});
    integrator->step(2);
    EXPECT_EQ(2, context->getState(State::Positions).getStepCount());
}

// Item 8: CO2, N2O and HCN from 3-decimal (nm, as a .gro file) coordinates step at 2 fs.
TEST_P(Faults, NearLinearMoleculesFromThreeDecimalCoordinatesStepAtTwoFemtoseconds) {
    struct Triatomic {
        const char* name;
        double masses[3], z[3];
    };
    const Triatomic molecules[] = {{"CO2", {15.999, 12.011, 15.999}, {-0.1162, 0, 0.1162}},
                                   {"N2O", {14.007, 14.007, 15.999}, {-0.1128, 0, 0.1184}},
                                   {"HCN", {1.008, 12.011, 14.007}, {-0.1065, 0, 0.1153}}};
    const int copies = 8;
    System system;
    vector<Vec3> positions;
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    for (int m = 0; m < 3; m++)
        for (int c = 0; c < copies; c++) {
            vector<Vec3> rotation = randomRotation(17 + 10 * m + c);
            const Vec3 center(0.7 * c, 0.7 * m, 0.3);
            vector<int> body;
            for (int k = 0; k < 3; k++) {
                Vec3 x = center + rotate(rotation, Vec3(0, 0, molecules[m].z[k]));
                for (int d = 0; d < 3; d++)
                    x[d] = std::round(x[d] * 1000) / 1000;  // 3 decimals
                body.push_back(system.addParticle(molecules[m].masses[k]));
                positions.push_back(x);
            }
            integrator->addRigidBody(body);
        }
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions(positions);
    for (int b = 0; b < 3 * copies; b++)
        EXPECT_TRUE(integrator->isBodyLinear(b)) << molecules[b / copies].name << " copy " << b % copies;
    EXPECT_EQ(5 * 3 * copies, integrator->getNumDegreesOfFreedom());
    context->setVelocitiesToTemperature(300, 7);
    EXPECT_NO_THROW(integrator->step(500));
    // Straight, and as long as the given (rounded) molecule to the rounding.
    vector<Vec3> x = snapshot(*context).positions;
    for (int b = 0; b < 3 * copies; b++) {
        const Vec3 e = x[3 * b + 1] - x[3 * b], f = x[3 * b + 2] - x[3 * b];
        EXPECT_LT(std::sqrt(e.cross(f).dot(e.cross(f)) / (e.dot(e) * f.dot(f))), 1e-9) << b;
        const Vec3 given = positions[3 * b + 2] - positions[3 * b];
        EXPECT_NEAR(std::sqrt(given.dot(given)), std::sqrt(f.dot(f)), 2e-3) << b;
    }
}

// Item 8: bodies a micrometre of a nanometre across, or with coinciding atoms, are points.
TEST_P(Faults, TinyBodiesArePointsAndStepAtTwoFemtoseconds) {
    System system;
    vector<Vec3> positions;
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    // A triangle 1e-6 nm across, and a pair 1e-6 nm apart.
    for (double m : {12.0, 1.0, 16.0, 14.0, 2.0})
        system.addParticle(m);
    positions = {Vec3(0, 0, 0), Vec3(1e-6, 0, 0), Vec3(0, 1e-6, 0), Vec3(1, 0, 0), Vec3(1, 1e-6, 0)};
    integrator->addRigidBody({0, 1, 2});
    integrator->addRigidBody({3, 4});
    CustomExternalForce* field = new CustomExternalForce("0.5*x*x + y");
    for (int i = 0; i < 5; i++)
        field->addParticle(i, {});
    system.addForce(field);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions(positions);
    EXPECT_EQ(3 + 3, integrator->getNumDegreesOfFreedom());
    context->setVelocitiesToTemperature(300, 3);
    EXPECT_NO_THROW(integrator->step(200));
    vector<Vec3> x = snapshot(*context).positions;
    EXPECT_TRUE(allFinite(x));
    EXPECT_NEAR(0.0, maxDistanceChange(positions, x, {{0, 1, 2}, {3, 4}}), 1e-12);
}

// Item 9: a water set collinear keeps the same shape, hence degrees of freedom, on every platform.
TEST_P(Faults, ACollinearWaterHasTheSameShapeOnEveryPlatform) {
    Molecule w = water();
    System system;
    for (double m : w.masses)
        system.addParticle(m);
    system.addConstraint(0, 1, 0.09572);
    system.addConstraint(0, 2, 0.09572);
    system.addConstraint(1, 2, 0.15139);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions({Vec3(0, 0, 0), Vec3(0.09572, 0, 0), Vec3(-0.09572, 0, 0)});
    // What Reference decides is the rule; every platform must decide the same.
    System reference = system;
    std::unique_ptr<RigidBodyIntegrator> referenceIntegrator = makeIntegrator(0.002);
    Context referenceContext(reference, *referenceIntegrator, Platform::getPlatformByName("Reference"));
    referenceContext.setPositions({Vec3(0, 0, 0), Vec3(0.09572, 0, 0), Vec3(-0.09572, 0, 0)});
    EXPECT_EQ(referenceIntegrator->getNumDegreesOfFreedom(), integrator->getNumDegreesOfFreedom());
    EXPECT_EQ(referenceIntegrator->isBodyLinear(0), integrator->isBodyLinear(0));
    EXPECT_EQ(0.0, maxDeviation(snapshot(referenceContext).positions, snapshot(*context).positions));
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, Faults, ::testing::ValuesIn(allConfigs()), configName);

// Item 8, the rule itself: a 1e-3 nm kink in CO2 is linear, a 5-degree bend is not.
TEST(FaultsCore, NearLinearThreshold) {
    using namespace RigidBodyMath;
    const vector<int> atoms = {0, 1, 2};
    const vector<double> masses = {15.999, 12.011, 15.999};
    auto shapeOf = [&](double offset) {
        const vector<Vec3> x = {Vec3(-0.1162, 0, 0), Vec3(0, offset, 0), Vec3(0.1162, 0, 0)};
        BodyView view{atoms.data(), 3, masses.data(), 44.009, false};
        const double* data = reinterpret_cast<const double*>(x.data());
        return classifyShape(secondMoment(view, data, centerOfMass(view, data)), view.totalMass);
    };
    EXPECT_EQ(Shape::Linear, shapeOf(0));
    EXPECT_EQ(Shape::Linear, shapeOf(1e-3));
    EXPECT_EQ(Shape::Linear, shapeOf(2e-3));
    EXPECT_EQ(Shape::General, shapeOf(0.1162 * std::tan(5 * M_PI / 180)));
    EXPECT_EQ(Shape::General, shapeOf(0.01));
}

// Item 4: a deeply nested document is refused before OpenMM's reader (which recurses) sees it.
TEST(FaultsXml, DeeplyNestedDocumentsAreRefused) {
    auto nested = [](int depth) {
        string xml;
        for (int i = 0; i < depth; i++)
            xml += "<a>";
        for (int i = 0; i < depth; i++)
            xml += "</a>";
        return xml;
    };
    EXPECT_NO_THROW(checkWellFormedXml(nested(MaxXmlDepth)));
    string message = messageOf([&] { checkWellFormedXml(nested(MaxXmlDepth + 1)); });
    EXPECT_NE(string::npos, message.find("nest deeper than")) << message;
    message = messageOf([&] { delete deserializeIntegratorXml(nested(100000)); });
    EXPECT_NE(string::npos, message.find("nest deeper than")) << message;
}

// Item 10: children of <Particle> are refused; a message names its type once.
TEST(FaultsXml, ParticleChildrenAreRefusedAndMessagesHaveOnePrefix) {
    MRattleIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1});
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", stream);
    string xml = stream.str();
    const size_t particle = xml.find("<Particle index=\"0\"/>");
    ASSERT_NE(string::npos, particle);
    xml.replace(particle, string("<Particle index=\"0\"/>").size(), "<Particle index=\"0\"><Junk/></Particle>");
    string message = messageOf([&] { delete deserializeIntegratorXml(xml); });
    EXPECT_NE(string::npos, message.find("unexpected element <Junk> in <Particle>")) << message;

    MRattleLangevinIntegrator langevin(300, 1, 0.002);
    std::stringstream langevinStream;
    XmlSerializer::serialize<Integrator>(&langevin, "Integrator", langevinStream);
    string langevinXml = langevinStream.str();
    const size_t step = langevinXml.find("stepSize=\"");
    ASSERT_NE(string::npos, step);
    langevinXml.replace(step, langevinXml.find('"', step + 10) + 1 - step, "stepSize=\"0\"");
    message = messageOf([&] { delete deserializeIntegratorXml(langevinXml); });
    EXPECT_EQ(0u, message.find("MRattleLangevinIntegrator XML: the step size")) << message;
    EXPECT_EQ(string::npos, message.find("XML: MRattleLangevinIntegrator XML")) << message;
}
