"""Ready-made test systems for rigid-body dynamics.

Every builder returns a :class:`Model`, a named tuple ``(topology, system, positions,
velocities)`` that plugs straight into OpenMM::

    model = mrattle.models.benzeneCluster(temperature=300*kelvin)
    simulation = Simulation(model.topology, model.system, mrattle.MRattleIntegrator(2*femtoseconds))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocities(model.velocities)

``velocities`` is None where the builder does not choose them (use
``context.setVelocitiesToTemperature``, which M-RATTLE makes exact for rigid bodies).

Benzene is OPLS-AA-like: 12 sites, C-C 0.1397 nm, C-H 0.1084 nm, masses 12.011/1.008,
C sigma 0.355 nm, epsilon 0.29288 kJ/mol, charge -0.115 e; H sigma 0.242 nm, epsilon
0.12552 kJ/mol, charge +0.115 e; geometric combination rules. Because OpenMM's
NonbondedForce combines sigma arithmetically, Coulomb is in a NonbondedForce and
Lennard-Jones in a CustomNonbondedForce with per-particle a = 2 sqrt(epsilon) sigma^6 and
b = 2 sqrt(epsilon) sigma^3, so that a1 a2/r^12 - b1 b2/r^6 is exactly the geometric-rule
LJ. The molecules also carry OPLS-AA-like bonds, angles, ring torsions and 1-4 pairs
(scaled by 0.5): the model is a valid flexible benzene, and with M-RATTLE every one of
those terms is internal to a rigid body and can be dropped with
:func:`mrattle.removeIntraBodyInteractions`.

Water is rigid 3-site TIP3P (O-H 0.09572 nm, H-O-H 104.52 degrees), held rigid by three
constraints per molecule, so OpenMM's own integrators (SETTLE) run the same System.
"""
import collections
import math
import os

import numpy as np
import openmm
from openmm import app, unit

Model = collections.namedtuple('Model', ['topology', 'system', 'positions', 'velocities'])

# Benzene (nm, daltons, e, kJ/mol).
BENZENE_CC = 0.1397
BENZENE_CH = 0.1084
CARBON_MASS = 12.011
HYDROGEN_MASS = 1.008
CARBON_LJ = (0.355, 0.29288)
HYDROGEN_LJ = (0.242, 0.12552)
CARBON_CHARGE = -0.115
HYDROGEN_CHARGE = 0.115
BENZENE_MOLAR_MASS = 6*(CARBON_MASS + HYDROGEN_MASS)
# OPLS-AA bonded parameters for aromatic CA/HA (kJ/mol/nm^2, kJ/mol/rad^2, kJ/mol).
CC_BOND_K = 392459.2
CH_BOND_K = 307105.6
CCC_ANGLE_K = 527.184
CCH_ANGLE_K = 292.88
RING_TORSION_V2 = 30.334
ONE_FOUR_SCALE = 0.5
# Periodic models switch Lennard-Jones off over the last SWITCH_WIDTH nm before the cutoff.
SWITCH_WIDTH = 0.1

# TIP3P water.
WATER_OH = 0.09572
WATER_HOH = 104.52*math.pi/180
OXYGEN_MASS = 15.999
WATER_HYDROGEN_MASS = 1.008
OXYGEN_CHARGE = -0.834
OXYGEN_LJ = (0.315061, 0.636386)


def benzeneSites():
    """The 12 sites of benzene about its centre, in nm (C1..C6 then H1..H6, in the xy plane)."""
    sites = []
    for radius in (BENZENE_CC, BENZENE_CC + BENZENE_CH):
        for k in range(6):
            angle = k*math.pi/3
            sites.append((radius*math.cos(angle), radius*math.sin(angle), 0.0))
    return np.array(sites)


def waterSites():
    """The 3 sites of water (O, H1, H2) about its centre of mass, in nm."""
    half = WATER_HOH/2
    sites = np.array([[0.0, 0.0, 0.0],
                      [WATER_OH*math.sin(half), WATER_OH*math.cos(half), 0.0],
                      [-WATER_OH*math.sin(half), WATER_OH*math.cos(half), 0.0]])
    masses = np.array([OXYGEN_MASS, WATER_HYDROGEN_MASS, WATER_HYDROGEN_MASS])
    return sites - masses.dot(sites)/masses.sum()


