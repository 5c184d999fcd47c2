/*
 * Checkpoints and saved states of the rigid-body integrators: a run continued from a
 * checkpoint (same Context, a new Context, Context::reinitialize) is bit for bit the
 * uninterrupted run on Reference and on CPU with one thread; a checkpoint that does not
 * fit (other bodies, other integrator, unknown format, truncated) is refused with a clear
 * OpenMMException and leaves the Context as it was; a State saved as XML continues with
 * the bodies rigid and the shapes they had.
 */
#include "RigidSplittingIntegrator.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

/** A linear triatomic (CO2-like, 0.116 nm bonds): a body with 5 degrees of freedom. */
Molecule linearTriatomic() {
    Molecule m;
    m.sites = {Vec3(-0.116, 0, 0), Vec3(0, 0, 0), Vec3(0.116, 0, 0)};
    m.masses = {15.999, 12.011, 15.999};
    m.charges = {-0.35, 0.7, -0.35};
    m.sigmas = {0.305, 0.28, 0.305};
    m.epsilons = {0.66, 0.23, 0.66};
    m.bonds = {{0, 1}, {1, 2}};
    return m;
}

Vec3 orient(const Vec3& v, double a, double b) {
    // Rotation about z by a, then about x by b: enough to give each copy its own orientation.
    Vec3 r(v[0] * std::cos(a) - v[1] * std::sin(a), v[0] * std::sin(a) + v[1] * std::cos(a), v[2]);
    return Vec3(r[0], r[1] * std::cos(b) - r[2] * std::sin(b), r[1] * std::sin(b) + r[2] * std::cos(b));
}

/**
 * A periodic cluster of 3x3x3 rigid molecules (benzene and linear triatomics
 * alternating) with Lennard-Jones and reaction-field Coulomb interactions, cut off at
 * 0.8 nm; bonds make each molecule one OpenMM molecule (so one body by default).
 */
struct MixedCluster {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > molecules;
};

enum Extras { NoExtras = 0, WithThermostat = 1, WithMotionRemover = 2 };

MixedCluster mixedCluster(int extras = NoExtras) {
    MixedCluster c;
    const int n = 3;
    const double spacing = 0.65, box = n * spacing;
    c.system.setDefaultPeriodicBoxVectors(Vec3(box, 0, 0), Vec3(0, box, 0), Vec3(0, 0, box));
    NonbondedForce* nonbonded = new NonbondedForce();
    nonbonded->setNonbondedMethod(NonbondedForce::CutoffPeriodic);
    nonbonded->setCutoffDistance(0.8);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    int k = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int l = 0; l < n; l++, k++) {
                Molecule m = (k % 2 == 0 ? benzene() : linearTriatomic());
                Vec3 center((i + 0.5) * spacing, (j + 0.5) * spacing, (l + 0.5) * spacing);
                vector<int> members;
                for (size_t s = 0; s < m.sites.size(); s++) {
                    members.push_back(c.system.addParticle(m.masses[s]));
                    c.positions.push_back(center + orient(m.sites[s], 0.7 * k, 0.3 + 1.1 * k));
                    nonbonded->addParticle(m.charges[s], m.sigmas[s], m.epsilons[s]);
                }
                for (auto& bond : m.bonds)
                    bonds->addBond(members[bond.first], members[bond.second], 0.1, 0.0);
                for (size_t a = 0; a < members.size(); a++)
                    for (size_t b = a + 1; b < members.size(); b++)
                        nonbonded->addException(members[a], members[b], 0, 1, 0);
                c.molecules.push_back(members);
            }
    c.system.addForce(nonbonded);
    c.system.addForce(bonds);
    if (extras & WithThermostat)
        c.system.addForce(new AndersenThermostat(300, 5.0));
    if (extras & WithMotionRemover)
        c.system.addForce(new CMMotionRemover(3));
    return c;
}

std::map<string, string> platformProperties(const string& name) {
    if (name == "CPU")
        return {{"Threads", "1"}};
    return {};
}

/** Everything a checkpoint restores, as the Context reports it. */
struct Snapshot {
    vector<Vec3> positions, velocities;
    double time = 0;
    long long stepCount = 0;
    Vec3 box[3];
    std::map<string, double> parameters;
};

