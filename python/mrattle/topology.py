"""Choosing rigid bodies from an OpenMM Topology: all waters, residues by name, or any
residue a function picks; the rest of the System stays flexible."""
from openmm import unit

# Residue names OpenMM's force fields and common PDB files use for water.
WATER_NAMES = frozenset(['HOH', 'WAT', 'SOL', 'H2O', 'TIP3', 'TIP4', 'TIP5', 'T3P', 'T4P', 'T5P', 'SPC', 'SPCE'])


def _selector(select):
    if select == 'water':
        return lambda residue: residue.name.upper() in WATER_NAMES
    if callable(select):
        return select
    if isinstance(select, str):
        names = {select}
    else:
        names = set(select)
    return lambda residue: residue.name in names


def rigidBodies(topology, system, select='water'):
    """The rigid bodies of the chosen residues: one body per residue, made of its massive
    atoms (virtual sites such as TIP4P's M site are left out: they follow their parents).

    Parameters
    ----------
    topology : openmm.app.Topology
    system : openmm.System
        the System created from that Topology (for masses and virtual sites)
    select : 'water', a residue name, a list of names, or a function(residue) -> bool
        which residues are rigid; every other atom stays free (flexible, with whatever
        constraints the System gives it, e.g. constraints=HBonds)

    Returns
    -------
    list of lists of int
        one list of atom indices per body, for RigidBodyIntegrator.addRigidBody()
    """
    if topology.getNumAtoms() != system.getNumParticles():
        raise ValueError('rigidBodies: the Topology has %d atoms and the System %d particles'
                         % (topology.getNumAtoms(), system.getNumParticles()))
    chosen = _selector(select)
    bodies = []
    for residue in topology.residues():
        if not chosen(residue):
            continue
        atoms = [atom.index for atom in residue.atoms()
                 if system.getParticleMass(atom.index).value_in_unit(unit.dalton) > 0
                 and not system.isVirtualSite(atom.index)]
        if len(atoms) >= 2:
            bodies.append(atoms)
    if not bodies:
        raise ValueError('rigidBodies: no residue of the Topology was selected by %r' % (select,))
    return bodies


def declareRigidBodies(integrator, topology, system, select='water'):
    """Declare rigidBodies(topology, system, select) on a rigid-body integrator (before it is
    bound to a Context): only those residues are rigid. Returns the number of bodies."""
    bodies = rigidBodies(topology, system, select)
    for body in bodies:
        integrator.addRigidBody(body)
    return len(bodies)
