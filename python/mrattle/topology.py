"""Choosing rigid bodies from an OpenMM Topology: all waters, residues by name or by a function,
atoms within them (by name per residue, or by a function of atoms), one body per residue or
bodies that span several residues (a domain); the rest of the System stays flexible."""
from openmm import unit

from .drude import drudePairs

# Residue names OpenMM's force fields and common PDB files use for water.
WATER_NAMES = frozenset(['HOH', 'WAT', 'SOL', 'H2O', 'TIP3', 'TIP4', 'TIP5', 'T3P', 'T4P', 'T5P', 'SPC', 'SPCE'])

#: How the chosen atoms are grouped into bodies: one per residue, one per chain, or one in all.
GROUPINGS = ('residue', 'chain', 'all')


def _residueSelector(select):
    if select == 'water':
        return lambda residue: residue.name.upper() in WATER_NAMES
    if callable(select):
        return select
    if isinstance(select, str):
        names = {select}
    else:
        names = set(select)
    return lambda residue: residue.name in names


def _atomSelector(select, atoms):
    """function(residue) -> the residue's chosen atoms (list, maybe empty), raising ValueError for
    an atom name the residue does not have."""
    if isinstance(select, dict):
        if atoms is not None:
            raise ValueError('rigidBodies: give atom names either in the dict select or as atoms, not both')
        for name, names in select.items():
            if isinstance(names, str) or not names:
                raise ValueError('rigidBodies: select[%r] must be a non-empty list of atom names, got %r'
                                 % (name, names))
        wanted = {name: list(names) for name, names in select.items()}
        return lambda residue: _byNames(residue, wanted.get(residue.name))
    chosen = _residueSelector(select)
    if atoms is None:
        return lambda residue: list(residue.atoms()) if chosen(residue) else []
    if callable(atoms):
        return lambda residue: [atom for atom in residue.atoms() if atoms(atom)] if chosen(residue) else []
    if isinstance(atoms, str) or not atoms:
        raise ValueError('rigidBodies: atoms must be a function(atom) -> bool or a non-empty list of atom names, '
                         'got %r' % (atoms,))
    names = list(atoms)
    return lambda residue: _byNames(residue, names) if chosen(residue) else []


def _byNames(residue, names):
    if names is None:
        return []
    byName = {atom.name: atom for atom in residue.atoms()}
    missing = [name for name in names if name not in byName]
    if missing:
        raise ValueError('rigidBodies: residue %s %d (chain %s) has no atom named %s; its atoms are %s'
                         % (residue.name, residue.index, residue.chain.id, ', '.join(missing),
                            ', '.join(byName)))
    return [byName[name] for name in names]


def rigidBodies(topology, system, select='water', atoms=None, group='residue'):
    """The rigid bodies of the chosen atoms, each made of its massive atoms (virtual sites such
    as TIP4P's M site are left out: they follow their parents; so are the Drude particles of a
    DrudeForce, which move relative to their cores, e.g. SWM4-NDP's or charmm_polar_2019's).

    Parameters
    ----------
    topology : openmm.app.Topology
    system : openmm.System
        the System created from that Topology (for masses and virtual sites)
    select : 'water', a residue name, a list of names, a function(residue) -> bool, or a dict
        which residues are rigid. A dict maps residue names to the atom names that are rigid in
        each residue of that name, e.g. {'PHE': ['CG', 'CD1', 'HD1', ...]} (a residue that lacks
        one of them is an error). Every other atom stays free (flexible, with whatever
        constraints the System gives it, e.g. constraints=HBonds)
    atoms : None, a list of atom names, or a function(atom) -> bool
        which atoms of the selected residues are rigid (None: all of them)
    group : 'residue', 'chain' or 'all'
        one body per residue (the default), one body of the chosen atoms of each chain (e.g. a
        protein domain chosen by residue index), or one body of every chosen atom

    The integrator checks every particle of the bodies when it is bound to a Context: a
    constraint joining a body to an atom outside it (constraints=HBonds and a body that takes a
    carbon but not its hydrogen) is refused with an OpenMMException naming the particle.

    Returns
    -------
    list of lists of int
        one list of atom indices per body (bodies of fewer than two massive atoms are dropped,
        they would be free particles), for RigidBodyIntegrator.addRigidBody()
    """
    if topology.getNumAtoms() != system.getNumParticles():
        raise ValueError('rigidBodies: the Topology has %d atoms and the System %d particles'
                         % (topology.getNumAtoms(), system.getNumParticles()))
    if group not in GROUPINGS:
        raise ValueError('rigidBodies: group must be one of %s, got %r' % (', '.join(GROUPINGS), group))
    chosenAtoms = _atomSelector(select, atoms)
    drudeParticles = _drudeParticles(system)
    groups = {}
    for residue in topology.residues():
        key = residue.index if group == 'residue' else residue.chain.index if group == 'chain' else 0
        members = [atom.index for atom in chosenAtoms(residue)
                   if system.getParticleMass(atom.index).value_in_unit(unit.dalton) > 0
                   and not system.isVirtualSite(atom.index) and atom.index not in drudeParticles]
        groups.setdefault(key, []).extend(members)
    bodies = [sorted(members) for key, members in sorted(groups.items()) if len(members) >= 2]
    if not bodies:
        raise ValueError('rigidBodies: no residue or atom of the Topology was selected by select=%r, atoms=%r'
                         % (select, atoms))
    return bodies


def _drudeParticles(system):
    """The Drude particles of the System's DrudeForces (none where OpenMM has no Drude plugin)."""
    return {drude for drude, core in drudePairs(system)}


def declareRigidBodies(integrator, topology, system, select='water', atoms=None, group='residue'):
    """Declare rigidBodies(topology, system, select, atoms, group) on a rigid-body integrator
    (before it is bound to a Context): only those atoms are rigid. Returns the number of bodies."""
    bodies = rigidBodies(topology, system, select, atoms, group)
    for body in bodies:
        integrator.addRigidBody(body)
    return len(bodies)
