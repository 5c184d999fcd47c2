#include "internal/BodyShapeConstraints.h"
#include "mrattle/RigidBodyMath.h"
#include <algorithm>
#include <cmath>
#include <utility>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

BodyShapeConstraints::BodyShapeConstraints(const System& system, const RigidBodyTopology& bodies) : topology(bodies) {
    const int n = system.getNumParticles();
    inverseMasses.resize(n);
    for (int i = 0; i < n; i++)
        inverseMasses[i] = (system.getParticleMass(i) == 0 ? 0.0 : 1.0 / system.getParticleMass(i));
    vector<vector<int> > internal(bodies.getNumBodies());
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int a, b;
        double d;
        system.getConstraintParameters(c, a, b, d);
        int body = bodies.getBodyOfParticle(a);
        if (body != -1 && body == bodies.getBodyOfParticle(b))
            internal[body].push_back(c);
    }
    constraintsOfBody.resize(bodies.getNumBodies());
    System shapes;
    for (int i = 0; i < n; i++)
        shapes.addParticle(system.getParticleMass(i));
    for (int body = 0; body < bodies.getNumBodies(); body++) {
        const int k = bodies.getBodyParticles(body).size();
        if ((int) internal[body].size() < (k == 2 ? 1 : 3 * k - 6))
            continue;
        for (int c : internal[body]) {
            int a, b;
            double d;
            system.getConstraintParameters(c, a, b, d);
            constraintsOfBody[body].push_back(distance.size());
            p1.push_back(a);
            p2.push_back(b);
            distance.push_back(d);
            shapes.addConstraint(a, b, d);
        }
    }
    if (shapes.getNumConstraints() > 0)
        constraints.reset(new ReferenceConstraints(shapes));
}

double BodyShapeConstraints::error(const vector<Vec3>& positions, int body, double storageError) const {
    double worst = 0;
    for (int c : constraintsOfBody[body]) {
        Vec3 d = positions[p1[c]] - positions[p2[c]];
        const double allowed = Tolerance * distance[c] + StorageErrorFactor * storageError;
        const double relative = Tolerance * std::fabs(std::sqrt(d.dot(d)) - distance[c]) / allowed;
        worst = std::isfinite(relative) ? std::max(worst, relative) : INFINITY;
    }
    return worst;
}

bool BodyShapeConstraints::apply(vector<Vec3>& positions, double storageError, vector<RigidBodyMath::Shape>* shapes) const {
    const bool constrained = applyConstraints(positions, storageError);
    return straighten(positions, shapes) || constrained;
}

bool BodyShapeConstraints::applyExactly(vector<Vec3>& positions, const vector<RigidBodyMath::Shape>* shapes) const {
    const bool constrained = applyConstraints(positions, 0, true);
    return straighten(positions, nullptr, constrained ? nullptr : shapes) || constrained;
}

bool BodyShapeConstraints::straighten(vector<Vec3>& positions, vector<RigidBodyMath::Shape>* shapes,
                                      const vector<RigidBodyMath::Shape>* known) const {
    const double* x = reinterpret_cast<const double*>(positions.data());
    bool changed = false;
    if (shapes != nullptr)
        shapes->resize(topology.getNumBodies());
    for (int body = 0; body < topology.getNumBodies(); body++) {
        const vector<int>& atoms = topology.getBodyParticles(body);
        const RigidBodyMath::BodyView view{atoms.data(), (int) atoms.size(), topology.getMasses().data(),
                                           topology.getBodyMass(body), false};
        // Centre and second moment by RigidBodyTopology::classifyShapes()'s arithmetic: its shapes.
        auto moments = [&]() {
            const Eigen::Vector3d center = RigidBodyMath::centerOfMass(view, x);
            return std::make_pair(center, Eigen::Matrix3d(RigidBodyMath::secondMoment(view, x, center)));
        };
        if (known != nullptr && (*known)[body] != RigidBodyMath::Shape::Linear)
            continue;
        if (atoms.size() < 3) {  // two atoms are always on a line
            if (shapes != nullptr)
                (*shapes)[body] = RigidBodyMath::classifyShape(moments().second, view.totalMass);
            continue;
        }
        const std::pair<Eigen::Vector3d, Eigen::Matrix3d> moment = moments();
        const RigidBodyMath::Shape shape = RigidBodyMath::classifyShape(moment.second, view.totalMass);
        if (shapes != nullptr)
            (*shapes)[body] = shape;
        if (shape != RigidBodyMath::Shape::Linear)
            continue;
        const Eigen::Vector3d axis = RigidBodyMath::axisToStraighten(moment.second, view.totalMass);
        if (axis.squaredNorm() == 0)
            continue;
        // The projection onto the axis through the centre keeps the centre of mass.
        const Eigen::Vector3d& center = moment.first;
        const Vec3 c(center[0], center[1], center[2]), u(axis[0], axis[1], axis[2]);
        for (int i : atoms)
            positions[i] = c + u * (positions[i] - c).dot(u);
        changed = true;
        if (shapes != nullptr)
            (*shapes)[body] = RigidBodyMath::classifyShape(moments().second, view.totalMass);
    }
    return changed;
}

bool BodyShapeConstraints::applyConstraints(vector<Vec3>& positions, double storageError, bool all) const {
    if (!constraints)
        return false;
    // Only bodies clearly off their geometry (a PDB file's waters are off by ~1e-3) move:
    // re-applying OpenMM's constraint code to exact bodies (after a barostat move, say)
    // would perturb their rigid shape at its accuracy.
    vector<char> off(topology.getNumBodies(), 0);
    bool anyOff = false;
    for (int body = 0; body < topology.getNumBodies(); body++)
        if (!constraintsOfBody[body].empty() && (all || error(positions, body, storageError) > Tolerance))
            anyOff = off[body] = 1;
    if (!anyOff)
        return false;
    given.assign(positions.begin(), positions.end());  // a buffer kept across calls: no fresh pages
    // The same array for old and new positions, as OpenMM's applyConstraints does: SETTLE
    // then rebuilds each water from its constraint geometry. (It only reads the masses.)
    constraints->apply(positions, positions, inverseMasses, 1e-10);
    bool changed = false;
    for (int body = 0; body < topology.getNumBodies(); body++) {
        if (constraintsOfBody[body].empty())
            continue;
        // OpenMM's CCMA gives up silently: a body it did not solve keeps its given shape.
        const bool keep = !off[body] || !(error(positions, body) <= Tolerance);
        for (int i : topology.getBodyParticles(body)) {
            if (keep)
                positions[i] = given[i];
            else
                changed = true;
        }
    }
    return changed;
}
