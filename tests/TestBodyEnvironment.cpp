/*
 * Rigid bodies in the rest of OpenMM: massless virtual sites follow their parents,
 * AndersenThermostat and MonteCarloBarostat act while bodies stay rigid, and forces outside
 * the integration force groups have no effect, and forces are evaluated as often as by
 * OpenMM's own integrators.
 *
 * A value-parameterised suite (BodyEnvironment) over every platform and rigid-body
 * integrator (allConfigs()).
 */
#include "TestSupport.h"
#include "openmm/internal/ForceImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>
#include <memory>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

NonbondedForce& nonbondedForce(System& system) {
    for (int f = 0; f < system.getNumForces(); f++)
        if (auto* force = dynamic_cast<NonbondedForce*>(&system.getForce(f)))
            return *force;
    throw OpenMMException("no NonbondedForce");
}

/** A Force that adds nothing and counts the force evaluations that include it. */
class CountingForce : public Force {
public:
    std::shared_ptr<int> evaluations = std::make_shared<int>(0);

protected:
    ForceImpl* createImpl() const override;
};

class CountingForceImpl : public ForceImpl {
public:
    explicit CountingForceImpl(const CountingForce& owner) : owner(owner) {
    }
    void initialize(ContextImpl& context) override {
    }
    const Force& getOwner() const override {
        return owner;
    }
    void updateContextState(ContextImpl& context, bool& forcesInvalid) override {
    }  // (ForceImpl's own would invalidate the forces at every step)
    double calcForcesAndEnergy(ContextImpl& context, bool includeForces, bool includeEnergy, int groups) override {
        if (includeForces && (groups & (1 << owner.getForceGroup())) != 0)
            (*owner.evaluations)++;
        return 0;
    }
    std::map<std::string, double> getDefaultParameters() override {
        return {};
    }
    std::vector<std::string> getKernelNames() override {
        return {};
    }

private:
    const CountingForce& owner;
};

ForceImpl* CountingForce::createImpl() const {
    return new CountingForceImpl(*this);
}

/** Force evaluations and accepted barostat moves over a run of steps, one step at a time. */
struct EvaluationCount {
    int evaluations = 0, acceptedMoves = 0;
};

/** 27 rigid waters (periodic cutoff) with a MonteCarloBarostat trying a move every second step. */
EvaluationCount countEvaluations(const std::string& platformName, Integrator& integrator, int steps) {
    ClusterOptions options;
    options.method = NonbondedForce::CutoffPeriodic;
    options.cutoff = 0.4;
    Cluster c = buildCluster(water(), 3, 0.31, 5, options);
    MonteCarloBarostat* barostat = new MonteCarloBarostat(1.0, 300, 2);
    barostat->setRandomNumberSeed(3);
    c.system->addForce(barostat);
    CountingForce* counter = new CountingForce();
    const std::shared_ptr<int> evaluations = counter->evaluations;
    c.system->addForce(counter);
    Context context(*c.system, integrator, platform(platformName), platformProperties(platformName));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 1);
    EvaluationCount count;
    *evaluations = 0;
    Vec3 a, b, box, before;
    context.getState(0).getPeriodicBoxVectors(a, b, before);
    for (int i = 0; i < steps; i++) {
        integrator.step(1);
        context.getState(0).getPeriodicBoxVectors(a, b, box);
        if (box != before && i > 0)  // a move at the first step's start costs nothing: no forces yet
            count.acceptedMoves++;
        before = box;
    }
    count.evaluations = *evaluations;
    return count;
}

/** Largest |(v_i - v_j) . (x_i - x_j)| / |x_i - x_j| over pairs inside bodies: zero for rigid velocities. */
double maxBondStretchRate(const State& state, const vector<vector<int> >& bodies) {
    const vector<Vec3>& x = state.getPositions();
    const vector<Vec3>& v = state.getVelocities();
    double worst = 0;
    for (const vector<int>& body : bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                Vec3 d = x[body[i]] - x[body[j]];
                worst = std::max(worst, std::fabs((v[body[i]] - v[body[j]]).dot(d)) / std::sqrt(d.dot(d)));
            }
    return worst;
}

class BodyEnvironment : public RigidBodyTest {};

} // namespace

