/*
 * Checkpoints and saved states, for every platform and rigid-body integrator (a
 * value-parameterised suite over allConfigs()):
 * - a run continued from a checkpoint (same Context, a new Context, Context::reinitialize)
 *   is bit for bit the uninterrupted run on Reference, and on CPU with one thread when no
 *   cutoff is used; with a cutoff the CPU platform's neighbour list, built at other steps,
 *   makes them differ at round-off, as it does for OpenMM's VerletIntegrator;
 * - a checkpoint that does not fit (other bodies, another integrator, unknown format,
 *   truncated, damaged) is refused with an OpenMMException that says what differs, and
 *   the Context then refuses to step until Context::reinitialize() (issue 22: OpenMM's
 *   own part of a damaged checkpoint can leave garbage only reinitialize() clears);
 * - setState() and setVelocities() give rigid velocities back bit for bit;
 * - stepping writes no Context checkpoint, whatever global parameters a refused
 *   checkpoint left behind.
 */
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
 * alternating) with Lennard-Jones and Coulomb interactions (reaction field cut off at 0.8 nm
 * with WithCutoff); bonds make each molecule one OpenMM molecule (so one body by default).
 */
struct MixedCluster {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > molecules;
};

enum Extras { NoExtras = 0, WithThermostat = 1, WithMotionRemover = 2, WithCutoff = 4 };

/** Without WithCutoff, the same molecules with no cutoff: the CPU platform then keeps no neighbour list. */
MixedCluster mixedCluster(int extras = NoExtras) {
    MixedCluster c;
    const int n = 3;
    const double spacing = 0.65, box = n * spacing;
    c.system.setDefaultPeriodicBoxVectors(Vec3(box, 0, 0), Vec3(0, box, 0), Vec3(0, 0, box));
    NonbondedForce* nonbonded = new NonbondedForce();
    nonbonded->setNonbondedMethod((extras & WithCutoff) ? NonbondedForce::CutoffPeriodic : NonbondedForce::NoCutoff);
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
    Config config;
    MixedCluster cluster;
    std::unique_ptr<RigidBodyIntegrator> integrator;
    std::unique_ptr<Context> context;

    TestRun(const Config& config, int extras = NoExtras, const vector<vector<int> >& bodies = {})
        : TestRun(config, makeIntegrator(config.integrator, 0.002), extras, bodies) {
    }
    TestRun(const Config& config, std::unique_ptr<RigidBodyIntegrator> integratorToUse, int extras = NoExtras,
            const vector<vector<int> >& bodies = {})
        : config(config), cluster(mixedCluster(extras)), integrator(std::move(integratorToUse)) {
        for (const auto& body : bodies)
            integrator->addRigidBody(body);
        context.reset(new Context(cluster.system, *integrator, platform(config.platform),
                                  platformProperties(config.platform)));
        context->setPositions(cluster.positions);
        context->setVelocitiesToTemperature(300, 7);
    }
};

/** Steps before the checkpoint and after it. */
const int StepsBefore = 40, StepsAfter = 60;

/** Largest coordinate difference between a continued run and the uninterrupted one. */
double continuedRunDifference(TestRun& run, bool expectBitwise) {
    run.integrator->step(StepsBefore);
    string checkpoint = checkpointOf(*run.context);
    run.integrator->step(StepsAfter);
    Snapshot uninterrupted = snapshot(*run.context);
    double energy = run.context->getState(State::Energy).getPotentialEnergy();

    loadCheckpoint(*run.context, checkpoint);
    run.integrator->step(StepsAfter);
    Snapshot continued = snapshot(*run.context);
    if (expectBitwise) {
        expectSameState(uninterrupted, continued);
        EXPECT_TRUE(sameBits(energy, run.context->getState(State::Energy).getPotentialEnergy()));
    }
    // The run really moved: the test compares trajectories, not a frozen state. (Over all
    // atoms: the thermostat's seed is random, and one coordinate can by chance end near its
    // start; 100 steps at 300 K move atoms by a tenth of a nanometre.)
    EXPECT_EQ(StepsBefore + StepsAfter, uninterrupted.stepCount);
    EXPECT_GT(maxDeviation(uninterrupted.positions, run.cluster.positions), 1e-2);
    return maxDeviation(uninterrupted.positions, continued.positions);
}

