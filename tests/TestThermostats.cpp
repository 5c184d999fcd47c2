/*
 * MRattleNoseHooverIntegrator and MRattleBussiIntegrator on every platform that runs them:
 * at zero coupling they are MRattleIntegrator bit for bit; they sample the canonical
 * kinetic-energy distribution of the rigid-body degrees of freedom (mean and variance,
 * with error bars from blocks), CSVR at infinite coupling each kinetic energy from the
 * chi-squared distribution; their conserved quantity (kinetic + potential + heat bath)
 * fluctuates as NVE's energy does and does not drift; checkpoints restart them bit for bit;
 * they run in a CompoundIntegrator and with a MonteCarloBarostat; bad settings are refused
 * and the settings serialize.
 */
#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

class Thermostat : public RigidBodyTest {
protected:
    /** The heat bath's energy of this config's integrator. */
    static double heatBathEnergy(RigidBodyIntegrator& integrator) {
        if (auto* chain = dynamic_cast<MRattleNoseHooverIntegrator*>(&integrator))
            return chain->computeHeatBathEnergy();
        return dynamic_cast<MRattleBussiIntegrator&>(integrator).computeHeatBathEnergy();
    }
    /** This config's integrator at this temperature and coupling (Bussi with a fixed seed). */
    std::unique_ptr<RigidBodyIntegrator> makeThermostat(double temperature, double frequency, double stepSize) const {
        if (GetParam().integrator == "MRattleNoseHoover")
            return std::unique_ptr<RigidBodyIntegrator>(new MRattleNoseHooverIntegrator(temperature, frequency, stepSize));
        auto* bussi = new MRattleBussiIntegrator(temperature, frequency, stepSize);
        bussi->setRandomNumberSeed(17);
        return std::unique_ptr<RigidBodyIntegrator>(bussi);
    }
};

vector<Config> thermostatConfigs() {
    vector<Config> configs = configsOf("MRattleNoseHoover");
    for (const Config& config : configsOf("MRattleBussi"))
        configs.push_back(config);
    return configs;
}

/** 27 rigid TIP3P-like waters in a periodic box at about 1 g/cm^3 (cutoff 0.45 nm, reaction field), with a CMMotionRemover. */
Cluster waterBox() {
    ClusterOptions options;
    options.method = NonbondedForce::CutoffPeriodic;
    options.cutoff = 0.45;
    Cluster c = buildCluster(water(), 3, 0.31, 12, options);
    c.system->addForce(new CMMotionRemover(1));
    return c;
}

/** Mean of a series and its standard error from numBlocks block means. */
struct Estimate {
    double value, error;
};
Estimate blockEstimate(const vector<double>& series, int numBlocks) {
    vector<double> blocks(numBlocks, 0.0);
    const int length = series.size() / numBlocks;
    for (int b = 0; b < numBlocks; b++) {
        for (int i = 0; i < length; i++)
            blocks[b] += series[b * length + i];
        blocks[b] /= length;
    }
    return {mean(blocks), standardDeviation(blocks) / std::sqrt(numBlocks - 1.0)};
}

} // namespace

TEST_P(Thermostat, ZeroCouplingIsMRattleBitForBit) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 3);
    vector<State> states;
    for (int kind = 0; kind < 2; kind++) {
        std::unique_ptr<RigidBodyIntegrator> integrator =
            kind == 0 ? std::unique_ptr<RigidBodyIntegrator>(new MRattleIntegrator(0.002)) : makeThermostat(300, 0.0, 0.002);
        std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
        context->setPositions(c.positions);
        context->setVelocitiesToTemperature(300, 3);
        integrator->step(100);
        states.push_back(context->getState(State::Positions | State::Velocities));
        if (kind == 1)
            EXPECT_EQ(0.0, heatBathEnergy(*integrator));
    }
    EXPECT_GT(maxDeviation(c.positions, states[0].getPositions()), 1e-3);
    EXPECT_EQ(0.0, maxDeviation(states[0].getPositions(), states[1].getPositions()));
    EXPECT_EQ(0.0, maxDeviation(states[0].getVelocities(), states[1].getVelocities()));
}

