/*
 * The search's report of an iteration in OpenMM's terms (MinimizationReporter::report()):
 * Cartesian positions and gradient, and the documented statistics.
 */
#include "RigidBodySearch.h"
#include <algorithm>
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

bool RigidBodySearch::reportIteration(const double* g) {
    const int numParticles = system.getNumParticles();
    // The iterate as the Context holds it (virtual sites computed), and the forces there.
    vector<Vec3> positions;
    impl.getPositions(positions);
    positionsOf(x.get(), trial);
    vector<double> flatPositions(3 * numParticles), gradient(3 * numParticles, 0.0);
    for (int i = 0; i < numParticles; i++)
        for (int d = 0; d < 3; d++)
            flatPositions[3 * i + d] = positions[i][d];
    // Bodies: minus the force projected on their rigid motion. Free particles: liblbfgs's
    // gradient (forces and springs), back in kJ/mol/nm.
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    for (size_t b = 0; b < bodies.size(); b++)
        bodies[b].projectForces(x.get() + offsets[b], lengthScale, reinterpret_cast<const double*>(trial.data()),
                                reinterpret_cast<const double*>(forces.data()), gradient.data());
    for (const RigidBodyMath::RigidBodyCoordinates& body : bodies)
        for (int i : body.getAtoms())
            for (int d = 0; d < 3; d++)
                gradient[3 * i + d] = -gradient[3 * i + d];
    const int freeOffset = numVariables - 3 * freeParticles.size();
    for (size_t k = 0; k < freeParticles.size(); k++)
        for (int d = 0; d < 3; d++)
            gradient[3 * freeParticles[k] + d] = g[freeOffset + 3 * k + d] / lengthScale;
    double maxConstraintError = 0;
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        const Vec3 delta = positions[p2] - positions[p1];
        if (distance > 0)
            maxConstraintError = std::max(maxConstraintError, std::fabs(std::sqrt(delta.dot(delta)) - distance) / distance);
    }
    std::map<std::string, double> args = {{"system energy", accepted.energy},
                                          {"restraint energy", accepted.springEnergy},
                                          {"restraint strength", springConstant},
                                          {"max constraint error", maxConstraintError}};
    return reporter->report(roundIterations++, flatPositions, gradient, args);
}
