"""Each example script runs (a few steps, in a temporary folder) and writes what it promises."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'examples')


def runExample(name, tmp_path, *arguments, output=True):
    command = [sys.executable, os.path.join(EXAMPLES, name)] + (['--output', str(tmp_path/'out')] if output else [])
    command += list(arguments)
    result = subprocess.run(command, cwd=str(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            universal_newlines=True, timeout=300, env=dict(os.environ, OPENMM_CPU_THREADS='1'))
    assert result.returncode == 0, result.stderr
    return result


@pytest.mark.parametrize('integrator', ['mrattle', 'splitting'])
def test_benzene_cluster(tmp_path, integrator):
    result = runExample('benzene_cluster.py', tmp_path, '--steps', '40', '--report-interval', '10',
                        '--platform', 'Reference', '--integrator', integrator)
    out = tmp_path/'out'
    assert sorted(os.listdir(str(out))) == ['cluster.pdb', 'energies.csv', 'energies.png', 'trajectory.dcd']
    with open(str(out/'energies.csv')) as stream:
        rows = list(csv.reader(stream))
    assert [int(row[0]) for row in rows[1:]] == [10, 20, 30, 40]
    assert os.path.getsize(str(out/'energies.png')) > 1000
    assert os.path.getsize(str(out/'trajectory.dcd')) > 4*324*3*4
    assert 'largest rigidity error' in result.stdout and 'ns/day' in result.stdout
    assert '100.0%' in result.stderr  # OpenMM's progress column
    # The rigidity error printed is tiny.
    line = [l for l in result.stdout.splitlines() if l.startswith('largest rigidity error')][0]
    assert float(line.split()[3]) < 1e-9


def test_benzene_cluster_rejects_bad_arguments(tmp_path):
    command = [sys.executable, os.path.join(EXAMPLES, 'benzene_cluster.py'), '--steps', '0']
    result = subprocess.run(command, cwd=str(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert result.returncode == 2 and b'must be positive' in result.stderr


def test_water_box(tmp_path):
    result = runExample('water_box.py', tmp_path, '--steps', '10', '--equilibration', '5', '--platform', 'CPU')
    assert '895 rigid molecules, 5367 degrees of freedom' in result.stdout
    assert os.path.isfile(str(tmp_path/'out'/'water.csv'))


def test_liquid_benzene(tmp_path):
    runExample('liquid_benzene.py', tmp_path, '--molecules', '27', '--cutoff', '0.7', '--steps', '20', '--platform', 'CPU')
    out = tmp_path/'out'
    for name in ('liquid_benzene.pdb', 'liquid_benzene.dcd', 'liquid_benzene.csv'):
        assert os.path.getsize(str(out/name)) > 0


def test_intra_body_speedup(tmp_path):
    result = runExample('intra_body_speedup.py', tmp_path, '--steps', '2', '--repeats', '1', '--liquid-molecules',
                        '27', '--liquid-cutoff', '0.7', output=False)
    rows = [line for line in result.stdout.splitlines() if line.endswith('x')]
    assert len(rows) == 4
    assert all(float(row.split()[-1].rstrip('x')) > 0 for row in rows)


def test_langevin_water(tmp_path):
    result = runExample('langevin_water.py', tmp_path, '--steps', '40', '--report-interval', '10', '--platform', 'CPU')
    out = tmp_path/'out'
    assert sorted(os.listdir(str(out))) == ['langevin_water.csv', 'langevin_water.png']
    with open(str(out/'langevin_water.csv')) as stream:
        rows = list(csv.reader(stream))
    assert [int(row[0]) for row in rows[1:]] == [10, 20, 30, 40]
    assert all(0.8 < float(row[4]) < 1.2 for row in rows[1:])  # density, g/mL
    assert os.path.getsize(str(out/'langevin_water.png')) > 1000
    assert '100.0%' in result.stderr and 'temperature' in result.stdout


def test_solvated_protein(tmp_path):
    result = runExample('solvated_protein.py', tmp_path, '--steps', '20', output=False)
    assert '2761 rigid waters' in result.stdout
    line = [l for l in result.stdout.splitlines() if l.startswith('temperature')][0]
    assert float(line.split('constraint error')[1].split()[0]) < 1e-5


@pytest.mark.parametrize('option', ['', '--flexible', '--gas'])
def test_polarizable_benzene(tmp_path, option):
    result = runExample('polarizable_benzene.py', tmp_path, '--quick', *([option] if option else []))
    name = 'polarizable_benzene_%s_%s' % ('flexible' if option == '--flexible' else 'rigid',
                                          'gas' if option == '--gas' else 'liquid')
    out = tmp_path/'out'
    assert sorted(os.listdir(str(out))) == [name + '.csv', name + '.pdb']
    with open(str(out/(name + '.csv'))) as stream:
        rows = list(csv.reader(stream))
    assert [int(row[0]) for row in rows[1:]] == [20, 30, 40]  # the production's reports, after 10 steps
    assert '100.0%' in result.stdout and 'potential energy per molecule' in result.stdout
    summary = {line[:32].strip(): line[32:].split() for line in result.stdout.splitlines() if line.startswith('  ')}
    assert ('density' in summary) == (option != '--gas')
    assert ('Drude temperature' in summary) == (option != '--flexible')
    if option != '--flexible':
        assert float(summary['largest rigidity error'][0]) < 1e-9


def test_polarizable_benzene_takes_2fs_steps_with_heavier_drude_particles(tmp_path):
    result = runExample('polarizable_benzene.py', tmp_path, '--quick', '--step-size', '2', '--drude-mass', '1.6')
    assert '2 fs steps' in result.stdout and '100.0%' in result.stdout
    summary = {line[:32].strip(): line[32:].split() for line in result.stdout.splitlines() if line.startswith('  ')}
    assert float(summary['largest rigidity error'][0]) < 1e-9
    assert 0 < float(summary['Drude temperature'][0]) < 30


#: Each example that takes --platform, with arguments for a few steps.
DEVICE_RUNS = [
    ('benzene_cluster.py', ['--steps', '10', '--report-interval', '5'], True),
    ('water_box.py', ['--steps', '4', '--equilibration', '2'], True),
    ('liquid_benzene.py', ['--molecules', '27', '--cutoff', '0.7', '--steps', '4'], True),
    ('langevin_water.py', ['--steps', '10', '--report-interval', '5'], True),
    ('solvated_protein.py', ['--steps', '4'], False),
]


@pytest.mark.parametrize('name,arguments,output', DEVICE_RUNS, ids=[run[0] for run in DEVICE_RUNS])
def test_examples_run_on_the_device(tmp_path, devicePlatform, name, arguments, output):
    """OpenMM's real inputs (tip3p.pdb, test.pdb) in the device's default precision, as a new user runs them."""
    runExample(name, tmp_path, *(arguments + ['--platform', devicePlatform.getName()]), output=output)


def test_rigid_ring(tmp_path):
    result = runExample('rigid_ring.py', tmp_path, '--steps', '40', '--platform', 'CPU', output=False)
    assert '4 phenylalanine rings of 11 atoms made rigid' in result.stdout
    rows = {line[:34].strip(): line[34:].split() for line in result.stdout.splitlines()
            if line.startswith(('flexible', 'rigid rings'))}
    assert sorted(rows) == ['flexible (VerletIntegrator)', 'rigid rings (MRattleIntegrator)']
    for values in rows.values():
        assert all(np.isfinite(float(v)) for v in values[:4])
    assert rows['rigid rings (MRattleIntegrator)'][4] != '-'  # the rings' translational / rotational temperatures