def benzene():
    """One isolated rigid benzene in vacuum (no cutoff), at the origin, in the xy plane."""
    return _benzeneModel(benzeneSites()[np.newaxis], box=None, cutoff=None)


def benzeneCluster(temperature=300*unit.kelvin, spacing=0.65*unit.nanometers, seed=1):
    """27 benzene molecules in vacuum on a 3x3x3 lattice with random orientations.

    The velocities are rigid-body velocities (random centre-of-mass and angular velocities
    drawn from the Maxwell-Boltzmann distribution), with zero total momentum and zero total
    angular momentum, scaled so the kinetic temperature with 6 degrees of freedom per
    molecule (what MRattleIntegrator.getNumDegreesOfFreedom() reports) is exactly
    ``temperature``.

    Parameters
    ----------
    temperature : Quantity or float (kelvin)
    spacing : Quantity or float (nm)
        the lattice spacing of the molecular centres
    seed : int
        random seed for orientations and velocities
    """
    temperature = _inUnit(temperature, unit.kelvin)
    spacing = _inUnit(spacing, unit.nanometers)
    if not temperature >= 0:
        raise ValueError('benzeneCluster: the temperature must be >= 0 K, got %g' % temperature)
    if not spacing > 0:
        raise ValueError('benzeneCluster: the spacing must be > 0 nm, got %g' % spacing)
    random = np.random.default_rng(seed)
    centres = np.array([(i, j, k) for i in range(3) for j in range(3) for k in range(3)], float)*spacing
    centres -= centres.mean(axis=0)
    coordinates = _placeRigidMolecules(benzeneSites(), centres, random, box=None)
    model = _benzeneModel(coordinates, box=None, cutoff=None)
    masses = _benzeneMasses()
    velocities = _rigidVelocities(coordinates, masses, temperature, random)
    return model._replace(velocities=velocities*unit.nanometers/unit.picoseconds)


def benzeneLiquid(numMolecules=64, density=0.8765*unit.grams/unit.milliliters, cutoff=0.9*unit.nanometers,
                  seed=1):
    """A periodic box of liquid benzene with PME electrostatics and cut-off LJ with long-range correction.

    Molecules start on a cubic lattice (the box holds the next cube number of sites, the
    first ``numMolecules`` are filled) with orientations chosen to avoid overlaps; the
    start is still far from equilibrium (it heats up at first): equilibrate before
    measuring anything.

    Parameters
    ----------
    numMolecules : int
    density : Quantity or float (g/mL)
    cutoff : Quantity or float (nm)
        the direct-space cutoff; must be at most half the box edge
    seed : int
    """
    if numMolecules < 1:
        raise ValueError('benzeneLiquid: numMolecules must be at least 1, got %d' % numMolecules)
    density = _inUnit(density, unit.grams/unit.milliliters)
    cutoff = _inUnit(cutoff, unit.nanometers)
    volume = numMolecules*BENZENE_MOLAR_MASS/unit.AVOGADRO_CONSTANT_NA.value_in_unit(unit.mole**-1)/density*1e21
    edge = volume**(1/3)
    if 2*cutoff > edge:
        raise ValueError('benzeneLiquid: the cutoff %g nm exceeds half the box edge (%g nm); use more molecules '
                         'or a shorter cutoff' % (cutoff, edge/2))
    random = np.random.default_rng(seed)
    centres = _latticeCentres(numMolecules, edge)
    coordinates = _placeRigidMolecules(benzeneSites(), centres, random, box=edge)
    return _benzeneModel(coordinates, box=edge, cutoff=cutoff)


