"""The M-RATTLE integrators on each device platform (OpenCL, CUDA) from Python: app.Simulation
with reporters, in each precision. Skipped where no device platform has the plugin's kernels
(pocl gives an OpenCL platform on a CPU)."""
import io
import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from mrattle.reporters import DRUDE_INTEGRATORS, HEAT_BATH_INTEGRATORS
from conftest import meanAndError

# The thermostats constructed as (temperature, collisionFrequency, stepSize): the Drude ones
# (OpenMM's Drude integrators' constructors) have tests of their own.
HEAT_BATH_INTEGRATORS = [cls for cls in HEAT_BATH_INTEGRATORS if cls not in DRUDE_INTEGRATORS]

@pytest.mark.parametrize('precision', ['single', 'mixed', 'double'])
def test_simulation_runs_on_the_device(devicePlatform, precision):
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, devicePlatform, {'Precision': precision})
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    log = io.StringIO()
    simulation.reporters.append(mrattle.StateDataReporter(log, 10, step=True, temperature=True))
    start = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    simulation.step(50)
    assert simulation.context.getPlatform().getName() == devicePlatform.getName()
    assert integrator.getNumDegreesOfFreedom() == 64*6
    positions = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    assert np.abs(positions - start).max() > 1e-3
    # Rigid: each water's O-H and H-H distances as they were set (to the precision's round-off).
    tolerance = {'single': 1e-5, 'mixed': 1e-6, 'double': 1e-10}[precision]
    for body in integrator.getBodiesInEffect():
        for i in range(3):
            for j in range(i + 1, 3):
                d0 = np.linalg.norm(start[body[i]] - start[body[j]])
                d1 = np.linalg.norm(positions[body[i]] - positions[body[j]])
                assert abs(d1 - d0) < tolerance
    temperatures = [float(line.split(',')[1]) for line in log.getvalue().splitlines()[1:]]
    assert len(temperatures) == 5 and all(100 < t < 600 for t in temperatures)


def test_splitting_integrator_is_refused_on_the_device_with_its_platforms(devicePlatform):
    model = mrattle.models.benzene()
    with pytest.raises(openmm.OpenMMException, match='Reference and CPU platforms only'):
        openmm.Context(model.system, mrattle.RigidSplittingIntegrator(0.002), devicePlatform)


DATA = os.path.join(os.path.dirname(app.__file__), 'data')

#: OpenMM's own inputs: (PDB file, force field files, what is rigid, which integrator).
REAL_INPUTS = [
    ('tip3p.pdb', ['amber14/tip3p.xml'], 'MRattle'),
    ('tip4pew.pdb', ['amber14/tip4pew.xml'], 'MRattleLangevin'),
    ('test.pdb', ['amber14-all.xml', 'amber14/tip3p.xml'], 'MRattle'),  # rigid waters, flexible villin
]


def makeIntegrator(kind, stepSize):
    if kind == 'MRattle':
        return mrattle.MRattleIntegrator(stepSize)
    integrator = mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, stepSize)
    integrator.setRandomNumberSeed(7)
    return integrator


@pytest.mark.parametrize('precision', ['single', 'mixed', 'double'])
@pytest.mark.parametrize('pdbName,forceFields,kind', REAL_INPUTS, ids=[entry[0] for entry in REAL_INPUTS])
def test_real_inputs_in_every_precision(devicePlatform, precision, pdbName, forceFields, kind):
    """Setting a PDB file's positions corrects each water onto its geometry once, never
    re-entering itself (it recursed until the stack overflowed in single and mixed
    precision), and positions read back and set again are left bit for bit."""
    pdb = app.PDBFile(os.path.join(DATA, pdbName))
    modeller = app.Modeller(pdb.topology, pdb.positions)
    forcefield = app.ForceField(*forceFields)
    if pdbName == 'tip4pew.pdb':
        modeller.addExtraParticles(forcefield)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                     constraints=app.HBonds, rigidWater=True)
    integrator = makeIntegrator(kind, 2*unit.femtoseconds)
    waters = [[atom.index for atom in residue.atoms() if atom.element is not None]
              for residue in modeller.topology.residues() if residue.name == 'HOH']
    if pdbName == 'test.pdb':
        for water in waters:  # the protein stays flexible, its bonds to hydrogen constrained
            integrator.addRigidBody(water)
    context = openmm.Context(system, integrator, devicePlatform, {'Precision': precision})
    context.setPositions(modeller.positions)
    stored = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    context.setPositions(stored)
    again = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    assert np.array_equal(stored, again), 'a second setPositions moved atoms by %g nm' % np.abs(again - stored).max()
    # The waters have their force field's geometry (to the precision's storage).
    # (PDB files' waters are off by ~1e-3 nm; single and mixed storage round a 3 nm box's to ~2e-6 nm.)
    tolerance = {'single': 1e-5, 'mixed': 1e-5, 'double': 1e-9}[precision]
    oh = system.getConstraintParameters(0)[2] if pdbName != 'test.pdb' else None
    for water in waters[:50]:
        d = [np.linalg.norm(again[water[0]] - again[water[k]]) for k in (1, 2)]
        assert abs(d[0] - d[1]) < tolerance
        if oh is not None:
            assert abs(d[0] - oh.value_in_unit(unit.nanometers)) < tolerance
    # OpenMM's most ordinary start: constraints applied after the positions (in single precision
    # their round-off changes the waters' shapes), then a step.
    context.applyConstraints(1e-6)
    context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    integrator.step(5)
    state = context.getState(getPositions=True, getEnergy=True)
    assert state.getStepCount() == 5
    assert np.isfinite(state.getPotentialEnergy().value_in_unit(unit.kilojoules_per_mole))


