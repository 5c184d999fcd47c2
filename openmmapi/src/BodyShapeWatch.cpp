#include "internal/BodyShapeWatch.h"
#include "RigidBodyTopology.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <sstream>

// The core is internal to the library (RigidBodySearch.h: why hidden).
#if defined(__GNUC__)
#pragma GCC visibility push(hidden)
#endif
#include "mrattle/RigidBodyCoordinates.h"
#if defined(__GNUC__)
#pragma GCC visibility pop
#endif

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void BodyShapeWatch::reset() {
    positionsSetCount = 0;
    seriesStart.clear();
    refusal.clear();
}

void BodyShapeWatch::positionsSet(ContextImpl& context) {
    if (!refusal.empty())
        reset();  // set again after a refusal: these positions start a new series
    if (positionsSetCount++ == 0) {
        context.getPositions(seriesStart);
        seriesStepCount = context.getStepCount();
    }
}

void BodyShapeWatch::requireShapesKept(ContextImpl& context, const RigidBodyTopology& topology) {
    if (!refusal.empty())
        throw OpenMMException(refusal);
    if (positionsSetCount < 2 || seriesStepCount != context.getStepCount()) {
        reset();
        return;
    }
    vector<Vec3> positions;
    context.getPositions(positions);
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    const double* start = reinterpret_cast<const double*>(seriesStart.data());
    const double* now = reinterpret_cast<const double*>(positions.data());
    int worstBody = -1;
    double worst = 0;
    for (int b = 0; b < topology.getNumBodies(); b++) {
        const double deviation = RigidBodyMath::largestShapeDeviation(start, now, topology.getBodyParticles(b));
        if (deviation > worst) {
            worst = deviation;
            worstBody = b;
        }
    }
    const int count = positionsSetCount;
    reset();
    if (!(worst > Tolerance))
        return;
    std::ostringstream message;
    message << "step: the positions were set " << count << " times since the last step, and they changed the shape "
            << "of body " << worstBody << " (particles " << topology.getBodyParticles(worstBody)[0] << ", ...) by "
            << worst << " nm: that is what a Cartesian minimizer does (OpenMM's LocalEnergyMinimizer called from "
            << "C++, or any tool that moves atoms one at a time). Minimize with MRattlePlugin::RigidBodyMinimizer::"
            << "minimize (Python: openmm.LocalEnergyMinimizer.minimize after 'import mrattle') to keep the bodies "
            << "rigid; or, to make these the bodies' shapes on purpose, set the positions once more and step";
    refusal = message.str();
    throw OpenMMException(refusal);
}