def waterBox(numMolecules=216, cutoff=0.9*unit.nanometers, density=0.997*unit.grams/unit.milliliters, seed=1,
             nonbondedMethod=app.PME):
    """A periodic box of rigid TIP3P water (three constraints per molecule) with PME.

    Parameters
    ----------
    numMolecules : int
    cutoff : Quantity or float (nm)
        the direct-space cutoff; must be at most half the box edge
    density : Quantity or float (g/mL)
    seed : int
    nonbondedMethod : openmm.app.PME, app.CutoffPeriodic or app.Ewald
    """
    if numMolecules < 1:
        raise ValueError('waterBox: numMolecules must be at least 1, got %d' % numMolecules)
    cutoff = _inUnit(cutoff, unit.nanometers)
    density = _inUnit(density, unit.grams/unit.milliliters)
    molarMass = OXYGEN_MASS + 2*WATER_HYDROGEN_MASS
    volume = numMolecules*molarMass/unit.AVOGADRO_CONSTANT_NA.value_in_unit(unit.mole**-1)/density*1e21
    edge = volume**(1/3)
    if 2*cutoff > edge:
        raise ValueError('waterBox: the cutoff %g nm exceeds half the box edge (%g nm); use more molecules '
                         'or a shorter cutoff' % (cutoff, edge/2))
    methods = {app.PME: openmm.NonbondedForce.PME, app.Ewald: openmm.NonbondedForce.Ewald,
               app.CutoffPeriodic: openmm.NonbondedForce.CutoffPeriodic}
    if nonbondedMethod not in methods:
        raise ValueError('waterBox: nonbondedMethod must be app.PME, app.Ewald or app.CutoffPeriodic')
    random = np.random.default_rng(seed)
    coordinates = _placeRigidMolecules(waterSites(), _latticeCentres(numMolecules, edge), random, box=edge)

    topology = app.Topology()
    chain = topology.addChain()
    system = openmm.System()
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(methods[nonbondedMethod])
    nonbonded.setCutoffDistance(cutoff)
    nonbonded.setUseSwitchingFunction(True)  # smooth LJ at the cutoff, for energy conservation
    nonbonded.setSwitchingDistance(cutoff - SWITCH_WIDTH)
    system.addForce(nonbonded)
    hydrogenLJ = (1.0, 0.0)
    for molecule in range(numMolecules):
        residue = topology.addResidue('HOH', chain)
        oxygen = topology.addAtom('O', app.element.oxygen, residue)
        hydrogens = [topology.addAtom(name, app.element.hydrogen, residue) for name in ('H1', 'H2')]
        for hydrogen in hydrogens:
            topology.addBond(oxygen, hydrogen)
        first = system.getNumParticles()
        for mass, charge, (sigma, epsilon) in ((OXYGEN_MASS, OXYGEN_CHARGE, OXYGEN_LJ),
                                               (WATER_HYDROGEN_MASS, -OXYGEN_CHARGE/2, hydrogenLJ),
                                               (WATER_HYDROGEN_MASS, -OXYGEN_CHARGE/2, hydrogenLJ)):
            system.addParticle(mass)
            nonbonded.addParticle(charge, sigma, epsilon)
        hh = 2*WATER_OH*math.sin(WATER_HOH/2)
        for i, j, distance in ((0, 1, WATER_OH), (0, 2, WATER_OH), (1, 2, hh)):
            system.addConstraint(first + i, first + j, distance)
            nonbonded.addException(first + i, first + j, 0.0, 1.0, 0.0)
    _setBox(topology, system, edge)
    positions = unit.Quantity([openmm.Vec3(*x) for x in coordinates.reshape(-1, 3)], unit.nanometers)
    return Model(topology, system, positions, None)


