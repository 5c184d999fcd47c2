/*
 * M-RATTLE on each device platform of the build's list (OpenCL, here through pocl on a
 * machine without a GPU; CUDA where built and a device is present), in each
 * precision mode, against the Reference platform: the 27-benzene cluster and a rigid
 * water box after 100 steps, rigidity and energy conservation over long runs, checkpoints,
 * virtual sites, free constrained particles next to bodies, a failed step. pocl compiles
 * kernels slowly, so the tests create few Contexts. A platform OpenMM lacks here, or
 * without a device, is skipped, saying why.
 */
#include "TestSupport.h"
#include "MRattleNoseHooverIntegrator.h"
#include "MRattlePlatforms.h"
#include <gtest/gtest.h>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

/** Every device platform of the build's list (those OpenMM lacks here are skipped, saying why). */
vector<string> builtDevicePlatforms() {
    vector<string> names;
    for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms)
        if (built.device)
            names.push_back(built.name);
    return names;
}

/** The suite runs once per device platform. */
class DevicePlatform : public ::testing::TestWithParam<string> {
protected:
    void SetUp() override {
        MRATTLE_SKIP_IF_UNAVAILABLE(GetParam());
    }
};

std::unique_ptr<Context> deviceContext(const string& platformName, const System& system, Integrator& integrator,
                                       const string& precision) {
    return std::unique_ptr<Context>(
        new Context(system, integrator, platform(platformName), {{"Precision", precision}}));
}

/** Positions after steps on a platform from a given rigid start. */
vector<Vec3> run(const System& system, const State& start, int steps, const string& platformName,
                 const string& precision = "") {
    MRattleIntegrator integrator(0.002);
    std::unique_ptr<Context> context;
    if (isDevicePlatform(platformName))
        context = deviceContext(platformName, system, integrator, precision);
    else
        context.reset(new Context(system, integrator, platform(platformName)));
    context->setState(start);
    integrator.step(steps);
    return context->getState(State::Positions).getPositions();
}

/** Total energy of a Context. */
double totalEnergy(Context& context) {
    State state = context.getState(State::Energy);
    return state.getKineticEnergy() + state.getPotentialEnergy();
}

/** NVE run: the total energy every `every` steps. */
vector<double> energySeries(Context& context, Integrator& integrator, int samples, int every) {
    vector<double> energies;
    for (int i = 0; i < samples; i++) {
        integrator.step(every);
        energies.push_back(totalEnergy(context));
    }
    return energies;
}

/** 64 rigid TIP3P waters: a periodic box with PME, or a cluster without cutoff. */
Cluster waterBox(NonbondedForce::NonbondedMethod method = NonbondedForce::PME) {
    ClusterOptions options;
    options.method = method;
    options.cutoff = 0.6;
    options.minSiteDistance = 0.17;
    return buildCluster(water(), 4, 0.32, 11, options);
}

/** Positions after 100 steps of OpenMM's VerletIntegrator with SETTLE (waters at their start geometry). */
vector<Vec3> settleRun(const State& start, const string& platformName, NonbondedForce::NonbondedMethod method) {
    Cluster c = waterBox(method);
    for (const vector<int>& w : c.molecules)
        for (int a = 0; a < 3; a++)
            for (int b = a + 1; b < 3; b++) {
                Vec3 d = start.getPositions()[w[a]] - start.getPositions()[w[b]];
                c.system->addConstraint(w[a], w[b], std::sqrt(d.dot(d)));
            }
    VerletIntegrator integrator(0.002);
    integrator.setConstraintTolerance(1e-10);
    std::unique_ptr<Context> context = (isDevicePlatform(platformName) ? deviceContext(platformName, *c.system, integrator, "double")
                                                                 : std::unique_ptr<Context>(new Context(*c.system, integrator, platform(platformName))));
    context->setState(start);
    integrator.step(100);
    return context->getState(State::Positions).getPositions();
}

/** A rigid start at 300 K (from Reference). */
State rigidStart(const Cluster& c) {
    MRattleIntegrator integrator(0.002);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 3);
    return context.getState(State::Positions | State::Velocities);
}

} // namespace

TEST_P(DevicePlatform, DoublePrecisionAgreesWithReference) {
    for (const string model : {"27 benzenes"}) {
        Cluster c = buildCluster(benzene(), 3, 0.7, 1);
        State start = rigidStart(c);
        vector<Vec3> opencl = run(*c.system, start, 100, GetParam(), "double");
        vector<Vec3> reference = run(*c.system, start, 100, "Reference");
        double difference = maxDeviation(opencl, reference);
        std::cout << model << ", 100 steps of 2 fs: " << GetParam() << " (double) vs Reference " << difference << " nm" << std::endl;
        EXPECT_GT(maxDeviation(start.getPositions(), reference), 1e-3) << model;  // they moved
        EXPECT_LT(difference, 1e-8) << model;
        EXPECT_LT(maxDistanceChange(start.getPositions(), opencl, c.molecules), 1e-10) << model;
    }
}

