#!/usr/bin/env python3
"""Liquid polarizable benzene (CHARMM Drude 2019) with rigid molecules: MRattleDrudeLangevinIntegrator.

OpenMM's charmm_polar_2019.xml (residue BENZ) with Drude particles added by
Modeller.addExtraParticles; each molecule's 12 atoms are one rigid body, its Drude particles
and lone pair are free (the lone pair a virtual site). PME, Lennard-Jones switched off at the
cut-off with the long-range correction, bodies at 298 K and Drude particles at 1 K with a hard
wall at 0.02 nm (the CHARMM Drude setting), Monte Carlo barostat at 1 bar (--pressure 0: NVT
at the starting density). --flexible runs the same model flexible with OpenMM's
DrudeLangevinIntegrator (constraints=HBonds); --gas runs one molecule without cut-off, for the
heat of vaporization (<E_gas> - <E_liq>/N + RT). 2 fs steps need --drude-mass 1.6 (at the
force field's 0.4 amu the Drude spring is past velocity Verlet's limit there, rigid or
flexible). Prints OpenMM's progress columns, then the production averages with block standard
errors and, rigid, the largest change of any intramolecular distance. Experiment at 298 K: 0.8765 g/mL, 33.9 kJ/mol.

    python3 examples/polarizable_benzene.py --molecules 216 --step-size 2 --drude-mass 1.6 --production 20
    python3 examples/polarizable_benzene.py --quick
"""
import argparse
import math
import os
from xml.etree import ElementTree

import numpy as np
import openmm
from openmm import app, unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--molecules', type=int, default=216, help='number of molecules (default 216)')
parser.add_argument('--density', type=float, default=0.8765, help='starting density, g/mL (default 0.8765)')
parser.add_argument('--cutoff', type=float, default=1.0, help='nm, at most half the box edge (default 1.0)')
parser.add_argument('--step-size', type=float, default=1.0, help='fs (default 1)')
parser.add_argument('--equilibration', type=float, default=5.0, help='ps (default 5)')
parser.add_argument('--production', type=float, default=20.0, help='ps (default 20)')
parser.add_argument('--report-interval', type=float, default=0.1, help='ps between reports (default 0.1)')
parser.add_argument('--temperature', type=float, default=298.0, help='K (default 298)')
parser.add_argument('--pressure', type=float, default=1.0, help='bar; 0 for constant volume (default 1)')
parser.add_argument('--flexible', action='store_true', help="OpenMM's DrudeLangevinIntegrator, constraints=HBonds")
parser.add_argument('--gas', action='store_true', help='one molecule in vacuum, no cut-off')
parser.add_argument('--quick', action='store_true', help='27 molecules, 0.7 nm cut-off, 40 steps: a smoke test')
parser.add_argument('--drude-mass', type=float, default=None,
                    help="amu, each Drude particle's mass, taken from its core (default the force field's, 0.4)")
