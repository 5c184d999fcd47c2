"""Both Drude integrators from Python, one suite: MRattleDrudeLangevinIntegrator with OpenMM's
DrudeLangevinIntegrator's units and settings, MRattleDrudeNoseHooverIntegrator with OpenMM's
DrudeNoseHooverIntegrator's, and XML; SWM4-NDP water (swm4ndp.xml, Modeller.addExtraParticles)
as rigid bodies with their Drude particles free, on Reference and on each device platform in
single precision: rigid, a checkpoint continuing bit for bit (Nose-Hoover: both chains in the
heat-bath energy and in it); the StateDataReporter's body and Drude temperature columns. What
only one of them has is guarded by its class."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from mrattle.reporters import DRUDE_INTEGRATORS, HEAT_BATH_INTEGRATORS

LANGEVIN, NOSE_HOOVER = mrattle.MRattleDrudeLangevinIntegrator, mrattle.MRattleDrudeNoseHooverIntegrator

#: Each class's body coupling (Langevin's friction, Nose-Hoover's collision frequency) and the names of its Drude coupling.
COUPLING = {LANGEVIN: (5/unit.picosecond, 'getFriction', 'getDrudeFriction', 'setDrudeFriction'),
            NOSE_HOOVER: (10/unit.picosecond, 'getCollisionFrequency', 'getDrudeCollisionFrequency',
                          'setDrudeCollisionFrequency')}

drudeIntegrators = pytest.mark.parametrize('cls', [LANGEVIN, NOSE_HOOVER], ids=lambda cls: cls.__name__)


def make(cls, stepSize=1*unit.femtoseconds):
    """300 K with the class's coupling, Drude 1 K at 20/ps: OpenMM's Drude integrators' arguments."""
    return cls(300*unit.kelvin, COUPLING[cls][0], 1*unit.kelvin, 20/unit.picosecond, stepSize)


@drudeIntegrators
def test_units_and_settings_like_openmms_drude_integrators(cls):
    coupling, getCoupling, getDrudeCoupling, setDrudeCoupling = COUPLING[cls]
    integrator = make(cls)
    assert integrator.getTemperature() == 300*unit.kelvin
    assert getattr(integrator, getCoupling)() == coupling
    assert integrator.getDrudeTemperature() == 1*unit.kelvin
    assert getattr(integrator, getDrudeCoupling)() == 20/unit.picosecond
    assert integrator.getStepSize() == 0.001*unit.picoseconds
    # OpenMM's defaults: DrudeLangevin no wall, DrudeNoseHoover 0.02 nm.
    assert integrator.getMaxDrudeDistance() == (0 if cls is LANGEVIN else 0.02)*unit.nanometer
    integrator.setMaxDrudeDistance(0.25*unit.angstroms)
    assert integrator.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.025)
    integrator.setDrudeTemperature(2*unit.kelvin)
    getattr(integrator, setDrudeCoupling)(0.01/unit.femtosecond)
    assert getattr(integrator, getDrudeCoupling)().value_in_unit(unit.picosecond**-1) == pytest.approx(10)
    with pytest.raises(openmm.OpenMMException, match='Drude temperature'):
        integrator.setDrudeTemperature(-1)
    with pytest.raises(openmm.OpenMMException, match='maximum Drude distance'):
        integrator.setMaxDrudeDistance(float('nan'))
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, cls)
    assert copy.getDrudeTemperature() == 2*unit.kelvin
    assert getattr(copy, getDrudeCoupling)().value_in_unit(unit.picosecond**-1) == pytest.approx(10)
    assert copy.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.025)
    assert cls in DRUDE_INTEGRATORS
    assert (cls in HEAT_BATH_INTEGRATORS) == (cls is NOSE_HOOVER)
    if cls is NOSE_HOOVER:
        assert (integrator.getChainLength(), integrator.getNumMultiTimeSteps(),
                integrator.getNumYoshidaSuzukiTimeSteps()) == (3, 3, 7)
        numbers = NOSE_HOOVER(np.float64(300), 10, 1, 20, 0.001, 4, 2, 5)
        assert (numbers.getChainLength(), numbers.getNumMultiTimeSteps(),
                numbers.getNumYoshidaSuzukiTimeSteps()) == (4, 2, 5)
        with pytest.raises(openmm.OpenMMException, match='Yoshida-Suzuki'):
            NOSE_HOOVER(300, 10, 1, 20, 0.001, 3, 3, 4)
        with pytest.raises(openmm.OpenMMException, match='not bound'):
            integrator.computeHeatBathEnergy()


