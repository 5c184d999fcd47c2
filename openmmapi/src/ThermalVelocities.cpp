#include "internal/ThermalVelocities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <random>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

vector<Vec3> ThermalVelocities::maxwellBoltzmann(const vector<double>& inverseMasses, double temperature, int randomSeed) {
    std::mt19937_64 generator(randomSeed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    vector<Vec3> velocities(inverseMasses.size(), Vec3());
    for (size_t i = 0; i < inverseMasses.size(); i++)
        if (inverseMasses[i] != 0) {
            const double scale = std::sqrt(BOLTZ * temperature * inverseMasses[i]);
            const double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * scale;
        }
    return velocities;
}

void ThermalVelocities::scaleToTemperature(const RigidBodyTopology& topology, const vector<double>& inverseMasses,
                                           int degreesOfFreedom, double temperature, vector<Vec3>& velocities) {
    const vector<double>& masses = topology.getMasses();
    double totalMass = 0;
    Vec3 momentum;
    for (size_t i = 0; i < velocities.size(); i++) {
        totalMass += masses[i];
        momentum += velocities[i] * masses[i];
    }
    if (topology.removesCenterOfMassMotion() && totalMass > 0) {
        const Vec3 centerVelocity = momentum / totalMass;
        for (size_t i = 0; i < velocities.size(); i++)
            if (inverseMasses[i] != 0)
                velocities[i] -= centerVelocity;
    }
    double kinetic = 0;
    for (size_t i = 0; i < velocities.size(); i++)
        if (inverseMasses[i] != 0)
            kinetic += 0.5 * velocities[i].dot(velocities[i]) / inverseMasses[i];
    if (kinetic > 0 && degreesOfFreedom > 0) {
        const double scale = std::sqrt(0.5 * degreesOfFreedom * BOLTZ * temperature / kinetic);
        for (Vec3& v : velocities)
            v *= scale;
    }
}