class Checkpoint : public RigidBodyTest {};
class SavedState : public RigidBodyTest {};

} // namespace

TEST_P(Checkpoint, ContinuedRunIsBitwiseIdentical) {
    TestRun run(GetParam());
    continuedRunDifference(run, true);
}

TEST_P(Checkpoint, ContinuedRunWithThermostatAndMotionRemoverIsBitwiseIdentical) {
    // The Andersen thermostat draws random numbers, OpenMM's and the kernel's (which
    // re-draws whole bodies): the checkpoint restores both.
    TestRun run(GetParam(), WithThermostat | WithMotionRemover);
    continuedRunDifference(run, true);
}

TEST_P(Checkpoint, WithACutoffOnlyReferenceRestartsAreExact) {
    // The CPU and OpenCL platforms keep neighbour lists (and more) built at earlier steps,
    // so with a cutoff a continued run can differ at round-off; measured against OpenMM's
    // own VerletIntegrator on the same System and platform, whose restart differs likewise
    // (the plugin's within 3x of it, measured): within 10x of it, or 1e-10 nm where it is exact.
    TestRun run(GetParam(), WithCutoff);
    const bool reference = GetParam().platform == "Reference";
    double difference = continuedRunDifference(run, reference);
    if (!reference) {
        MixedCluster cluster = mixedCluster(WithCutoff);
        VerletIntegrator verlet(0.002);
        std::unique_ptr<Context> context = makeContext(cluster.system, verlet);
        context->setState(run.context->getState(State::Positions | State::Velocities));
        verlet.step(StepsBefore);
        string checkpoint = checkpointOf(*context);
        verlet.step(StepsAfter);
        vector<Vec3> uninterrupted = context->getState(State::Positions).getPositions();
        loadCheckpoint(*context, checkpoint);
        verlet.step(StepsAfter);
        double verletDifference = maxDeviation(uninterrupted, context->getState(State::Positions).getPositions());
        std::cout << GetParam().platform << ", cutoff 0.8 nm, " << StepsAfter
                  << " steps after a checkpoint: continued run differs by " << difference
                  << " nm (VerletIntegrator: " << verletDifference << " nm)" << std::endl;
        EXPECT_LT(difference, std::max(10 * verletDifference, 1e-10));
    }
}

TEST_P(Checkpoint, RestartInNewContextIsBitwiseIdentical) {
    for (int extras : {NoExtras, WithThermostat}) {
        TestRun run(GetParam(), extras);
        run.integrator->step(StepsBefore);
        string checkpoint = checkpointOf(*run.context);
        run.integrator->step(StepsAfter);
        Snapshot uninterrupted = snapshot(*run.context);
        run.context.reset();

        // A restart as in a new process: a new System, integrator and Context.
        MixedCluster cluster = mixedCluster(extras);
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
        std::unique_ptr<Context> context = makeContext(cluster.system, *integrator);
        loadCheckpoint(*context, checkpoint);
        integrator->step(StepsAfter);
        expectSameState(uninterrupted, snapshot(*context));
    }
}

TEST_P(Checkpoint, ReinitializePreservingStateContinuesTheRun) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    // Context::reinitialize(true) goes through a checkpoint.
    TestRun uninterrupted(GetParam()), reinitialized(GetParam());
    uninterrupted.integrator->step(StepsBefore + StepsAfter);
    reinitialized.integrator->step(StepsBefore);
    reinitialized.context->reinitialize(true);
    EXPECT_EQ(StepsBefore, reinitialized.context->getState(State::Positions).getStepCount());
    reinitialized.integrator->step(StepsAfter);
    expectSameState(snapshot(*uninterrupted.context), snapshot(*reinitialized.context));
    EXPECT_EQ(uninterrupted.integrator->getNumDegreesOfFreedom(), reinitialized.integrator->getNumDegreesOfFreedom());
}

