"""Rigid bodies chosen from a Topology, on OpenMM's own inputs: rigid water with a flexible
protein (test.pdb), TIP4P-Ew with its virtual sites (tip4pew.pdb)."""
import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import meanAndError

DATA = os.path.join(os.path.dirname(app.__file__), 'data')


def test_waters_rigid_protein_flexible_with_hbond_constraints():
    pdb = app.PDBFile(os.path.join(DATA, 'test.pdb'))
    forceField = app.ForceField('amber14-all.xml', 'amber14/tip3p.xml')
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                     constraints=app.HBonds, rigidWater=True)
    integrator = mrattle.MRattleIntegrator(1*unit.femtoseconds)
    assert mrattle.declareRigidBodies(integrator, pdb.topology, system, 'water') == 2761
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('CPU'))
    context.setPositions(pdb.positions)
    context.applyConstraints(1e-10)
    context.setPositions(context.getState(getPositions=True).getPositions())
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    protein = [atom.index for atom in pdb.topology.atoms() if atom.residue.name != 'HOH']
    assert sorted(integrator.getFreeParticles()) == protein
    free = set(protein)
    hbonds = [i for i in range(system.getNumConstraints()) if system.getConstraintParameters(i)[0] in free]
    assert len(hbonds) > 100
    # Rigid bodies 6 DOF each (CMMotionRemover: -3), protein 3 per atom less its constraints.
    assert integrator.getNumDegreesOfFreedom() == 6*2761 + 3*len(protein) - len(hbonds) - 3
    integrator.step(50)
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    for i in hbonds:
        p1, p2, distance = system.getConstraintParameters(i)
        assert abs(np.linalg.norm(x[p1] - x[p2]) - distance.value_in_unit(unit.nanometers)) < 2e-6
    for body in integrator.getBodiesInEffect()[:200]:
        assert abs(np.linalg.norm(x[body[0]] - x[body[1]]) - 0.09572) < 1e-8


def test_tip4pew_virtual_sites_are_left_out_and_follow():
    pdb = app.PDBFile(os.path.join(DATA, 'tip4pew.pdb'))
    forceField = app.ForceField('amber14/tip4pew.xml')
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                     rigidWater=True)
    bodies = mrattle.rigidBodies(pdb.topology, system, 'water')
    assert all(len(body) == 3 for body in bodies)
    assert not any(system.isVirtualSite(i) for body in bodies for i in body)
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('CPU'))
    context.setPositions(pdb.positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 2)
    integrator.step(20)
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    for i in range(system.getNumParticles()):
        if system.isVirtualSite(i):
            site = system.getVirtualSite(i)
            expected = sum(site.getWeight(k)*x[site.getParticle(k)] for k in range(site.getNumParticles()))
            assert np.linalg.norm(x[i] - expected) < 1e-10


def test_selections_and_errors():
    pdb = app.PDBFile(os.path.join(DATA, 'test.pdb'))
    system = app.ForceField('amber14-all.xml', 'amber14/tip3p.xml').createSystem(pdb.topology, constraints=app.HBonds)
    assert len(mrattle.rigidBodies(pdb.topology, system, ['HOH'])) == 2761
    assert len(mrattle.rigidBodies(pdb.topology, system, lambda residue: residue.name == 'PHE')) == 4  # villin's four Phe
    with pytest.raises(ValueError, match='no residue'):
        mrattle.rigidBodies(pdb.topology, system, 'XYZ')
    small = openmm.System()
    small.addParticle(1.0)
    with pytest.raises(ValueError, match='atoms and the System'):
        mrattle.rigidBodies(pdb.topology, small)


@pytest.mark.parametrize('platformName', mrattle.PLATFORMS)
@pytest.mark.parametrize('pdbName,forceFieldName', [('tip3p.pdb', 'amber14/tip3p.xml'), ('tip4pew.pdb', 'amber14/tip4pew.xml'),
                                                     ('tip5p.pdb', 'tip5p.xml'), ('spce.pdb', 'amber14/spce.xml')])
