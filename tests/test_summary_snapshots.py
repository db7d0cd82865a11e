"""Every shipped scenario's summary keeps its content when code moves (the summaries' safety net, beside
``test_truth_digests.py``'s truth).

``tests/data/summary_snapshots.json`` holds, per shipped scenario, the summary of its first
:data:`STEPS` steps on the direct engine (every key but ``wall_seconds``, as strict JSON: non-finite numbers
are ``null``, :func:`acds_runtime.summary.summary_json`) and the text its summary modules print
(:func:`acds_runtime.summary.print_tables`, the report lines). A refactor that moves a summary, a report
line or a plot between packages leaves both as they are; the test names the scenario and the first key that
differs.

A summary changed on purpose: record again with ``.venv/bin/python tests/test_summary_snapshots.py NAME ...``
(every scenario when none is named) and say why in the commit.
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
from pathlib import Path

import pytest
from acds_common.plugins import KEYS_ATTRIBUTE, SUMMARIES, plugins
from acds_common.scenario import SCENARIO_DIR, load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.summary import COMMON_KEYS, print_tables, summary_json

DATA = Path(__file__).resolve().parent / 'data' / 'summary_snapshots.json'
#: Steps of each snapshot run: short (the whole file records in about a minute), long enough that every
#: mission's summary has values.
STEPS = 300


def snapshot(name: str) -> dict:
    """The summary (without ``wall_seconds``) and the printed tables of ``name``'s first :data:`STEPS` steps."""
    sc = load_scenario(name)
    summary = DirectRun(sc, steps=min(STEPS, sc.total_steps())).run().summary
    summary.pop('wall_seconds')
    tables = io.StringIO()
    with contextlib.redirect_stdout(tables):
        print_tables(summary)
    return {'summary': json.loads(summary_json(summary)[0]), 'tables': tables.getvalue()}


def _first_difference(a, b, where: str = '') -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in list(a) + [k for k in b if k not in a]:
            if key not in a or key not in b:
                return f'{where}.{key}: only in {"recorded" if key in a else "now"}'
            diff = _first_difference(a[key], b[key], f'{where}.{key}')
            if diff:
                return diff
        if list(a) != list(b):
            return f'{where}: key order {list(a)} != {list(b)}'
        return None
    return None if a == b else f'{where}: recorded {a!r}, now {b!r}'


RECORDED: dict = json.loads(DATA.read_text()) if DATA.exists() else {}


def test_every_shipped_scenario_is_recorded():
    assert sorted(RECORDED) == sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml'))


def test_every_summary_key_is_declared():
    """Every key of every recorded summary is the runtime's own or one a summary plug-in declares
    (``SUMMARY_KEYS``: what the one-line conflict check between packages compares)."""
    declared = set(COMMON_KEYS) | {k for p in plugins(SUMMARIES) for k in getattr(p.module, KEYS_ATTRIBUTE, ())}
    undeclared = {name: sorted(set(rec['summary']) - declared) for name, rec in RECORDED.items()}
    assert not any(undeclared.values()), {n: keys for n, keys in undeclared.items() if keys}


@pytest.mark.parametrize('name', sorted(RECORDED))
def test_summary_unchanged(name):
    now = snapshot(name)
    diff = _first_difference(RECORDED[name]['summary'], now['summary'], 'summary')
    assert diff is None, f'{name}: {diff}'
    assert now['tables'] == RECORDED[name]['tables'], f'{name}: printed tables differ'


def record(names: list[str]) -> None:
    """Record (or re-record) the named scenarios, every one when none is named."""
    for name in names or sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml')):
        RECORDED[name] = snapshot(name)
        print(name, file=sys.stderr)
    DATA.write_text(json.dumps(dict(sorted(RECORDED.items())), indent=1, ensure_ascii=False) + '\n')


if __name__ == '__main__':
    record(sys.argv[1:])