namespace {

/**
 * Loading a bad checkpoint throws an OpenMMException whose message contains each of the
 * expected phrases and says what to do; stepping is refused, setState() or not, until
 * Context::reinitialize(); then with the state set again the run is the one a good
 * checkpoint gives.
 */
void expectRefusedUntilStateIsSet(TestRun& run, const string& badCheckpoint, const vector<string>& phrases) {
    string good = checkpointOf(*run.context);
    State saved = run.context->getState(State::Positions | State::Velocities | State::Parameters);
    string message = messageOf([&] { loadCheckpoint(*run.context, badCheckpoint); });
    for (const string& phrase : phrases)
        EXPECT_NE(string::npos, message.find(phrase)) << "'" << phrase << "' not in: " << message;
    EXPECT_NE(string::npos, message.find("call Context::reinitialize()")) << message;

    string refusal = messageOf([&] { run.integrator->step(1); });
    EXPECT_NE(string::npos, refusal.find("loadCheckpoint() was refused")) << refusal;
    run.context->setPositions(saved.getPositions());
    EXPECT_THROW(run.integrator->step(1), OpenMMException) << "stepped with the checkpoint's velocities";
    run.context->setState(saved);
    EXPECT_THROW(run.integrator->step(1), OpenMMException) << "stepped before reinitialize()";
    run.context->reinitialize();
    run.context->setState(saved);
    run.integrator->step(10);
    Snapshot afterRefusal = snapshot(*run.context);

    loadCheckpoint(*run.context, good);
    run.integrator->step(10);
    // An integrator's own state (a random stream, a thermostat's chain) restarts at
    // reinitialize() (a State does not hold it), so only one without it continues as the
    // good checkpoint's.
    if (!run.config.traits().hasOwnState)
        expectSameState(afterRefusal, snapshot(*run.context));
}

/** Where the integrator's part of a checkpoint starts. */
size_t integratorDataOffset(const string& checkpoint) {
    size_t offset = checkpoint.rfind("MRattleC");
    EXPECT_NE(string::npos, offset);
    return offset;
}

} // namespace

TEST_P(Checkpoint, RefusesCheckpointWithOtherBodies) {
    TestRun run(GetParam());
    run.integrator->step(5);
    const vector<vector<int> >& molecules = run.cluster.molecules;

    // One molecule fewer is rigid (its atoms are free particles).
    vector<vector<int> > fewer(molecules.begin() + 1, molecules.end());
    TestRun other(GetParam(), NoExtras, fewer);
    other.integrator->step(3);
    expectRefusedUntilStateIsSet(run, checkpointOf(*other.context), {"rigid bodies", "27", "26"});

    // As many bodies, other memberships: molecule 0 split in two, molecules 1 and 2 joined.
    vector<vector<int> > regrouped(molecules.begin() + 3, molecules.end());
    regrouped.push_back(vector<int>(molecules[0].begin(), molecules[0].begin() + 6));
    regrouped.push_back(vector<int>(molecules[0].begin() + 6, molecules[0].end()));
    vector<int> joined = molecules[1];
    joined.insert(joined.end(), molecules[2].begin(), molecules[2].end());
    regrouped.push_back(joined);
    ASSERT_EQ(molecules.size(), regrouped.size());
    TestRun sameCount(GetParam(), NoExtras, regrouped);
    expectRefusedUntilStateIsSet(run, checkpointOf(*sameCount.context), {"rigid bodies", "signature"});

    // The same bodies listed in another order are the same bodies.
    vector<vector<int> > reordered(molecules.rbegin(), molecules.rend());
    std::reverse(reordered[0].begin(), reordered[0].end());
    TestRun sameBodies(GetParam(), NoExtras, reordered);
    sameBodies.integrator->step(3);
    Snapshot expected = snapshot(*sameBodies.context);
    loadCheckpoint(*run.context, checkpointOf(*sameBodies.context));
    expectSameState(expected, snapshot(*run.context));
    run.integrator->step(1);
}