def test_waters_take_their_force_field_geometry(platformName, pdbName, forceFieldName):
    """The PDB files' waters are off their model's geometry by ~1e-3: a fully constrained
    body takes its constraint geometry when positions are set (OpenMM's SETTLE, good to
    ~3e-8 in 7.7) and keeps it while stepping."""
    pdb = app.PDBFile(os.path.join(DATA, pdbName))
    system = app.ForceField(forceFieldName).createSystem(pdb.topology, nonbondedMethod=app.PME,
                                                         nonbondedCutoff=0.7*unit.nanometers, rigidWater=True)
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    properties = {'Precision': 'double'} if platformName in mrattle.DEVICE_PLATFORMS else {}
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(platformName), properties)
    context.setPositions(pdb.positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)

    def worst(x):
        return max(abs(np.linalg.norm(x[p1] - x[p2]) - d.value_in_unit(unit.nanometers))/d.value_in_unit(unit.nanometers)
                   for p1, p2, d in (system.getConstraintParameters(i) for i in range(system.getNumConstraints())))
    assert worst(pdb.getPositions(asNumpy=True).value_in_unit(unit.nanometers)) > 1e-4  # the file's waters are off
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    assert worst(x) < 1e-7
    integrator.step(5)
    y = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    assert worst(y) < 1e-7
    for i in range(system.getNumParticles()):  # virtual sites (TIP4P/TIP5P) follow the corrected bodies
        if system.isVirtualSite(i):
            site = system.getVirtualSite(i)
            if isinstance(site, openmm.ThreeParticleAverageSite):
                expected = sum(site.getWeight(k)*y[site.getParticle(k)] for k in range(3))
                assert np.linalg.norm(y[i] - expected) < 1e-9


def test_villin_with_rigid_water_conserves_energy_like_verlet_with_settle_and_ccma():
    """OpenMM's test.pdb: rigid waters (M-RATTLE) and a flexible protein (RATTLE for its
    H-bond constraints) against VerletIntegrator with SETTLE and CCMA, NVE at 1 and 2 fs
    from three thermalized starts: the total-energy fluctuations agree (their log ratio's
    mean over the six runs within four standard errors of 0, or of 10%) and the protein's
    H-bond lengths hold to the tolerance."""
    pdb = app.PDBFile(os.path.join(DATA, 'test.pdb'))
    forceField = app.ForceField('amber14-all.xml', 'amber14/tip3p.xml')
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                     constraints=app.HBonds, rigidWater=True)
    cpu = openmm.Platform.getPlatformByName('CPU')
    thermalize = openmm.LangevinMiddleIntegrator(300*unit.kelvin, 5/unit.picosecond, 1*unit.femtoseconds)
    thermalize.setRandomNumberSeed(1)
    context = openmm.Context(system, thermalize, cpu)
    context.setPositions(pdb.positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    thermalize.step(200)
    starts = []
    for _ in range(3):
        thermalize.step(100)
        starts.append(context.getState(getPositions=True, getVelocities=True))
    del context

    def fluctuation(name, h, start):
        if name == 'M-RATTLE':
            integrator = mrattle.MRattleIntegrator(h*unit.femtoseconds)
            mrattle.declareRigidBodies(integrator, pdb.topology, system, 'water')
        else:
            integrator = openmm.VerletIntegrator(h*unit.femtoseconds)
        integrator.setConstraintTolerance(1e-6)
        context = openmm.Context(system, integrator, cpu)
        context.setPositions(start.getPositions())
        context.setVelocities(start.getVelocities())
        energies = []
        for k in range(100//h):
            integrator.step(2//h)
            state = context.getState(getEnergy=True)
            energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole))
        if name == 'M-RATTLE':
            x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
            free = set(integrator.getFreeParticles())
            for i in range(system.getNumConstraints()):
                p1, p2, distance = system.getConstraintParameters(i)
                if p1 in free:
                    d = distance.value_in_unit(unit.nanometers)
                    assert abs(np.linalg.norm(x[p1] - x[p2]) - d) < 3e-6*d
        return np.std(energies)

    logRatios, logGrowth = [], []
    for start in starts:
        rattle = {h: fluctuation('M-RATTLE', h, start) for h in (1, 2)}
        for h in (1, 2):
            logRatios.append(np.log(rattle[h]/fluctuation('Verlet', h, start)))
        logGrowth.append(np.log(rattle[2]/rattle[1]))
    mean, error = meanAndError(logRatios)
    print(f'fluctuation ratio M-RATTLE/Verlet: {np.exp(mean):.3f} (log ratio {mean:.3f} +- {error:.3f}, '
          f'{len(logRatios)} runs)')
    assert error < np.log(1.25), logRatios  # the mean ratio known to 25%
    assert abs(mean) < max(4*error, np.log(1.1)), logRatios
    # Twice the step, larger fluctuations (about 4x: the error is O(h^2)).
    growth, growthError = meanAndError(logGrowth)
    assert growth - 4*growthError > 0, logGrowth


def test_a_protein_made_rigid_by_default_is_warned_about_once():
    pdb = app.PDBFile(os.path.join(DATA, 'test.pdb'))
    system = app.ForceField('amber14-all.xml', 'amber14/tip3p.xml').createSystem(
        pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers, constraints=app.HBonds)
    integrator = mrattle.MRattleIntegrator(1*unit.femtoseconds)  # no body declared: every molecule rigid
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('CPU'))
    context.setPositions(pdb.positions)
    assert len(integrator.getLargeDefaultBodies()) == 1
    with pytest.warns(UserWarning, match=r'1 molecule\(s\) of more than 30 atoms .*the largest has 582 atoms'):
        integrator.step(1)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        integrator.step(1)  # once only
    declared = mrattle.MRattleIntegrator(1*unit.femtoseconds)
    mrattle.declareRigidBodies(declared, pdb.topology, system, 'water')
    openmm.Context(system, declared, openmm.Platform.getPlatformByName('Reference'))
    assert declared.getLargeDefaultBodies() == []


