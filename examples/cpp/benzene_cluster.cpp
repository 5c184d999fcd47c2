/*
 * NVE dynamics of 27 rigid benzene molecules with MRattleIntegrator, from C++.
 *
 * Builds the cluster (a 3 x 3 x 3 lattice, 0.65 nm apart, random orientations; LJ and
 * charges between molecules, nothing inside them), runs it on the CPU platform and prints
 * the largest change of any intra-molecular distance, the total-energy fluctuation and
 * drift, the temperature with the rigid-body degrees of freedom, and the speed.
 *
 *     benzene_cluster [steps=5000] [step size in fs=2] [platform=CPU]
 */
#include "MRattleIntegrator.h"
#include "OpenMM.h"
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

using namespace OpenMM;
using std::vector;

// Linking libMRattlePluginReference registers nothing by itself: this is its entry point
// (an installed plugin is found by Platform::loadPluginsFromDirectory instead).
extern "C" void registerMRattleReferenceKernelFactories();

namespace {

const double BoltzmannConstant = 0.0083144626;  // kJ/mol/K

struct Site {
    Vec3 position;
    double mass, charge, sigma, epsilon;
};

/** Benzene about its centre: 6 C on a ring of radius 0.1397 nm, 6 H 0.1084 nm further out. */
vector<Site> benzene() {
    vector<Site> sites;
    for (int k = 0; k < 12; k++) {
        double angle = (k % 6) * M_PI / 3, radius = (k < 6 ? 0.1397 : 0.1397 + 0.1084);
        Vec3 x(radius * std::cos(angle), radius * std::sin(angle), 0);
        sites.push_back(k < 6 ? Site{x, 12.011, -0.115, 0.355, 0.29288} : Site{x, 1.008, 0.115, 0.242, 0.12552});
    }
    return sites;
}

/** A uniformly random rotation applied to v (q: a unit quaternion w, x, y, z). */
Vec3 rotate(const double q[4], const Vec3& v) {
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    return Vec3((1 - 2 * (y * y + z * z)) * v[0] + 2 * (x * y - w * z) * v[1] + 2 * (x * z + w * y) * v[2],
                2 * (x * y + w * z) * v[0] + (1 - 2 * (x * x + z * z)) * v[1] + 2 * (y * z - w * x) * v[2],
                2 * (x * z - w * y) * v[0] + 2 * (y * z + w * x) * v[1] + (1 - 2 * (x * x + y * y)) * v[2]);
}

/** Builds the System and positions; molecules[m] lists the particles of molecule m. */
void buildCluster(System& system, vector<Vec3>& positions, vector<vector<int> >& molecules) {
    const vector<Site> molecule = benzene();
    const int n = 3;
    const double spacing = 0.65;
    std::mt19937 random(1);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    NonbondedForce* nonbonded = new NonbondedForce();  // NoCutoff: a cluster in vacuum
    HarmonicBondForce* bonds = new HarmonicBondForce();  // makes OpenMM see molecules; no effect on rigid bodies
    for (int i = 0; i < n * n * n; i++) {
        Vec3 center = Vec3(i % n, (i / n) % n, i / (n * n)) * spacing;
        double q[4], norm = 0;
        for (double& c : q) {
            c = gaussian(random);
            norm += c * c;
        }
        for (double& c : q)
            c /= std::sqrt(norm);
        vector<int> members;
        for (const Site& site : molecule) {
            members.push_back(system.addParticle(site.mass));
            positions.push_back(center + rotate(q, site.position));
            nonbonded->addParticle(site.charge, site.sigma, site.epsilon);
        }
        for (int k = 0; k < 6; k++) {
            bonds->addBond(members[k], members[(k + 1) % 6], 0.1397, 1e5);
            bonds->addBond(members[k], members[k + 6], 0.1084, 1e5);
        }
        // Forces inside a rigid body cannot move it: exclude them and save their cost.
        for (size_t a = 0; a < members.size(); a++)
            for (size_t b = a + 1; b < members.size(); b++)
                nonbonded->addException(members[a], members[b], 0, 1, 0);
        molecules.push_back(members);
    }
    system.addForce(nonbonded);
    system.addForce(bonds);
}

double largestDistanceChange(const vector<Vec3>& a, const vector<Vec3>& b, const vector<vector<int> >& molecules) {
    double worst = 0;
    for (const vector<int>& m : molecules)
        for (size_t i = 0; i < m.size(); i++)
            for (size_t j = i + 1; j < m.size(); j++) {
                Vec3 da = a[m[i]] - a[m[j]], db = b[m[i]] - b[m[j]];
                worst = std::max(worst, std::fabs(std::sqrt(da.dot(da)) - std::sqrt(db.dot(db))));
            }
    return worst;
}

} // namespace