def swm4ndp(numMolecules):
    """numMolecules SWM4-NDP waters in vacuum, and their O-H-H bodies (rigidBodies leaves the Drude particles out)."""
    model = mrattle.models.swm4ndpWater(numMolecules)
    bodies = mrattle.rigidBodies(model.topology, model.system)
    assert all(len(body) == 3 for body in bodies)
    return model.system, model.positions, bodies


def boundContext(system, positions, bodies, integrator, platform=None, properties=None, seed=1):
    """A Context (Reference by default) of the System with the bodies declared, at the positions, velocities at 300 K."""
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, platform or openmm.Platform.getPlatformByName('Reference'),
                             properties or {})
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, seed)
    return context


def assertRigid(bodies, start, end, tolerance):
    for body in bodies:
        before = np.linalg.norm(start[body][:, None] - start[body][None], axis=2)
        after = np.linalg.norm(end[body][:, None] - end[body][None], axis=2)
        assert np.max(np.abs(after - before)) < tolerance


def swm4ndp_rigid_with_a_checkpoint_bit_for_bit(cls, platform, properties, rigidity):
    """8 SWM4-NDP waters (their M sites virtual) with the wall of real runs (0.02 nm), 300
    steps (Langevin 1 fs, Nose-Hoover 0.5 fs) with a checkpoint after 100: the 100 steps after
    loading it are the 100 run on (Nose-Hoover: both chains' energy with them); the bodies
    stay rigid, the wall holds the Drude particles, both temperatures finite and of the right size."""
    system, positions, bodies = swm4ndp(8)
    integrator = make(cls, (1 if cls is LANGEVIN else 0.5)*unit.femtoseconds)
    integrator.setMaxDrudeDistance(0.02*unit.nanometer)
    if cls is LANGEVIN:
        integrator.setRandomNumberSeed(4)
    context = boundContext(system, positions, bodies, integrator, platform, properties, seed=2)
    # 6 per body and 3 per Drude particle, less the CMMotionRemover's 3.
    assert integrator.getNumDegreesOfFreedom() == 8*6 + 8*3 - 3
    heatBath = integrator.computeHeatBathEnergy if cls is NOSE_HOOVER else lambda: None
    start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    integrator.step(100)
    checkpoint = context.createCheckpoint()
    bath = heatBath()
    if cls is NOSE_HOOVER:
        assert bath != 0*unit.kilojoules_per_mole
    integrator.step(100)
    straight = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    straightBath = heatBath()
    context.loadCheckpoint(checkpoint)
    assert heatBath() == bath
    integrator.step(100)
    again = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    assert np.array_equal(straight, again)
    assert heatBath() == straightBath
    assertRigid(bodies, start, again, rigidity)
    drude = [f for f in system.getForces() if isinstance(f, openmm.DrudeForce)][0]
    for k in range(drude.getNumParticles()):
        particle, core = drude.getParticleParameters(k)[:2]
        assert np.linalg.norm(again[particle] - again[core]) <= 0.02*(1 + 1e-5)
    assert 100 < integrator.computeBodyTemperature().value_in_unit(unit.kelvin) < 600
    assert 0 < integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) < 100  # > 0: the Drude particles move


@drudeIntegrators
def test_swm4ndp_rigid_with_free_drude_particles_and_a_checkpoint_bit_for_bit(cls):
    swm4ndp_rigid_with_a_checkpoint_bit_for_bit(cls, openmm.Platform.getPlatformByName('Reference'), {}, 1e-10)


@drudeIntegrators
def test_swm4ndp_on_the_device_in_single_precision(cls, devicePlatform):
    """The device's default precision: rigid to float's round-off."""
    swm4ndp_rigid_with_a_checkpoint_bit_for_bit(cls, devicePlatform, {'Precision': 'single'}, 1e-5)


@drudeIntegrators
def test_drude_particles_in_default_bodies_are_refused(cls):
    system, positions, bodies = swm4ndp(2)
    with pytest.raises(openmm.OpenMMException, match='Drude particle 4'):
        openmm.Context(system, make(cls), openmm.Platform.getPlatformByName('Reference'))


