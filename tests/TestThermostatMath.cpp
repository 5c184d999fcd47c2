/*
 * The thermostats' maths on its own (RigidBodyThermostats): the Yoshida-Suzuki weights,
 * the Nose-Hoover chain's propagation against its conserved extended energy, and the exact
 * CSVR draw's conditional and stationary moments against Bussi et al.'s formulas, with
 * error bars.
 */
#include "internal/RigidBodyThermostats.h"
#include "openmm/OpenMMException.h"
#include <gtest/gtest.h>
#include <cmath>
#include <numeric>
#include <iostream>
#include <random>
#include <vector>

using namespace MRattlePlugin::RigidBodyThermostats;
using std::vector;

namespace {

/** Sample mean, variance and their standard errors (independent samples). */
struct Moments {
    double mean, variance, meanError, varianceError;
};
Moments momentsOf(const vector<double>& x) {
    const double n = x.size();
    double mean = std::accumulate(x.begin(), x.end(), 0.0) / n, m2 = 0, m4 = 0;
    for (double value : x) {
        const double d = (value - mean) * (value - mean);
        m2 += d;
        m4 += d * d;
    }
    m2 /= n;
    m4 /= n;
    return {mean, m2, std::sqrt(m2 / n), std::sqrt((m4 - m2 * m2) / n)};
}

/** The largest change of K + the chain's energy when the chain alone acts on K for this many half steps. */
double extendedEnergyError(int order, int numMTS, int steps) {
    const double dof = 30, kT = 2.5, frequency = 10, halfStep = 0.001;
    NoseHooverChain chain(3);
    double kinetic = 2 * 0.5 * dof * kT;  // twice the canonical mean: the chain must take energy out
    const vector<double> weights = yoshidaSuzukiWeights(order);
    const double start = kinetic + chain.energy(dof, kT, frequency);
    double worst = 0;
    for (int i = 0; i < steps; i++) {
        const double scale = chain.propagate(kinetic, dof, kT, frequency, halfStep, numMTS, weights);
        kinetic *= scale * scale;
        worst = std::max(worst, std::abs(kinetic + chain.energy(dof, kT, frequency) - start));
    }
    EXPECT_LT(kinetic, 1.5 * 0.5 * dof * kT) << "the chain took no energy out";
    return worst / start;
}

} // namespace

TEST(ThermostatMath, YoshidaSuzukiWeightsSumToOneSymmetrically) {
    for (int order : {1, 3, 5, 7}) {
        ASSERT_TRUE(isSupportedYoshidaSuzukiOrder(order));
        const vector<double> w = yoshidaSuzukiWeights(order);
        ASSERT_EQ((int) w.size(), order);
        EXPECT_NEAR(std::accumulate(w.begin(), w.end(), 0.0), 1.0, 1e-14) << "order " << order;
        for (int i = 0; i < order; i++)
            EXPECT_EQ(w[i], w[order - 1 - i]) << "order " << order;
        // Third-order condition of a symmetric composition: sum w^3 = 0 (orders above 1).
        double cubes = 0;
        for (double x : w)
            cubes += x * x * x;
        if (order > 1)
            EXPECT_NEAR(cubes, 0.0, 1e-12) << "order " << order;
    }
    for (int order : {0, 2, 4, 9, -1}) {
        EXPECT_FALSE(isSupportedYoshidaSuzukiOrder(order));
        EXPECT_THROW(yoshidaSuzukiWeights(order), OpenMM::OpenMMException);
    }
}

TEST(ThermostatMath, NoseHooverChainConservesTheExtendedEnergy) {
    // The chain acting alone on K conserves K + its energy exactly; the factorisation's
    // error must fall with more sub-steps and a higher Yoshida-Suzuki order.
    const double order1 = extendedEnergyError(1, 1, 2000);
    const double order1mts3 = extendedEnergyError(1, 3, 2000);
    const double order7mts3 = extendedEnergyError(7, 3, 2000);
    std::cout << "relative extended-energy error: YS1 MTS1 " << order1 << ", YS1 MTS3 " << order1mts3
              << ", YS7 MTS3 " << order7mts3 << std::endl;
    EXPECT_LT(order1, 1e-3);
    EXPECT_LT(order1mts3, order1 / 5);    // second order in the sub-step: 9x smaller
    EXPECT_LT(order7mts3, order1mts3 / 100);
}

TEST(ThermostatMath, NoseHooverChainAtZeroFrequencyDoesNothing) {
    NoseHooverChain chain(3);
    EXPECT_EQ(chain.propagate(123.0, 30, 2.5, 0.0, 0.001, 3, yoshidaSuzukiWeights(7)), 1.0);
    EXPECT_EQ(chain.energy(30, 2.5, 0.0), 0.0);
    for (int j = 0; j < 3; j++)
        EXPECT_EQ(chain.velocities[j], 0.0);
}

TEST(ThermostatMath, CsvrDrawHasBussisConditionalMoments) {
    // From a fixed K: E[K'] = c K + (1 - c) Kbar, Var[K'] = 2 (1 - c)^2 Kbar^2 / dof + 4 c (1 - c) K Kbar / dof.
    const double dof = 7, kT = 2.5, frequency = 2, t = 0.1, kinetic = 20;
    const double c = std::exp(-frequency * t), meanKinetic = 0.5 * dof * kT;
    std::mt19937_64 random(42);
    vector<double> drawn;
    for (int i = 0; i < 200000; i++) {
        const double alpha = csvrScale(kinetic, dof, kT, frequency, t, random);
        drawn.push_back(alpha * alpha * kinetic);
    }
    const Moments m = momentsOf(drawn);
    const double expectedMean = c * kinetic + (1 - c) * meanKinetic;
    const double expectedVariance =
        2 * (1 - c) * (1 - c) * meanKinetic * meanKinetic / dof + 4 * c * (1 - c) * kinetic * meanKinetic / dof;
    EXPECT_NEAR(m.mean, expectedMean, 4 * m.meanError);
    EXPECT_NEAR(m.variance, expectedVariance, 4 * m.varianceError);
}

TEST(ThermostatMath, CsvrKeepsTheCanonicalKineticEnergyDistribution) {
    // Repeated draws are a Markov chain whose stationary law is Gamma(dof / 2, kT): mean
    // dof kT / 2, variance dof kT^2 / 2. Every 20th of a weakly correlated chain is kept.
    for (double dof : {1.0, 2.0, 5.0, 300.0}) {
        const double kT = 2.5, frequency = 1, t = 0.5;
        std::mt19937_64 random(7);
        double kinetic = 3 * dof * kT;
        vector<double> samples;
        for (int i = 0; i < 400000; i++) {
            kinetic *= std::pow(csvrScale(kinetic, dof, kT, frequency, t, random), 2);
            if (i >= 1000 && i % 20 == 0)
                samples.push_back(kinetic);
        }
        const Moments m = momentsOf(samples);
        EXPECT_NEAR(m.mean, 0.5 * dof * kT, 4 * m.meanError) << "dof " << dof;
        EXPECT_NEAR(m.variance, 0.5 * dof * kT * kT, 4 * m.varianceError) << "dof " << dof;
    }
}

TEST(ThermostatMath, CsvrAtZeroFrequencyDoesNothingAndDrawsNothing) {
    std::mt19937_64 random(3), untouched(3);
    EXPECT_EQ(csvrScale(50.0, 30, 2.5, 0.0, 0.001, random), 1.0);
    EXPECT_EQ(random(), untouched());
}