int main(int argc, char* argv[]) {
    const int steps = (argc > 1 ? std::atoi(argv[1]) : 5000);
    const double stepSize = (argc > 2 ? std::atof(argv[2]) : 2.0) * 1e-3;
    const std::string platformName = (argc > 3 ? argv[3] : "CPU");
    if (steps < 1 || !(stepSize > 0)) {
        std::fprintf(stderr, "usage: %s [steps > 0] [step size in fs > 0] [platform]\n", argv[0]);
        return 2;
    }
    try {
#ifdef MRATTLE_OPENMM_PLUGIN_DIR
        // Set by this project's CMake: the platform plugins of the OpenMM it was built
        // against, unless the user names others.
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
#endif
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        registerMRattleReferenceKernelFactories();

        System system;
        vector<Vec3> positions;
        vector<vector<int> > molecules;
        buildCluster(system, positions, molecules);
        MRattlePlugin::MRattleIntegrator integrator(stepSize);
        Context context(system, integrator, Platform::getPlatformByName(platformName));
        context.setPositions(positions);
        context.setVelocitiesToTemperature(250, 1);
        const int dof = integrator.getNumDegreesOfFreedom();
        std::printf("%d rigid bodies, %d degrees of freedom, %s platform, %d steps of %g fs\n",
                    integrator.getNumBodiesInEffect(), dof, context.getPlatform().getName().c_str(), steps,
                    stepSize * 1e3);

        // Sample the total energy 100 times (or every step for short runs).
        const int interval = std::max(1, steps / 100);
        vector<double> times, energies;
        double worstRigidity = 0, temperatureSum = 0;
        auto start = std::chrono::steady_clock::now();
        for (int done = 0; done <= steps; done += interval) {
            if (done > 0)
                integrator.step(interval);
            State state = context.getState(State::Positions | State::Energy);
            times.push_back(state.getTime());
            energies.push_back(state.getKineticEnergy() + state.getPotentialEnergy());
            temperatureSum += 2 * state.getKineticEnergy() / (dof * BoltzmannConstant);
            worstRigidity = std::max(worstRigidity, largestDistanceChange(positions, state.getPositions(), molecules));
        }
        double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        // Drift: slope of the least-squares line through E(t); fluctuation: its standard deviation.
        const int n = energies.size();
        double meanTime = 0, meanEnergy = 0;
        for (int i = 0; i < n; i++) {
            meanTime += times[i] / n;
            meanEnergy += energies[i] / n;
        }
        double covariance = 0, variance = 0, spread = 0;
        for (int i = 0; i < n; i++) {
            covariance += (times[i] - meanTime) * (energies[i] - meanEnergy);
            variance += (times[i] - meanTime) * (times[i] - meanTime);
            spread += (energies[i] - meanEnergy) * (energies[i] - meanEnergy);
        }
        const double slope = (variance > 0 ? covariance / variance : 0.0);  // kJ/mol/ps
        std::printf("largest change of an intra-molecular distance: %.3g nm\n", worstRigidity);
        std::printf("total energy: mean %.4f kJ/mol, fluctuation (std) %.3g kJ/mol, drift %.3g kJ/mol/ns\n", meanEnergy,
                    std::sqrt(spread / n), slope * 1000);
        std::printf("mean temperature (%d rigid-body degrees of freedom): %.1f K\n", dof, temperatureSum / n);
        std::printf("speed: %.3g ms/step, %.3g ns/day\n", 1e3 * seconds / steps, steps * stepSize * 1e-3 * 86400 / seconds);
        return worstRigidity < 1e-8 ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
