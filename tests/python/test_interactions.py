"""removeIntraBodyInteractions: what it removes, and that the motion does not change."""
import numpy as np
import openmm
import pytest
from openmm import unit

import mrattle
from conftest import makeContext


def forcesByType(system):
    return {type(force).__name__: force for force in system.getForces()}


def run(system, model, platform, steps):
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    integrator.setConstraintTolerance(1e-12)
    context = makeContext(system, integrator, platform, model.positions, model.velocities)
    integrator.step(steps)
    state = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    return integrator.getNumBodiesInEffect(), state


def test_cluster_terms_removed_and_molecules_kept():
    model = mrattle.models.benzeneCluster()
    stripped = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    before, after = forcesByType(model.system), forcesByType(stripped)
    assert set(before) == {'HarmonicBondForce', 'HarmonicAngleForce', 'PeriodicTorsionForce', 'NonbondedForce',
                           'CustomNonbondedForce'}
    assert set(after) == {'NonbondedForce', 'CustomNonbondedForce'}
    assert after['NonbondedForce'].getNumExceptions() == 27*66
    assert after['CustomNonbondedForce'].getNumExclusions() == 27*66
    for i in range(after['NonbondedForce'].getNumExceptions()):
        p1, p2, chargeProd, sigma, epsilon = after['NonbondedForce'].getExceptionParameters(i)
        assert p1//12 == p2//12 and chargeProd._value == 0 and epsilon._value == 0
    # Each molecule is still one molecule (11 constraints each, at the rigid distances).
    assert stripped.getNumConstraints() == 27*11
    x = np.array(model.positions.value_in_unit(unit.nanometers))
    for c in range(stripped.getNumConstraints()):
        i, j, distance = stripped.getConstraintParameters(c)
        assert i//12 == j//12
        assert distance.value_in_unit(unit.nanometers) == pytest.approx(np.linalg.norm(x[i] - x[j]), abs=1e-15)
    assert model.system.getNumConstraints() == 0  # the input is not modified
    assert len(model.system.getForces()) == 5


def test_trajectory_unchanged(platform):
    model = mrattle.models.benzeneCluster(temperature=300*unit.kelvin)
    stripped = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    fullBodies, full = run(model.system, model, platform, 100)
    strippedBodies, reduced = run(stripped, model, platform, 100)
    assert strippedBodies == fullBodies == 27
    a = full.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    b = reduced.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    moved = np.abs(a - np.array(model.positions.value_in_unit(unit.nanometers))).max()
    assert moved > 1e-2
    # Reference: double precision, only the order of force sums changes. CPU: single-precision nonbonded.
    tolerance = 1e-10 if platform.getName() == 'Reference' else 1e-5
    assert np.abs(a - b).max() < tolerance
    # The potential energy changes by the constant intra-molecular energy, the kinetic not at all.
    assert full.getKineticEnergy().value_in_unit(unit.kilojoules_per_mole) == \
        pytest.approx(reduced.getKineticEnergy().value_in_unit(unit.kilojoules_per_mole), rel=1e-4)


def test_water_keeps_constraints_and_explicit_bodies():
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    stripped = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    assert stripped.getNumConstraints() == model.system.getNumConstraints()
    assert forcesByType(stripped)['NonbondedForce'].getNumExceptions() == 81
    # Explicit bodies: only the first two molecules.
    partial = mrattle.removeIntraBodyInteractions(model.system, model.positions, [[0, 1, 2], [3, 4, 5]])
    assert forcesByType(partial)['NonbondedForce'].getNumExceptions() == 81
    # Bodies from a bound integrator.
    integrator = mrattle.MRattleIntegrator(0.001)
    integrator.addRigidBody([0, 1, 2])
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    fromIntegrator = mrattle.removeIntraBodyInteractions(model.system, model.positions, integrator)
    assert openmm.XmlSerializer.serialize(fromIntegrator) == openmm.XmlSerializer.serialize(
        mrattle.removeIntraBodyInteractions(model.system, model.positions, [[0, 1, 2]]))
    del context
    # Checked by the integrators' own rules (RigidBodyTopology), with their messages.
    with pytest.raises(openmm.OpenMMException, match='removeIntraBodyInteractions: Particle 2 is listed in rigid '
                                                     'bodies 0 and 1'):
        mrattle.removeIntraBodyInteractions(model.system, model.positions, [[0, 1, 2], [2, 3]])
    with pytest.raises(openmm.OpenMMException, match='lists particle 1000, but the System has only 81 particles'):
        mrattle.removeIntraBodyInteractions(model.system, model.positions, [[0, 1000]])
    with pytest.raises(openmm.OpenMMException, match='Constraint 0 joins particle 0 of rigid body 0 to particle 1'):
        mrattle.removeIntraBodyInteractions(model.system, model.positions, [[0, 2]])


