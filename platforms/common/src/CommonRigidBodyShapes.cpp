/*
 * CommonRigidBodyState: the bodies' shapes (classified when positions are set), their
 * reference geometry and orientation (from which every step rebuilds them), and checkpoints.
 */
#include "CommonRigidBodyState.h"
#include "internal/FiniteValues.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/internal/ContextImpl.h"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

double CommonRigidBodyState::storageError(ContextImpl& context, const vector<Vec3>& positions) const {
    double coordinate = 0;
    for (const Vec3& x : positions)
        coordinate = std::max(coordinate, std::max(std::fabs(x[0]), std::max(std::fabs(x[1]), std::fabs(x[2]))));
    return coordinateRoundoff() * (coordinate + largestBoxVector(context));
}

double CommonRigidBodyState::coordinateRoundoff() const {
    // Double, or float (mixed precision too: OpenMM 7.7 stores positions set from the host
    // without their float correction).
    return cc.getUseDoublePrecision() ? std::ldexp(1.0, -53) : std::ldexp(1.0, -24);
}

double CommonRigidBodyState::largestBoxVector(ContextImpl& context) {
    // OpenMM stores coordinates shifted into the periodic box: up to a box length more.
    Vec3 a, b, c;
    context.getPeriodicBoxVectors(a, b, c);
    return std::sqrt(std::max(a.dot(a), std::max(b.dot(b), c.dot(c))));
}

void CommonRigidBodyState::updateShapes(ContextImpl& context) {
    if (writingCorrectedShapes)
        return;  // the positions this call itself is writing: classified below, once written
    ContextSelector selector(cc);
    rememberOrder();  // setting positions clears OpenMM's cell offsets
    // Bodies that are their reference turned (a State's positions) keep it: nothing to classify.
    if (!keepReference && fitsReference(context))
        return;
    // Host buffers are members: at 100k atoms fresh ones cost more in page faults than the work.
    vector<Vec3>& positions = hostPositions;
    context.getPositions(positions);
    FiniteValues::require(positions, "position");
    if (shapeConstraints->apply(positions, storageError(context, positions), &shapes)) {
        // Back to the device once; a body on its geometry to the storage's precision is not corrected again.
        writingCorrectedShapes = true;
        try {
            context.setPositions(positions);
        } catch (...) {
            writingCorrectedShapes = false;
            throw;
        }
        writingCorrectedShapes = false;
        context.getPositions(positions);
        shapes = bodies.classifyShapes(positions);  // as stored
    }
    if (keepReference)
        keepReference = false;  // a checkpoint's positions: its reference came with them
    else
        setReference(positions);  // in double precision only what fitsReference() compares with
    // The device's codes change only when a body's shape does.
    bool changed = false;
    for (int b = 0; b < numBodies; b++) {
        const int code = shapeCode(shapes[b]);
        changed = changed || code != uploadedShapeCodes[b];
        uploadedShapeCodes[b] = code;
    }
    if (changed)
        bodyShape.upload(uploadedShapeCodes);
}

void CommonRigidBodyState::setReference(vector<Vec3>& exact) {
    // Single and mixed precision: fully constrained bodies exactly on their constraint geometry
    // (in double), the shape every step rebuilds. Double: the shapes as set, which fitsReference()
    // compares with (OpenMM's SETTLE is exact only to about 5e-9 nm).
    if (rebuildsShapes())
        shapeConstraints->applyExactly(exact, &shapes);
    // Written in the device's element type, into buffers kept across calls.
    const bool useDouble = bodyReference.getElementSize() == sizeof(mm_double4);
    if (useDouble)
        referenceDouble.resize(bodyReference.getSize(), mm_double4(0, 0, 0, 0));
    else
        referenceSingle.resize(bodyReference.getSize(), mm_float4(0, 0, 0, 0));
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
            if (useDouble)
                referenceDouble[k++] = mm_double4(r[0], r[1], r[2], 0);
            else
                referenceSingle[k++] = mm_float4((float) r[0], (float) r[1], (float) r[2], 0);
        }
    }
    if (useDouble)
        bodyReference.upload(referenceDouble);
    else
        bodyReference.upload(referenceSingle);
    uploadIdentityOrientations();
    chooseFrames(exact);
}

