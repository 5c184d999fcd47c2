#ifndef MRATTLE_DRUDE_GROUPS_H_
#define MRATTLE_DRUDE_GROUPS_H_

#include "RigidBodyTopology.h"
#include "internal/windowsExportMRattle.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <utility>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

/**
 * The Drude oscillators of a System (its DrudeForce's pairs) grouped for the Drude
 * integrators' split of the velocities (docs/ALGORITHM.md, "Drude oscillators"): each body
 * with the Drude particles of its cores (an augmented body), each free core with its Drude
 * particles (a free pair). R is a group's rigid motions with every Drude particle carried at
 * its core's velocity (translation only for a free pair); the rest, C, is the Drude
 * particles' motion relative to their cores: 3 degrees of freedom each. A host helper every
 * platform's state can use.
 */
class OPENMM_EXPORT_MRATTLE DrudeGroups {
public:
    struct Group {
        std::vector<int> particles;   // the body's atoms or the free core, then the Drude particles
        std::vector<int> places;      // per particle, whose position places it in R: itself, or a Drude particle's core
        bool rotates;                 // R holds the group's rotations (an augmented body), else translations only
    };
    DrudeGroups() = default;
    /**
     * The pairs of the System's DrudeForce (none without OpenMM's Drude plugin in the build)
     * grouped by the topology in effect. Throws an OpenMMException naming the particle for a
     * Drude particle in a body, a Drude particle or core without mass, a Drude particle in
     * two pairs or that is also a core.
     */
    DrudeGroups(const OpenMM::System& system, const RigidBodyTopology& topology, const char* integratorName);
    const std::vector<Group>& getGroups() const {
        return groups;
    }
    /** (Drude particle, core) for every pair. */
    const std::vector<std::pair<int, int> >& getPairs() const {
        return pairs;
    }
    int getNumDrudeParticles() const {
        return pairs.size();
    }
    /**
     * Throws an OpenMMException unless the System's DrudeForces hold numDrudeParticles pairs, the
     * number a step kernel was made with: a DrudeForce added or given pairs after the Context was
     * created, which the Context does not see until Context::reinitialize(). O(forces); a step
     * calls it before moving anything.
     */
    static void requireNumDrudeParticles(const OpenMM::System& system, int numDrudeParticles, const char* integratorName);
    /** Whether the particle is in a group (its velocity is split; every other one is at the system's temperature). */
    bool isGrouped(int particle) const {
        return particle < (int) grouped.size() && grouped[particle];
    }
    /**
     * R's part of the velocities v on one group: the M-orthogonal projection onto the
     * group's rigid motions, each particle at its place (or onto its translation), written to
     * out at the group's particles.
     */
    static void rigidPart(const Group& group, const std::vector<OpenMM::Vec3>& x, const std::vector<OpenMM::Vec3>& v,
                          const std::vector<double>& masses, std::vector<OpenMM::Vec3>& out);
    /** The kinetic energy of C, sum over groups of m |v - v_R|^2 / 2 (kJ/mol). */
    double relativeKineticEnergy(const std::vector<OpenMM::Vec3>& x, const std::vector<OpenMM::Vec3>& v,
                                 const std::vector<double>& masses) const;
    /**
     * The Drude temperature 2 KE_C / (3 n_drude k_B) in K (0 without Drude particles): what the
     * Drude integrators' computeDrudeTemperature() returns, KE_C from their step kernel.
     */
    static double drudeTemperature(double relativeKineticEnergy, int numDrudes);
    /**
     * Scales the relative part (v - v_R) of every group's velocities v, set for a Context's
     * positions, by factor: the Drude particles' relative motion drawn at a temperature of its own.
     */
    static void scaleRelativeMotion(OpenMM::ContextImpl& context, const RigidBodyTopology& topology,
                                    const char* integratorName, double factor, std::vector<OpenMM::Vec3>& v);
    /**
     * The bodies' and free particles' temperature 2 (KE - KE_C) / ((dof - 3 n_drude) k_B) in K
     * (0 without such degrees of freedom), given the kinetic energy KE and dof degrees of
     * freedom in all: what computeBodyTemperature() returns.
     */
    static double bodyTemperature(double kineticEnergy, double relativeKineticEnergy, int dof, int numDrudes);

private:
    static std::vector<std::pair<int, int> > drudePairs(const OpenMM::System& system);
    std::vector<Group> groups;
    std::vector<std::pair<int, int> > pairs;
    std::vector<bool> grouped;
};

} // namespace MRattlePlugin

#endif
