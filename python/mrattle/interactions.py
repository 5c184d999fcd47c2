"""Removal of interactions that cannot affect rigid-body motion."""
import math
import re
import xml.etree.ElementTree as ElementTree

import openmm
from openmm import unit

from .integrators import RigidBodyIntegrator, RigidBodyTopology

# Bonded forces whose terms are dropped when every particle of a term is in one body:
# force type -> (list element, term element). The particles of a term are its attributes
# p1, p2, ... (a1..a4 and b1..b4 for CMAP torsions).
_BONDED_TERMS = {
    'HarmonicBondForce': ('Bonds', 'Bond'),
    'HarmonicAngleForce': ('Angles', 'Angle'),
    'PeriodicTorsionForce': ('Torsions', 'Torsion'),
    'RBTorsionForce': ('Torsions', 'Torsion'),
    'CMAPTorsionForce': ('Torsions', 'Torsion'),
    'CustomBondForce': ('Bonds', 'Bond'),
    'CustomAngleForce': ('Angles', 'Angle'),
    'CustomTorsionForce': ('Torsions', 'Torsion'),
    'CustomCompoundBondForce': ('Bonds', 'Bond'),
}
_PARTICLE_ATTRIBUTE = re.compile(r'^(p|a|b)\d+$')


def _checkFinitePositions(system, positions):
    """The constraints are made at these positions' distances: refuse positions that are not finite numbers."""
    if unit.is_quantity(positions):
        positions = positions.value_in_unit(unit.nanometers)
    if len(positions) != system.getNumParticles():
        raise openmm.OpenMMException('removeIntraBodyInteractions: %d positions for a System of %d particles'
                                     % (len(positions), system.getNumParticles()))
    for i, position in enumerate(positions):
        if unit.is_quantity(position):
            position = position.value_in_unit(unit.nanometers)
        if not all(math.isfinite(float(value)) for value in position):
            raise openmm.OpenMMException('removeIntraBodyInteractions: the position of particle %d is not finite: %s'
                                         % (i, tuple(position)))


def removeIntraBodyInteractions(system, positions, bodies):
    """A copy of a System without the interactions inside rigid bodies.

    Forces between particles of one rigid body have zero net force and zero net torque on
    it, so under a rigid-body integrator they never affect the motion: this removes them
    so they are not computed. The potential energy changes by a constant (the removed
    intra-body energy); the trajectory does not change.

    What is removed, for pairs or terms whose particles all lie in one body:

    - bonded terms of HarmonicBondForce, HarmonicAngleForce, PeriodicTorsionForce,
      RBTorsionForce, CMAPTorsionForce, CustomBondForce, CustomAngleForce,
      CustomTorsionForce and CustomCompoundBondForce (forces left empty are dropped);
    - NonbondedForce pairs: made exceptions with zero charge product and epsilon, which
      OpenMM skips (with Ewald/PME the reciprocal-space part of an excluded pair is still
      subtracted, as for any exclusion);
    - CustomNonbondedForce pairs: made exclusions.

    The bonds removed were what made each molecule one molecule for OpenMM (and so one
    rigid body for an integrator with no addRigidBody() call): to keep that, each body's
    particles are joined by a chain of constraints at their distances in ``positions``,
    unless constraints already join them. Rigid-body integrators ignore constraints inside
    a body, so they cost nothing per step; other tools (minimizer, applyConstraints) see
    the molecules as rigid.

    Other forces (implicit solvent, AMOEBA, CustomCentroidBondForce, ...) are kept as they
    are. A virtual site counts as part of a body when all the particles it is built from are.
    A long-range (dispersion) correction that discounts excluded pairs changes slightly,
    which matters only at constant pressure.

    Parameters
    ----------
    system : openmm.System
        not modified
    positions : list of Vec3 or Quantity
        positions of the rigid geometry (for the constraint lengths)
    bodies : list of lists of int, a RigidBodyIntegrator, or 'molecules'
        the rigid bodies: the integrator that will run the System (its bodies in effect if
        it is bound to a Context, else its declared bodies, else the molecules it will make
        rigid), a list of bodies, or 'molecules' for every molecule of the System with two or
        more massive particles. Required: a default could remove the bonded terms of
        particles that the integrator leaves free. They are resolved by the integrators' own
        rules (the C++ RigidBodyTopology, mrattle.integrators.RigidBodyTopology), so a list is
        refused as a bound integrator would refuse it: an OpenMMException names the particle
        out of range, listed in two bodies, massless or a virtual site, or joined by a
        constraint to a particle outside its body.

    Returns
    -------
    openmm.System
        the new System
    """
    bodyOfParticle = _bodyOfParticle(system, _bodyTopology(system, bodies))
    _checkFinitePositions(system, positions)

    def inOneBody(particles):
        owner = bodyOfParticle[particles[0]]
        return owner >= 0 and all(bodyOfParticle[p] == owner for p in particles)

    # Bonded terms are removed in the System's XML: OpenMM forces cannot delete terms, and
    # the XML keeps every other setting (parameters, groups, names) of every force.
    root = ElementTree.fromstring(openmm.XmlSerializer.serialize(system))
    forces = root.find('Forces')
    for force in list(forces):
        layout = _BONDED_TERMS.get(force.get('type'))
        if layout is None:
            continue
        terms = force.find(layout[0])
        for term in list(terms.findall(layout[1])):
            particles = [int(value) for name, value in term.attrib.items() if _PARTICLE_ATTRIBUTE.match(name)]
            if particles and inOneBody(particles):
                terms.remove(term)
        if len(terms) == 0:
            forces.remove(force)
    newSystem = openmm.XmlSerializer.deserialize(ElementTree.tostring(root, encoding='unicode'))

    bodyMembers = {}
    for particle, body in enumerate(bodyOfParticle):
        if body >= 0 and not system.isVirtualSite(particle):
            bodyMembers.setdefault(body, []).append(particle)
    _joinBodiesByConstraints(newSystem, bodyMembers.values(), positions)
    for particle, body in enumerate(bodyOfParticle):
        if body >= 0 and system.isVirtualSite(particle):
            bodyMembers[body].append(particle)
    intraPairs = [(members[i], members[j]) for members in bodyMembers.values()
                  for i in range(len(members)) for j in range(i + 1, len(members))]
    for force in newSystem.getForces():
        if isinstance(force, openmm.NonbondedForce):
            for p1, p2 in intraPairs:
                force.addException(p1, p2, 0.0, 1.0, 0.0, True)
        elif isinstance(force, openmm.CustomNonbondedForce):
            existing = set()
            for i in range(force.getNumExclusions()):
                p1, p2 = force.getExclusionParticles(i)
                existing.add((min(p1, p2), max(p1, p2)))
            for p1, p2 in intraPairs:
                if (min(p1, p2), max(p1, p2)) not in existing:
                    force.addExclusion(p1, p2)
    return newSystem