TEST_P(BodyEnvironment, VirtualSitesFollowTheirParents) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    // TIP4P-Ew-like: the negative charge on a massless site M on the H-O-H bisector.
    Cluster c = buildCluster(water(), 2, 0.32, 9);
    NonbondedForce& nonbonded = nonbondedForce(*c.system);
    const double wO = 0.786646558, wH = 0.106676721;
    vector<int> sites;
    for (const vector<int>& w : c.molecules) {
        int m = c.system->addParticle(0.0);
        c.system->setVirtualSite(m, new ThreeParticleAverageSite(w[0], w[1], w[2], wO, wH, wH));
        c.positions.push_back(c.positions[w[0]] * wO + c.positions[w[1]] * wH + c.positions[w[2]] * wH);
        nonbonded.setParticleParameters(w[0], 0.0, 0.316435, 0.680946);
        nonbonded.setParticleParameters(w[1], 0.52422, 1, 0);
        nonbonded.setParticleParameters(w[2], 0.52422, 1, 0);
        nonbonded.addParticle(-1.04844, 1, 0);
        for (int atom : w)
            nonbonded.addException(m, atom, 0, 1, 0);
        sites.push_back(m);
    }
    // The forces on M must reach the bodies for the energy error to be second order: the
    // energy fluctuation over 1 ps at 2 fs must be 4 times that at 1 fs (log2 of the ratio,
    // the order, 2). That holds on average only: the trajectory is chaotic, and over 20
    // starts the order of one start spread by 0.13 (MRattle) to 0.21 (splitting), ratios
    // of 3.3 to 5.6 (OpenMM 7.7, Reference and CPU; a single start judged against 4 +- 1
    // failed with another build's CPU rounding at 5.36). So the order is the mean over
    // several starts (velocity seeds), with its standard error.
    const int starts = 10;
    vector<double> fluctuation[2];  // per start, at 2 fs and at 1 fs
    for (int k = 0; k < 2; k++) {
        const double h = (k == 0 ? 0.002 : 0.001);
        // One Context per step size (a new one per start costs seconds on OpenCL); each
        // start sets positions and velocities anew, and a velocity Verlet step depends on
        // nothing else.
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(h);
        std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
        for (int seed = 1; seed <= starts; seed++) {
            context->setPositions(c.positions);
            context->setVelocitiesToTemperature(300, seed);
            EXPECT_EQ(c.molecules, integrator->getBodiesInEffect());
            EXPECT_TRUE(integrator->getFreeParticles().empty());
            EXPECT_EQ(8 * 6, integrator->getNumDegreesOfFreedom());
            vector<double> energy;
            double worstSite = 0, worstShape = 0;
            for (int sample = 0; sample < 100; sample++) {
                integrator->step((int) std::lround(0.01 / h));
                State s = context->getState(State::Positions | State::Energy);
                const vector<Vec3>& x = s.getPositions();
                energy.push_back(s.getKineticEnergy() + s.getPotentialEnergy());
                for (size_t m = 0; m < sites.size(); m++) {
                    const vector<int>& w = c.molecules[m];
                    worstSite = std::max(worstSite, maxDeviation({x[sites[m]]}, {x[w[0]] * wO + x[w[1]] * wH + x[w[2]] * wH}));
                }
                worstShape = std::max(worstShape, maxDistanceChange(c.positions, x, c.molecules));
            }
            EXPECT_LT(worstSite, 1e-12);
            EXPECT_LT(worstShape, 1e-12);
            fluctuation[k].push_back(standardDeviation(energy));
        }
    }
    vector<double> order;
    for (int i = 0; i < starts; i++) {
        order.push_back(std::log2(fluctuation[0][i] / fluctuation[1][i]));
        std::cout << "TIP4P-like cluster, start " << i + 1 << ": energy std " << fluctuation[0][i] << " (2 fs) "
                  << fluctuation[1][i] << " (1 fs) kJ/mol, order " << order.back() << std::endl;
    }
    const double meanOrder = mean(order), error = standardDeviation(order) / std::sqrt(starts - 1.0);
    std::cout << "TIP4P-like cluster: order " << meanOrder << " +- " << error << " over " << starts << " starts"
              << std::endl;
    // The band of the single-run check this replaces (a ratio of 4 +- 1: order 1.58-2.32),
    // now on a mean whose error is known to be a fraction of the band's width.
    EXPECT_GT(meanOrder, std::log2(3.0));
    EXPECT_LT(meanOrder, std::log2(5.0));
    EXPECT_LT(error, 0.1);
}