TEST_P(DevicePlatform, WaterBoxAgreesWithReferenceAsVerletWithSettleDoes) {
    // Light, fast waters amplify the platforms' force differences (PME, or the order of
    // sums without cutoff) within 100 steps, so the yardstick is OpenMM's own
    // VerletIntegrator with SETTLE on the same box and start.
    for (auto method : {NonbondedForce::PME, NonbondedForce::NoCutoff}) {
        const string name = (method == NonbondedForce::PME ? "PME" : "no cutoff");
        Cluster c = waterBox(method);
        State start = rigidStart(c);
        const double mrattle =
            maxDeviation(run(*c.system, start, 100, GetParam(), "double"), run(*c.system, start, 100, "Reference"));
        const double settle = maxDeviation(settleRun(start, GetParam(), method), settleRun(start, "Reference", method));
        std::cout << "64 TIP3P waters, " << name << ", 100 steps of 2 fs, " << GetParam() << " (double) vs Reference: M-RATTLE "
                  << mrattle << " nm, VerletIntegrator with SETTLE " << settle << " nm" << std::endl;
        EXPECT_GT(settle, 0.0) << name;
        EXPECT_LT(mrattle, 3 * settle) << name;
    }
}

TEST_P(DevicePlatform, MixedPrecisionAgreesAndStaysRigid) {
    Cluster c = buildCluster(benzene(), 3, 0.7, 1);
    State start = rigidStart(c);
    vector<Vec3> reference100 = run(*c.system, start, 100, "Reference");
    MRattleIntegrator integrator(0.002);
    std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, integrator, "mixed");
    context->setState(start);
    // OpenMM stores mixed-precision positions at its own precision: rigidity is measured
    // from the positions the Context reports, not the double-precision ones set.
    const vector<Vec3> stored = context->getState(State::Positions).getPositions();
    integrator.step(100);
    const double difference = maxDeviation(context->getState(State::Positions).getPositions(), reference100);
    integrator.step(9900);
    const double rigidity = maxDistanceChange(stored, context->getState(State::Positions).getPositions(), c.molecules);
    std::cout << "27 benzenes, " << GetParam() << " mixed: " << difference << " nm from Reference after 100 steps; rigidity "
              << rigidity << " nm after 10,000 steps of 2 fs" << std::endl;
    EXPECT_LT(difference, 1e-4);
    EXPECT_LT(rigidity, 1e-6);
}

TEST_P(DevicePlatform, MixedPrecisionConservesEnergyLikeReference) {
    // The NVE energy fluctuation of one chaotic trajectory is itself noisy: two Reference
    // runs whose starts differ by 1e-9 nm differ by ~20% over 10,000 steps. So each
    // platform runs 4 independent starts, and the means are compared with their errors.
    Cluster c = buildCluster(benzene(), 3, 0.7, 1);
    const int starts = 4;
    vector<double> fluctuation[2];
    for (int seed = 1; seed <= starts; seed++) {
        MRattleIntegrator setup(0.002);
        Context setupContext(*c.system, setup, platform("Reference"));
        setupContext.setPositions(c.positions);
        setupContext.setVelocitiesToTemperature(300, seed);
        State start = setupContext.getState(State::Positions | State::Velocities);
        for (int p = 0; p < 2; p++) {
            MRattleIntegrator integrator(0.002);
            std::unique_ptr<Context> context = (p == 0 ? std::unique_ptr<Context>(new Context(*c.system, integrator, platform("Reference")))
                                                       : deviceContext(GetParam(), *c.system, integrator, "mixed"));
            context->setState(start);
            integrator.step(100);
            fluctuation[p].push_back(standardDeviation(energySeries(*context, integrator, 50, 80)));
        }
    }
    const double reference = mean(fluctuation[0]), mixed = mean(fluctuation[1]);
    const double referenceError = standardDeviation(fluctuation[0]) / std::sqrt(starts - 1.0);
    const double mixedError = standardDeviation(fluctuation[1]) / std::sqrt(starts - 1.0);
    const double ratio = mixed / reference;
    const double ratioError = ratio * std::sqrt(std::pow(referenceError / reference, 2) + std::pow(mixedError / mixed, 2));
    std::cout << "27 benzenes, NVE energy fluctuation over 4,000 steps of 2 fs, mean of " << starts
              << " starts: Reference " << reference << " +- " << referenceError << ", " << GetParam() << " mixed " << mixed << " +- "
              << mixedError << " kJ/mol; ratio " << ratio << " +- " << ratioError << std::endl;
    EXPECT_GT(reference, 0.0);
    // Within 10% of Reference's, or within what the runs can resolve (3 standard errors),
    // which must be enough to see a mixed-precision step twice as noisy (0.25 measured).
    EXPECT_LT(std::fabs(ratio - 1), std::max(0.1, 3 * ratioError));
    EXPECT_LT(ratioError, 0.33);
}

