"""The thermostats' validation benchmark (benchmarks/python/suite/thermostats.py and its rows in
suite/equipartition.py): a few steps of a thermostat run through the equipartition table, and the
follow-up studies' tables (step sizes, density) from rows whose differences are known."""
import math
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, 'benchmarks', 'python'))
from suite import equipartition, thermostats  # noqa: E402


def test_a_thermostat_row_of_the_equipartition_table():
    system, positions, bodies = thermostats.water()
    start = equipartition.equilibrate(system, positions, 0.004, threads=1)
    rows = equipartition.run_one('TIP3P', system, bodies, start, 'M-RATTLE CSVR', 2, 0.0, 0.04, 4, threads=1)
    assert [r['method'] for r in rows] == ['M-RATTLE CSVR']
    row = rows[0]
    assert row['failure'] is None
    assert 200 < row['Ttrans'][0] < 400 and 200 < row['Trot'][0] < 400
    assert math.isfinite(row['drift'])
    md = equipartition.report(rows, {'TIP3P': len(bodies)}, True, 0.004, 0.0, 0.04, 4, 1)
    assert any(line.startswith('| TIP3P | 2 | M-RATTLE CSVR |') for line in md)
    # The thermostats run at every step of the table for TIP3P only.
    assert ('M-RATTLE Nose-Hoover chain', 5) in equipartition.model_runs('TIP3P')
    assert not [run for run in equipartition.model_runs('SPC/E') if run[0] in equipartition.THERMOSTATS]
    assert {run[0] for run in equipartition.model_runs('TIP3P', equipartition.THERMOSTATS)} == \
        set(equipartition.THERMOSTATS)


def sampled(method, step_fs, potential, se=0.03):
    kT = thermostats.langevin.KB * thermostats.TEMPERATURE
    return dict(method=method, step_fs=step_fs, ps=20.0, potential_per_molecule=potential,
                potential_per_molecule_se=se, kinetic_mean=0.5 * 5367 * kT, kinetic_mean_se=1.0)


def test_step_size_table_is_against_langevin_middle_pooled_over_its_steps():
    rows = [sampled('M-RATTLE CSVR', 2, -40.0), sampled('M-RATTLE Nose-Hoover chain', 2, -40.0),
            sampled('LangevinMiddle + SETTLE', 2, -40.1), sampled('LangevinMiddle + SETTLE', 1, -40.3)]
    md = thermostats.report_step_sizes(rows, 5367, 0.0)
    assert '-40.200 +- 0.021 kJ/mol' in md[1]  # (-40.1 - 40.3) / 2, 0.03 / sqrt(2)
    csvr = [line for line in md if line.startswith('| M-RATTLE CSVR | 2 |')][0]
    assert '| 300.0 +- 0.0 |' in csvr
    assert csvr.endswith('| +0.200 +- 0.037 (+5.4) |')
    assert any(line.startswith('\nThe two thermostats pooled at each step') and '2 fs +0.200 +- 0.030 (+6.7 SE)' in line
               for line in md)
    assert thermostats.pooled(rows[:2]) == pytest.approx((-40.0, 0.03 / math.sqrt(2)))


def test_density_table_differences():
    rows = [dict(method='M-RATTLE Nose-Hoover chain', step_fs=2, ps=40.0, discarded_ps=4.0, density=0.990,
                 density_se=0.003, potential_per_molecule=-40.0, potential_per_molecule_se=0.02, T=300.0, T_se=0.5),
            dict(method='LangevinMiddle + SETTLE', step_fs=2, ps=40.0, discarded_ps=4.0, density=0.986,
                 density_se=0.004, potential_per_molecule=-40.1, potential_per_molecule_se=0.02, T=299.0, T_se=0.5),
            dict(method='M-RATTLE CSVR', step_fs=2, ps=40.0, discarded_ps=4.0, failure='energy not finite')]
    md = thermostats.report_density(rows)
    assert any(line.startswith('| M-RATTLE Nose-Hoover chain | 0.9900 +- 0.0030 | +0.0040 +- 0.0050 (+0.8) |')
               for line in md)
    assert any(line.startswith('| M-RATTLE CSVR | failed: energy not finite') for line in md)
    assert thermostats.combined(rows[0], rows[1], 'density', 'density_se') == pytest.approx((0.004, 0.005, 0.8))


def test_step_squared_fit_recovers_a_known_line():
    points = [dict(step_fs=h, potential_per_molecule=-40.0 + 0.01 * h * h, potential_per_molecule_se=0.02)
              for h in (0.5, 1, 2)]
    (u0, u0_se), (c, c_se), chi2, dof = thermostats.fit_step_squared(points)
    assert (u0, c, chi2, dof) == (pytest.approx(-40.0), pytest.approx(0.01), pytest.approx(0, abs=1e-12), 1)
    assert 0 < u0_se < 0.02 and 0 < c_se < 0.02