TEST_P(Thermostat, SamplesTheCanonicalKineticEnergy) {
    // Rigid water at 300 K, 1 fs: the kinetic energy of N = 6 * 27 - 3 degrees of freedom
    // is Gamma-distributed, mean N kT / 2 and variance N (kT)^2 / 2. Both are estimated from
    // 20 blocks of 2 ps (far longer than the thermostat's correlation time at 10/ps), and
    // must agree within 4 standard errors. The variance is what tells a canonical
    // thermostat from one that only fixes the mean (Berendsen's would give about a third).
    Cluster c = waterBox();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeThermostat(300, 10.0, 0.001);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 5);
    integrator->step(2000);
    const int dof = integrator->getNumDegreesOfFreedom();
    ASSERT_EQ(6 * 27 - 3, dof);
    const double kT = BOLTZ * 300, meanKinetic = 0.5 * dof * kT, variance = 0.5 * dof * kT * kT;
    vector<double> kinetic;
    for (int i = 0; i < 4000; i++) {
        integrator->step(10);
        kinetic.push_back(context->getState(State::Energy).getKineticEnergy());
    }
    const Estimate m = blockEstimate(kinetic, 20);
    vector<double> squares;
    for (double k : kinetic)
        squares.push_back((k - m.value) * (k - m.value));
    const Estimate v = blockEstimate(squares, 20);
    std::cout << GetParam().integrator << " on " << GetParam().platform << ": <K> = " << m.value << " +- " << m.error
              << " (canonical " << meanKinetic << "), var K = " << v.value << " +- " << v.error << " (canonical "
              << variance << ") kJ^2/mol^2" << std::endl;
    EXPECT_LT(std::fabs(m.value - meanKinetic), 4 * m.error);
    EXPECT_LT(std::fabs(v.value - variance), 4 * v.error);
    EXPECT_LT(v.error, 0.15 * variance);  // resolves a variance off by a sixth
}

TEST_P(Thermostat, CsvrAtInfiniteCouplingDrawsEachKineticEnergyAfresh) {
    // CSVR with c = exp(-frequency h / 2) = 0 draws the kinetic energy of each half step anew:
    // K / (kT / 2) is chi-squared with dof degrees of freedom (R_1^2 and the sum of dof - 1
    // more squared normals), every step independent. With and without the CMMotionRemover
    // (dof - 1 even and odd); 3000 steps each resolve the mean to 0.2% and the variance to 3%.
    if (GetParam().integrator != "MRattleBussi")
        GTEST_SKIP() << "a CSVR property";
    for (bool remover : {true, false}) {
        Cluster c = waterBox();
        if (!remover)
            c.system->removeForce(c.system->getNumForces() - 1);
        MRattleBussiIntegrator integrator(300, 1e6, 0.001);
        integrator.setRandomNumberSeed(23);
        std::unique_ptr<Context> context = makeContext(*c.system, integrator);
        context->setPositions(c.positions);
        context->setVelocitiesToTemperature(300, 5);
        const double dof = integrator.getNumDegreesOfFreedom(), kT = BOLTZ * 300;
        vector<double> chi;
        for (int i = 0; i < 3000; i++) {
            integrator.step(1);
            chi.push_back(context->getState(State::Energy).getKineticEnergy() / (0.5 * kT));
        }
        const double m = mean(chi), sd = standardDeviation(chi), n = chi.size();
        // Standard errors of the chi-squared distribution's mean and variance (kurtosis 3 + 12 / dof).
        const double meanError = std::sqrt(2 * dof / n), varianceError = 2 * dof * std::sqrt((2 + 12 / dof) / n);
        std::cout << (remover ? "with" : "without") << " the remover, dof " << dof << ": mean " << m << " +- "
                  << meanError << ", variance " << sd * sd << " +- " << varianceError << " (chi-squared: " << dof
                  << ", " << 2 * dof << ")" << std::endl;
        EXPECT_LT(std::fabs(m - dof), 4 * meanError);
        EXPECT_LT(std::fabs(sd * sd - 2 * dof), 4 * varianceError);
    }
}

