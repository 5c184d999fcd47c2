#include "ReferenceRigidBodyState.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <string>

// The Drude integrators' phases of ReferenceRigidBodyState: the split noise, the hard wall, and
// the two-chain thermostat's kinetic energies and scaling.

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceRigidBodyState::addDrudeNoise(const DrudeGroups& groups, double friction, double temperature,
                                            double drudeFriction, double drudeTemperature, double h) {
    phase([&] {
        const vector<Vec3>& x = positions();
        vector<Vec3>& v = velocities();
        const int n = v.size();
        const double a = std::exp(-friction * h), aDrude = std::exp(-drudeFriction * h);
        const double scale = std::sqrt(BOLTZ * temperature * (1 - a * a));
        const double scaleDrude = std::sqrt(BOLTZ * drudeTemperature * (1 - aDrude * aDrude));
        // u = M^-1/2 xi, drawn in particle order (three per massive particle, as addNoise).
        std::normal_distribution<double> gaussian(0.0, 1.0);
        drudeNoise.assign(n, Vec3());
        drudeRigid.assign(n, Vec3());
        for (int i = 0; i < n; i++)
            if (inverseMass[i] != 0) {
                const double gx = gaussian(random), gy = gaussian(random), gz = gaussian(random);
                drudeNoise[i] = Vec3(gx, gy, gz) * std::sqrt(inverseMass[i]);
            }
        for (int i = 0; i < n; i++)
            if (inverseMass[i] != 0 && !groups.isGrouped(i))
                v[i] = v[i] * a + drudeNoise[i] * scale;
        // A group: v' = a v_R + a_d v_C + scale P_R u + scaleDrude (u - P_R u); project() then
        // takes u - P_R u to P_C u (R lies in the constrained space, M-orthogonal to C).
        vector<Vec3>& rigidNoise = nextVelocities;   // a step buffer, free between phases
        for (const DrudeGroups::Group& group : groups.getGroups()) {
            DrudeGroups::rigidPart(group, x, v, mass, drudeRigid);
            DrudeGroups::rigidPart(group, x, drudeNoise, mass, rigidNoise);
            for (int i : group.particles)
                v[i] = drudeRigid[i] * a + (v[i] - drudeRigid[i]) * aDrude + rigidNoise[i] * scale +
                       (drudeNoise[i] - rigidNoise[i]) * scaleDrude;
        }
    });
}

void ReferenceRigidBodyState::bounceDrudes(const DrudeGroups& groups, double maxDistance, double drudeTemperature,
                                           double h) {
    if (maxDistance <= 0)
        return;
    phase([&] {
        vector<Vec3>& x = positions();
        vector<Vec3>& v = velocities();
        const double kTDrude = BOLTZ * drudeTemperature;
        for (const auto& pair : groups.getPairs()) {
            const int drude = pair.first, core = pair.second;
            const Vec3 delta = x[drude] - x[core];
            const double r = std::sqrt(delta.dot(delta));
            if (!(r > maxDistance))
                continue;
            if (!(r <= 2 * maxDistance))
                throw OpenMMException("Drude particle " + std::to_string(drude) + " is " + std::to_string(r) +
                                      " nm from its core " + std::to_string(core) +
                                      ", beyond twice the hard wall's maxDrudeDistance (" +
                                      std::to_string(maxDistance) + " nm)");
            const Vec3 direction = delta / r;   // from the core to the Drude particle
            const double beyond = r - maxDistance;
            if (bodies.getBodyOfParticle(core) >= 0) {
                // The core is in a body: the Drude particle alone bounces, its speed relative to
                // the core along the bond set to sqrt(kT_d / m) inwards.
                const double relative = (v[drude] - v[core]).dot(direction);
                const double time = (relative != 0 ? std::min(beyond / std::fabs(relative), h) : h);
                const double bounced = -std::sqrt(kTDrude * inverseMass[drude]);
                x[drude] += direction * (-beyond + time * bounced);
                v[drude] += direction * (bounced - relative);
            } else {
                // A free core: OpenMM's two-particle bounce about the pair's centre of mass.
                const double m1 = mass[drude], m2 = mass[core], inverseTotal = 1 / (m1 + m2);
                double along1 = v[drude].dot(direction), along2 = v[core].dot(direction);
                const Vec3 across1 = v[drude] - direction * along1, across2 = v[core] - direction * along2;
                const double centre = (m1 * along1 + m2 * along2) * inverseTotal;
                along1 -= centre;
                along2 -= centre;
                const double time = (along1 != along2 ? std::min(beyond / std::fabs(along1 - along2), h) : h);
                const double speed = std::sqrt(kTDrude * inverseMass[drude]);
                const double sign = (along1 - along2 < 0 ? -1.0 : 1.0);   // outwards (or at rest): inwards after
                along1 = -sign * speed * m2 * inverseTotal;
                along2 = sign * speed * m1 * inverseTotal;
                x[drude] += direction * (-beyond * m2 * inverseTotal + time * along1);
                x[core] += direction * (beyond * m1 * inverseTotal + time * along2);
                v[drude] = across1 + direction * (along1 + centre);
                v[core] = across2 + direction * (along2 + centre);
            }
        }
    });
}

void ReferenceRigidBodyState::computeDrudeKineticEnergies(const DrudeGroups& groups, double& rigid, double& relative) {
    const vector<Vec3>& v = velocities();
    relative = groups.relativeKineticEnergy(positions(), v, mass);
    rigid = kineticEnergyOf(v) - relative;
}

void ReferenceRigidBodyState::scaleDrudeVelocities(const DrudeGroups& groups, double factor, double drudeFactor) {
    if (factor == 1 && drudeFactor == 1)
        return;   // chains at rest (frequencies 0): the velocities as they are, bit for bit
    phase([&] {
        const vector<Vec3>& x = positions();
        vector<Vec3>& v = velocities();
        const int n = v.size();
        drudeRigid.assign(n, Vec3());
        for (const DrudeGroups::Group& group : groups.getGroups())
            DrudeGroups::rigidPart(group, x, v, mass, drudeRigid);
        for (int i = 0; i < n; i++)
            v[i] = (groups.isGrouped(i) ? drudeRigid[i] * factor + (v[i] - drudeRigid[i]) * drudeFactor
                                        : v[i] * factor);
    });
}