Snapshot snapshot(Context& context) {
    State state = context.getState(State::Positions | State::Velocities | State::Parameters);
    Snapshot s;
    s.positions = state.getPositions();
    s.velocities = state.getVelocities();
    s.time = state.getTime();
    s.stepCount = state.getStepCount();
    state.getPeriodicBoxVectors(s.box[0], s.box[1], s.box[2]);
    s.parameters = state.getParameters();
    return s;
}

bool sameBits(double a, double b) {
    return std::memcmp(&a, &b, sizeof(double)) == 0;
}

/** Number of coordinates whose bits differ, and the largest difference. */
::testing::AssertionResult bitwiseEqual(const vector<Vec3>& a, const vector<Vec3>& b) {
    if (a.size() != b.size())
        return ::testing::AssertionFailure() << "sizes differ: " << a.size() << " and " << b.size();
    int differing = 0;
    double largest = 0;
    for (size_t i = 0; i < a.size(); i++)
        for (int d = 0; d < 3; d++)
            if (!sameBits(a[i][d], b[i][d])) {
                differing++;
                largest = std::max(largest, std::fabs(a[i][d] - b[i][d]));
            }
    if (differing == 0)
        return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << differing << " of " << 3 * a.size()
                                         << " coordinates differ, by up to " << largest;
}

void expectSameState(const Snapshot& expected, const Snapshot& actual) {
    EXPECT_TRUE(bitwiseEqual(expected.positions, actual.positions)) << "positions";
    EXPECT_TRUE(bitwiseEqual(expected.velocities, actual.velocities)) << "velocities";
    EXPECT_TRUE(sameBits(expected.time, actual.time)) << expected.time << " vs " << actual.time;
    EXPECT_EQ(expected.stepCount, actual.stepCount);
    for (int i = 0; i < 3; i++)
        EXPECT_TRUE(bitwiseEqual({expected.box[i]}, {actual.box[i]})) << "box vector " << i;
    EXPECT_EQ(expected.parameters, actual.parameters);
}

string checkpointOf(Context& context) {
    std::ostringstream stream;
    context.createCheckpoint(stream);
    return stream.str();
}

void loadCheckpoint(Context& context, const string& checkpoint) {
    std::istringstream stream(checkpoint);
    context.loadCheckpoint(stream);
}

/** A Context on a cluster, at 300 K. */
struct TestRun {
    MixedCluster cluster;
    std::unique_ptr<RigidBodyIntegrator> integrator;
    std::unique_ptr<Context> context;

    TestRun(const string& platformName, int extras = NoExtras, bool splitting = false,
        const vector<vector<int> >& bodies = {}) : cluster(mixedCluster(extras)) {
        if (splitting)
            integrator.reset(new RigidSplittingIntegrator(0.002));
        else
            integrator.reset(new MRattleIntegrator(0.002));
        for (const auto& body : bodies)
            integrator->addRigidBody(body);
        context.reset(new Context(cluster.system, *integrator, platform(platformName), platformProperties(platformName)));
        context->setPositions(cluster.positions);
        context->setVelocitiesToTemperature(300, 7);
    }
};

/** Steps before the checkpoint and after it. */
const int StepsBefore = 40, StepsAfter = 60;

void continuedRunMatchesUninterrupted(const string& platformName, int extras, bool splitting) {
    TestRun run(platformName, extras, splitting);
    run.integrator->step(StepsBefore);
    string checkpoint = checkpointOf(*run.context);
    run.integrator->step(StepsAfter);
    Snapshot uninterrupted = snapshot(*run.context);
    double energy = run.context->getState(State::Energy).getPotentialEnergy();

    loadCheckpoint(*run.context, checkpoint);
    run.integrator->step(StepsAfter);
    expectSameState(uninterrupted, snapshot(*run.context));
    EXPECT_TRUE(sameBits(energy, run.context->getState(State::Energy).getPotentialEnergy()));
    // The run really moved: the test compares trajectories, not a frozen state.
    EXPECT_EQ(StepsBefore + StepsAfter, uninterrupted.stepCount);
    EXPECT_GT(std::fabs(uninterrupted.positions[0][0] - run.cluster.positions[0][0]), 1e-4);
}