TEST_P(Thermostat, ConservedQuantityFluctuatesAsNVEsEnergyAndDoesNotDrift) {
    // Kinetic + potential + heat bath over 2 ps at 1 fs, beside MRattleIntegrator's energy
    // from the same start: its fluctuation is of the same size (the step's error), and its
    // drift over the run (with its error bar, from block means) is NVE's within 4 combined
    // standard errors, NVE's none. The errors (about 1 kJ/mol) are below a tenth of the
    // energy the bath moved meanwhile (its standard deviation, 19-63 kJ/mol), so a bath that
    // missed a fifth of it would fail.
    Cluster c = waterBox();
    vector<double> fluctuation;
    vector<Drift> drifts;
    double moved = 0;
    for (int kind = 0; kind < 2; kind++) {
        std::unique_ptr<RigidBodyIntegrator> integrator =
            kind == 0 ? std::unique_ptr<RigidBodyIntegrator>(new MRattleIntegrator(0.001)) : makeThermostat(300, 10.0, 0.001);
        std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
        context->setPositions(c.positions);
        context->setVelocitiesToTemperature(300, 5);
        integrator->step(500);
        vector<double> conserved, bath;
        for (int i = 0; i < 200; i++) {
            integrator->step(10);
            State s = context->getState(State::Energy);
            bath.push_back(kind == 0 ? 0.0 : heatBathEnergy(*integrator));
            conserved.push_back(s.getKineticEnergy() + s.getPotentialEnergy() + bath.back());
        }
        fluctuation.push_back(standardDeviation(conserved));
        drifts.push_back(driftOfBlockMeans(conserved));
        moved = standardDeviation(bath);
        std::cout << (kind == 0 ? "MRattle" : GetParam().integrator) << " on " << GetParam().platform
                  << ": conserved quantity rms " << fluctuation.back() << ", drift over 2 ps " << drifts.back().change
                  << " +- " << drifts.back().error << " kJ/mol; the bath's energy moved by " << moved << std::endl;
    }
    EXPECT_LT(std::fabs(drifts[0].change), 4 * drifts[0].error) << "NVE";
    const double combined = std::hypot(drifts[0].error, drifts[1].error);
    EXPECT_LT(std::fabs(drifts[1].change - drifts[0].change), 4 * combined);
    EXPECT_LT(combined, 0.1 * moved) << "the drift's error bar too wide to see the bath's energy";
    EXPECT_LT(fluctuation[1], 3 * fluctuation[0]);
}

TEST_P(Thermostat, CheckpointRestartsBitForBit) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.5, 4);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeThermostat(300, 20.0, 0.002);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(200, 1);
    integrator->step(20);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    integrator->step(40);
    State uninterrupted = context->getState(State::Positions | State::Velocities);
    const double bath = heatBathEnergy(*integrator);
    EXPECT_NE(0.0, bath);
    std::istringstream again(checkpoint.str());
    context->loadCheckpoint(again);
    integrator->step(40);
    EXPECT_EQ(bath, heatBathEnergy(*integrator));
    State continued = context->getState(State::Positions | State::Velocities);
    std::unique_ptr<RigidBodyIntegrator> restartedIntegrator = makeThermostat(300, 20.0, 0.002);
    if (auto* bussi = dynamic_cast<MRattleBussiIntegrator*>(restartedIntegrator.get()))
        bussi->setRandomNumberSeed(99);  // the checkpoint's stream, whatever the seed
    std::unique_ptr<Context> restarted = makeContext(*c.system, *restartedIntegrator);
    std::istringstream fresh(checkpoint.str());
    restarted->loadCheckpoint(fresh);
    restartedIntegrator->step(40);
    EXPECT_EQ(bath, heatBathEnergy(*restartedIntegrator));
    for (const State& state : {continued, restarted->getState(State::Positions | State::Velocities)}) {
        EXPECT_EQ(0.0, maxDeviation(uninterrupted.getPositions(), state.getPositions()));
        EXPECT_EQ(0.0, maxDeviation(uninterrupted.getVelocities(), state.getVelocities()));
    }
}