TEST_P(DevicePlatform, SinglePrecisionRunsAndIsMeasured) {
    Cluster c = buildCluster(benzene(), 3, 0.7, 1);
    State start = rigidStart(c);
    MRattleIntegrator integrator(0.002);
    std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, integrator, "single");
    context->setState(start);
    const vector<Vec3> stored = context->getState(State::Positions).getPositions();
    vector<double> energies = energySeries(*context, integrator, 100, 100);
    const double rigidity = maxDistanceChange(stored, context->getState(State::Positions).getPositions(), c.molecules);
    std::cout << "27 benzenes, " << GetParam() << " single, 10,000 steps of 2 fs: rigidity " << rigidity << " nm, energy fluctuation "
              << standardDeviation(energies) << " kJ/mol, drift " << linearSlope(energies) * energies.size()
              << " kJ/mol" << std::endl;
    for (double energy : energies)
        ASSERT_TRUE(std::isfinite(energy));
    // Single precision: 4.5e-7 nm and 0.56 kJ/mol measured (docs/platforms.md); 10x as a guard.
    EXPECT_LT(rigidity, 5e-6);
    EXPECT_LT(standardDeviation(energies), 5.6);
}

TEST_P(DevicePlatform, CheckpointRestartIsBitForBit) {
    // With an Andersen thermostat (random numbers and body collisions) in double and mixed
    // precision, without a cutoff. (With PME and the thermostat the continued run has been
    // seen to differ at round-off: docs/platforms.md.)
    for (const string precision : {"mixed", "double"}) {
        Cluster c = waterBox(NonbondedForce::NoCutoff);
        c.system->addForce(new AndersenThermostat(300, 20.0));
        MRattleIntegrator integrator(0.002);
        std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, integrator, precision);
        context->setState(rigidStart(c));
        integrator.step(20);
        std::stringstream checkpoint;
        context->createCheckpoint(checkpoint);
        integrator.step(100);
        State uninterrupted = context->getState(State::Positions | State::Velocities);
        context->loadCheckpoint(checkpoint);
        integrator.step(100);
        State continued = context->getState(State::Positions | State::Velocities);
        EXPECT_EQ(120, continued.getStepCount());
        EXPECT_GT(maxDeviation(rigidStart(c).getPositions(), continued.getPositions()), 1e-3);
        for (size_t i = 0; i < continued.getPositions().size(); i++)
            for (int d = 0; d < 3; d++) {
                ASSERT_EQ(uninterrupted.getPositions()[i][d], continued.getPositions()[i][d]) << precision << " atom " << i;
                ASSERT_EQ(uninterrupted.getVelocities()[i][d], continued.getVelocities()[i][d]) << precision << " atom " << i;
            }
    }
}

TEST_P(DevicePlatform, PositionsSetAgainAreCheckedOnTheDeviceAgainstEachBodysShape) {
    // 64 waters, 63 constrained to their geometry and the first rigid by declaration alone.
    // A saved State set again fits every body's reference turned (kernels/fitReference.cc:
    // no download); positions that do not fit are classified on the host as at the first
    // set: an off-geometry water is put back on its constraints, a new shape is kept, NaN refused
    // (in a body, and in a free atom, which no body's fit reads).
    Cluster c = waterBox(NonbondedForce::NoCutoff);
    const int freeAtom = c.system->addParticle(4.0);
    for (int f = 0; f < c.system->getNumForces(); f++)
        if (NonbondedForce* nonbonded = dynamic_cast<NonbondedForce*>(&c.system->getForce(f)))
            nonbonded->addParticle(0, 0.1, 0);
    c.positions.push_back(Vec3(3, 3, 3));
    const State start = rigidStart(c);
    for (size_t m = 1; m < c.molecules.size(); m++)
        for (int a = 0; a < 3; a++)
            for (int b = a + 1; b < 3; b++) {
                const Vec3 d = start.getPositions()[c.molecules[m][a]] - start.getPositions()[c.molecules[m][b]];
                c.system->addConstraint(c.molecules[m][a], c.molecules[m][b], std::sqrt(d.dot(d)));
            }
    const vector<vector<int> > constrained(c.molecules.begin() + 1, c.molecules.end()), declared(1, c.molecules[0]);
    for (const string precision : {"single", "mixed", "double"}) {
        const double roundoff = (precision == "double" ? 1e-12 : 1e-5);
        // OpenMM's host constraint code puts a water back on its geometry to about 5e-8 of it.
        const double onGeometry = std::max(roundoff, 1e-8);
        // OpenMM 7.7 stores positions set from the host as floats in mixed precision too.
        const double stored = (precision == "mixed" ? 1e-6 : 0.0);
        MRattleIntegrator integrator(0.002);
        std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, integrator, precision);
        context->setState(start);
        integrator.step(20);
        const State saved = context->getState(State::Positions | State::Velocities);
        integrator.step(20);
        const vector<Vec3> after40 = context->getState(State::Positions).getPositions();
        context->setState(saved);
        EXPECT_LE(maxDeviation(saved.getPositions(), context->getState(State::Positions).getPositions()), stored) << precision;
        integrator.step(20);
        vector<Vec3> moved = context->getState(State::Positions).getPositions();
        EXPECT_LT(maxDeviation(after40, moved), roundoff) << precision;
        // An H of a constrained water 1e-3 nm off, the declared water 1% larger.
        moved[c.molecules[1][1]] += Vec3(1e-3, 0, 0);
        const Vec3 center = moved[c.molecules[0][0]];
        for (int atom : c.molecules[0])
            moved[atom] = center + (moved[atom] - center) * 1.01;
        context->setPositions(moved);
        EXPECT_LT(maxDistanceChange(start.getPositions(), context->getState(State::Positions).getPositions(), constrained),
                  onGeometry) << precision;
        integrator.step(20);
        const vector<Vec3> stepped = context->getState(State::Positions).getPositions();
        EXPECT_LT(maxDistanceChange(moved, stepped, declared), roundoff) << precision;
        EXPECT_GT(maxDistanceChange(start.getPositions(), stepped, declared), 5e-4) << precision;
        EXPECT_LT(maxDistanceChange(start.getPositions(), stepped, constrained), onGeometry) << precision;
        for (int nanAtom : {c.molecules[5][2], freeAtom}) {
            vector<Vec3> bad = stepped;  // positions that fit but for the NaN
            bad[nanAtom][1] = std::nan("");
            EXPECT_NE(string::npos, messageOf([&]() { context->setPositions(bad); })
                                        .find("the position of particle " + std::to_string(nanAtom) + " is not finite"))
                << precision << " atom " << nanAtom;
        }
    }
}