def test_terms_crossing_bodies_are_kept():
    system = openmm.System()
    for i in range(4):
        system.addParticle(1.0)
    bonds = openmm.HarmonicBondForce()
    bonds.addBond(0, 1, 0.1, 1000)
    bonds.addBond(1, 2, 0.1, 1000)  # crosses bodies: kept
    bonds.addBond(2, 3, 0.1, 1000)
    system.addForce(bonds)
    custom = openmm.CustomNonbondedForce('r')
    for i in range(4):
        custom.addParticle([])
    system.addForce(custom)
    torsions = openmm.CustomTorsionForce('theta')
    torsions.addTorsion(0, 1, 2, 3)
    system.addForce(torsions)
    positions = [openmm.Vec3(0.1*i, 0.01*i*i, 0) for i in range(4)]
    stripped = mrattle.removeIntraBodyInteractions(system, positions, [[0, 1], [2, 3]])
    kept = forcesByType(stripped)
    assert kept['HarmonicBondForce'].getNumBonds() == 1
    assert kept['HarmonicBondForce'].getBondParameters(0)[:2] == [1, 2]
    assert kept['CustomTorsionForce'].getNumTorsions() == 1
    assert sorted(tuple(kept['CustomNonbondedForce'].getExclusionParticles(i)) for i in range(2)) == [(0, 1), (2, 3)]


def test_virtual_sites_count_as_part_of_their_body():
    """TIP4P-Ew from OpenMM's own PDB and force field: the M site of each water is built
    from its O and Hs, so its pairs with them are intra-body (already excluded here)."""
    import os
    from openmm import app
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip4pew.pdb'))
    system = app.ForceField('tip4pew.xml').createSystem(pdb.topology, nonbondedMethod=app.PME,
                                                        nonbondedCutoff=0.9*unit.nanometers, rigidWater=True)
    assert sum(system.isVirtualSite(i) for i in range(system.getNumParticles())) == 895
    stripped = mrattle.removeIntraBodyInteractions(system, pdb.positions, 'molecules')
    nonbonded = forcesByType(stripped)['NonbondedForce']
    assert nonbonded.getNumExceptions() == 895*6  # O-H, O-H, H-H, and M with each: nothing new
    assert stripped.getNumConstraints() == system.getNumConstraints()
    # A body plus a virtual site built from two bodies: that site belongs to neither.
    system2 = openmm.System()
    for i in range(5):
        system2.addParticle(1.0 if i < 4 else 0.0)
    system2.setVirtualSite(4, openmm.TwoParticleAverageSite(1, 2, 0.5, 0.5))
    custom = openmm.CustomNonbondedForce('r')
    for i in range(5):
        custom.addParticle([])
    system2.addForce(custom)
    positions = [openmm.Vec3(0.1*i, 0, 0) for i in range(5)]
    stripped2 = mrattle.removeIntraBodyInteractions(system2, positions, [[0, 1], [2, 3]])
    result = forcesByType(stripped2)  # (the System must outlive its forces' proxies)
    pairs = sorted(tuple(result['CustomNonbondedForce'].getExclusionParticles(i))
                   for i in range(result['CustomNonbondedForce'].getNumExclusions()))
    assert pairs == [(0, 1), (2, 3)]


def test_positions_that_are_not_finite_are_refused():
    model = mrattle.models.benzene()
    positions = [openmm.Vec3(*p) for p in model.positions.value_in_unit(unit.nanometers)]
    positions[3] = openmm.Vec3(float('nan'), 0, 0)
    with pytest.raises(openmm.OpenMMException, match='position of particle 3 is not finite'):
        mrattle.removeIntraBodyInteractions(model.system, positions, 'molecules')
    with pytest.raises(openmm.OpenMMException, match='positions for a System'):
        mrattle.removeIntraBodyInteractions(model.system, positions[:5], 'molecules')


def test_bodies_must_be_given():
    """No default: a waters-only integrator must not lose the protein's bonded terms (issue 12)."""
    model = mrattle.models.benzeneCluster()
    with pytest.raises(TypeError):
        mrattle.removeIntraBodyInteractions(model.system, model.positions)
    with pytest.raises(TypeError, match='pass the bodies'):
        mrattle.removeIntraBodyInteractions(model.system, model.positions, None)
    with pytest.raises(ValueError, match="'molecules'"):
        mrattle.removeIntraBodyInteractions(model.system, model.positions, 'waters')
    # An integrator not yet bound: its declared bodies, or the molecules it would make rigid.
    declared = mrattle.MRattleIntegrator(0.002)
    declared.addRigidBody(list(range(12)))
    partial = mrattle.removeIntraBodyInteractions(model.system, model.positions, declared)
    everything = mrattle.removeIntraBodyInteractions(model.system, model.positions, mrattle.MRattleIntegrator(0.002))
    assert partial.getNumConstraints() < everything.getNumConstraints()