parser.add_argument('--seed', type=int, default=1, help='random seed (default 1)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
parser.add_argument('--output', default='output', help='output folder (default ./output)')
arguments = parser.parse_args()
if arguments.quick:
    arguments.molecules, arguments.cutoff = 27, 0.7
    arguments.equilibration, arguments.production, arguments.report_interval = 10e-3, 30e-3, 10e-3
os.makedirs(arguments.output, exist_ok=True)
name = 'polarizable_benzene_%s_%s' % ('flexible' if arguments.flexible else 'rigid', 'gas' if arguments.gas else 'liquid')
random = np.random.default_rng(arguments.seed)
temperature = arguments.temperature*unit.kelvin
stepSize = arguments.step_size*unit.femtoseconds


def benzene():
    """BENZ's 12 atoms (names as in the force field's template) at its equilibrium bond lengths, in nm, centred."""
    ring = ['CG', 'CD1', 'CE1', 'CZ', 'CE2', 'CD2']   # in order around the ring
    names, coordinates = [], []
    for k, carbon in enumerate(ring):
        direction = np.array([math.cos(k*math.pi/3), math.sin(k*math.pi/3), 0.0])
        names += [carbon, 'H' + carbon[1:]]
        coordinates += [0.1375*direction, (0.1375 + 0.108)*direction]   # CD2R6A-CD2R6A, CD2R6A-HDR6A
    return names, np.array(coordinates)


def randomRotation():
    q = random.normal(size=4)
    a, b, c, d = q/np.linalg.norm(q)
    return np.array([[a*a+b*b-c*c-d*d, 2*(b*c-a*d), 2*(b*d+a*c)],
                     [2*(b*c+a*d), a*a-b*b+c*c-d*d, 2*(c*d-a*b)],
                     [2*(b*d-a*c), 2*(c*d+a*b), a*a-b*b-c*c+d*d]])


def benzeneBox(numMolecules, density):
    """Molecules on a cubic lattice, randomly turned, in a cubic box of the given density (g/mL)."""
    names, geometry = benzene()
    molarMass = 6*12.011 + 6*1.008
    edge = (numMolecules*molarMass/(density*6.02214076e23)*1e21)**(1/3)   # nm
    perEdge = math.ceil(numMolecules**(1/3) - 1e-9)
    topology, positions = app.Topology(), []
    chain = topology.addChain()
    for index in range(numMolecules):
        residue = topology.addResidue('BENZ', chain)
        atoms = [topology.addAtom(atom, app.element.carbon if atom[0] == 'C' else app.element.hydrogen, residue)
                 for atom in names]
        for k in range(0, 12, 2):   # C-H and C-C around the ring
            topology.addBond(atoms[k], atoms[k + 1])
            topology.addBond(atoms[k], atoms[(k + 2) % 12])
        site = (np.array(np.unravel_index(index, (perEdge,)*3)) + 0.5)*edge/perEdge
        positions += list(site + geometry @ randomRotation().T)
    if numMolecules > 1:
        topology.setPeriodicBoxVectors(np.eye(3)*edge*unit.nanometers)
    return topology, positions*unit.nanometers


def lennardJonesIntoNonbondedForce(system):
    """Move the force field's Lennard-Jones CustomNonbondedForce (per-type tables acoef, bcoef, built
    for NBFIX) into the NonbondedForce as per-particle sigma and epsilon: the same energy when every
    pair follows CHARMM's combination rule (checked; benzene has no NBFIX), about 7 times faster on CPU."""
    index = [i for i, f in enumerate(system.getForces()) if isinstance(f, openmm.CustomNonbondedForce)]
    nonbonded = [f for f in system.getForces() if isinstance(f, openmm.NonbondedForce)][0]
    assert len(index) == 1
    custom = system.getForce(index[0])
    assert custom.getNumExclusions() == nonbonded.getNumExceptions()
    tables = {function.get('name'): np.array([float(v.get('v')) for v in function.iter('Value')]).reshape(
        int(function.get('xsize')), -1) for function in ElementTree.fromstring(
        openmm.XmlSerializer.serialize(custom)).iter('Function')}
    a, b = tables['acoef'], tables['bcoef']
    diagonal = np.maximum(np.diag(a), 1e-300)
    sigma, epsilon = np.where(np.diag(a) > 0, (diagonal/np.maximum(np.diag(b), 1e-300))**(1/6), 1.0), np.diag(b)**2/(4*diagonal)
    pairSigma, pairEpsilon = (sigma[:, None] + sigma[None])/2, np.sqrt(epsilon[:, None]*epsilon[None])
    if not (np.allclose(4*pairEpsilon*pairSigma**12, a, rtol=1e-6, atol=0) and
            np.allclose(4*pairEpsilon*pairSigma**6, b, rtol=1e-6, atol=0)):
        raise ValueError('the Lennard-Jones tables do not follow the combination rule (NBFIX): keep them')
    for particle in range(system.getNumParticles()):
        charge = nonbonded.getParticleParameters(particle)[0]
        kind = int(custom.getParticleParameters(particle)[0])
        nonbonded.setParticleParameters(particle, charge, sigma[kind], epsilon[kind])
    nonbonded.setUseSwitchingFunction(custom.getUseSwitchingFunction())
    nonbonded.setSwitchingDistance(custom.getSwitchingDistance())
    nonbonded.setUseDispersionCorrection(custom.getUseLongRangeCorrection())
    system.removeForce(index[0])


forcefield = app.ForceField('charmm_polar_2019.xml')
topology, positions = benzeneBox(1 if arguments.gas else arguments.molecules, arguments.density)
modeller = app.Modeller(topology, positions)
modeller.addExtraParticles(forcefield)
numMolecules = modeller.topology.getNumResidues()
if arguments.gas:
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.NoCutoff,
                                     constraints=app.HBonds if arguments.flexible else None)
else:
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=arguments.cutoff*unit.nanometers, switchDistance=
                                     (arguments.cutoff - 0.2)*unit.nanometers, ewaldErrorTolerance=5e-4,
                                     constraints=app.HBonds if arguments.flexible else None)
    lennardJonesIntoNonbondedForce(system)
    if arguments.pressure > 0:
        system.addForce(openmm.MonteCarloBarostat(arguments.pressure*unit.bar, temperature, 25))

if arguments.drude_mass is not None:
    mrattle.setDrudeMass(system, arguments.drude_mass*unit.amu)

# OpenMM's Drude setting: bodies (or atoms) coupled at 5/ps, Drude particles at 1 K and 20/ps, hard wall at 0.02 nm.
drudeSettings = (temperature, 5/unit.picosecond, 1*unit.kelvin, 20/unit.picosecond, stepSize)
if arguments.flexible:
    integrator = openmm.DrudeLangevinIntegrator(*drudeSettings)
else:
    integrator = mrattle.MRattleDrudeLangevinIntegrator(*drudeSettings)
    # Each molecule's atoms are one body; its Drude particles (no element) and lone pair (a virtual site) stay free.
    bodies = mrattle.rigidBodies(modeller.topology, system, 'BENZ', atoms=lambda atom: atom.element is not None)
    for body in bodies:
        integrator.addRigidBody(body)
