"""mrattle.minimizeEnergy, openmm.LocalEnergyMinimizer.minimize and app.Simulation.minimizeEnergy
with the plugin's integrators: the energy goes down, bodies keep their shapes, dynamics follow;
reporters are called with OpenMM's arguments and can stop the search; other integrators keep
OpenMM's minimizer; arguments take units and numpy values."""
import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties


def maxShapeChange(a, b, bodies):
    a, b = np.asarray(a), np.asarray(b)
    worst = 0.0
    for body in bodies:
        da = np.linalg.norm(a[body][:, None] - a[body][None], axis=2)
        db = np.linalg.norm(b[body][:, None] - b[body][None], axis=2)
        worst = max(worst, np.abs(da - db).max())
    return worst


def positions(context):
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)


def energy(context):
    return context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoules_per_mole)


def simulationOf(model, integrator, platform):
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    return simulation


def test_simulation_minimizes_rigidly_then_steps(platform):
    model = mrattle.models.benzeneCluster()
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = simulationOf(model, integrator, platform)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy(tolerance=0.5*unit.kilojoules_per_mole/unit.nanometer)
    after = positions(simulation.context)
    bodies = integrator.getBodiesInEffect()
    assert energy(simulation.context) < start - 10
    assert maxShapeChange(before, after, bodies) < 1e-12
    assert np.abs(after - before).max() > 1e-3
    simulation.step(10)
    assert maxShapeChange(before, positions(simulation.context), bodies) < 1e-9


def test_other_integrators_keep_openmms_minimizer():
    # OpenMM's minimizer deforms the benzenes of this flexible System; ours never does.
    model = mrattle.models.benzeneCluster()
    reference = openmm.Platform.getPlatformByName('Reference')
    simulation = simulationOf(model, openmm.VerletIntegrator(0.001), reference)
    before = positions(simulation.context)
    simulation.minimizeEnergy(maxIterations=50)
    molecules = [list(range(12*m, 12*m + 12)) for m in range(27)]
    assert maxShapeChange(before, positions(simulation.context), molecules) > 1e-4
    assert not mrattle.RigidBodyMinimizer.appliesTo(simulation.context)


def test_compound_integrator_minimizes_rigidly():
    model = mrattle.models.benzeneCluster()
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(openmm.VerletIntegrator(0.001))
    compound.addIntegrator(mrattle.MRattleIntegrator(0.001))
    simulation = simulationOf(model, compound, openmm.Platform.getPlatformByName('Reference'))
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy(tolerance=1*unit.kilojoules_per_mole/unit.nanometer, maxIterations=np.int64(40))
    molecules = [list(range(12*m, 12*m + 12)) for m in range(27)]
    assert energy(simulation.context) < start
    assert maxShapeChange(before, positions(simulation.context), molecules) < 1e-12


def test_default_tolerance_minimizes_a_loose_start(platform):
    # The 27-benzene cluster from its lattice start: the rms generalized force per degree of
    # freedom is 10.7 kJ/mol/nm there (per particle 4.4, under the default 10, which made the
    # earlier |x|-scaled test return at once). Now the default call goes well down.
    model = mrattle.models.benzeneCluster()
    simulation = simulationOf(model, mrattle.MRattleIntegrator(0.001), platform)
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy()
    assert energy(simulation.context) < start - 300
    assert maxShapeChange(before, positions(simulation.context), BENZENES) < 1e-12
    report = mrattle.minimizeEnergy(simulation.context)
    assert report.iterations == 0 and report.rmsForce <= 10