# A phenylalanine side chain's ring with its hydrogens (amber14's atom names).
PHE_RING = ['CG', 'CD1', 'HD1', 'CD2', 'HD2', 'CE1', 'HE1', 'CE2', 'HE2', 'CZ', 'HZ']


def villinInVacuum():
    """OpenMM's villin headpiece (test.pdb) without its water and ions, amber14, no cutoff, H-bond constraints."""
    pdb = app.PDBFile(os.path.join(DATA, 'test.pdb'))
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.delete([residue for residue in modeller.topology.residues() if residue.name in ('HOH', 'Cl', 'Na')])
    system = app.ForceField('amber14-all.xml').createSystem(modeller.topology, constraints=app.HBonds)
    return modeller.topology, modeller.positions, system


def stepAndCheckRigid(topology, positions, system, bodies, steps=20):
    integrator = mrattle.MRattleIntegrator(1*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    before = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    integrator.step(steps)
    after = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    for body in bodies:
        d0 = np.linalg.norm(before[body][:, None] - before[body][None], axis=2)
        d1 = np.linalg.norm(after[body][:, None] - after[body][None], axis=2)
        assert np.max(np.abs(d1 - d0)) < 1e-10
    return integrator, context, before, after


def test_atom_names_per_residue_make_rigid_rings_in_a_flexible_protein():
    topology, positions, system = villinInVacuum()
    bodies = mrattle.rigidBodies(topology, system, {'PHE': PHE_RING})
    assert len(bodies) == 4
    atoms = list(topology.atoms())
    for body in bodies:
        assert [atoms[i].name for i in body] == PHE_RING or sorted(atoms[i].name for i in body) == sorted(PHE_RING)
        assert len({atoms[i].residue.index for i in body}) == 1
    # The same bodies by a residue selection and atom names, or a function of atoms.
    assert mrattle.rigidBodies(topology, system, 'PHE', atoms=PHE_RING) == bodies
    assert mrattle.rigidBodies(topology, system, 'PHE', atoms=lambda atom: atom.name in PHE_RING) == bodies
    integrator, context, before, after = stepAndCheckRigid(topology, positions, system, bodies)
    # The rest of the protein is flexible: a CB-CG bond next to a ring changes length.
    ring = bodies[0]
    cb = [a.index for a in atoms if a.residue.index == atoms[ring[0]].residue.index and a.name == 'CB'][0]
    cg = [i for i in ring if atoms[i].name == 'CG'][0]
    assert abs(np.linalg.norm(after[cb] - after[cg]) - np.linalg.norm(before[cb] - before[cg])) > 1e-6
    # 6 per ring, 3 per other atom less the H-bond constraints not inside a ring, minus the CMMotionRemover's 3.
    inRing = {i for body in bodies for i in body}
    outside = [c for c in range(system.getNumConstraints())
               if not set(system.getConstraintParameters(c)[:2]) <= inRing]
    assert integrator.getNumDegreesOfFreedom() == 6*4 + 3*(system.getNumParticles() - len(inRing)) - len(outside) - 3


def test_a_domain_spanning_residues_is_one_body():
    topology, positions, system = villinInVacuum()
    domain = mrattle.rigidBodies(topology, system, lambda residue: 4 <= residue.index < 14, group='chain')
    assert len(domain) == 1
    residues = list(topology.residues())
    expected = sorted(atom.index for residue in residues[4:14] for atom in residue.atoms())
    assert domain[0] == expected
    assert len(mrattle.rigidBodies(topology, system, lambda residue: 4 <= residue.index < 14)) == 10
    stepAndCheckRigid(topology, positions, system, domain, steps=10)


def test_a_body_cut_through_a_constraint_is_refused_naming_the_particle():
    topology, positions, system = villinInVacuum()
    carbons = mrattle.rigidBodies(topology, system, {'PHE': ['CG', 'CD1', 'CD2', 'CE1', 'CE2', 'CZ']})
    integrator = mrattle.MRattleIntegrator(1*unit.femtoseconds)
    for body in carbons:
        integrator.addRigidBody(body)
    with pytest.raises(openmm.OpenMMException, match=r'joins particle \d+ of rigid body 0 to particle \d+ outside'):
        openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))