namespace {

struct ThermostatRun {
    double rigidity, stretchRate, volumeChange, meanTemperature, temperatureError;
};

/**
 * 64 rigid waters in a periodic box at about liquid density, started at 150 K, with an
 * AndersenThermostat at 300 K and optionally a MonteCarloBarostat; 2000 steps with the
 * config's platform and integrator. The full length on every config: the temperature is a
 * statistical check (its error from 15 block means of 5 samples, 200 fs each), and a shorter run would
 * loosen it; about 1.9 s on Reference, 0.2 s on CPU.
 * constrainWaters adds the O-H, O-H, H-H constraints (ignored by the integrator): they
 * make OpenMM's thermostat randomize each water as a whole.
 */
ThermostatRun runThermostat(const Config& config, bool constrainWaters, bool barostat) {
    ClusterOptions options;
    options.method = NonbondedForce::CutoffPeriodic;
    options.cutoff = 0.5;
    options.minSiteDistance = 0.2;
    Cluster c = buildCluster(water(), 4, 0.31, 5, options);
    if (constrainWaters)
        for (const vector<int>& w : c.molecules)
            for (int i = 0; i < 3; i++)
                for (int j = i + 1; j < 3; j++) {
                    Vec3 d = c.positions[w[i]] - c.positions[w[j]];
                    c.system->addConstraint(w[i], w[j], std::sqrt(d.dot(d)));
                }
    // Seeded: with OpenMM's random seeds the statistical checks below failed now and then.
    AndersenThermostat* thermostat = new AndersenThermostat(300, 20);
    thermostat->setRandomNumberSeed(11);
    c.system->addForce(thermostat);
    if (barostat) {
        MonteCarloBarostat* pressure = new MonteCarloBarostat(1.0, 300, 5);
        pressure->setRandomNumberSeed(12);
        c.system->addForce(pressure);
    }
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(config.integrator, 0.002);
    Context context(*c.system, *integrator, platform(config.platform), platformProperties(config.platform));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(150, 1);
    const int dof = integrator->getNumDegreesOfFreedom();
    EXPECT_EQ(64 * 6, dof);
    const double volume0 = std::pow(0.31 * 4, 3);
    vector<double> temperatures;
    ThermostatRun result = {0, 0, 0, 0, 0};
    for (int chunk = 0; chunk < 100; chunk++) {
        integrator->step(20);
        State s = context.getState(State::Positions | State::Velocities | State::Energy);
        result.rigidity = std::max(result.rigidity, maxDistanceChange(c.positions, s.getPositions(), c.molecules));
        result.stretchRate = std::max(result.stretchRate, maxBondStretchRate(s, c.molecules));
        if (chunk >= 25)
            temperatures.push_back(2 * s.getKineticEnergy() / (dof * BOLTZ));
    }
    Vec3 a, b, box;
    context.getState(0).getPeriodicBoxVectors(a, b, box);
    result.volumeChange = a[0] * b[1] * box[2] / volume0 - 1;
    std::tie(result.meanTemperature, result.temperatureError) = blockMean(temperatures, 15);
    std::cout << "water box, Andersen" << (barostat ? " and barostat" : "")
              << (constrainWaters ? ", constrained waters" : ", bonded waters") << ": rigidity " << result.rigidity
              << " nm, stretch rate " << result.stretchRate << " nm/ps, relative volume change " << result.volumeChange
              << ", mean temperature " << result.meanTemperature << " +- " << result.temperatureError << " K"
              << std::endl;
    return result;
}

} // namespace

TEST_P(BodyEnvironment, ThermostatAndBarostatKeepBodiesRigid) {
    ThermostatRun run = runThermostat(GetParam(), true, true);
    EXPECT_LT(run.rigidity, 1e-10);
    EXPECT_LT(run.stretchRate, 1e-10);
    EXPECT_GT(std::fabs(run.volumeChange), 1e-4);  // the barostat acted
    // The thermostat brought it from 150 K to 300 K (75 samples of a 384-DOF system).
    EXPECT_NEAR(300, run.meanTemperature, 4 * run.temperatureError);
    EXPECT_LT(run.temperatureError, 8.0);
}