void CommonRigidBodyState::chooseFrames(const vector<Vec3>& exact) {
    // Well-spread atoms, so the turn is no less exact than the coordinates: i furthest from
    // the first atom, j furthest from i, k furthest from their line (none for a linear body).
    hostFrames.assign(std::max(1, numBodies), mm_int4(0, 0, 0, 0));
    for (int b = 0; b < numBodies; b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        if (atoms.size() < 2)
            continue;
        auto furthest = [&](auto distance) {
            int best = 0;
            for (int k = 1; k < (int) atoms.size(); k++)
                if (distance(exact[atoms[k]]) > distance(exact[atoms[best]]))
                    best = k;
            return best;
        };
        const int i = furthest([&](const Vec3& x) { return (x - exact[atoms[0]]).dot(x - exact[atoms[0]]); });
        const Vec3 xi = exact[atoms[i]];
        const int j = furthest([&](const Vec3& x) { return (x - xi).dot(x - xi); });
        const Vec3 line = exact[atoms[j]] - xi;
        auto offLine = [&](const Vec3& x) { return (x - xi).cross(line).dot((x - xi).cross(line)); };
        const int k = furthest(offLine);
        const bool linear = shapes[b] == RigidBodyMath::Shape::Linear;
        if (i != j && (linear || offLine(exact[atoms[k]]) > 0))
            hostFrames[b] = mm_int4(i, j, linear ? -1 : k, 1);
    }
    bodyFrame.upload(hostFrames);
    referenceOnDevice = true;
}

bool CommonRigidBodyState::fitsReference(ContextImpl& context) {
    if (!referenceOnDevice)
        return false;
    if (!fitBodies) {
        fitBodies = stepProgram->createKernel("fitBodiesToReference");
        Arguments arguments(fitBodies, doubleMixed());
        arguments.add(cc.getNumAtoms());
        arguments.add(numBodies);
        arguments.add(bodyStart);
        arguments.add(bodyAtoms);
        arguments.add(bodyShape);
        arguments.add(bodyFrame);
        arguments.add(bodyReference);
        arguments.add(bodyOrientation);
        arguments.add(cc.getPosq());
        arguments.add(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
        fitRoundoff = arguments.addMixed(0.0);
        arguments.addMixed(0.0);
        arguments.add(screenVerdict);
    }
    setMixedArg(fitBodies, fitRoundoff, coordinateRoundoff());
    setMixedArg(fitBodies, fitRoundoff + 1, largestBoxVector(context));
    fitBodies->execute(std::max(numBodies, cc.getNumAtoms()));
    return !screenFound();
}

vector<double> CommonRigidBodyState::identityOrientations() const {
    vector<double> orientations(9 * std::max(1, numBodies), 0.0);
    for (size_t b = 0; b < orientations.size(); b += 9)
        orientations[b] = orientations[b + 4] = orientations[b + 8] = 1;
    return orientations;
}

void CommonRigidBodyState::uploadIdentityOrientations() {
    if (bodyOrientation.getElementSize() == sizeof(double)) {
        if (identityDouble.empty())
            identityDouble = identityOrientations();
        bodyOrientation.upload(identityDouble);
    } else {
        if (identitySingle.empty()) {
            const vector<double> identity = identityOrientations();
            identitySingle.assign(identity.begin(), identity.end());
        }
        bodyOrientation.upload(identitySingle);
    }
}

void CommonRigidBodyState::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    ContextSelector selector(cc);
    const_cast<CommonRigidBodyState*>(this)->synchronize();  // a step not yet checked may have failed
    // The integrator's declared arrays first, in its own layout; then the bodies' reference
    // geometry and orientations, which read to the end. The random stream is OpenMM's, in its part.
    if (!declared.empty()) {
        const IntegratorParameterValues values = integratorValues();
        vector<const vector<double>*> inOrder;
        for (const DeclaredArray& array : declared)
            inOrder.push_back(&values.at(array.name));
        writeIntegratorVariables(stream, inOrder, lengthFirst);
    }
    vector<double> values;
    if (rebuildsShapes()) {
        const vector<double> reference = downloadAsDouble(bodyReference, 4);
        for (size_t k = 0; k < reference.size(); k += 4)
            values.insert(values.end(), {reference[k], reference[k + 1], reference[k + 2]});
        const vector<double> orientations = downloadAsDouble(bodyOrientation);
        values.insert(values.end(), orientations.begin(), orientations.end());
    }
    stream.write((const char*) values.data(), values.size() * sizeof(double));
}

void CommonRigidBodyState::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    ContextSelector selector(cc);
    // The declared arrays read aside: nothing changes unless all of the checkpoint fits.
    IntegratorParameterValues integratorValues;
    vector<vector<double>*> into;
    std::string names;
    for (const DeclaredArray& array : declared) {
        integratorValues[array.name].resize(array.size);
        names += (names.empty() ? "" : " and ") + array.name;
    }
    for (const DeclaredArray& array : declared)
        into.push_back(&integratorValues[array.name]);
    if (!into.empty())
        readIntegratorVariables(stream, names, into, lengthFirst);
    // The rest of the stream is what createCheckpoint() wrote after them. Checkpoints of
    // format 3 hold the device's own 4-byte length prefix of an empty state instead: no state.
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
    resetFailure();
    rememberOrder();
    setIntegratorParameters(context, integratorValues);
}

void CommonRigidBodyState::discardRefusedCheckpoint(ContextImpl& context) {
    // OpenMM's device random state is its own and stays valid; nothing of ours was read.
}