TEST_P(Checkpoint, RefusesCheckpointOfAnotherIntegrator) {
    TestRun run(GetParam());
    run.integrator->step(5);
    MixedCluster cluster = mixedCluster();
    VerletIntegrator verlet(0.002);
    std::unique_ptr<Context> verletContext = makeContext(cluster.system, verlet);
    verletContext->setPositions(cluster.positions);
    expectRefusedUntilStateIsSet(run, checkpointOf(*verletContext), {"no rigid-body integrator data"});

    // Every other rigid-body integrator that runs on this platform.
    for (const Config& other : allConfigs()) {
        if (other.platform != GetParam().platform || other.integrator == GetParam().integrator)
            continue;
        TestRun otherRun(other);
        // On a device platform OpenMM's own part of a stochastic integrator's checkpoint holds
        // its device random state, which a deterministic one's lacks: the plugin's part is then
        // not where it looks, and the refusal says the integrator is another one without naming it.
        const bool otherLayout =
            isDevicePlatform(other.platform) && other.traits().stochastic != GetParam().traits().stochastic;
        expectRefusedUntilStateIsSet(run, checkpointOf(*otherRun.context),
                                     otherLayout ? vector<string>{"a different integrator"}
                                                 : vector<string>{"Integrate" + other.integrator + "Step",
                                                                  "Integrate" + GetParam().integrator + "Step"});
    }
}

TEST_P(Checkpoint, RefusesUnknownFormatVersionAndDamage) {
    TestRun run(GetParam());
    run.integrator->step(5);
    string checkpoint = checkpointOf(*run.context);
    size_t offset = integratorDataOffset(checkpoint);
    int32_t version = 99;
    checkpoint.replace(offset + 8, sizeof(version), reinterpret_cast<const char*>(&version), sizeof(version));
    expectRefusedUntilStateIsSet(run, checkpoint, {"format version 99", "reads versions 3 to 4"});

    string badMagic = checkpointOf(*run.context);
    badMagic[integratorDataOffset(badMagic) + 2] = 'X';
    expectRefusedUntilStateIsSet(run, badMagic, {"malformed"});

    // A flipped bit in the integrator's name: the message shows the name, unprintable bytes escaped.
    string flipped = checkpointOf(*run.context);
    flipped[integratorDataOffset(flipped) + 16] ^= 0x80;
    expectRefusedUntilStateIsSet(run, flipped, {"kernel '\\x", "this one uses"});
}

TEST_P(Checkpoint, RefusesTruncatedCheckpoint) {
    TestRun run(GetParam());
    run.integrator->step(5);
    string checkpoint = checkpointOf(*run.context);
    size_t offset = integratorDataOffset(checkpoint);
    // In the kernel's state, in the integrator's name, at the start of the integrator's
    // data, and in the middle of the positions (OpenMM then reads what there is).
    expectRefusedUntilStateIsSet(run, checkpoint.substr(0, checkpoint.size() - 3), {"truncated"});
    expectRefusedUntilStateIsSet(run, checkpoint.substr(0, offset + 15), {"truncated"});
    expectRefusedUntilStateIsSet(run, checkpoint.substr(0, offset), {"truncated"});
    expectRefusedUntilStateIsSet(run, checkpoint.substr(0, offset / 3), {"truncated"});
}

TEST_P(Checkpoint, SteppingWritesNoCheckpointEvenWithJunkLeftByARefusedOne) {
    // A checkpoint from another System, with a global parameter this one lacks, and other
    // bodies: OpenMM adds the parameter before the integrator refuses the checkpoint.
    MixedCluster other = mixedCluster();
    CustomExternalForce* external = new CustomExternalForce("junk*x");
    external->addGlobalParameter("junk", 0.0);
    other.system.addForce(external);
    MRattleIntegrator otherIntegrator(0.002);
    otherIntegrator.addRigidBody(other.molecules[0]);
    Context otherContext(other.system, otherIntegrator, platform(GetParam().platform));
    otherContext.setPositions(other.positions);
    const string junkCheckpoint = checkpointOf(otherContext);

    std::unique_ptr<RigidBodyIntegrator> counting = makeCountingCheckpoints(GetParam().integrator, 0.002);
    const CheckpointCounter& counter = dynamic_cast<const CheckpointCounter&>(*counting);
    TestRun run(GetParam(), std::move(counting), WithThermostat);
    auto written = [&] { return counter.checkpointsWritten; };
    run.context->setParameter(AndersenThermostat::Temperature(), 310);
    State saved = run.context->getState(State::Positions | State::Velocities | State::Parameters);
    const string refusal = messageOf([&] { loadCheckpoint(*run.context, junkCheckpoint); });
    EXPECT_EQ(1, run.context->getParameters().count("junk")) << "OpenMM left the checkpoint's parameter";
    run.context->setState(saved);
    // Refused by the integrator (OpenCL's own part may refuse it first: other precision).
    if (refusal.find("OpenMM had already loaded") != string::npos) {
        EXPECT_THROW(run.integrator->step(1), OpenMMException) << "stepped with the junk before reinitialize()";
        run.context->reinitialize();
        EXPECT_EQ(0, run.context->getParameters().count("junk")) << "reinitialize() clears the checkpoint's parameter";
        run.context->setState(saved);
    }
    const int before = written();
    for (int i = 0; i < 50; i++) {
        run.context->setParameter(AndersenThermostat::Temperature(), 300 + i);
        run.integrator->step(1);
    }
    run.context->setVelocitiesToTemperature(300, 3);
    run.integrator->step(50);
    EXPECT_EQ(before, written()) << "a step, setParameter() or setVelocities() wrote a checkpoint";
    checkpointOf(*run.context);
    EXPECT_EQ(before + 1, written());  // the counter counts
}