def swm4ndpWater(numMolecules=None, boxSize=None, cutoff=0.8*unit.nanometers):
    """Polarizable SWM4-NDP water (OpenMM's swm4ndp.xml: O, H1, H2, an M virtual site and a
    Drude particle on O, added by Modeller.addExtraParticles; rigid water constraints), whose
    bodies are rigidBodies(model.topology, model.system) (O, H1, H2; the Drude particles free).

    Either numMolecules (default 8) waters taken from OpenMM's tip3p.pdb, in vacuum without
    cutoff: a small test system for the Drude integrators; or, with boxSize (a length), a cubic
    box of that edge filled by Modeller.addSolvent, with PME at cutoff: a liquid.
    """
    forcefield = app.ForceField('swm4ndp.xml')
    if boxSize is not None:
        if numMolecules is not None:
            raise ValueError('swm4ndpWater: give numMolecules or boxSize, not both')
        edge = _inUnit(boxSize, unit.nanometers)
        modeller = app.Modeller(app.Topology(), [])
        modeller.addSolvent(app.ForceField('amber14/tip3p.xml'), boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
        modeller.addExtraParticles(forcefield)
        system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=cutoff,
                                         rigidWater=True)
        return Model(modeller.topology, system, modeller.positions, None)
    numMolecules = 8 if numMolecules is None else numMolecules
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
    waters = list(pdb.topology.residues())
    if not 1 <= numMolecules <= len(waters):
        raise ValueError('swm4ndpWater: numMolecules must be 1 to %d (tip3p.pdb\'s waters), got %d'
                         % (len(waters), numMolecules))
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.delete(waters[numMolecules:])
    modeller.addExtraParticles(forcefield)
    modeller.topology.setPeriodicBoxVectors(None)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.NoCutoff)
    return Model(modeller.topology, system, modeller.positions, None)


# ---- Internals ---------------------------------------------------------------------------------

def _inUnit(value, targetUnit):
    return value.value_in_unit(targetUnit) if unit.is_quantity(value) else float(value)


def _benzeneMasses():
    return np.array([CARBON_MASS]*6 + [HYDROGEN_MASS]*6)