void newContextMatchesUninterrupted(const string& platformName, int extras, bool splitting) {
    TestRun run(platformName, extras, splitting);
    run.integrator->step(StepsBefore);
    string checkpoint = checkpointOf(*run.context);
    run.integrator->step(StepsAfter);
    Snapshot uninterrupted = snapshot(*run.context);
    run.context.reset();

    // A restart as in a new process: a new System, integrator and Context.
    MixedCluster cluster = mixedCluster(extras);
    std::unique_ptr<RigidBodyIntegrator> integrator;
    if (splitting)
        integrator.reset(new RigidSplittingIntegrator(0.002));
    else
        integrator.reset(new MRattleIntegrator(0.002));
    Context context(cluster.system, *integrator, platform(platformName), platformProperties(platformName));
    loadCheckpoint(context, checkpoint);
    integrator->step(StepsAfter);
    expectSameState(uninterrupted, snapshot(context));
}

} // namespace

TEST(Checkpoint, ContinuedRunIsBitwiseIdenticalOnReference) {
    continuedRunMatchesUninterrupted("Reference", NoExtras, false);
}

TEST(Checkpoint, ContinuedRunIsBitwiseIdenticalOnCpuWithOneThread) {
    continuedRunMatchesUninterrupted("CPU", NoExtras, false);
}

TEST(Checkpoint, ContinuedRunWithThermostatAndMotionRemoverIsBitwiseIdentical) {
    // The Andersen thermostat draws random numbers: the checkpoint restores the generator too.
    continuedRunMatchesUninterrupted("Reference", WithThermostat | WithMotionRemover, false);
    continuedRunMatchesUninterrupted("CPU", WithThermostat | WithMotionRemover, false);
}

TEST(Checkpoint, RigidSplittingContinuedRunIsBitwiseIdentical) {
    continuedRunMatchesUninterrupted("Reference", NoExtras, true);
    continuedRunMatchesUninterrupted("CPU", NoExtras, true);
}

TEST(Checkpoint, RestartInNewContextIsBitwiseIdenticalOnReference) {
    newContextMatchesUninterrupted("Reference", NoExtras, false);
    newContextMatchesUninterrupted("Reference", WithThermostat, false);
}

TEST(Checkpoint, RestartInNewContextIsBitwiseIdenticalOnCpuWithOneThread) {
    newContextMatchesUninterrupted("CPU", NoExtras, false);
}

TEST(Checkpoint, ReinitializePreservingStateContinuesTheRun) {
    // Context::reinitialize(true) goes through a checkpoint: it continues the run that
    // wrote a checkpoint at that step (on Reference, also the run that wrote none).
    for (const string platformName : {"Reference", "CPU"}) {
        TestRun uninterrupted(platformName), reinitialized(platformName);
        uninterrupted.integrator->step(StepsBefore);
        checkpointOf(*uninterrupted.context);
        uninterrupted.integrator->step(StepsAfter);
        reinitialized.integrator->step(StepsBefore);
        reinitialized.context->reinitialize(true);
        EXPECT_EQ(StepsBefore, reinitialized.context->getState(State::Positions).getStepCount());
        reinitialized.integrator->step(StepsAfter);
        expectSameState(snapshot(*uninterrupted.context), snapshot(*reinitialized.context));
        EXPECT_EQ(uninterrupted.integrator->getNumDegreesOfFreedom(), reinitialized.integrator->getNumDegreesOfFreedom());
    }
    TestRun withoutCheckpoint("Reference"), reinitialized("Reference");
    withoutCheckpoint.integrator->step(StepsBefore + StepsAfter);
    reinitialized.integrator->step(StepsBefore);
    reinitialized.context->reinitialize(true);
    reinitialized.integrator->step(StepsAfter);
    expectSameState(snapshot(*withoutCheckpoint.context), snapshot(*reinitialized.context));
}

