#ifndef MRATTLE_BODY_SHAPE_WATCH_H_
#define MRATTLE_BODY_SHAPE_WATCH_H_

#include "openmm/Vec3.h"
#include "internal/windowsExportMRattle.h"
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyTopology;

/**
 * Catches what a Cartesian minimizer (OpenMM's LocalEnergyMinimizer called from C++, or any
 * tool that moves atoms one by one through setPositions()) does to the bodies: positions
 * set more than once between two steps that changed a body's shape. Positions set once
 * before a step take effect as they are (a new configuration: its shapes are the bodies'
 * from then on); a series of them must keep the shapes of its first, or the next step
 * throws (docs/usage.md, body shapes). The series starts again at a step, a checkpoint
 * load, reset(), and after a refusal at the next setPositions().
 */
class OPENMM_EXPORT_MRATTLE BodyShapeWatch {
public:
    /**
     * A body is deformed when an atom is farther than this (nm) from its shape at the
     * series' start, superposed: above the round-off of shapes restored by constraints
     * (SETTLE, ~1e-8 nm) and below the deformations of a minimizer (2e-3 nm for benzene).
     */
    static constexpr double Tolerance = 1e-6;
    /** Forget the series (a new Context, a step taken, a checkpoint loaded). */
    void reset();
    /** Positions were set (not by the rigid minimizer's search): the first of a series is kept. */
    void positionsSet(OpenMM::ContextImpl& context);
    /**
     * Before a step: throw an OpenMMException naming the body and the change if the
     * positions were set more than once since the last step and a body's shape changed
     * (and keep throwing until positions are set again). A series begun at another step
     * count (another integrator stepped, the step count was set) is not judged.
     */
    void requireShapesKept(OpenMM::ContextImpl& context, const RigidBodyTopology& topology);

private:
    int positionsSetCount = 0;
    long long seriesStepCount = 0;
    std::vector<OpenMM::Vec3> seriesStart;
    /** The message of a refused series, repeated until positions are set again; empty if none. */
    std::string refusal;
};

} // namespace MRattlePlugin

#endif