TEST_P(DevicePlatform, FreeConstrainedParticlesBesideBodies) {
    // 27 tetrahedral molecules: 14 declared rigid, the other 13 free with their four bonds
    // to the centre constrained (RATTLE clusters on the device) and no other constraint.
    Cluster c = buildCluster(tetrahedral(), 3, 0.5, 6);
    vector<vector<int> > rigid;
    for (size_t m = 0; m < c.molecules.size(); m++) {
        const vector<int>& atoms = c.molecules[m];
        if (m % 2 == 0)
            rigid.push_back(atoms);
        else
            for (int k = 1; k < 5; k++) {
                Vec3 d = c.positions[atoms[k]] - c.positions[atoms[0]];
                c.system->addConstraint(atoms[0], atoms[k], std::sqrt(d.dot(d)));
            }
    }
    State start;
    {
        MRattleIntegrator integrator(0.001);
        for (const vector<int>& body : rigid)
            integrator.addRigidBody(body);
        Context context(*c.system, integrator, platform("Reference"));
        context.setPositions(c.positions);
        context.setVelocitiesToTemperature(300, 4);
        start = context.getState(State::Positions | State::Velocities);
    }
    vector<vector<Vec3> > results;
    for (const string name : {string("Reference"), GetParam()}) {
        MRattleIntegrator integrator(0.001);
        integrator.setConstraintTolerance(1e-8);
        for (const vector<int>& body : rigid)
            integrator.addRigidBody(body);
        std::unique_ptr<Context> context = (isDevicePlatform(name) ? deviceContext(name, *c.system, integrator, "double")
                                                             : std::unique_ptr<Context>(new Context(*c.system, integrator, platform(name))));
        context->setState(start);
        EXPECT_EQ(14, integrator.getNumBodiesInEffect());
        integrator.step(100);
        State state = context->getState(State::Positions | State::Velocities);
        results.push_back(state.getPositions());
        // The constraints hold, positions and velocities.
        for (int k = 0; k < c.system->getNumConstraints(); k++) {
            int p1, p2;
            double distance;
            c.system->getConstraintParameters(k, p1, p2, distance);
            Vec3 r = state.getPositions()[p1] - state.getPositions()[p2];
            Vec3 v = state.getVelocities()[p1] - state.getVelocities()[p2];
            EXPECT_NEAR(distance, std::sqrt(r.dot(r)), 1e-7) << name << " constraint " << k;
            EXPECT_LT(std::fabs(r.dot(v)) / r.dot(r), 1e-6) << name << " constraint " << k;
        }
        EXPECT_LT(maxDistanceChange(start.getPositions(), state.getPositions(), rigid), 1e-10) << name;
    }
    std::cout << "free constrained molecules beside bodies, 100 steps: " << GetParam() << " (double) vs Reference "
              << maxDeviation(results[0], results[1]) << " nm" << std::endl;
    EXPECT_GT(maxDeviation(start.getPositions(), results[0]), 1e-3);
    EXPECT_LT(maxDeviation(results[0], results[1]), 1e-6);
}

TEST_P(DevicePlatform, SplittingIntegratorNamesThePlatformsItSupports) {
    Cluster c = buildCluster(benzene(), 1, 0.7, 1);
    std::unique_ptr<RigidBodyIntegrator> splitting = makeIntegrator("RigidSplitting", 0.002);
    string message = messageOf([&] { deviceContext(GetParam(), *c.system, *splitting, "double"); });
    EXPECT_NE(string::npos, message.find("RigidSplittingIntegrator")) << message;
    EXPECT_NE(string::npos, message.find("Reference")) << message;
    EXPECT_NE(string::npos, message.find("CPU")) << message;
    EXPECT_EQ(string::npos, message.find(GetParam() + ",")) << message;
}




