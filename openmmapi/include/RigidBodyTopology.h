#ifndef MRATTLE_RIGID_BODY_TOPOLOGY_H_
#define MRATTLE_RIGID_BODY_TOPOLOGY_H_

#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "internal/windowsExportMRattle.h"
#include <cstdint>
#include <vector>

namespace MRattlePlugin {

#ifndef SWIG
namespace RigidBodyMath {
enum class Shape;   // mrattle/RigidBodyMath.h: general, linear, a point
}
#endif

/**
 * The one home of rigid-body topology, shared by every rigid-body integrator and kernel:
 * which particles form each body, which particles are free, which constraints must still
 * be enforced, the masses and the degrees of freedom. It is fixed once an integrator is
 * bound to a Context; the integrator hands a copy to its kernel. The shapes the bodies
 * have at given positions are classified here, by one rule for every platform; the
 * platform's state keeps them.
 *
 * Body semantics: with no explicit bodies, every molecule (OpenMM's connected components
 * of bonds and constraints) with two or more massive, non-virtual particles is a body.
 * With explicit bodies, only those are rigid. A body of one particle is a free particle.
 * Virtual sites and massless particles are never body members.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyTopology {
public:
    RigidBodyTopology() = default;
    /**
     * Resolve the bodies of a System. Throws OpenMMException naming the body and
     * particle for: an index out of range, a particle listed twice, a massless particle
     * or virtual site listed as a member, a constraint joining a body to a particle
     * outside it; and naming the particle for a mass that is negative or not finite.
     *
     * @param explicitBodies  bodies added to the integrator (empty: use the molecules)
     * @param molecules       the System's molecules, as ContextImpl::getMolecules()
     */
    RigidBodyTopology(const OpenMM::System& system, const std::vector<std::vector<int> >& explicitBodies,
                 const std::vector<std::vector<int> >& molecules);

    /** Check one explicit body on its own (at addRigidBody time): not empty, no negative index, no repeat. */
    static void checkBodyDefinition(int bodyIndex, const std::vector<int>& particles);

    int getNumBodies() const { return bodies.size(); }
    const std::vector<std::vector<int> >& getBodies() const { return bodies; }
    const std::vector<int>& getBodyParticles(int body) const { return bodies[body]; }
    /** The body a particle belongs to, or -1 for a free particle, massless particle or virtual site. */
    int getBodyOfParticle(int particle) const { return bodyOfParticle[particle]; }
    /** Massive, non-virtual particles that belong to no body. */
    const std::vector<int>& getFreeParticles() const { return freeParticles; }
    /** Indices of the System's constraints between free particles (enforced RATTLE-style). */
    const std::vector<int>& getFreeConstraints() const { return freeConstraints; }
    /** Number of System constraints between two massless particles (OpenMM ignores them, and so does this). */
    int getNumMasslessConstraints() const { return masslessConstraints; }
    /** Number of System constraints with both ends in one body (ignored: redundant). */
    int getNumIgnoredConstraints() const { return ignoredConstraints; }
    double getBodyMass(int body) const { return bodyMass[body]; }
    /** True if the System has a CMMotionRemover (it removes 3 degrees of freedom). */
    bool removesCenterOfMassMotion() const { return hasCMMotionRemover; }

    /**
     * The bodies' degrees of freedom (bodyDegreesOfFreedom: 6 per body, 5 if linear, 3 if
     * its atoms coincide; the kernel knows the shapes), plus 3 per free particle, minus free
     * constraints, minus 3 with a CMMotionRemover.
     */
    int getNumDegreesOfFreedom(int bodyDegreesOfFreedom) const;
    /**
     * getNumDegreesOfFreedom() split between the bodies' translations, their rotations and the
     * free particles (the three add up to it). Translational: 3 per body. Rotational: the rest
     * of the bodies' degrees of freedom (3 per body, 2 if linear, 0 if its atoms coincide).
     * Free: 3 per free particle minus free constraints. A CMMotionRemover's 3 are taken from
     * the translational and the free ones in proportion to their mass (the bodies' total mass
     * and the free particles' over the sum of the two): at equipartition with zero total
     * momentum that is the share of the kinetic energy each loses, so each part's temperature
     * is then the bath's. Rotations lose none (a body's rotation is about its own centre).
     */
    double getTranslationalDegreesOfFreedom() const;
    int getRotationalDegreesOfFreedom(int bodyDegreesOfFreedom) const;
    double getFreeDegreesOfFreedom() const;
#ifndef SWIG
    /** Each body's shape (general, linear, a point) at these positions. */
    std::vector<RigidBodyMath::Shape> classifyShapes(const std::vector<OpenMM::Vec3>& positions) const;
    /** The bodies' degrees of freedom for these shapes: 6 each, 5 if linear, 3 if a point. */
    static int getBodyDegreesOfFreedom(const std::vector<RigidBodyMath::Shape>& shapes);
#endif
    /**
     * A hash of the partition of particles into bodies, the same whatever order the bodies
     * or their members were listed in: checkpoints carry it so that one written with other
     * bodies is refused.
     */
    uint64_t getSignature() const { return signature; }
    /** Particle masses, indexed by particle. */
    const std::vector<double>& getMasses() const { return masses; }

private:
    // The constructor's steps, in order.
    /** Read the particle masses, refusing a negative or non-finite one. */
    void readMasses(const OpenMM::System& system);
    /** The default bodies: each molecule's massive, non-virtual particles. */
    std::vector<std::vector<int> > massiveMembersOf(const OpenMM::System& system,
                                                    const std::vector<std::vector<int> >& molecules) const;
    /** Check the explicit bodies against the System: indices in range, no virtual site or massless member, no overlap. */
    void checkExplicitBodies(const OpenMM::System& system, const std::vector<std::vector<int> >& explicitBodies) const;
    /**
     * Make the candidates of 2+ particles the bodies and every other massive particle free;
     * return, for each body, its index among the candidates (for messages).
     */
    std::vector<int> assignBodies(const OpenMM::System& system, const std::vector<std::vector<int> >& candidates);
    /** Sort the System's constraints (massless, inside a body, between free particles); refuse one leaving a body. */
    void classifyConstraints(const OpenMM::System& system, const std::vector<int>& definitionIndex);
    static bool findCMMotionRemover(const OpenMM::System& system);
    /** With a Monte Carlo barostat (it scales molecules apart), refuse a body spanning two molecules. */
    void checkBarostatKeepsBodiesWhole(const OpenMM::System& system, const std::vector<std::vector<int> >& molecules,
                                       const std::vector<int>& definitionIndex) const;
    /** The value of getSignature(), from the bodies. */
    uint64_t partitionSignature() const;
    bool isMassive(const OpenMM::System& system, int particle) const;
    /** The part of a CMMotionRemover's 3 degrees of freedom taken from the free particles: their share of the mass. */
    double removedFromFree() const;
    std::vector<std::vector<int> > bodies;
    std::vector<int> bodyOfParticle;
    std::vector<int> freeParticles;
    std::vector<int> freeConstraints;
    std::vector<double> masses;
    std::vector<double> bodyMass;
    int ignoredConstraints = 0;
    int masslessConstraints = 0;
    bool hasCMMotionRemover = false;
    uint64_t signature = 0;
};

} // namespace MRattlePlugin

#endif
