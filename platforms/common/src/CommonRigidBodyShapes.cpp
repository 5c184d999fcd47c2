/*
 * CommonRigidBodyDynamics and the bodies' shapes: classified when positions are set, their
 * reference geometry and orientation (from which every step rebuilds them), and those in
 * checkpoints.
 */
#include "CommonRigidBodyDynamics.h"
#include "internal/FiniteValues.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

/** The reference geometry (3 numbers per body atom) and the orientations (9 per body), in double. */
template <class Vector4, class Real>
void appendShapeState(const ComputeArray& reference, const ComputeArray& orientation, vector<double>& values) {
    vector<Vector4> positions;
    reference.download(positions);
    for (const Vector4& r : positions)
        values.insert(values.end(), {(double) r.x, (double) r.y, (double) r.z});
    vector<Real> matrices;
    orientation.download(matrices);
    values.insert(values.end(), matrices.begin(), matrices.end());
}

} // namespace

double CommonRigidBodyDynamics::storageError(ContextImpl& context, const vector<Vec3>& positions) const {
    // Relative round-off of a stored coordinate: double, or float (mixed precision too: OpenMM
    // 7.7 stores positions set from the host without their float correction, measured).
    const double roundoff = cc.getUseDoublePrecision() ? std::ldexp(1.0, -53) : std::ldexp(1.0, -24);
    // OpenMM stores coordinates shifted into the periodic box: up to a box length more.
    Vec3 a, b, c;
    context.getPeriodicBoxVectors(a, b, c);
    double largest = std::sqrt(std::max(a.dot(a), std::max(b.dot(b), c.dot(c))));
    double coordinate = 0;
    for (const Vec3& x : positions)
        coordinate = std::max(coordinate, std::max(std::fabs(x[0]), std::max(std::fabs(x[1]), std::fabs(x[2]))));
    return roundoff * (coordinate + largest);
}

void CommonRigidBodyDynamics::updateShapes(ContextImpl& context) {
    if (writingCorrectedShapes)
        return;  // the positions this call itself is writing: classified below, once written
    stepFailure.rememberOrder();  // setting positions clears OpenMM's cell offsets
    // Positions were just uploaded from the host: classify on the host with the core.
    vector<Vec3> positions;
    context.getPositions(positions);
    FiniteValues::require(positions, "position");
    if (shapeConstraints->apply(positions, storageError(context, positions))) {
        // Back to the device, once: the correction is left alone by its own notification,
        // and a body on its geometry to the storage's precision is not corrected again.
        writingCorrectedShapes = true;
        try {
            context.setPositions(positions);
        } catch (...) {
            writingCorrectedShapes = false;
            throw;
        }
        writingCorrectedShapes = false;
        context.getPositions(positions);
    }
    shapes = bodies.classifyShapes(positions);
    if (keepReference)
        keepReference = false;  // a checkpoint's positions: its reference came with them
    else if (rebuildsShapes())
        setReference(positions);
    vector<int> codes(std::max(1, numBodies), shapeCode(RigidBodyMath::Shape::General));
    for (int b = 0; b < numBodies; b++)
        codes[b] = shapeCode(shapes[b]);
    bodyShape.upload(codes);
}

void CommonRigidBodyDynamics::setReference(const vector<Vec3>& positions) {
    // In double, and fully constrained bodies exactly on their constraint geometry (not the
    // storage's rounding of it): the shape every step rebuilds.
    vector<Vec3> exact = positions;
    shapeConstraints->applyExactly(exact);
    vector<mm_double4> reference(std::max<size_t>(1, systemBodyAtoms.size()), mm_double4(0, 0, 0, 0));
    for (int b = 0, k = 0; b < numBodies; b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        double mass = 0;
        Vec3 center;
        for (int atom : atoms) {
            mass += 1 / inverseMasses[atom];
            center += exact[atom] / inverseMasses[atom];
        }
        center /= mass;
        for (int atom : atoms) {
            const Vec3 r = exact[atom] - center;
            reference[k++] = mm_double4(r[0], r[1], r[2], 0);
        }
    }
    bodyReference.upload(reference, true);
    bodyOrientation.upload(identityOrientations(), true);
}

vector<double> CommonRigidBodyDynamics::identityOrientations() const {
    vector<double> orientations(9 * std::max(1, numBodies), 0.0);
    for (size_t b = 0; b < orientations.size(); b += 9)
        orientations[b] = orientations[b + 4] = orientations[b + 8] = 1;
    return orientations;
}

void CommonRigidBodyDynamics::createCheckpoint(std::ostream& stream) const {
    stepFailure.synchronize();
    // The random stream (Andersen collisions, Langevin noise) is OpenMM's
    // IntegrationUtilities', which OpenMM's own part of the checkpoint holds. Ours: the
    // bodies' reference geometry (it stays that of the positions first set).
    vector<double> values;
    if (rebuildsShapes()) {
        if (bodyReference.getElementSize() == sizeof(mm_double4))
            appendShapeState<mm_double4, double>(bodyReference, bodyOrientation, values);
        else
            appendShapeState<mm_float4, float>(bodyReference, bodyOrientation, values);
    }
    // Unframed: the checkpoint header (RigidBodyCheckpointHeader) frames the kernel's state.
    stream.write((const char*) values.data(), values.size() * sizeof(double));
}

void CommonRigidBodyDynamics::loadCheckpoint(std::istream& stream) {
    // The stream holds exactly what createCheckpoint() wrote. Checkpoints of format 3 hold
    // the device's own 4-byte length prefix of an empty state instead: no state.
    std::string state((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    if (state == std::string(sizeof(int32_t), '\0'))
        state.clear();
    const size_t expected = rebuildsShapes() ? (bodyReference.getSize() * 3 + bodyOrientation.getSize()) * sizeof(double) : 0;
    if (!state.empty() && state.size() != expected)
        throw OpenMMException("the checkpoint's kernel data is not this platform's (a state of " +
                              std::to_string(state.size()) + " bytes where " + std::to_string(expected) +
                              (expected > 0 ? " or none are" : " are") + " expected)");
    if (!state.empty()) {
        // The reference geometry goes with the positions OpenMM has just read (updateShapes keeps it).
        vector<double> values(state.size() / sizeof(double));
        std::copy(state.begin(), state.end(), (char*) values.data());
        vector<mm_double4> reference(bodyReference.getSize());
        for (size_t k = 0; k < reference.size(); k++)
            reference[k] = mm_double4(values[3 * k], values[3 * k + 1], values[3 * k + 2], 0);
        bodyReference.upload(reference, true);
        bodyOrientation.upload(vector<double>(values.begin() + 3 * reference.size(), values.end()), true);
        keepReference = true;
    }
    stepFailure.reset();
    stepFailure.rememberOrder();
}
