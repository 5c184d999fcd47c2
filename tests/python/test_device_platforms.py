"""The M-RATTLE integrators on each device platform (OpenCL, CUDA) from Python: app.Simulation
with reporters, in each precision. Skipped where no device platform has the plugin's kernels
(pocl gives an OpenCL platform on a CPU)."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle

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