def test_atom_selection_errors():
    topology, positions, system = villinInVacuum()
    with pytest.raises(ValueError, match='PHE .* has no atom named XX'):
        mrattle.rigidBodies(topology, system, {'PHE': ['CG', 'XX']})
    with pytest.raises(ValueError, match='either in the dict'):
        mrattle.rigidBodies(topology, system, {'PHE': PHE_RING}, atoms=['CG'])
    with pytest.raises(ValueError, match='non-empty list'):
        mrattle.rigidBodies(topology, system, {'PHE': 'CG'})
    with pytest.raises(ValueError, match='group must be one of'):
        mrattle.rigidBodies(topology, system, 'PHE', group='domain')
    with pytest.raises(ValueError, match='no residue or atom'):
        mrattle.rigidBodies(topology, system, 'PHE', atoms=lambda atom: False)


def test_python_resolves_bodies_with_the_integrators_rules():
    """mrattle.integrators.RigidBodyTopology is the C++ class the integrators resolve their
    bodies with: made from the System, it gives what a bound integrator has in effect."""
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    system = model.system
    system.addForce(openmm.CMMotionRemover())
    reference = openmm.Platform.getPlatformByName('Reference')
    for declared in ([], [[0, 1, 2], [6, 7, 8]]):
        integrator = mrattle.MRattleIntegrator(0.001)
        for body in declared:
            integrator.addRigidBody(body)
        context = openmm.Context(system, integrator, reference)
        context.setPositions(model.positions)
        topology = mrattle.integrators.RigidBodyTopology(system, declared, context.getMolecules())
        assert topology.getBodies() == integrator.getBodiesInEffect()
        assert topology.getFreeParticles() == integrator.getFreeParticles()
        owners = topology.getBodyOfParticles()
        assert len(owners) == system.getNumParticles()
        for index, body in enumerate(topology.getBodies()):
            assert all(owners[particle] == index for particle in body)
        assert all(owners[particle] == -1 for particle in topology.getFreeParticles())
        # No body is linear: 6 each.
        assert topology.getNumDegreesOfFreedom(6*topology.getNumBodies()) == integrator.getNumDegreesOfFreedom()
        del context
    # The same checks as addRigidBody's and the Context's, with the same messages.
    with pytest.raises(openmm.OpenMMException, match='Particle 2 is listed in rigid bodies 0 and 1'):
        mrattle.integrators.RigidBodyTopology(system, [[0, 1, 2], [2, 3]], [])
    with pytest.raises(openmm.OpenMMException, match='lists particle 99, but the System has only 81 particles'):
        mrattle.integrators.RigidBodyTopology(system, [[0, 99]], [])
    with pytest.raises(TypeError):
        mrattle.integrators.RigidBodyTopology(system, [[0, 'a']], [])