def _benzeneModel(coordinates, box, cutoff):
    """Topology and System for benzene molecules at coordinates (molecules x 12 x 3, nm)."""
    numMolecules = len(coordinates)
    topology = app.Topology()
    chain = topology.addChain()
    system = openmm.System()
    bonds = openmm.HarmonicBondForce()
    angles = openmm.HarmonicAngleForce()
    torsions = openmm.PeriodicTorsionForce()
    coulomb = openmm.NonbondedForce()
    lennardJones = openmm.CustomNonbondedForce('(a1*a2*s - b1*b2)*s; s = 1/r^6')
    lennardJones.addPerParticleParameter('a')
    lennardJones.addPerParticleParameter('b')
    if box is None:
        coulomb.setNonbondedMethod(openmm.NonbondedForce.NoCutoff)
        lennardJones.setNonbondedMethod(openmm.CustomNonbondedForce.NoCutoff)
    else:
        coulomb.setNonbondedMethod(openmm.NonbondedForce.PME)
        coulomb.setCutoffDistance(cutoff)
        lennardJones.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffPeriodic)
        lennardJones.setCutoffDistance(cutoff)
        lennardJones.setUseLongRangeCorrection(True)
        # Switch LJ off smoothly over the last 0.1 nm: a hard cutoff makes the energy jump
        # whenever a pair crosses it, which shows as a drift in NVE (+300 kJ/mol/ns for 64
        # molecules, whatever the step size).
        lennardJones.setUseSwitchingFunction(True)
        lennardJones.setSwitchingDistance(cutoff - SWITCH_WIDTH)
    for force in (bonds, angles, torsions, coulomb, lennardJones):
        system.addForce(force)
    lennardJones.setName('LennardJones')

    # Ring topology: carbon k bonds to carbons k+-1 and to hydrogen k (index 6+k).
    ringBonds = [(k, (k + 1) % 6) for k in range(6)]
    chBonds = [(k, 6 + k) for k in range(6)]
    neighbours = {atom: set() for atom in range(12)}
    for i, j in ringBonds + chBonds:
        neighbours[i].add(j)
        neighbours[j].add(i)
    pairs14 = set()
    for i, j in ringBonds:
        for a in neighbours[i] - {j}:
            for d in neighbours[j] - {i}:
                pairs14.add((min(a, d), max(a, d)))
    pairs12 = {(min(i, j), max(i, j)) for i, j in ringBonds + chBonds}
    pairs13 = {(min(a, c), max(a, c)) for b in range(12) for a in neighbours[b] for c in neighbours[b] if a < c}
    pairs14 -= pairs12 | pairs13

    siteNames = ['C%d' % (k + 1) for k in range(6)] + ['H%d' % (k + 1) for k in range(6)]
    siteParameters = [(CARBON_MASS, CARBON_CHARGE, CARBON_LJ)]*6 + [(HYDROGEN_MASS, HYDROGEN_CHARGE, HYDROGEN_LJ)]*6
    for molecule in range(numMolecules):
        residue = topology.addResidue('BNZ', chain)
        atoms = [topology.addAtom(name, app.element.carbon if name[0] == 'C' else app.element.hydrogen, residue)
                 for name in siteNames]
        first = system.getNumParticles()
        for mass, charge, (sigma, epsilon) in siteParameters:
            system.addParticle(mass)
            coulomb.addParticle(charge, 1.0, 0.0)
            lennardJones.addParticle([2*math.sqrt(epsilon)*sigma**6, 2*math.sqrt(epsilon)*sigma**3])
        for i, j in ringBonds + chBonds:
            topology.addBond(atoms[i], atoms[j])
            length, k = (BENZENE_CC, CC_BOND_K) if j < 6 else (BENZENE_CH, CH_BOND_K)
            bonds.addBond(first + i, first + j, length, k)
        for b in range(6):
            for a in neighbours[b]:
                for c in neighbours[b]:
                    if a < c:
                        k = CCC_ANGLE_K if c < 6 else CCH_ANGLE_K
                        angles.addAngle(first + a, first + b, first + c, 2*math.pi/3, k)
        for i, j in ringBonds:
            for a in neighbours[i] - {j}:
                for d in neighbours[j] - {i}:
                    torsions.addTorsion(first + a, first + i, first + j, first + d, 2, math.pi, RING_TORSION_V2/2)
        for i, j in sorted(pairs12 | pairs13):
            coulomb.addException(first + i, first + j, 0.0, 1.0, 0.0)
            lennardJones.addExclusion(first + i, first + j)
        for i, j in sorted(pairs14):
            (qi, (si, ei)), (qj, (sj, ej)) = [siteParameters[n][1:] for n in (i, j)]
            coulomb.addException(first + i, first + j, ONE_FOUR_SCALE*qi*qj, math.sqrt(si*sj),
                                 ONE_FOUR_SCALE*math.sqrt(ei*ej))
            lennardJones.addExclusion(first + i, first + j)
    if box is not None:
        _setBox(topology, system, box)
    positions = unit.Quantity([openmm.Vec3(*x) for x in np.asarray(coordinates).reshape(-1, 3)], unit.nanometers)
    return Model(topology, system, positions, None)


def _setBox(topology, system, edge):
    vectors = [openmm.Vec3(edge, 0, 0), openmm.Vec3(0, edge, 0), openmm.Vec3(0, 0, edge)]
    system.setDefaultPeriodicBoxVectors(*vectors)
    topology.setPeriodicBoxVectors(vectors*unit.nanometers)


def _latticeCentres(numMolecules, edge):
    """The first numMolecules sites of the smallest cubic lattice with enough sites in a box of this edge."""
    perSide = int(math.ceil(numMolecules**(1/3) - 1e-9))
    spacing = edge/perSide
    sites = [((i + 0.5)*spacing, (j + 0.5)*spacing, (k + 0.5)*spacing)
             for i in range(perSide) for j in range(perSide) for k in range(perSide)]
    return np.array(sites[:numMolecules])


def _randomRotation(random):
    """A rotation matrix uniformly distributed over SO(3) (from a random unit quaternion)."""
    w, x, y, z = (lambda q: q/np.linalg.norm(q))(random.normal(size=4))
    return np.array([[1 - 2*(y*y + z*z), 2*(x*y - z*w), 2*(x*z + y*w)],
                     [2*(x*y + z*w), 1 - 2*(x*x + z*z), 2*(y*z - x*w)],
                     [2*(x*z - y*w), 2*(y*z + x*w), 1 - 2*(x*x + y*y)]])