def test_arguments_take_units_and_numpy_and_bad_ones_are_refused():
    model = mrattle.models.benzeneCluster()
    simulation = simulationOf(model, mrattle.MRattleIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    context = simulation.context
    report = mrattle.minimizeEnergy(context, 0.01*unit.kilocalories_per_mole/unit.angstrom, maxIterations=np.int32(3))
    assert report.iterations == 3 and report.finalEnergy < report.initialEnergy
    report = mrattle.minimizeEnergy(context, np.float64(1e9))
    assert report.iterations == 0
    with pytest.raises(TypeError, match='force'):
        mrattle.minimizeEnergy(context, 1*unit.nanometer)
    with pytest.raises(TypeError, match='maxIterations'):
        mrattle.minimizeEnergy(context, 10, 2.5)
    with pytest.raises(openmm.OpenMMException, match='tolerance'):
        mrattle.minimizeEnergy(context, -1)
    with pytest.raises(openmm.OpenMMException, match='maxIterations'):
        mrattle.minimizeEnergy(context, 10, -1)
    with pytest.raises(TypeError, match='reporter'):
        openmm.LocalEnergyMinimizer.minimize(context, 10, 0, object())
    flexible = openmm.Context(model.system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    flexible.setPositions(model.positions)
    with pytest.raises(openmm.OpenMMException, match='LocalEnergyMinimizer'):
        mrattle.minimizeEnergy(flexible)


def test_tip3p_rigid_water_minimizes_far():
    # The case: OpenMM's minimizer with MRattleIntegrator lowered this by 38 kJ/mol.
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
    system = app.ForceField('tip3p.xml').createSystem(pdb.topology, nonbondedMethod=app.PME, rigidWater=True)
    cpu = openmm.Platform.getPlatformByName('CPU')
    integrator = mrattle.MRattleIntegrator(0.002)
    simulation = app.Simulation(pdb.topology, system, integrator, cpu, {'Threads': '1'})
    simulation.context.setPositions(pdb.positions)
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy()
    assert energy(simulation.context) < start - 5000
    assert maxShapeChange(before, positions(simulation.context), integrator.getBodiesInEffect()) < 1e-12


BENZENES = [list(range(12*m, 12*m + 12)) for m in range(27)]


def isRigidField(x, field, bodies):
    """Largest |d . (f_i - f_j)| over the pairs of each body (d = x_i - x_j): zero for a rigid-motion field."""
    worst = 0.0
    for body in bodies:
        d = x[body][:, None] - x[body][None]
        df = field[body][:, None] - field[body][None]
        worst = max(worst, np.abs(np.sum(d*df, axis=2)).max())
    return worst


class Recorder:
    """Records every report; stops after `stopAt` (an iteration index) if given."""
    def __init__(self, stopAt=None):
        self.calls, self.stopAt = [], stopAt

    def report(self, iteration, x, grad, args):
        self.calls.append((iteration, np.reshape(x, (-1, 3)), np.reshape(grad, (-1, 3)), dict(args)))
        return self.stopAt is not None and iteration >= self.stopAt


def test_local_energy_minimizer_is_rigid_with_the_plugins_integrators(platform):
    model = mrattle.models.benzeneCluster()
    context = simulationOf(model, mrattle.MRattleIntegrator(0.001), platform).context
    start, before = energy(context), positions(context)
    openmm.LocalEnergyMinimizer.minimize(context, 1*unit.kilojoules_per_mole/unit.nanometer, 60)
    assert energy(context) < start - 100
    assert maxShapeChange(before, positions(context), BENZENES) < 1e-12
    # The same call with OpenMM's own integrator is OpenMM's minimizer: it deforms the benzenes.
    flexible = simulationOf(model, openmm.VerletIntegrator(0.001), platform).context
    openmm.LocalEnergyMinimizer.minimize(flexible, 1, 20)
    assert maxShapeChange(before, positions(flexible), BENZENES) > 1e-4


def test_local_energy_minimizer_is_rigid_on_a_device_platform(devicePlatform):
    model = mrattle.models.benzeneCluster()
    context = simulationOf(model, mrattle.MRattleIntegrator(0.001), devicePlatform).context
    start, before = energy(context), positions(context)
    openmm.LocalEnergyMinimizer.minimize(context, 1, 10)
    assert energy(context) < start - 10
    assert maxShapeChange(before, positions(context), BENZENES) < 1e-12


def test_reporter_gets_openmms_arguments_for_the_rigid_search():
    model = mrattle.models.benzeneCluster()
    context = simulationOf(model, mrattle.MRattleIntegrator(0.001), openmm.Platform.getPlatformByName('Reference')).context
    before = positions(context)
    recorder = Recorder()
    report = mrattle.minimizeEnergy(context, 1, 30, reporter=recorder)
    assert report.iterations == 30
    assert [call[0] for call in recorder.calls] == list(range(30))
    for iteration, x, grad, args in recorder.calls:
        assert set(args) == {'system energy', 'restraint energy', 'restraint strength', 'max constraint error'}
        assert args['restraint energy'] == 0 and args['max constraint error'] == 0  # no constraints here
        assert x.shape == grad.shape == (324, 3)
        assert maxShapeChange(before, x, BENZENES) < 1e-12
        # The gradient is minus the force projected on rigid motion: a rigid-motion field.
        assert isRigidField(x, grad, BENZENES) < 1e-9*np.abs(grad).max()
    energies = [call[3]['system energy'] for call in recorder.calls]
    assert all(b <= a for a, b in zip(energies, energies[1:]))
    iteration, x, grad, args = recorder.calls[-1]
    assert np.abs(x - positions(context)).max() < 1e-12
    assert args['system energy'] == pytest.approx(report.finalEnergy, rel=1e-12)
    # Its rms per degree of freedom (6 per benzene), in a particle's units, is the search's test and report.
    assert np.sqrt(3*np.sum(grad**2)/(6*27)) == pytest.approx(report.rmsForce, rel=1e-9)
    # Its rigid part agrees with OpenMM's forces: the same net force on each body.
    forces = context.getState(getForces=True).getForces(asNumpy=True).value_in_unit(unit.kilojoules_per_mole/unit.nanometer)
    for body in BENZENES:
        assert np.abs(-grad[body].sum(axis=0) - forces[body].sum(axis=0)).max() < 1e-9*np.abs(forces).max()


def test_reporter_stops_the_search_and_its_exceptions_pass_through():
    model = mrattle.models.benzeneCluster()
    context = simulationOf(model, mrattle.MRattleIntegrator(0.001), openmm.Platform.getPlatformByName('Reference')).context
    stopper = Recorder(stopAt=2)
    openmm.LocalEnergyMinimizer.minimize(context, 0.1, 0, stopper)
    assert [call[0] for call in stopper.calls] == [0, 1, 2]
    assert energy(context) == pytest.approx(stopper.calls[-1][3]['system energy'], rel=1e-12)

    class Failing:
        def report(self, iteration, x, grad, args):
            raise ValueError('stop here')
    before = energy(context)
    with pytest.raises(ValueError, match='stop here'):
        mrattle.minimizeEnergy(context, 0.1, 0, Failing())
    assert energy(context) <= before


@pytest.mark.skipif(not hasattr(openmm, 'MinimizationReporter'),
                    reason='OpenMM %s has no MinimizationReporter (OpenMM 8.1 and later)' % openmm.__version__)
def test_openmm_minimization_reporter_through_simulation():
    model = mrattle.models.benzeneCluster()
    simulation = simulationOf(model, mrattle.MRattleIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    before = positions(simulation.context)

    class Recording(openmm.MinimizationReporter):
        def __init__(self, stopAt):
            super().__init__()
            self.calls, self.stopAt = [], stopAt

        def report(self, iteration, x, grad, args):
            self.calls.append((iteration, np.reshape(x, (-1, 3)), dict(args)))
            return iteration >= self.stopAt
    recording = Recording(stopAt=1000)
    simulation.minimizeEnergy(tolerance=1, maxIterations=20, reporter=recording)
    assert [call[0] for call in recording.calls] == list(range(20))
    assert all(maxShapeChange(before, x, BENZENES) < 1e-12 for _, x, _ in recording.calls)
    assert np.abs(recording.calls[-1][1] - positions(simulation.context)).max() < 1e-12
    stopping = Recording(stopAt=0)
    start = energy(simulation.context)
    simulation.minimizeEnergy(tolerance=0.1, reporter=stopping)
    assert len(stopping.calls) == 1
    assert energy(simulation.context) == pytest.approx(stopping.calls[0][2]['system energy'], rel=1e-12)
    assert energy(simulation.context) <= start