TEST_P(DevicePlatform, FailedStepIsReportedWithTheStateBeforeIt) {
    // A spinning diatomic whose drift in one step is five times its length: no rotation
    // satisfies the reset. Every platform refuses the step that fails, before its step count
    // moves (the device records the failure, does nothing more, and the host reads the flag
    // at the end of the step), with the Context as it was before the step: no read of the
    // state can return frozen positions under an advancing step count.
    System system;
    system.addParticle(12.0);
    system.addParticle(16.0);
    HarmonicBondForce* bond = new HarmonicBondForce();
    bond->addBond(0, 1, 0.1, 0.0);
    system.addForce(bond);
    const vector<Vec3> positions = {Vec3(0, 0, 0), Vec3(0.1, 0, 0)};
    const vector<Vec3> velocities = {Vec3(0, 50 * 16.0 / 28, 0), Vec3(0, -50 * 12.0 / 28, 0)};
    for (const IntegratorTraits& traits : integrators())
    for (const string name : {string("Reference"), GetParam()}) {
        if (!traits.runsOnDevicePlatforms)
            continue;
        const string& kind = traits.name;
        // The Langevin step writes the state in its middle: the device puts back a copy.
        std::unique_ptr<RigidBodyIntegrator> integratorPointer = makeIntegrator(kind, 0.01);
        RigidBodyIntegrator& integrator = *integratorPointer;
        std::unique_ptr<Context> context = (isDevicePlatform(name) ? deviceContext(name, system, integrator, "double")
                                                             : std::unique_ptr<Context>(new Context(system, integrator, platform(name))));
        context->setPositions(positions);
        context->setVelocities(velocities);
        ASSERT_TRUE(integrator.isBodyLinear(0));
        string message = messageOf([&] { integrator.step(3); });
        EXPECT_NE(string::npos, message.find("no rotation")) << kind << " on " << name << ": " << message;
        EXPECT_EQ(0u, message.find(kind + "Integrator: ")) << kind << " on " << name << ": " << message;
        State state = context->getState(State::Positions | State::Velocities);
        EXPECT_EQ(0, state.getStepCount()) << kind << " on " << name;
        EXPECT_EQ(0.0, state.getTime()) << kind << " on " << name;
        EXPECT_LT(maxDeviation(positions, state.getPositions()), 1e-12) << kind << " on " << name;
        EXPECT_LT(maxDeviation(velocities, state.getVelocities()), 1e-12) << kind << " on " << name;
        // The Context is usable again once the cause is removed.
        integrator.setStepSize(0.0001);
        integrator.step(5);
        EXPECT_EQ(5, context->getState(State::Positions).getStepCount()) << name;
    }
}

namespace {

/**
 * A diatomic body in a periodic 3 nm box with a cutoff (so that the device reorders and
 * wraps atoms: first at the end of the first step), and a strip 1.3 < x < 2 where a huge
 * force along -y acts: an atom entering it spins the body up so fast that no rotation
 * satisfies its next reset.
 */
System stripSystem() {
    System system;
    system.setDefaultPeriodicBoxVectors(Vec3(3, 0, 0), Vec3(0, 3, 0), Vec3(0, 0, 3));
    system.addParticle(12.0);
    system.addParticle(16.0);
    HarmonicBondForce* bond = new HarmonicBondForce();  // one molecule for OpenMM's wrapping
    bond->addBond(0, 1, 0.1, 0.0);
    system.addForce(bond);
    CustomExternalForce* strip = new CustomExternalForce("1e7*y*step(x-1.3)*step(2-x)");
    strip->addParticle(0, {});
    strip->addParticle(1, {});
    system.addForce(strip);
    NonbondedForce* cutoff = new NonbondedForce();
    cutoff->setNonbondedMethod(NonbondedForce::CutoffPeriodic);
    cutoff->setCutoffDistance(1.0);
    cutoff->addParticle(0, 0.1, 0);
    cutoff->addParticle(0, 0.1, 0);
    cutoff->addException(0, 1, 0, 0.1, 0);
    system.addForce(cutoff);
    return system;
}

} // namespace

TEST_P(DevicePlatform, AFailureInsideStepNIsFoundLateAndUndoneExactly) {
    // The device checks the failure flag lazily (every 16 steps) and at the end of step(n): a run of
    // step(300) that fails at about step 100 must end exactly as step(1) calls do just
    // before the failing step (positions, velocities, time, step count), and raise.
    System system = stripSystem();
    const vector<Vec3> positions = {Vec3(1.0, 1.5, 1.5), Vec3(1.1, 1.5, 1.5)};
    const vector<Vec3> velocities = {Vec3(1, 0, 0), Vec3(1, 0, 0)};
    State beforeFailure;
    string stepwiseMessage;
    {
        MRattleIntegrator integrator(0.002);
        std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "double");
        context->setPositions(positions);
        context->setVelocities(velocities);
        for (int i = 0; i < 300 && stepwiseMessage.empty(); i++) {
            State state = context->getState(State::Positions | State::Velocities);
            try {
                integrator.step(1);
            } catch (const OpenMMException& e) {
                stepwiseMessage = e.what();
                beforeFailure = state;
            }
        }
    }
    ASSERT_NE(string::npos, stepwiseMessage.find("no rotation")) << stepwiseMessage;
    ASSERT_GT(beforeFailure.getStepCount(), 50);
    MRattleIntegrator integrator(0.002);
    std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "double");
    context->setPositions(positions);
    context->setVelocities(velocities);
    const string message = messageOf([&] { integrator.step(300); });
    EXPECT_EQ(0u, message.find("MRattleIntegrator: at step " + std::to_string(beforeFailure.getStepCount()) + " "))
        << message;
    State state = context->getState(State::Positions | State::Velocities);
    std::cout << "a failure at step " << beforeFailure.getStepCount() << " inside step(300) on " << GetParam()
              << ": state put back within " << maxDeviation(beforeFailure.getPositions(), state.getPositions())
              << " nm of the stepwise run's" << std::endl;
    EXPECT_EQ(beforeFailure.getStepCount(), state.getStepCount());
    EXPECT_EQ(beforeFailure.getTime(), state.getTime());
    EXPECT_EQ(0.0, maxDeviation(beforeFailure.getPositions(), state.getPositions()));
    EXPECT_EQ(0.0, maxDeviation(beforeFailure.getVelocities(), state.getVelocities()));
    // Usable again once the body is out of the strip.
    context->setPositions(positions);
    context->setVelocities(velocities);
    integrator.step(10);
    EXPECT_EQ(beforeFailure.getStepCount() + 10, context->getState(State::Positions).getStepCount());
}