namespace {

/**
 * Loading a bad checkpoint throws an OpenMMException whose message contains each of
 * the expected phrases, and leaves the Context exactly as it was: same state, and the
 * same trajectory afterwards as a run that never tried.
 */
void expectRefusedAndUnchanged(TestRun& run, const string& badCheckpoint, const vector<string>& phrases) {
    string good = checkpointOf(*run.context);
    Snapshot before = snapshot(*run.context);
    string message = messageOf([&] { loadCheckpoint(*run.context, badCheckpoint); });
    for (const string& phrase : phrases)
        EXPECT_NE(string::npos, message.find(phrase)) << "'" << phrase << "' not in: " << message;
    EXPECT_NE(string::npos, message.find("left as it was")) << message;
    expectSameState(before, snapshot(*run.context));
    run.integrator->step(10);
    Snapshot afterRefusal = snapshot(*run.context);
    loadCheckpoint(*run.context, good);
    run.integrator->step(10);
    expectSameState(afterRefusal, snapshot(*run.context));
}

/** Where the integrator's part of a checkpoint starts. */
size_t integratorDataOffset(const string& checkpoint) {
    size_t offset = checkpoint.rfind("MRattleC");
    EXPECT_NE(string::npos, offset);
    return offset;
}

} // namespace

TEST(Checkpoint, RefusesCheckpointWithOtherBodies) {
    TestRun run("Reference");
    run.integrator->step(5);
    const vector<vector<int> >& molecules = run.cluster.molecules;

    // One molecule fewer is rigid (its atoms are free particles).
    vector<vector<int> > fewer(molecules.begin() + 1, molecules.end());
    TestRun other("Reference", NoExtras, false, fewer);
    other.integrator->step(3);
    expectRefusedAndUnchanged(run, checkpointOf(*other.context), {"rigid bodies", "27", "26"});

    // As many bodies, other memberships: molecule 0 split in two, molecules 1 and 2 joined.
    vector<vector<int> > regrouped(molecules.begin() + 3, molecules.end());
    regrouped.push_back(vector<int>(molecules[0].begin(), molecules[0].begin() + 6));
    regrouped.push_back(vector<int>(molecules[0].begin() + 6, molecules[0].end()));
    vector<int> joined = molecules[1];
    joined.insert(joined.end(), molecules[2].begin(), molecules[2].end());
    regrouped.push_back(joined);
    ASSERT_EQ(molecules.size(), regrouped.size());
    TestRun sameCount("Reference", NoExtras, false, regrouped);
    expectRefusedAndUnchanged(run, checkpointOf(*sameCount.context), {"rigid bodies", "signature"});

    // The same bodies listed in another order are the same bodies.
    vector<vector<int> > reordered(molecules.rbegin(), molecules.rend());
    std::reverse(reordered[0].begin(), reordered[0].end());
    TestRun sameBodies("Reference", NoExtras, false, reordered);
    sameBodies.integrator->step(3);
    Snapshot expected = snapshot(*sameBodies.context);
    loadCheckpoint(*run.context, checkpointOf(*sameBodies.context));
    expectSameState(expected, snapshot(*run.context));
}

TEST(Checkpoint, RefusesCheckpointOfAnotherIntegrator) {
    TestRun run("Reference");
    run.integrator->step(5);
    MixedCluster cluster = mixedCluster();
    VerletIntegrator verlet(0.002);
    Context verletContext(cluster.system, verlet, platform("Reference"));
    verletContext.setPositions(cluster.positions);
    expectRefusedAndUnchanged(run, checkpointOf(verletContext), {"no rigid-body integrator data"});

    TestRun splitting("Reference", NoExtras, true);
    expectRefusedAndUnchanged(run, checkpointOf(*splitting.context), {"IntegrateRigidSplittingStep", "IntegrateMRattleStep"});
}

TEST(Checkpoint, RefusesUnknownFormatVersion) {
    TestRun run("Reference");
    run.integrator->step(5);
    string checkpoint = checkpointOf(*run.context);
    size_t offset = integratorDataOffset(checkpoint);
    int32_t version = 99;
    checkpoint.replace(offset + 8, sizeof(version), reinterpret_cast<const char*>(&version), sizeof(version));
    expectRefusedAndUnchanged(run, checkpoint, {"format version 99", "reads version 1"});

    string badMagic = checkpointOf(*run.context);
    badMagic[integratorDataOffset(badMagic) + 2] = 'X';
    expectRefusedAndUnchanged(run, badMagic, {"malformed"});
}

