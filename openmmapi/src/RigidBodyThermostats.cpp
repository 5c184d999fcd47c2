#include "internal/RigidBodyThermostats.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace MRattlePlugin;
using OpenMM::OpenMMException;
using std::vector;

bool RigidBodyThermostats::isSupportedYoshidaSuzukiOrder(int order) {
    return order == 1 || order == 3 || order == 5 || order == 7;
}

void RigidBodyThermostats::requireChainSettings(const char* integratorName, int chainLength, int numMTS,
                                                int numYoshidaSuzuki) {
    const std::string name(integratorName);
    if (chainLength < 1)
        throw OpenMMException(name + ": the chain length must be 1 or more, got " + std::to_string(chainLength));
    if (numMTS < 1)
        throw OpenMMException(name + ": the number of multiple time steps must be 1 or more, got " +
                              std::to_string(numMTS));
    if (!isSupportedYoshidaSuzukiOrder(numYoshidaSuzuki))
        throw OpenMMException(name + ": the number of Yoshida-Suzuki time steps must be 1, 3, 5 or 7, got " +
                              std::to_string(numYoshidaSuzuki));
}

vector<double> RigidBodyThermostats::yoshidaSuzukiWeights(int order) {
    // Symmetric compositions of a second-order step (Yoshida 1990; Suzuki 1991). Order 7 is
    // Yoshida's solution A of the 7-stage 6th-order composition, as in Martyna et al. 1996.
    switch (order) {
    case 1:
        return {1.0};
    case 3: {
        const double w = 1 / (2 - std::cbrt(2.0));
        return {w, 1 - 2 * w, w};
    }
    case 5: {
        const double w = 1 / (4 - std::cbrt(4.0));
        return {w, w, 1 - 4 * w, w, w};
    }
    case 7: {
        const double w1 = 0.784513610477560, w2 = 0.235573213359357, w3 = -1.17767998417887;
        const double w0 = 1 - 2 * (w1 + w2 + w3);
        return {w1, w2, w3, w0, w3, w2, w1};
    }
    default:
        throw OpenMMException("the Yoshida-Suzuki order must be 1, 3, 5 or 7, got " + std::to_string(order));
    }
}

double RigidBodyThermostats::NoseHooverChain::propagate(double kineticEnergy, double dof, double kT, double frequency,
                                                        double t, int numMTS, const vector<double>& weights) {
    const int length = velocities.size();
    if (length == 0 || frequency == 0 || t == 0)
        return 1.0;
    // Q_1 = dof kT / w^2, Q_j = kT / w^2: the chain's accelerations G_j, with the masses
    // divided out (so w = 0 is a chain that does not move).
    const double w2 = frequency * frequency;
    double twiceKinetic = 2 * kineticEnergy, scale = 1;
    auto acceleration = [&](int j) {
        return j == 0 ? (twiceKinetic - dof * kT) * w2 / (dof * kT)
                      : (j == 1 ? dof : 1.0) * velocities[j - 1] * velocities[j - 1] - w2;
    };
    // G_j for j > 0 is (Q_{j-1} v_{j-1}^2 - kT) / Q_j: with Q_{j-1}/Q_j = dof (j = 1) or 1.
    // The line above writes it as ratio * v^2 - w^2 (kT / Q_j = w^2).
    // A velocity's half update over time s/2, with friction from the next thermostat.
    auto halfUpdate = [&](int j, double s) {
        if (j == length - 1) {
            velocities[j] += 0.5 * s * acceleration(j);
            return;
        }
        const double e = std::exp(-0.25 * s * velocities[j + 1]);
        velocities[j] = e * (e * velocities[j] + 0.5 * s * acceleration(j));
    };
    for (int mts = 0; mts < numMTS; mts++)
        for (double weight : weights) {
            const double s = weight * t / numMTS;
            for (int j = length - 1; j >= 0; j--)
                halfUpdate(j, s);
            const double factor = std::exp(-s * velocities[0]);
            scale *= factor;
            twiceKinetic *= factor * factor;
            for (int j = 0; j < length; j++)
                positions[j] += s * velocities[j];
            for (int j = 0; j < length; j++)
                halfUpdate(j, s);
        }
    return scale;
}

double RigidBodyThermostats::NoseHooverChain::energy(double dof, double kT, double frequency) const {
    double energy = 0;
    for (size_t j = 0; j < velocities.size(); j++) {
        const double massOverKT = (j == 0 ? dof : 1.0) / (frequency * frequency);
        if (velocities[j] != 0)  // w = 0: a chain that never moved holds no energy
            energy += 0.5 * massOverKT * kT * velocities[j] * velocities[j];
        energy += (j == 0 ? dof : 1.0) * kT * positions[j];
    }
    return energy;
}

double RigidBodyThermostats::csvrScale(double kineticEnergy, double dof, double kT, double frequency, double t,
                                       std::mt19937_64& random) {
    if (frequency == 0 || !(kineticEnergy > 0) || !(dof > 0))
        return 1.0;
    const double c = std::exp(-frequency * t);
    const double meanKinetic = 0.5 * dof * kT;
    const double r1 = std::normal_distribution<double>(0.0, 1.0)(random);
    // The other dof - 1 squared normals: a chi-squared variable, 2 Gamma((dof - 1) / 2, 1).
    const double others = dof > 1 ? 2 * std::gamma_distribution<double>(0.5 * (dof - 1), 1.0)(random) : 0.0;
    // The velocity component along the old velocities is sqrt(c K) + r1 sqrt((1 - c) Kbar / dof);
    // K' written as its square plus the rest is the paper's formula, and never negative.
    const double along = std::sqrt(c * kineticEnergy) + r1 * std::sqrt((1 - c) * meanKinetic / dof);
    const double newKinetic = along * along + (1 - c) * meanKinetic * others / dof;
    const double alpha = std::sqrt(newKinetic / kineticEnergy);
    return along < 0 ? -alpha : alpha;
}

// The names a State's integrator parameters use (RigidBodyIntegrator checks them before a set).
RigidBodyThermostats::NoseHooverChain RigidBodyThermostats::NoseHooverChain::fromParameters(
    const IntegratorParameterValues& values) {
    NoseHooverChain chain;
    chain.positions = values.at("chainPositions");
    chain.velocities = values.at("chainVelocities");
    return chain;
}

double RigidBodyThermostats::csvrWork(const IntegratorParameterValues& values) {
    return values.at("rescalingWork").at(0);
}
