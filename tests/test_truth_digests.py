"""Every shipped scenario keeps its truth: the safety net of refactors (issue 19, "Bit-identical").

``tests/data/truth_digests.json`` holds, per shipped scenario, the truth digest of the whole run on the
direct engine (``steps``, ``truth_digest``), of its first ``prefix_steps`` steps (``prefix_digest``),
and the wall time the whole run took when it was recorded (``wall_s``, direct engine, on the 2-core
machine shared by several engineers, before the open-graph redesign of issue 19).

* Every scenario's prefix is checked on the direct engine (a few seconds each).
* A scenario whose whole run took at most :data:`FULL_WALL_S` is checked whole; the longer ones (minutes
  each, the Workshop's 16 orbits, the SSS spin-up's 66,000 steps) only with ``ACDS_FULL_DIGESTS=1``
  (``ACDS_FULL_DIGESTS=1 .venv/bin/python -m pytest tests/test_truth_digests.py -n 2``; 203 s on 2 cores).
* The per-process graph gives the recorded prefix digest for one scenario of each graph shape that
  ``tests/test_engines.py`` does not run (formation, wheels only, magnetics bench, SSS without controller).

A scenario changed on purpose changes its digest: record the new one with
``.venv/bin/python tests/test_truth_digests.py NAME ...`` and say why in the commit.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import pytest
from acds_common.scenario import SCENARIO_DIR, load_scenario
from acds_runtime.direct import DirectRun

DATA = Path(__file__).resolve().parent / 'data' / 'truth_digests.json'
RECORDED = json.loads(DATA.read_text())
PREFIX = RECORDED['prefix_steps']
SCENARIOS: dict[str, dict] = RECORDED['scenarios']
#: Whole runs up to this wall time (as recorded) are checked by default.
FULL_WALL_S = 30.0
FULL = os.environ.get('ACDS_FULL_DIGESTS') == '1'
#: One scenario per graph shape test_engines.py does not run through the per-process graph.
GRAPH_SHAPES = ['emff_testbed_hold', 'free_tumble_heao_b', 'magnetics_bench_heao_b', 'sss_a_spin_up']


def _digest(name: str, prefix: bool = False) -> str:
    sc = load_scenario(name)
    return DirectRun(sc, steps=min(PREFIX, sc.total_steps()) if prefix else None).run().summary['truth_digest']


def test_every_shipped_scenario_is_recorded():
    assert sorted(SCENARIOS) == sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml'))
    assert all({'steps', 'truth_digest', 'prefix_digest', 'wall_s'} <= set(rec) for rec in SCENARIOS.values())


@pytest.mark.parametrize('name', sorted(SCENARIOS))
def test_prefix_digest(name):
    assert _digest(name, prefix=True) == SCENARIOS[name]['prefix_digest']


@pytest.mark.slow
@pytest.mark.parametrize('name', sorted(SCENARIOS))
def test_full_run_digest(name):
    rec = SCENARIOS[name]
    if rec['wall_s'] > FULL_WALL_S and not FULL:
        pytest.skip(f'{rec["wall_s"]:.0f} s recorded; ACDS_FULL_DIGESTS=1 runs it')
    assert _digest(name) == rec['truth_digest']


@pytest.mark.slow
@pytest.mark.parametrize('name', GRAPH_SHAPES)
def test_graph_prefix_digest(launch_graph, name):
    with launch_graph(name, steps=min(PREFIX, load_scenario(name).total_steps())) as graph:
        result = graph.wait()
    assert result.summary['truth_digest'] == SCENARIOS[name]['prefix_digest']


def record(names: list[str]) -> None:
    """Record (or re-record) the named scenarios, every one when none is named."""
    for name in names or sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml')):
        sc = load_scenario(name)
        t0 = time.monotonic()
        full = DirectRun(sc).run()
        SCENARIOS[name] = {'steps': full.steps, 'truth_digest': full.summary['truth_digest'],
                           'prefix_digest': _digest(name, prefix=True),
                           'wall_s': round(time.monotonic() - t0, 1)}
        DATA.write_text(json.dumps(RECORDED, indent=1, sort_keys=True) + '\n')
        print(name, SCENARIOS[name], flush=True)


if __name__ == '__main__':
    record(sys.argv[1:])