TEST_P(Thermostat, RunsInACompoundIntegratorAndWithABarostat) {
    Cluster c = waterBox();
    MonteCarloBarostat* barostat = new MonteCarloBarostat(1.0, 300, 5);
    barostat->setRandomNumberSeed(3);   // seeded: 40 attempts, of which none accepted was a rare failure
    c.system->addForce(barostat);
    CompoundIntegrator compound;
    compound.addIntegrator(makeThermostat(300, 10.0, 0.001).release());
    compound.addIntegrator(new MRattleIntegrator(0.001));
    std::unique_ptr<Context> context = makeContext(*c.system, compound);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 2);
    const double volume = context->getState(State::Positions).getPeriodicBoxVolume();
    for (int round = 0; round < 4; round++) {
        compound.setCurrentIntegrator(round % 2 == 0 ? 0 : 1);
        compound.step(50);
    }
    State state = context->getState(State::Positions | State::Energy);
    EXPECT_NE(volume, state.getPeriodicBoxVolume());  // the barostat moved
    EXPECT_TRUE(std::isfinite(state.getPotentialEnergy()));
    EXPECT_LT(maxDistanceChange(c.positions, state.getPositions(), c.molecules), 1e-9);
}

TEST_P(Thermostat, AFailedStepLeavesTheThermostatAsItWas) {
    // Two waters, one driven into a wall sqrt(c - x) whose force stops being finite past c:
    // the step that crosses it is refused, and the particles and the heat bath are as before it.
    Cluster c = buildCluster(water(), 2, 0.4, 3, ClusterOptions());
    CustomExternalForce* wall = new CustomExternalForce("sqrt(0.3 - x)");
    for (int i = 0; i < c.system->getNumParticles(); i++)
        wall->addParticle(i);
    c.system->addForce(wall);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeThermostat(300, 20.0, 0.002);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    vector<Vec3> velocities(c.system->getNumParticles(), Vec3(2.0, 0, 0));
    context->setVelocities(velocities);
    bool refused = false;
    for (int i = 0; i < 200 && !refused; i++) {
        State before = context->getState(State::Positions | State::Velocities);
        const double bath = heatBathEnergy(*integrator);
        string message;
        try {
            integrator->step(1);
            context->getState(State::Energy);  // on a device platform the failure may be reported here
            continue;
        } catch (const OpenMMException& e) {
            message = e.what();
        }
        refused = true;
        EXPECT_NE(string::npos, message.find("not finite")) << message;
        State after = context->getState(State::Positions | State::Velocities);
        EXPECT_EQ(before.getStepCount(), after.getStepCount());
        EXPECT_EQ(0.0, maxDeviation(before.getPositions(), after.getPositions()));
        EXPECT_EQ(0.0, maxDeviation(before.getVelocities(), after.getVelocities()));
        EXPECT_EQ(bath, heatBathEnergy(*integrator));
        EXPECT_NE(0.0, bath);  // the thermostat had acted before
    }
    EXPECT_TRUE(refused) << "the waters never reached the wall";
}