def totalEnergies(context, integrator, samples, every):
    energies = []
    for _ in range(samples):
        integrator.step(every)
        state = context.getState(getEnergy=True)
        energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoules_per_mole))
    return np.array(energies)


def test_nve_energy_has_no_jumps_past_reorderings(devicePlatform):
    """OpenMM reorders atoms about every 250 steps of a periodic system: the next step must
    kick with the forces of the atoms' new order (it used those of the old one, and the
    energy jumped by tens of kJ/mol at each reordering). Judged against OpenMM's own
    VerletIntegrator with SETTLE on the same box, platform and precision, with energies read
    every 50 steps only (an energy read recomputes the forces and hid the fault)."""
    model = mrattle.models.waterBox(numMolecules=216, cutoff=0.9*unit.nanometers)
    jumps = {}
    for name, integrator in [('M-RATTLE', mrattle.MRattleIntegrator(1*unit.femtoseconds)),
                             ('Verlet+SETTLE', openmm.VerletIntegrator(1*unit.femtoseconds))]:
        context = openmm.Context(model.system, integrator, devicePlatform, {'Precision': 'mixed'})
        context.setPositions(model.positions)
        context.setVelocitiesToTemperature(300*unit.kelvin, 1)
        integrator.step(50)
        energies = totalEnergies(context, integrator, 22, 50)  # 1100 steps: four reorderings
        jumps[name] = np.abs(np.diff(energies)).max()
    assert jumps['M-RATTLE'] < 3*jumps['Verlet+SETTLE'] + 1.0, jumps


def test_langevin_temperature_past_reorderings(devicePlatform):
    """The bath's temperature, within its error bar, over runs with reorderings every 250
    steps (the stale forces after each one heated a 300 K water box to 349 +- 3 K).
    OpenMM's equilibrated tip3p.pdb box at 1/ps; each of three seeds gives the mean
    rigid-body kinetic temperature of 1.5 ps; the error bar is the standard error of those
    three means (block errors within one run were seen to underestimate it: seeds 5 and 11
    gave 301.7 and 294.6 K with block errors of 1.6 and 0.9 K), judged with Student's t for
    2 degrees of freedom at 99.5% (9.92)."""
    pdb = app.PDBFile(os.path.join(DATA, 'tip3p.pdb'))
    system = app.ForceField('amber14/tip3p.xml').createSystem(pdb.topology, nonbondedMethod=app.PME,
                                                              nonbondedCutoff=0.9*unit.nanometers, rigidWater=True)
    means = []
    for seed in (11, 12, 13):
        integrator = mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtoseconds)
        integrator.setRandomNumberSeed(seed)
        context = openmm.Context(system, integrator, devicePlatform, {'Precision': 'mixed'})
        context.setPositions(pdb.positions)
        context.setVelocitiesToTemperature(300*unit.kelvin, seed)
        integrator.step(250)
        temperatures = []
        for _ in range(30):  # 750 steps: three reorderings
            integrator.step(25)
            temperatures.append(integrator.computeSystemTemperature().value_in_unit(unit.kelvin))
        means.append(np.mean(temperatures))
    mean, error = meanAndError(means)
    assert abs(mean - 300) < 9.92*error, (means, mean, error)


@pytest.mark.parametrize('precision', ['single', 'mixed'])
@pytest.mark.parametrize('cls', HEAT_BATH_INTEGRATORS, ids=lambda cls: cls.__name__)
def test_thermostats_in_single_and_mixed_precision(devicePlatform, precision, cls):
    """The thermostats' device kernels in the precisions the C++ suite does not run (it runs
    double): a 64-water box started hot cools towards the bath, and the conserved quantity
    (kinetic + potential + heat bath) moves far less than the bath's energy."""
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    integrator = cls(300*unit.kelvin, 20/unit.picosecond, 1*unit.femtoseconds)
    context = openmm.Context(model.system, integrator, devicePlatform, {'Precision': precision})
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(450*unit.kelvin, 2)
    conserved, bath = [], []
    for _ in range(20):
        integrator.step(20)
        state = context.getState(getEnergy=True)
        bath.append(integrator.computeHeatBathEnergy().value_in_unit(unit.kilojoules_per_mole))
        conserved.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoules_per_mole)
                         + bath[-1])
    assert integrator.computeSystemTemperature() < 400*unit.kelvin
    assert bath[-1] > 200  # it took the excess out
    assert np.ptp(conserved) < 0.1 * np.ptp(bath)