integrator.setMaxDrudeDistance(0.02*unit.nanometers)
integrator.setRandomNumberSeed(arguments.seed)
simulation = app.Simulation(modeller.topology, system, integrator, openmm.Platform.getPlatformByName(arguments.platform))
simulation.context.setPositions(modeller.positions)
simulation.minimizeEnergy(maxIterations=500)   # rigid for the plugin's integrator (docs/minimization.md)
simulation.context.setVelocitiesToTemperature(temperature, arguments.seed)
# Cold Drude particles to start: each moves with its core.
drudeForce = [f for f in system.getForces() if isinstance(f, openmm.DrudeForce)][0]
velocities = simulation.context.getState(getVelocities=True).getVelocities(asNumpy=True)
for pair in range(drudeForce.getNumParticles()):
    drude, core = drudeForce.getParticleParameters(pair)[:2]
    velocities[drude] = velocities[core]
simulation.context.setVelocities(velocities)
with open(os.path.join(arguments.output, name + '.pdb'), 'w') as pdb:
    app.PDBFile.writeFile(modeller.topology, simulation.context.getState(getPositions=True).getPositions(), pdb)
print('%d BENZ molecules, %d particles, %s, %g fs steps, %s'
      % (numMolecules, system.getNumParticles(), 'flexible (DrudeLangevinIntegrator, HBonds)' if arguments.flexible
         else '%d rigid bodies (MRattleDrudeLangevinIntegrator)' % len(bodies), arguments.step_size,
         'vacuum' if arguments.gas else 'NPT %g bar' % arguments.pressure if arguments.pressure > 0 else 'NVT'))


class RigidityReporter:
    """The largest change of any distance within a body since the first report, in nm."""

    def __init__(self, interval, bodies):
        self.interval, self.bodies, self.reference, self.largest = interval, bodies, None, 0.0

    def describeNextReport(self, simulation):
        return (self.interval - simulation.currentStep % self.interval, True, False, False, False)

    def report(self, simulation, state):
        positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
        distances = [np.linalg.norm(positions[body][:, None] - positions[body][None], axis=2) for body in self.bodies]
        if self.reference is None:
            self.reference = distances
        self.largest = max([self.largest] + [np.abs(d - d0).max() for d, d0 in zip(distances, self.reference)])


def steps(picoseconds):
    return max(1, int(round(picoseconds*1000/arguments.step_size)))


interval = steps(arguments.report_interval)
rigidity = None if arguments.flexible else RigidityReporter(interval, bodies)
if rigidity:
    simulation.reporters.append(rigidity)
    rigidity.report(simulation, simulation.context.getState(getPositions=True))
columns = dict(step=True, time=True, potentialEnergy=True, temperature=True, speed=True,
               density=not arguments.gas, volume=not arguments.gas)
if not arguments.flexible:
    columns.update(bodyTemperature=True, drudeTemperature=True)
totalSteps = steps(arguments.equilibration) + steps(arguments.production)
simulation.reporters.append(mrattle.StateDataReporter(os.sys.stdout, max(1, totalSteps//(20*interval))*interval,
                                                      totalSteps=totalSteps, progress=True, **columns))
print('equilibration, %g ps' % arguments.equilibration)
simulation.step(steps(arguments.equilibration))
log = os.path.join(arguments.output, name + '.csv')
with open(log, 'w') as stream:
    simulation.reporters.append(mrattle.StateDataReporter(stream, interval, **columns))
    print('production, %g ps' % arguments.production)
    simulation.step(steps(arguments.production))

# Production averages, with the standard error of 10 block means (fewer for a short run).
with open(log) as stream:
    header = stream.readline().strip('#\n').replace('"', '').split(',')
data = np.atleast_2d(np.loadtxt(log, delimiter=',', comments='#'))
series = dict(zip(header, data.T))


def average(column, scale=1.0):
    values = series[column]*scale
    blocks = np.array_split(values, min(10, len(values)))
    means = np.array([block.mean() for block in blocks])
    return values.mean(), means.std(ddof=1)/math.sqrt(len(means)) if len(means) > 1 else float('nan')


print('averages over %g ps (%d samples, block standard errors):' % (arguments.production, len(data)))
print('  potential energy per molecule  %.3f +- %.3f kJ/mol' % average('Potential Energy (kJ/mole)', 1/numMolecules))
if not arguments.gas:
    print('  density                        %.4f +- %.4f g/mL' % average('Density (g/mL)'))
if not arguments.flexible:
    print('  body temperature               %.2f +- %.2f K' % average('Body Temperature (K)'))
    print('  Drude temperature              %.3f +- %.3f K' % average('Drude Temperature (K)'))
    print('  largest rigidity error         %.3g nm' % rigidity.largest)
else:
    print('  temperature (Drude included)   %.2f +- %.2f K' % average('Temperature (K)'))