TEST(Checkpoint, RefusesTruncatedCheckpoint) {
    TestRun run("Reference");
    run.integrator->step(5);
    string checkpoint = checkpointOf(*run.context);
    size_t offset = integratorDataOffset(checkpoint);
    // In the body signature, in the integrator's name, at the start of the integrator's
    // data, and in the middle of the positions (OpenMM then reads what there is).
    expectRefusedAndUnchanged(run, checkpoint.substr(0, checkpoint.size() - 3), {"truncated"});
    expectRefusedAndUnchanged(run, checkpoint.substr(0, offset + 15), {"truncated"});
    expectRefusedAndUnchanged(run, checkpoint.substr(0, offset), {"truncated"});
    expectRefusedAndUnchanged(run, checkpoint.substr(0, offset / 3), {"truncated"});
}

TEST(Checkpoint, RefusedLoadRestoresParametersAndBox) {
    // Global parameters and the box are overwritten by OpenMM before the integrator sees
    // the checkpoint; they are put back too. (The other Context is made first: creating a
    // Context with an Andersen thermostat reseeds the Reference platform's random
    // generator, which all Contexts of the process share.)
    TestRun other("Reference", WithThermostat, false, {mixedCluster().molecules[0]});
    other.context->setParameter(AndersenThermostat::Temperature(), 400);
    other.context->setPeriodicBoxVectors(Vec3(2.1, 0, 0), Vec3(0, 2.1, 0), Vec3(0, 0, 2.1));
    other.context->setTime(12.5);
    string otherCheckpoint = checkpointOf(*other.context);
    TestRun run("Reference", WithThermostat);
    run.context->setParameter(AndersenThermostat::Temperature(), 250);
    run.integrator->step(5);
    expectRefusedAndUnchanged(run, otherCheckpoint, {"rigid bodies"});
    EXPECT_EQ(250, run.context->getParameter(AndersenThermostat::Temperature()));
}

TEST(SavedState, XmlStateContinuesWithBodiesRigidAndShapesKept) {
    for (const string platformName : {"Reference", "CPU"}) {
        TestRun run(platformName);
        run.integrator->step(StepsBefore);
        State saved = run.context->getState(State::Positions | State::Velocities | State::Parameters);
        std::stringstream xml;
        XmlSerializer::serialize<State>(&saved, "State", xml);
        run.integrator->step(StepsAfter);
        Snapshot uninterrupted = snapshot(*run.context);

        MixedCluster cluster = mixedCluster();
        MRattleIntegrator integrator(0.002);
        Context context(cluster.system, integrator, platform(platformName), platformProperties(platformName));
        std::unique_ptr<State> loaded(XmlSerializer::deserialize<State>(xml));
        context.setState(*loaded);
        Snapshot restored = snapshot(context);
        // Positions as saved; velocities re-projected onto rigid motion: equal to round-off.
        EXPECT_TRUE(bitwiseEqual(saved.getPositions(), restored.positions));
        for (size_t i = 0; i < restored.velocities.size(); i++)
            for (int d = 0; d < 3; d++)
                EXPECT_NEAR(saved.getVelocities()[i][d], restored.velocities[i][d], 1e-12);
        EXPECT_EQ(saved.getStepCount(), restored.stepCount);
        // 14 benzenes with 6 degrees of freedom, 13 linear molecules with 5.
        EXPECT_EQ(14 * 6 + 13 * 5, integrator.getNumDegreesOfFreedom());
        EXPECT_EQ(run.integrator->getNumDegreesOfFreedom(), integrator.getNumDegreesOfFreedom());
        for (int b = 0; b < integrator.getNumBodiesInEffect(); b++)
            EXPECT_EQ(integrator.getBodiesInEffect()[b].size() == 3, integrator.isBodyLinear(b)) << "body " << b;

        integrator.step(StepsAfter);
        Snapshot continued = snapshot(context);
        EXPECT_LT(maxDistanceChange(cluster.positions, continued.positions, integrator.getBodiesInEffect()), 1e-10);
        double largest = 0;
        for (size_t i = 0; i < continued.positions.size(); i++) {
            Vec3 d = continued.positions[i] - uninterrupted.positions[i];
            largest = std::max(largest, std::sqrt(d.dot(d)));
        }
        // The same trajectory but for the round-off of the projection (single precision on CPU).
        EXPECT_LT(largest, platformName == "Reference" ? 1e-9 : 1e-5) << platformName;
    }
}
