"""A mission is added by installing a package, with no edit in the runtime or the CLI (docs/architecture.md "Adding a mission").

``tests/fixtures/extra_mission_pkg`` lives outside ``ros_ws/src`` and nothing the workspace ships names it: a
peak-body-rate mission that declares, in its setup.py alone, a summary section with its report line
(``acds.summaries``), a figure (``acds.plots``) and a verb (``acds.verbs``). The test installs it into a
temporary folder (``pip install --target``, as ``test_extra_node_package.py`` installs a node package) and, in
a fresh process with that folder on ``PYTHONPATH``: the summary of a direct-engine run carries its keys (the
peak of |ω| the bag's truth odometry gives, computed here independently) while the truth digest stays the
recorded one; ``acds peak-rate`` prints its report line; ``acds plot`` draws its figure.

Bad input: a package whose plug-in declares a summary key, a verb or a plot name another package already
declares makes ``acds`` print one line naming both packages and exit 2, before any verb runs (three fixture
distributions written into a temporary folder: a dist-info with its entry points, and the module).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from acds_runtime.testing import install_outside

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / 'tests' / 'fixtures' / 'extra_mission_pkg'
SCENARIO = 'free_tumble_heao_b'
STEPS = 200  # the truth digests' prefix

RUN = textwrap.dedent('''
    import json, math, sys
    from pathlib import Path
    from acds_common import topics
    from acds_common.cdr import Codec
    from acds_common.scenario import load_scenario
    from acds_runtime.bag.reader import open_bag
    from acds_runtime.direct import DirectRun

    name, out, steps = sys.argv[1], Path(sys.argv[2]), int(sys.argv[3])
    summary = DirectRun(load_scenario(name), steps=steps, record=out / 'bag').run().summary
    odom = topics.resolve(topics.TRUTH_ODOMETRY)
    codec = Codec(topics.type_of(odom))
    rates = [codec.decode(data)[1].angular for topic, _t, data in open_bag(out / 'bag').messages() if topic == odom]
    json.dump({'summary': {k: v for k, v in summary.items() if k != 'wall_seconds'},
               'peak_deg_s': max(math.degrees(math.sqrt(sum(v * v for v in w))) for w in rates)},
              (out / 'result.json').open('w'))
''')


def _env(site: Path, tmp: Path) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(site), ROS_LOG_DIR=str(tmp / 'ros_log'), MPLBACKEND='Agg')


def _acds(env: dict[str, str], *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], env=env, capture_output=True, text=True,
                          timeout=600, check=False)


def test_a_mission_package_installed_outside_the_workspace_adds_its_summary_figure_and_verb(tmp_path):
    site = install_outside(FIXTURE, tmp_path)
    env = _env(site, tmp_path)
    proc = subprocess.run([sys.executable, '-c', RUN, SCENARIO, str(tmp_path), str(STEPS)], env=env,
                          capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = json.loads((tmp_path / 'result.json').read_text())
    summary = out['summary']
    recorded = json.loads((ROOT / 'tests' / 'data' / 'truth_digests.json').read_text())
    assert recorded['prefix_steps'] == STEPS
    assert summary['truth_digest'] == recorded['scenarios'][SCENARIO]['prefix_digest']
    assert summary['peak_body_rate_deg_s'] == pytest.approx(out['peak_deg_s'], rel=1e-12)
    assert 0 <= summary['peak_body_rate_min'] <= summary['sim_minutes']

    verb = _acds(env, 'peak-rate', SCENARIO, '--steps', str(STEPS))
    assert verb.returncode == 0, verb.stderr[-3000:]
    assert f'peak body rate {summary["peak_body_rate_deg_s"]:.4f} deg/s' in verb.stdout

    plot = _acds(env, 'plot', str(tmp_path / 'bag'), '--out', str(tmp_path / 'plots'))
    assert plot.returncode == 0, plot.stderr[-3000:]
    assert (tmp_path / 'plots' / 'peak_rate.png').is_file()


#: Fixture distributions that declare what a shipped package already declares: (entry-point group, module text,
#: the shipped package the line must name).
CLASHES = {
    'summary_key': ('acds.summaries', 'SUMMARY_KEYS = ("acquisition_time_min",)\n', 'heao_mission'),
    'verb': ('acds.verbs', 'def register(sub):\n    sub.add_parser("duty-curve")\n', 'heao_mission'),
    'plot': ('acds.plots', 'def applies(ctx):\n    return False\n', 'ascs_mode_manager'),
}


@pytest.mark.parametrize('kind', sorted(CLASHES))
def test_a_plug_in_declaring_what_another_package_declares_is_one_line_and_exit_2(tmp_path, kind):
    group, text, shipped = CLASHES[kind]
    site = tmp_path / 'site'
    (site / 'acds_clash').mkdir(parents=True)
    (site / 'acds_clash' / '__init__.py').write_text(text)
    info = site / 'acds_clash-0.1.0.dist-info'
    info.mkdir()
    (info / 'METADATA').write_text('Metadata-Version: 2.1\nName: acds_clash\nVersion: 0.1.0\n')
    name = 'sss' if kind == 'plot' else 'clash'  # a plot name is its entry-point name: the SSS figures' name
    (info / 'entry_points.txt').write_text(f'[{group}]\n{name} = acds_clash\n')
    proc = _acds(_env(site, tmp_path), 'scenarios')
    assert proc.returncode == 2, proc.stdout[-2000:] + proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and shipped in lines[0] and 'acds_clash' in lines[0], proc.stderr
    assert not proc.stdout


def test_the_workspace_does_not_know_the_fixture_mission():
    """The proof means something: no shipped file names the fixture's package, keys or verb."""
    shipped = [p for base in ('ros_ws/src', 'scripts', 'scenarios') for p in (ROOT / base).rglob('*')
               if p.is_file() and p.suffix in ('.py', '.sh', '.cfg', '.yaml', '.xml', '')]
    for path in shipped:
        text = path.read_text(errors='replace')
        assert not any(w in text for w in ('acds_extra_mission', 'peak_body_rate', 'peak-rate')), path