@drudeIntegrators
def test_reporter_writes_body_and_drude_temperatures(cls):
    assert set(DRUDE_INTEGRATORS) == {LANGEVIN, NOSE_HOOVER}
    system, positions, bodies = swm4ndp(4)
    integrator = cls(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin, 20/unit.picosecond, 0.5*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    simulation = app.Simulation(app.Topology(), system, integrator, openmm.Platform.getPlatformByName('Reference'))
    simulation.context.setPositions(positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    log = io.StringIO()
    heatBath = cls in HEAT_BATH_INTEGRATORS
    simulation.reporters.append(mrattle.StateDataReporter(log, 10, step=True, temperature=True, bodyTemperature=True,
                                                          drudeTemperature=True, conservedEnergy=heatBath))
    simulation.step(30)
    lines = log.getvalue().splitlines()
    header = lines[0].split(',')
    body, drude = header.index('"Body Temperature (K)"'), header.index('"Drude Temperature (K)"')
    assert drude == body + 1 and body > header.index('"Temperature (K)"')
    last = [float(value) for value in lines[-1].split(',')]
    assert len(lines) == 4 and last[0] == 30
    assert last[body] == pytest.approx(integrator.computeBodyTemperature().value_in_unit(unit.kelvin), rel=1e-6)
    assert last[drude] == pytest.approx(integrator.computeDrudeTemperature().value_in_unit(unit.kelvin), rel=1e-6)
    assert last[body] > 0 and last[drude] > 0
    assert ('"Conserved Energy (kJ/mole)"' in header) == heatBath
    # An integrator without Drude temperatures is refused, naming what the columns need.
    other = app.Simulation(app.Topology(), system, mrattle.MRattleIntegrator(0.0005),
                           openmm.Platform.getPlatformByName('Reference'))
    other.context.setPositions(positions)
    with pytest.raises(ValueError, match='MRattleDrudeNoseHooverIntegrator'):
        other.reporters.append(mrattle.StateDataReporter(io.StringIO(), 1, drudeTemperature=True))
        other.step(1)


def test_set_drude_mass_moves_mass_from_each_core():
    system, positions, bodies = swm4ndp(4)
    before = [system.getParticleMass(i).value_in_unit(unit.amu) for i in range(system.getNumParticles())]
    drude = [f for f in system.getForces() if isinstance(f, openmm.DrudeForce)][0]
    pairs = [drude.getParticleParameters(k)[:2] for k in range(drude.getNumParticles())]
    assert mrattle.setDrudeMass(system, 1.6*unit.amu) == 4
    after = [system.getParticleMass(i).value_in_unit(unit.amu) for i in range(system.getNumParticles())]
    for particle, core in pairs:
        assert after[particle] == pytest.approx(1.6)
        assert after[particle] + after[core] == pytest.approx(before[particle] + before[core], rel=1e-14)
    moved = {i for pair in pairs for i in pair}
    assert all(after[i] == before[i] for i in range(len(before)) if i not in moved)
    mrattle.setDrudeMass(system, np.float64(0.8))  # a number is in amu; numpy's too
    assert system.getParticleMass(pairs[0][0]).value_in_unit(unit.amu) == pytest.approx(0.8)
    mrattle.setDrudeMass(system, 0.4*unit.dalton)
    assert [system.getParticleMass(i).value_in_unit(unit.amu) for i in range(len(before))] == pytest.approx(before)
    for bad in (0, -1, float('nan'), float('inf')):
        with pytest.raises(ValueError, match='finite number > 0'):
            mrattle.setDrudeMass(system, bad)
    with pytest.raises(ValueError, match='core particle %d without mass' % pairs[0][1]):
        mrattle.setDrudeMass(system, 16*unit.amu)
    with pytest.raises(ValueError, match='no DrudeForce'):
        mrattle.setDrudeMass(openmm.System(), 1.6)


@pytest.mark.parametrize('drudeMass', [None, 1.6], ids=['force field 0.4 amu', '1.6 amu'])
def test_2fs_steps_need_a_heavier_drude_particle(drudeMass):
    """The Drude spring (k = 4.2e5 kJ/mol/nm^2) with 0.4 amu has omega h = 2.05 at 2 fs, past
    velocity Verlet's limit: its Drude particles are thrown beyond the wall within a few steps.
    With 1.6 amu (omega h = 1.0, as 0.4 amu at 1 fs) 8 waters take 500 steps, rigid, held by the wall."""
    system, positions, bodies = swm4ndp(8)
    if drudeMass:
        mrattle.setDrudeMass(system, drudeMass)
    integrator = make(LANGEVIN, 2*unit.femtoseconds)
    integrator.setMaxDrudeDistance(0.02*unit.nanometer)
    integrator.setRandomNumberSeed(5)
    context = boundContext(system, positions, bodies, integrator, seed=6)
    start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    if drudeMass is None:
        with pytest.raises(openmm.OpenMMException, match='beyond twice the hard wall'):
            integrator.step(500)
        return
    integrator.step(500)
    final = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    assertRigid(bodies, start, final, 1e-10)
    assert 0 < integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) < 30