/*
 * The bug this caught: when the thermostat's collisions hit single atoms of a body
 * (molecules held by bonds only), projecting the partly randomized body onto rigid motion
 * does not keep the rigid-body Boltzmann distribution, and the water settled at 264-269 K
 * for 300 K. The integrator now gives a collided body fresh velocities for all its atoms.
 */
TEST_P(BodyEnvironment, ThermostatReachesTemperatureWithBondedBodies) {
    ThermostatRun run = runThermostat(GetParam(), false, false);
    EXPECT_LT(run.rigidity, 1e-10);
    EXPECT_NEAR(300, run.meanTemperature, 4 * run.temperatureError);
    EXPECT_LT(run.temperatureError, 8.0);
}

TEST_P(BodyEnvironment, ForcesOutsideIntegrationGroupsHaveNoEffect) {
    Cluster plain = buildCluster(tetrahedral(), 2, 0.45, 5);
    Cluster withExtra = buildCluster(tetrahedral(), 2, 0.45, 5);
    CustomExternalForce* spring = new CustomExternalForce("500*(x^2+y^2+z^2)");
    for (int i = 0; i < withExtra.system->getNumParticles(); i++)
        spring->addParticle(i);
    spring->setForceGroup(3);
    withExtra.system->addForce(spring);
    vector<vector<Vec3> > final;
    vector<Vec3> start;  // the same velocities in every run: OpenMM's setVelocitiesToTemperature
                         // shifts a leapfrog integrator's by half a kick of all force groups
    for (int run = 0; run < 3; run++) {
        Cluster& c = (run == 0 ? plain : withExtra);
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
        if (run == 1)
            integrator->setIntegrationForceGroups(1 << 0);  // the spring's group 3 excluded
        std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
        context->setPositions(c.positions);
        if (run == 0) {
            context->setVelocitiesToTemperature(300, 4);
            start = context->getState(State::Velocities).getVelocities();
        }
        else
            context->setVelocities(start);
        integrator->step(200);
        final.push_back(context->getState(State::Positions).getPositions());
    }
    EXPECT_EQ(0.0, maxDeviation(final[0], final[1]));
    EXPECT_GT(maxDeviation(final[0], final[2]), 1e-3);  // with the group included the spring acts
}

TEST_P(BodyEnvironment, ForcesAreEvaluatedNoMoreOftenThanByOpenMMsOwnIntegrators) {
    // A leapfrog integrator (MRattleLangevin) computes its forces at each step's start, after
    // the barostat's move and any reordering, as LangevinMiddleIntegrator: one evaluation a
    // step. A velocity-Verlet one needs them after its drift, so the first step, an accepted
    // move and a device reordering each cost one more; OpenMM's NoseHooverIntegrator pays
    // at least as much (it also computes forces at every step's start).
    const int steps = 30;
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    const EvaluationCount count = countEvaluations(GetParam().platform, *integrator, steps);
    EXPECT_GT(count.acceptedMoves, 0);  // the barostat acted
    const bool leapfrog = GetParam().traits().forcesAtStepStart;
    std::unique_ptr<Integrator> openmm(leapfrog ? (Integrator*) new LangevinMiddleIntegrator(300, 1, 0.002)
                                                : (Integrator*) new NoseHooverIntegrator(300, 10, 0.002));
    const int openmmEvaluations = countEvaluations(GetParam().platform, *openmm, steps).evaluations;
    std::cout << steps << " steps, " << count.acceptedMoves << " accepted moves: " << count.evaluations
              << " force evaluations; OpenMM's " << (leapfrog ? "LangevinMiddle" : "NoseHoover") << "Integrator "
              << openmmEvaluations << std::endl;
    if (leapfrog) {
        EXPECT_EQ(steps, openmmEvaluations);
        EXPECT_EQ(steps, count.evaluations);
    } else {
        EXPECT_LE(count.evaluations, openmmEvaluations);
        EXPECT_GE(count.evaluations, steps + 1 + count.acceptedMoves);
        EXPECT_LE(count.evaluations, steps + 2 + count.acceptedMoves);
    }
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, BodyEnvironment, ::testing::ValuesIn(allConfigs()), configName);
