"""python -m mrattle.testInstallation lists the platforms with the plugin's kernels and finds each agreeing with
Reference for every deterministic integrator it runs (MRattleIntegrator, MRattleNoseHooverIntegrator, the Drude
Nose-Hoover one where OpenMM has its Drude plugin) and running the others (CSVR)."""
import subprocess
import sys

import mrattle
from mrattle.testInstallation import INTEGRATORS


def test_installation_check_passes_on_every_platform():
    result = subprocess.run([sys.executable, '-m', 'mrattle.testInstallation'], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'M-RATTLE plugin %s from ' % mrattle.__version__ in result.stdout
    assert "Platforms with the plugin's kernels: " + ', '.join(mrattle.PLATFORMS) in result.stdout
    lines = [line.split() for line in result.stdout.splitlines()]
    for integrator in ('MRattleIntegrator', 'MRattleNoseHooverIntegrator', 'MRattleBussiIntegrator'):
        assert integrator in [entry[0] for entry in INTEGRATORS]
    for entry in INTEGRATORS:
        assert [entry[0] + ':'] in lines, result.stdout
    deterministic = sum(entry[2] for entry in INTEGRATORS)
    for name in mrattle.PLATFORMS:
        # The deterministic integrators agree with Reference; CSVR (its own random numbers) runs.
        assert sum(line[:2] == [name, 'agrees'] for line in lines) == deterministic, result.stdout
        assert sum(line[:2] == [name, 'runs'] for line in lines) == len(INTEGRATORS) - deterministic, result.stdout
