"""python -m mrattle.testInstallation lists the platforms with the plugin's kernels and finds each agreeing with Reference."""
import subprocess
import sys

import mrattle


def test_installation_check_passes_on_every_platform():
    result = subprocess.run([sys.executable, '-m', 'mrattle.testInstallation'], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Platforms with the plugin's kernels: " + ', '.join(mrattle.PLATFORMS) in result.stdout
    for name in mrattle.PLATFORMS:
        assert any(line.split()[:2] == [name, 'agrees'] for line in result.stdout.splitlines()), result.stdout