def _joinBodiesByConstraints(system, bodies, positions):
    """Add constraints along a chain through each body unless its particles are already
    connected by constraints among themselves."""
    if openmm.unit.is_quantity(positions):
        positions = positions.value_in_unit(openmm.unit.nanometers)
    parent = {}

    def root(p):
        while parent.get(p, p) != p:
            p = parent[p]
        return p

    for i in range(system.getNumConstraints()):
        p1, p2, distance = system.getConstraintParameters(i)
        parent[root(p1)] = root(p2)
    for body in bodies:
        for previous, particle in zip(body, body[1:]):
            if root(previous) != root(particle):
                delta = [a - b for a, b in zip(positions[particle], positions[previous])]
                system.addConstraint(previous, particle, sum(d*d for d in delta)**0.5)
                parent[root(previous)] = root(particle)


def _bodyTopology(system, bodies):
    """The bodies as the integrator resolves them: the C++ RigidBodyTopology that every
    rigid-body integrator builds when it is bound to a Context, made here from the System."""
    if bodies is None:
        raise TypeError("removeIntraBodyInteractions: pass the bodies: the integrator that will run the System, "
                        "a list of bodies, or 'molecules' for every molecule")
    explicit = None
    if isinstance(bodies, RigidBodyIntegrator):
        try:
            explicit = bodies.getBodiesInEffect()
        except openmm.OpenMMException:  # not bound to a Context: what it will use
            explicit = [bodies.getRigidBodyParticles(b) for b in range(bodies.getNumRigidBodies())] or None
    elif isinstance(bodies, str):
        if bodies != 'molecules':
            raise ValueError("removeIntraBodyInteractions: bodies must be a list, an integrator or 'molecules', got %r"
                             % bodies)
    else:
        explicit = [list(body) for body in bodies]
    try:
        if explicit is not None:
            # Explicit bodies need no molecules (only a barostat's check, which the
            # integrator makes when it is bound, reads them).
            return RigidBodyTopology(system, explicit, [])
        return RigidBodyTopology(system, [], _molecules(system))
    except openmm.OpenMMException as error:
        raise openmm.OpenMMException('removeIntraBodyInteractions: %s' % error) from None


def _molecules(system):
    """OpenMM's molecules (particles joined by bonds, constraints and virtual sites), as
    Context.getMolecules() gives them. OpenMM finds them only in a Context: the bonds come
    from each force's ForceImpl (getBondedParticles()), which exists only there; so a
    throwaway Context on the Reference platform."""
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    molecules = [list(molecule) for molecule in context.getMolecules()]
    del context
    return molecules


def _bodyOfParticle(system, topology):
    """particle -> body index (-1: none): the topology's bodies (of 2+ particles), plus the
    virtual sites built only from particles of one body."""
    owner = topology.getBodyOfParticles()
    for particle in range(system.getNumParticles()):
        if system.isVirtualSite(particle):
            site = system.getVirtualSite(particle)
            parents = {owner[site.getParticle(i)] for i in range(site.getNumParticles())}
            if len(parents) == 1 and -1 not in parents:
                owner[particle] = parents.pop()
    return owner