TEST_P(DevicePlatform, AFailureFoundByTheStepsOwnBackupIsUndoneToThatStepsStart) {
    // A step's backup is made by its first launch, whose work groups may start after another
    // group of that launch has failed: each must still back up its atoms, or the state put
    // back mixes two times. The hook MRATTLE_TEST_FAIL_AT_STEP sets the flag before that
    // launch as if a group of the step had failed first, so every group finds it set: every
    // atom (and the Nose-Hoover chain) must come back at the failed step's start.
    Cluster c = waterBox(NonbondedForce::NoCutoff);
    const State start = rigidStart(c);
    const int failAt = 7;
    for (bool chain : {false, true}) {
        auto make = [&]() -> std::unique_ptr<Integrator> {
            if (chain)
                return std::unique_ptr<Integrator>(new MRattleNoseHooverIntegrator(300, 10, 0.002));
            return std::unique_ptr<Integrator>(new MRattleIntegrator(0.002));
        };
        const string name = chain ? "MRattleNoseHooverIntegrator" : "MRattleIntegrator";
        State before;
        double heatBath = 0;
        {
            std::unique_ptr<Integrator> integrator = make();
            std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, *integrator, "double");
            context->setPositions(start.getPositions());
            context->setVelocities(start.getVelocities());
            integrator->step(failAt);
            before = context->getState(State::Positions | State::Velocities);
            if (chain)
                heatBath = static_cast<MRattleNoseHooverIntegrator&>(*integrator).computeHeatBathEnergy();
        }
        std::unique_ptr<Integrator> integrator = make();
        setenv("MRATTLE_TEST_FAIL_AT_STEP", std::to_string(failAt).c_str(), 1);
        std::unique_ptr<Context> context = deviceContext(GetParam(), *c.system, *integrator, "double");
        unsetenv("MRATTLE_TEST_FAIL_AT_STEP");
        context->setPositions(start.getPositions());
        context->setVelocities(start.getVelocities());
        const string message = messageOf([&] { integrator->step(20); });
        EXPECT_EQ(0u, message.find(name + ": at step " + std::to_string(failAt) + " ")) << message;
        State state = context->getState(State::Positions | State::Velocities);
        EXPECT_EQ(failAt, state.getStepCount()) << name;
        EXPECT_EQ(before.getTime(), state.getTime()) << name;
        EXPECT_EQ(0.0, maxDeviation(before.getPositions(), state.getPositions())) << name;
        EXPECT_EQ(0.0, maxDeviation(before.getVelocities(), state.getVelocities())) << name;
        if (chain)
            EXPECT_EQ(heatBath, static_cast<MRattleNoseHooverIntegrator&>(*integrator).computeHeatBathEnergy());
    }
}

TEST_P(DevicePlatform, AFailureFoundAtAReorderingIsUndoneInTheNewOrder) {
    // A spinning body drifts across the box's edge in 249 short steps; then a step ten
    // times as long fails (no rotation), and OpenMM's next reordering (every 250 steps; it
    // wraps the body back by a box vector) comes before the lazy check, so the failure is
    // found there: the state put back is the one before the failed step, as OpenMM reports
    // it (cell offsets undone), in mixed precision.
    System system = stripSystem();
    const vector<Vec3> positions = {Vec3(2.80, 0.5, 0.5), Vec3(2.90, 0.5, 0.5)};
    const vector<Vec3> velocities = {Vec3(2, 50 * 16.0 / 28, 0), Vec3(2, -50 * 12.0 / 28, 0)};
    MRattleIntegrator integrator(0.0005);
    std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "mixed");
    context->setPositions(positions);
    context->setVelocities(velocities);
    integrator.step(249);
    const State before = context->getState(State::Positions | State::Velocities);
    ASSERT_GT(0.5 * (before.getPositions()[0][0] + before.getPositions()[1][0]), 3.0);  // across the edge
    integrator.setStepSize(0.01);
    const string message = messageOf([&] { integrator.step(3); });
    EXPECT_EQ(0u, message.find("MRattleIntegrator: at step 249 ")) << message;
    State state = context->getState(State::Positions | State::Velocities);
    EXPECT_EQ(249, state.getStepCount());
    EXPECT_EQ(before.getTime(), state.getTime());
    EXPECT_LT(maxDeviation(before.getPositions(), state.getPositions()), 1e-12);
    EXPECT_EQ(0.0, maxDeviation(before.getVelocities(), state.getVelocities()));
    integrator.setStepSize(0.0005);
    integrator.step(5);
    state = context->getState(State::Positions);
    EXPECT_EQ(254, state.getStepCount());
    const Vec3 bond = state.getPositions()[1] - state.getPositions()[0];
    EXPECT_LT(std::fabs(std::sqrt(bond.dot(bond)) - 0.1), 1e-6);
}