TEST(ThermostatApi, RefusesBadSettings) {
    EXPECT_NE(string::npos, messageOf([] { MRattleNoseHooverIntegrator(0, 1, 0.002); }).find("temperature"));
    EXPECT_NE(string::npos, messageOf([] { MRattleNoseHooverIntegrator(300, -1, 0.002); }).find("collision frequency"));
    EXPECT_NE(string::npos, messageOf([] { MRattleNoseHooverIntegrator(300, 1, 0.002, 0); }).find("chain length"));
    EXPECT_NE(string::npos, messageOf([] { MRattleNoseHooverIntegrator(300, 1, 0.002, 3, 0); }).find("multiple time steps"));
    EXPECT_NE(string::npos, messageOf([] { MRattleNoseHooverIntegrator(300, 1, 0.002, 3, 3, 4); }).find("Yoshida-Suzuki"));
    EXPECT_NE(string::npos, messageOf([] { MRattleBussiIntegrator(-1, 1, 0.002); }).find("temperature"));
    EXPECT_NE(string::npos, messageOf([] { MRattleBussiIntegrator(300, std::nan(""), 0.002); }).find("collision frequency"));
    MRattleBussiIntegrator bussi(300, 2.0, 0.002);
    EXPECT_EQ(0.5, bussi.getTimeConstant());
    bussi.setTimeConstant(0.25);
    EXPECT_EQ(4.0, bussi.getCollisionFrequency());
    bussi.setTimeConstant(INFINITY);
    EXPECT_EQ(0.0, bussi.getCollisionFrequency());
    EXPECT_NE(string::npos, messageOf([&] { bussi.setTimeConstant(0); }).find("time constant"));
    EXPECT_NE(string::npos, messageOf([&] { bussi.computeHeatBathEnergy(); }).find("not bound"));
    MRattleNoseHooverIntegrator chain(300, 2.0, 0.002);
    EXPECT_NE(string::npos, messageOf([&] { chain.computeHeatBathEnergy(); }).find("not bound"));
}

TEST(ThermostatApi, SettingsSerialize) {
    MRattleNoseHooverIntegrator chain(310, 2.5, 0.003, 5, 2, 3);
    chain.addRigidBody({0, 1, 2});
    const string chainXml = toXml(chain);
    std::unique_ptr<Integrator> copy = fromXml(chainXml);
    MRattleNoseHooverIntegrator& readChain = dynamic_cast<MRattleNoseHooverIntegrator&>(*copy);
    EXPECT_EQ(310, readChain.getTemperature());
    EXPECT_EQ(2.5, readChain.getCollisionFrequency());
    EXPECT_EQ(0.003, readChain.getStepSize());
    EXPECT_EQ(5, readChain.getChainLength());
    EXPECT_EQ(2, readChain.getNumMultiTimeSteps());
    EXPECT_EQ(3, readChain.getNumYoshidaSuzukiTimeSteps());
    EXPECT_EQ(1, readChain.getNumRigidBodies());
    EXPECT_NE(string::npos,
              messageOfXmlWith(chainXml, "numYoshidaSuzuki=\"3\"", "numYoshidaSuzuki=\"2\"").find("Yoshida-Suzuki"));

    MRattleBussiIntegrator bussi(290, 4.0, 0.001);
    bussi.setRandomNumberSeed(77);
    const string bussiXml = toXml(bussi);
    std::unique_ptr<Integrator> copy2 = fromXml(bussiXml);
    MRattleBussiIntegrator& readBussi = dynamic_cast<MRattleBussiIntegrator&>(*copy2);
    EXPECT_EQ(290, readBussi.getTemperature());
    EXPECT_EQ(4.0, readBussi.getCollisionFrequency());
    EXPECT_EQ(0.001, readBussi.getStepSize());
    EXPECT_EQ(77, readBussi.getRandomNumberSeed());
    EXPECT_NE(string::npos, messageOfXmlWith(bussiXml, "collisionFrequency=\"4\"", "collisionFrequency=\"-4\"")
                                .find("collision frequency"));
}

INSTANTIATE_TEST_SUITE_P(Platforms, Thermostat, ::testing::ValuesIn(thermostatConfigs()), configName);
