"""MRattleNoseHooverIntegrator and MRattleBussiIntegrator from Python: units and numpy values
as OpenMM's NoseHooverIntegrator, a Simulation whose StateDataReporter writes the heat-bath and
conserved energies (the conserved one flat beside the total), serialization, checkpoints."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties
from mrattle.reporters import DRUDE_INTEGRATORS, HEAT_BATH_INTEGRATORS

# The thermostats constructed as (temperature, collisionFrequency, stepSize): the Drude ones
# (OpenMM's Drude integrators' constructors) have tests of their own.
HEAT_BATH_INTEGRATORS = [cls for cls in HEAT_BATH_INTEGRATORS if cls not in DRUDE_INTEGRATORS]


def test_units_and_numpy_values():
    chain = mrattle.MRattleNoseHooverIntegrator(310*unit.kelvin, 2/unit.picosecond, 2*unit.femtoseconds)
    assert chain.getTemperature() == 310*unit.kelvin
    assert chain.getCollisionFrequency() == 2/unit.picosecond
    assert chain.getStepSize() == 0.002*unit.picoseconds
    assert (chain.getChainLength(), chain.getNumMultiTimeSteps(), chain.getNumYoshidaSuzukiTimeSteps()) == (3, 3, 7)
    chain.setCollisionFrequency(0.02/unit.femtosecond)
    assert chain.getCollisionFrequency().value_in_unit(unit.picosecond**-1) == pytest.approx(20)
    numbers = mrattle.MRattleNoseHooverIntegrator(np.float64(300), np.int64(5), np.float32(0.002), np.int32(4), 2, 5)
    assert (numbers.getChainLength(), numbers.getNumMultiTimeSteps(), numbers.getNumYoshidaSuzukiTimeSteps()) == (4, 2, 5)
    with pytest.raises(openmm.OpenMMException, match='Yoshida-Suzuki'):
        mrattle.MRattleNoseHooverIntegrator(300, 5, 0.002, 3, 3, 4)
    bussi = mrattle.MRattleBussiIntegrator(300*unit.kelvin, 4/unit.picosecond, 1*unit.femtoseconds)
    assert bussi.getTimeConstant() == 0.25*unit.picoseconds
    bussi.setTimeConstant(500*unit.femtoseconds)
    assert bussi.getCollisionFrequency() == 2/unit.picosecond
    with pytest.raises(openmm.OpenMMException, match='temperature'):
        bussi.setTemperature(-1*unit.kelvin)
    with pytest.raises(openmm.OpenMMException, match='not bound'):
        bussi.computeHeatBathEnergy()


@pytest.mark.parametrize('cls', HEAT_BATH_INTEGRATORS, ids=lambda cls: cls.__name__)
def test_reporter_writes_a_flat_conserved_energy(platform, cls):
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    integrator = cls(300*unit.kelvin, 10/unit.picosecond, 1*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(400*unit.kelvin, 1)  # hot: the bath takes energy out
    log = io.StringIO()
    simulation.reporters.append(mrattle.StateDataReporter(log, 20, step=True, totalEnergy=True, temperature=True,
                                                          heatBathEnergy=True, conservedEnergy=True))
    simulation.step(600)
    lines = log.getvalue().splitlines()
    header = lines[0].split(',')
    assert header[-2:] == ['"Heat Bath Energy (kJ/mole)"', '"Conserved Energy (kJ/mole)"']
    rows = np.array([[float(value) for value in line.split(',')] for line in lines[1:]])
    total, bath, conserved = rows[:, 1], rows[:, 3], rows[:, 4]
    assert np.allclose(conserved, total + bath, rtol=0, atol=1e-3)
    # The energy the bath took out (the temperature itself is no test here: the lattice start
    # releases potential energy for a picosecond, and 10 samples of 64 waters read 360-440 K).
    assert bath[-1] > 100
    # The bath's energy moves by hundreds of kJ/mol; the conserved sum by the step's error.
    assert np.ptp(conserved) < 0.1 * np.ptp(total)
    with pytest.raises(ValueError, match='computeHeatBathEnergy'):
        other = app.Simulation(model.topology, model.system, mrattle.MRattleIntegrator(0.001), platform,
                               platformProperties(platform))
        other.context.setPositions(model.positions)
        other.reporters.append(mrattle.StateDataReporter(io.StringIO(), 1, heatBathEnergy=True))
        other.step(1)


@pytest.mark.parametrize('cls', HEAT_BATH_INTEGRATORS, ids=lambda cls: cls.__name__)
def test_serialization_and_checkpoint(platform, cls, tmp_path):
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    integrator = cls(300*unit.kelvin, 10/unit.picosecond, 2*unit.femtoseconds)
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, cls)
    assert copy.getCollisionFrequency() == 10/unit.picosecond
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    simulation.step(10)
    path = str(tmp_path/'run.chk')
    simulation.saveCheckpoint(path)
    simulation.step(20)
    uninterrupted = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    bath = integrator.computeHeatBathEnergy()
    simulation.loadCheckpoint(path)
    simulation.step(20)
    continued = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    if platform.getName() == 'Reference':
        assert np.array_equal(uninterrupted, continued)
        assert integrator.computeHeatBathEnergy() == bath
    else:  # the CPU neighbour list: round-off (docs/serialization.md)
        assert np.abs(uninterrupted - continued).max() < 1e-4