TEST_P(DevicePlatform, ABodyOfTwoMoleculesAcrossTheBoxEdgeStaysWholeThroughReorderings) {
    // Two waters declared as one body with nothing joining them (two molecules for OpenMM),
    // straddling the x edge of a periodic box with a cutoff: OpenMM's reorderings (the first
    // at the first step, then every 250 steps) wrap each molecule on its own unless it knows
    // the body (CommonBodyForceInfo). Before, the body was torn by a box length.
    const Molecule w = water();
    System system;
    system.setDefaultPeriodicBoxVectors(Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2));
    NonbondedForce* cutoff = new NonbondedForce();
    cutoff->setNonbondedMethod(NonbondedForce::CutoffPeriodic);
    cutoff->setCutoffDistance(0.9);
    vector<Vec3> positions;
    vector<int> body;
    for (int copy = 0; copy < 2; copy++)
        for (size_t k = 0; k < w.sites.size(); k++) {
            body.push_back(system.addParticle(w.masses[k]));
            cutoff->addParticle(0, 0.1, 0);
            positions.push_back(w.sites[k] + Vec3(copy == 0 ? 1.93 : 2.07, 1, 1));
        }
    system.addForce(cutoff);
    MRattleIntegrator integrator(0.002);
    integrator.addRigidBody(body);
    std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "double");
    context->setPositions(positions);
    context->setVelocitiesToTemperature(300, 5);
    const vector<Vec3> start = context->getState(State::Positions).getPositions();
    double largest = 0;
    for (int block = 0; block < 4; block++) {
        integrator.step(260);  // past a reordering each time
        largest = std::max(largest, maxDistanceChange(start, context->getState(State::Positions).getPositions(), {body}));
    }
    std::cout << "a body of two waters across the box edge, 1,040 steps, " << GetParam()
              << " (double): intra-body distances changed by " << largest << " nm" << std::endl;
    EXPECT_LT(largest, 1e-10);
}

TEST_P(DevicePlatform, AnInfiniteForceIsFoundByTheSpeedItGives) {
    // OpenMM sums device forces in fixed point: an infinite force arrives as about 2e9
    // kJ/mol/nm, which the step sees as a speed beyond CommonRigidBodyState::LargestSpeed. (A
    // NaN force arrives as that too on x86, as through pocl, but as 0 on CUDA: not tested.)
    System system;
    for (double m : {16.0, 1.0, 1.0})
        system.addParticle(m);
    CustomExternalForce* push = new CustomExternalForce("k*x");
    push->addGlobalParameter("k", 0.0);
    for (int i = 0; i < 3; i++)
        push->addParticle(i, {});
    system.addForce(push);
    MRattleIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1, 2});
    std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "double");
    context->setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0)});
    context->setVelocities({Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0)});
    integrator.step(3);
    const State before = context->getState(State::Positions | State::Velocities);
    context->setParameter("k", std::numeric_limits<double>::infinity());
    const string message = messageOf([&] { integrator.step(5); });
    EXPECT_NE(string::npos, message.find("not finite")) << message;
    const State after = context->getState(State::Positions | State::Velocities);
    EXPECT_EQ(before.getStepCount(), after.getStepCount());
    EXPECT_EQ(0.0, maxDeviation(before.getPositions(), after.getPositions()));
    EXPECT_EQ(0.0, maxDeviation(before.getVelocities(), after.getVelocities()));
    context->setParameter("k", 0.0);
    integrator.step(2);
    EXPECT_EQ(before.getStepCount() + 2, context->getState(State::Positions).getStepCount());
}

namespace {

/** The largest |O-H - 0.09572| over waters whose atoms are 3w, 3w+1, 3w+2 (O, H, H). */
double largestOHError(const vector<Vec3>& x) {
    double largest = 0;
    for (size_t w = 0; w + 2 < x.size(); w += 3)
        for (int h = 1; h <= 2; h++) {
            const Vec3 d = x[w + h] - x[w];
            largest = std::max(largest, std::fabs(std::sqrt(d.dot(d)) - 0.09572));
        }
    return largest;
}

} // namespace

