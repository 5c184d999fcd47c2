#ifndef MRATTLE_BODY_SHAPE_CONSTRAINTS_H_
#define MRATTLE_BODY_SHAPE_CONSTRAINTS_H_

#include "RigidBodyTopology.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/reference/ReferenceConstraints.h"
#include "internal/windowsExportMRattle.h"
#include <memory>
#include <vector>

namespace MRattlePlugin {

/**
 * Bodies whose internal constraints determine their shape (at least 3k - 6 of them for
 * k >= 3 atoms, one for two; rigid water, any fully constrained molecule) take their
 * constraint geometry when positions are set, as OpenMM's own integrators converge to it.
 * Only bodies off that geometry by more than Tolerance are moved (by OpenMM's own
 * constraint code: SETTLE for water, CCMA otherwise): bodies already on it keep their exact
 * rigid shape. A body whose constraints do not converge (singular, e.g. planar) keeps the
 * shape it was given. Bodies that RigidBodyMath::classifyShape() finds linear but whose
 * atoms are off their axis (a bent CO2 from 3-decimal coordinates) are then placed on it,
 * keeping their centre of mass, so that every platform integrates the same straight body.
 */
class OPENMM_EXPORT_MRATTLE BodyShapeConstraints {
public:
    /** topology must outlive this object (a platform state owns both). */
    BodyShapeConstraints(const OpenMM::System& system, const RigidBodyTopology& topology);
    /**
     * Move the bodies that are off their constraint geometry onto it, then straighten
     * near-linear bodies; true if any moved.
     *
     * @param storageError  how far (nm) a platform's stored coordinates can be from the ones
     *                      set (0 in double precision; single precision rounds a 3 nm box's
     *                      coordinates by ~1e-7 nm): a distance within Tolerance of its
     *                      constraint plus what that rounding can make of it is on the
     *                      geometry, so a body corrected once is left alone when its stored
     *                      positions are set again (the correction is idempotent)
     * @param shapes        if given, set to each body's RigidBodyMath::classifyShape() at the
     *                      positions returned (what RigidBodyTopology::classifyShapes() gives)
     */
    bool apply(std::vector<OpenMM::Vec3>& positions, double storageError = 0,
               std::vector<RigidBodyMath::Shape>* shapes = nullptr) const;
    /**
     * The same for every constrained body however close it is (to OpenMM's constraint
     * accuracy, 1e-10): the exact shape a device platform keeps as a body's reference.
     * shapes, if given, are apply()'s at these positions: bodies that are not linear are not
     * classified again unless a constraint moved them.
     */
    bool applyExactly(std::vector<OpenMM::Vec3>& positions,
                      const std::vector<RigidBodyMath::Shape>* shapes = nullptr) const;
    /** The largest error of a body's shape constraints at these positions, relative to Tolerance plus the storage allowance. */
    double error(const std::vector<OpenMM::Vec3>& positions, int body, double storageError = 0) const;
    /** Relative constraint error above which a body's shape is corrected (OpenMM 7.7's SETTLE is good to ~3e-8). */
    static constexpr double Tolerance = 1e-6;
    /**
     * What rounding each stored coordinate by storageError can do to a distance: both ends,
     * three coordinates each (2 sqrt(3)), times 8 to spare (single precision leaves waters
     * about 4x a float's rounding off their geometry).
     */
    static constexpr double StorageErrorFactor = 16 * 1.7320508075688772;

private:
    /** Place the atoms of each near-linear body on its axis; true if any moved. */
    bool straighten(std::vector<OpenMM::Vec3>& positions, std::vector<RigidBodyMath::Shape>* shapes = nullptr,
                    const std::vector<RigidBodyMath::Shape>* known = nullptr) const;
    /** The constraint-geometry correction alone (of every constrained body if all). */
    bool applyConstraints(std::vector<OpenMM::Vec3>& positions, double storageError, bool all = false) const;
    const RigidBodyTopology& topology;  // the owning state's, which outlives this
    mutable std::vector<double> inverseMasses;  // non-const in OpenMM's ReferenceConstraints::apply()
    std::unique_ptr<OpenMM::ReferenceConstraints> constraints;
    std::vector<std::vector<int> > constraintsOfBody;  // indices into the three arrays below
    std::vector<int> p1, p2;
    std::vector<double> distance;
    /** applyConstraints' copy of the positions, kept to reuse its memory. */
    mutable std::vector<OpenMM::Vec3> given;
};

} // namespace MRattlePlugin

#endif
