"""The model builders: composition, rigid geometry, momenta."""
import itertools
import math

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from mrattle import models


def distances(x):
    return np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)


def test_benzene_geometry_and_parameters():
    model = models.benzene()
    x = np.array(model.positions.value_in_unit(unit.nanometers))
    assert model.system.getNumParticles() == 12 and model.topology.getNumAtoms() == 12
    d = distances(x)
    for k in range(6):
        assert d[k, (k + 1) % 6] == pytest.approx(0.1397, abs=1e-12)
        assert d[k, 6 + k] == pytest.approx(0.1084, abs=1e-12)
    assert np.abs(x[:, 2]).max() < 1e-15  # planar
    masses = [model.system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(12)]
    assert masses == [12.011]*6 + [1.008]*6
    coulomb = [f for f in model.system.getForces() if isinstance(f, openmm.NonbondedForce)][0]
    lj = [f for f in model.system.getForces() if isinstance(f, openmm.CustomNonbondedForce)][0]
    assert coulomb.getParticleParameters(0)[0].value_in_unit(unit.elementary_charge) == -0.115
    assert coulomb.getParticleParameters(6)[0].value_in_unit(unit.elementary_charge) == 0.115
    # The custom LJ is the geometric-rule LJ: check one C-H pair energy against the formula.
    a0, b0 = lj.getParticleParameters(0)
    a6, b6 = lj.getParticleParameters(6)
    r = 0.4
    sigma, epsilon = math.sqrt(0.355*0.242), math.sqrt(0.29288*0.12552)
    assert a0*a6/r**12 - b0*b6/r**6 == pytest.approx(4*epsilon*((sigma/r)**12 - (sigma/r)**6), rel=1e-12)


def test_cluster_momenta_and_rigid_velocities():
    model = models.benzeneCluster(temperature=300*unit.kelvin, seed=3)
    x = np.array(model.positions.value_in_unit(unit.nanometers))
    v = np.array(model.velocities.value_in_unit(unit.nanometers/unit.picoseconds))
    m = np.array([model.system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(len(x))])
    assert len(x) == 324 and model.topology.getNumResidues() == 27
    momentum = m.dot(v)
    centre = m.dot(x)/m.sum()
    angular = (m[:, None]*np.cross(x - centre, v)).sum(axis=0)
    assert np.abs(momentum).max() < 1e-10
    assert np.abs(angular).max() < 1e-10
    # Each molecule's velocities are rigid: no intra-molecular distance changes to first order.
    for molecule in range(27):
        atoms = slice(12*molecule, 12*molecule + 12)
        dx, dv = x[atoms][:, None] - x[atoms][None], v[atoms][:, None] - v[atoms][None]
        assert np.abs((dx*dv).sum(axis=2)).max() < 1e-12
    # Molecules do not overlap.
    closest = min(np.linalg.norm(x[i] - x[j]) for i in range(324) for j in range(i + 1, 324) if i//12 != j//12)
    assert closest > 0.2


def test_cluster_at_zero_kelvin_and_bad_arguments():
    model = models.benzeneCluster(temperature=0)
    assert np.abs(np.array(model.velocities.value_in_unit(unit.nanometers/unit.picoseconds))).max() == 0
    with pytest.raises(ValueError, match='temperature'):
        models.benzeneCluster(temperature=-1*unit.kelvin)
    with pytest.raises(ValueError, match='spacing'):
        models.benzeneCluster(spacing=0)


def test_liquid_and_water_boxes():
    liquid = models.benzeneLiquid(numMolecules=30, cutoff=0.8*unit.nanometers)
    assert liquid.system.getNumParticles() == 360 and liquid.system.usesPeriodicBoundaryConditions()
    box = liquid.system.getDefaultPeriodicBoxVectors()[0][0].value_in_unit(unit.nanometers)
    mass = 30*models.BENZENE_MOLAR_MASS/6.02214076e23
    assert mass/(box*1e-7)**3 == pytest.approx(0.8765, rel=1e-6)
    nonbonded = [f for f in liquid.system.getForces() if isinstance(f, openmm.NonbondedForce)][0]
    assert nonbonded.getNonbondedMethod() == openmm.NonbondedForce.PME
    water = models.waterBox(numMolecules=64, cutoff=0.6*unit.nanometers)
    assert water.system.getNumParticles() == 192 and water.system.getNumConstraints() == 192
    x = np.array(water.positions.value_in_unit(unit.nanometers))
    for c in range(water.system.getNumConstraints()):
        i, j, length = water.system.getConstraintParameters(c)
        assert np.linalg.norm(x[i] - x[j]) == pytest.approx(length.value_in_unit(unit.nanometers), abs=1e-12)
    with pytest.raises(ValueError, match='cutoff'):
        models.waterBox(numMolecules=8, cutoff=1.0)
    with pytest.raises(ValueError, match='numMolecules'):
        models.benzeneLiquid(numMolecules=0)


def test_builder_writes_pdb(tmp_path):
    model = models.benzeneCluster()
    path = str(tmp_path/'cluster.pdb')
    with open(path, 'w') as stream:
        app.PDBFile.writeFile(model.topology, model.positions, stream)
    pdb = app.PDBFile(path)
    assert pdb.topology.getNumAtoms() == 324
    assert [r.name for r in pdb.topology.residues()] == ['BNZ']*27


def test_swm4ndp_water_in_vacuum_and_as_a_periodic_box():
    # In vacuum: 8 molecules of 5 particles (O, H1, H2, the M site, a Drude particle), no cutoff.
    vacuum = models.swm4ndpWater()
    assert vacuum.system.getNumParticles() == 40 and not vacuum.system.usesPeriodicBoundaryConditions()
    # A box: filled by Modeller.addSolvent, PME at the cutoff, one Drude particle per water, rigid O-H-H.
    box = models.swm4ndpWater(boxSize=1.9 * unit.nanometers, cutoff=0.7 * unit.nanometers)
    nonbonded = next(f for f in box.system.getForces() if isinstance(f, openmm.NonbondedForce))
    drude = next(f for f in box.system.getForces() if isinstance(f, openmm.DrudeForce))
    waters = box.topology.getNumResidues()
    assert waters > 150 and box.system.getNumParticles() == 5 * waters and drude.getNumParticles() == waters
    assert nonbonded.getNonbondedMethod() == openmm.NonbondedForce.PME
    assert nonbonded.getCutoffDistance().value_in_unit(unit.nanometers) == pytest.approx(0.7)
    a, b, c = box.system.getDefaultPeriodicBoxVectors()
    assert [v.value_in_unit(unit.nanometers) for v in (a[0], b[1], c[2])] == [pytest.approx(1.9)] * 3
    assert box.system.getNumConstraints() == 3 * waters
    assert len(mrattle.rigidBodies(box.topology, box.system, atoms=['O', 'H1', 'H2'])) == waters
    with pytest.raises(ValueError, match='numMolecules or boxSize'):
        models.swm4ndpWater(4, boxSize=1.9 * unit.nanometers)
    with pytest.raises(ValueError, match='numMolecules must be'):
        models.swm4ndpWater(0)