def _placeRigidMolecules(sites, centres, random, box, attempts=60, sweeps=4):
    """Copies of a molecule at the given centres with orientations that avoid overlaps.

    Each molecule starts at a random orientation; then, sweep after sweep, each one takes
    whichever of its current and several new random orientations overlaps its neighbours
    least, scored by a soft repulsion sum((0.25 nm/r)^12) over atoms closer than 0.35 nm.
    """
    count = len(centres)
    molecules = np.array([centre + sites.dot(_randomRotation(random).T) for centre in centres])
    reach = 2*np.linalg.norm(sites, axis=1).max() + 0.35
    for sweep in range(sweeps):
        for k in range(count):
            offsets = centres - centres[k]
            if box is not None:
                offsets -= box*np.round(offsets/box)
            neighbours = np.where((np.linalg.norm(offsets, axis=1) < reach) & (np.arange(count) != k))[0]
            if len(neighbours) == 0:
                continue
            candidates = np.array([molecules[k]] + [centres[k] + sites.dot(_randomRotation(random).T)
                                                    for attempt in range(attempts)])
            molecules[k] = candidates[_overlapScores(candidates, molecules[neighbours].reshape(-1, 3), box).argmin()]
    return molecules


def _overlapScores(candidates, others, box):
    """Soft repulsion of each candidate placement (candidates x sites x 3) with the other atoms."""
    delta = candidates[:, :, np.newaxis, :] - others[np.newaxis, np.newaxis, :, :]
    if box is not None:
        delta -= box*np.round(delta/box)
    squared = (delta**2).sum(axis=3)
    repulsion = np.where(squared < 0.35**2, (0.25**2/np.maximum(squared, 1e-6))**6, 0.0)
    return repulsion.sum(axis=(1, 2))


def _rigidVelocities(coordinates, masses, temperature, random):
    """Maxwell-Boltzmann rigid-body velocities of molecules (molecules x sites x 3), with zero
    total linear and angular momentum, at exactly temperature with 6 DOF per molecule."""
    kT = (unit.MOLAR_GAS_CONSTANT_R*temperature*unit.kelvin).value_in_unit(unit.kilojoules_per_mole)
    totalMass = masses.sum()
    velocities = np.zeros_like(coordinates)
    for molecule, x in enumerate(coordinates):
        centre = masses.dot(x)/totalMass
        arms = x - centre
        inertia = np.einsum('i,ij,ik->jk', masses, arms, arms)
        inertia = np.trace(inertia)*np.eye(3) - inertia
        # Angular velocity with covariance kT I^-1: a Gaussian angular momentum with covariance kT I.
        eigenvalues, axes = np.linalg.eigh(inertia)
        momentum = axes.dot(random.normal(size=3)*np.sqrt(kT*eigenvalues))
        omega = np.linalg.solve(inertia, momentum)
        velocities[molecule] = random.normal(size=3)*math.sqrt(kT/totalMass) + np.cross(omega, arms)
    # Remove the whole cluster's linear and angular momentum: subtracting a rigid motion of
    # the whole keeps every molecule's velocity rigid.
    allMasses = np.tile(masses, len(coordinates))
    x = coordinates.reshape(-1, 3)
    v = velocities.reshape(-1, 3)
    centre = allMasses.dot(x)/allMasses.sum()
    v -= allMasses.dot(v)/allMasses.sum()
    arms = x - centre
    angularMomentum = np.einsum('i,ij->j', allMasses, np.cross(arms, v))
    inertia = np.einsum('i,ij,ik->jk', allMasses, arms, arms)
    inertia = np.trace(inertia)*np.eye(3) - inertia
    v -= np.cross(np.linalg.solve(inertia, angularMomentum), arms)
    kinetic = 0.5*allMasses.dot((v**2).sum(axis=1))
    dof = 6*len(coordinates)
    v *= math.sqrt(0.5*dof*kT/kinetic) if kinetic > 0 else 0.0
    return [openmm.Vec3(*row) for row in v]