TEST_P(SavedState, GivesRigidVelocitiesBackBitForBit) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    TestRun run(GetParam());
    run.integrator->step(StepsBefore);
    State saved = run.context->getState(State::Positions | State::Velocities | State::Parameters);
    std::stringstream xml;
    XmlSerializer::serialize<State>(&saved, "State", xml);
    run.integrator->step(StepsAfter);
    Snapshot uninterrupted = snapshot(*run.context);

    // Into a new Context through XML, as Simulation.saveState()/loadState() do.
    MixedCluster cluster = mixedCluster();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(cluster.system, *integrator);
    std::unique_ptr<State> loaded(XmlSerializer::deserialize<State>(xml));
    context->setState(*loaded);
    Snapshot restored = snapshot(*context);
    EXPECT_TRUE(bitwiseEqual(saved.getPositions(), restored.positions));
    EXPECT_TRUE(bitwiseEqual(saved.getVelocities(), restored.velocities));
    EXPECT_EQ(saved.getStepCount(), restored.stepCount);
    // 14 benzenes with 6 degrees of freedom, 13 linear molecules with 5.
    EXPECT_EQ(14 * 6 + 13 * 5, integrator->getNumDegreesOfFreedom());
    for (int b = 0; b < integrator->getNumBodiesInEffect(); b++)
        EXPECT_EQ(integrator->getBodiesInEffect()[b].size() == 3, integrator->isBodyLinear(b)) << "body " << b;
    // The same trajectory, bit for bit (the forces are computed afresh, as after a checkpoint).
    integrator->step(StepsAfter);
    expectSameState(uninterrupted, snapshot(*context));
}

TEST_P(SavedState, SetVelocitiesProjectsOnlyVelocitiesThatAreNotRigid) {
    TestRun run(GetParam());
    run.integrator->step(10);
    State state = run.context->getState(State::Positions | State::Velocities);
    run.context->setVelocities(state.getVelocities());
    EXPECT_TRUE(bitwiseEqual(state.getVelocities(), snapshot(*run.context).velocities));

    // One atom of body 0 pushed: that body is projected back onto rigid motion, the others are untouched.
    vector<Vec3> pushed = state.getVelocities();
    pushed[0] += Vec3(0.5, -0.3, 0.2);
    run.context->setVelocities(pushed);
    vector<Vec3> projected = snapshot(*run.context).velocities;
    const vector<int>& body = run.integrator->getBodiesInEffect()[0];
    const vector<Vec3>& x = state.getPositions();
    for (int i : body)
        for (int j : body) {
            // d|x_i - x_j|^2/dt = 0 for rigid motion.
            double rate = 2 * (x[i] - x[j]).dot(projected[i] - projected[j]);
            EXPECT_NEAR(0.0, rate, 1e-12) << i << "-" << j;
        }
    EXPECT_GT(maxDeviation(state.getVelocities(), projected), 1e-3);
    for (int i = 0; i < (int) pushed.size(); i++)
        if (std::find(body.begin(), body.end(), i) == body.end())
            EXPECT_TRUE(bitwiseEqual({pushed[i]}, {projected[i]})) << "particle " << i;
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, Checkpoint, ::testing::ValuesIn(allConfigs()), configName);
INSTANTIATE_TEST_SUITE_P(AllConfigs, SavedState, ::testing::ValuesIn(allConfigs()), configName);