TEST_P(DevicePlatform, WaterShapesStayExactFarFromTheOriginLikeSettle) {
    // 27 rigid TIP3P waters (constrained as OpenMM's rigid water is) 30 nm from the origin,
    // no forces, 50,000 steps of 2 fs: each step rebuilds a body from its reference geometry
    // (CommonRigidBodyState::setReference), so the O-H error stays at the storage's
    // round-off as SETTLE's does instead of random-walking (before: 300x SETTLE's in single
    // precision after 10,000 steps). The yardstick: OpenMM's Verlet with SETTLE, same run.
    const double OH = 0.09572, HH = 2 * OH * std::sin(104.52 * M_PI / 360);
    System system;
    vector<Vec3> positions;
    for (int w = 0; w < 27; w++) {
        const int o = system.addParticle(15.9994), h1 = system.addParticle(1.008), h2 = system.addParticle(1.008);
        system.addConstraint(o, h1, OH);
        system.addConstraint(o, h2, OH);
        system.addConstraint(h1, h2, HH);
        const vector<Vec3> rotation = randomRotation(100 + w);
        const Vec3 center(30 + 0.4 * (w % 3), 30 + 0.4 * ((w / 3) % 3), 30 + 0.4 * (w / 9));
        positions.push_back(center);
        positions.push_back(center + rotate(rotation, Vec3(OH, 0, 0)));
        positions.push_back(center + rotate(rotation, Vec3(OH * std::cos(104.52 * M_PI / 180), OH * std::sin(104.52 * M_PI / 180), 0)));
    }
    for (const string precision : {"single", "mixed"}) {
        double errors[2];
        for (int run = 0; run < 2; run++) {
            std::unique_ptr<Integrator> integrator(run == 0 ? (Integrator*) new VerletIntegrator(0.002)
                                                            : (Integrator*) new MRattleIntegrator(0.002));
            std::unique_ptr<Context> context = deviceContext(GetParam(), system, *integrator, precision);
            context->setPositions(positions);
            context->setVelocitiesToTemperature(300, 9);
            errors[run] = 0;
            for (int block = 0; block < 10; block++) {
                integrator->step(5000);
                errors[run] = std::max(errors[run], largestOHError(context->getState(State::Positions).getPositions()));
            }
        }
        std::cout << "27 waters 30 nm from the origin, 50,000 steps of 2 fs, " << GetParam() << " " << precision
                  << ": largest O-H error (every 5,000 steps) Verlet+SETTLE " << errors[0] << " nm, M-RATTLE "
                  << errors[1] << " nm" << std::endl;
        EXPECT_GT(errors[0], 0.0) << precision;
        EXPECT_LE(errors[1], std::max(2 * errors[0], 1e-8)) << precision;
    }
}

TEST_P(DevicePlatform, ARigidIdealGasUnderABarostatKeepsItsBodiesInMixedPrecision) {
    // OpenMM's testIdealGas in rigid form: 64 rigid dimers (a zero-force bond makes each one
    // molecule for the barostat), no interactions, 600 K, a MonteCarloBarostat at 1 bar,
    // 20,000 steps of 10 fs in mixed precision. The bodies keep their shape within 1e-6 nm
    // (before the reference geometry: 9.6e-5 nm on OpenCL, issue 31).
    System system;
    system.setDefaultPeriodicBoxVectors(Vec3(4, 0, 0), Vec3(0, 4, 0), Vec3(0, 0, 4));
    HarmonicBondForce* bonds = new HarmonicBondForce();
    MRattleIntegrator integrator(0.01);
    vector<Vec3> positions;
    vector<vector<int> > dimers;
    for (int d = 0; d < 64; d++) {
        const int a = system.addParticle(14.0), b = system.addParticle(14.0);
        bonds->addBond(a, b, 0.11, 0.0);
        integrator.addRigidBody({a, b});
        dimers.push_back({a, b});
        const Vec3 center(0.5 + (d % 4), 0.5 + (d / 4) % 4, 0.5 + d / 16);
        const vector<Vec3> rotation = randomRotation(200 + d);
        positions.push_back(center - rotate(rotation, Vec3(0.055, 0, 0)));
        positions.push_back(center + rotate(rotation, Vec3(0.055, 0, 0)));
    }
    bonds->setUsesPeriodicBoundaryConditions(true);  // a periodic System, as a barostat needs
    system.addForce(bonds);
    system.addForce(new MonteCarloBarostat(1.0, 600.0, 25));
    system.addForce(new AndersenThermostat(600.0, 1.0));
    std::unique_ptr<Context> context = deviceContext(GetParam(), system, integrator, "mixed");
    context->setPositions(positions);
    context->setVelocitiesToTemperature(600, 11);
    const State start = context->getState(State::Positions);
    integrator.step(20000);
    const State end = context->getState(State::Positions);
    Vec3 a, b, c, a0, b0, c0;
    start.getPeriodicBoxVectors(a0, b0, c0);
    end.getPeriodicBoxVectors(a, b, c);
    const double deformation = maxDistanceChange(start.getPositions(), end.getPositions(), dimers);
    std::cout << "64 rigid dimers under a MonteCarloBarostat, 20,000 steps of 10 fs, " << GetParam()
              << " mixed: box " << a0[0] << " -> " << a[0] << " nm, largest change of a body's length " << deformation
              << " nm" << std::endl;
    EXPECT_NE(a0[0], a[0]);  // the barostat acted
    EXPECT_LT(deformation, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Devices, DevicePlatform, ::testing::ValuesIn(builtDevicePlatforms()),
                         [](const ::testing::TestParamInfo<string>& info) { return info.param; });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(DevicePlatform);
