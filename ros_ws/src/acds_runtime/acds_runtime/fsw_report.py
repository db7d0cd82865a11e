"""The report of a Monte Carlo study flown by the user's flight software: paired with the built-in law, and its timing.

Pairs. Sample K flown by the user's node and by the built-in node (direct engine, the same draws: common random
numbers). ``identical`` counts the pairs whose truth digests are equal (the same truth data bit for bit). Per
quantity, the percentiles of each side and of the per-sample difference (flight software − built-in), each with
the percentile-bootstrap interval of :func:`acds_runtime.dispersion_report.describe` (the same resampling,
seeded by the study seed and the quantity). The quantities are the summary's numeric scalar keys that vary
over the study (a key the same in every sample of both sides tells nothing); a time key (``*_min``) that is
None was not reached by the end of the run and is censored as in a dispersion study; a difference is over the
pairs where both sides have a value (``one_sided`` counts the others). The samples that differ most: the
largest difference of any quantity relative to the built-in side's median of it, named so ``acds run
--sample`` replays them.

Timing. Per sample, the run monitor's step time of each external node (:mod:`acds_runtime.external`: from the
arrival of the last input of step k to that of its outputs, DDS delivery included): p50, p99, max and the steps
over ``--deadline-ms``; over the study, each per-sample figure's median, 90th percentile and maximum over the
samples, the overruns in all, and the samples with the largest step time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .dispersion_report import Quantity, describe, percentile

#: Summary keys that describe the run rather than the flight: never compared.
NOT_COMPARED = ('steps', 'sim_minutes', 'wall_seconds', 'truth_messages')
#: Stream offset of the differences' bootstrap (the quantities themselves use 2·i and 2·i + 1).
DIFFERENCE_STREAM = 1000
#: Samples named as differing most, and as the slowest.
WORST = 3


def _numeric(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def compared_keys(pairs: Sequence[tuple[int, dict[str, Any], dict[str, Any]]]) -> list[str]:
    """The quantities of the pairs (module doc), in the summary's order."""
    keys: dict[str, set[Any]] = {}
    for _i, ours, theirs in pairs:
        for side in (ours, theirs):
            for k, v in side.items():
                if k not in NOT_COMPARED and 'wall' not in k and (v is None or _numeric(v)):
                    keys.setdefault(k, set()).add(v)
    numeric = {k for k, vs in keys.items() if any(_numeric(v) for v in vs)}
    return [k for k in keys if k in numeric and len(keys[k]) > 1]


def _quantity(key: str) -> Quantity:
    return Quantity(key, key, '', 'all', key.endswith('_min'))


def paired(pairs: Sequence[tuple[int, dict[str, Any], dict[str, Any]]], seed: int) -> dict[str, Any]:
    """``{'pairs', 'identical', 'failed', 'quantities': {key: {'built_in', 'flight_software', 'difference',
    'one_sided', 'max_abs_difference'}}, 'differ_most': [{'index', 'key', 'difference', 'relative'}]}`` (module
    doc); ``pairs``: (index, the flight software's summary, the built-in's)."""
    ok = [(i, a, b) for i, a, b in pairs if 'error' not in a and 'error' not in b]
    out: dict[str, Any] = {'pairs': len(pairs), 'compared': len(ok), 'failed': len(pairs) - len(ok),
                           'identical': sum(a.get('truth_digest') == b.get('truth_digest') for _i, a, b in ok),
                           'quantities': {}}
    score: dict[int, tuple[float, str, float]] = {}
    for n, key in enumerate(compared_keys(ok)):
        q = _quantity(key)
        diffs = [{key: a[key] - b[key] if _numeric(a.get(key)) and _numeric(b.get(key)) else None}
                 for _i, a, b in ok]
        stats = {'built_in': describe([b for _i, _a, b in ok], q, seed, 2 * n),
                 'flight_software': describe([a for _i, a, _b in ok], q, seed, 2 * n + 1),
                 'difference': describe(diffs, Quantity(key, key, '', 'all', False), seed, DIFFERENCE_STREAM + n),
                 'one_sided': sum((a.get(key) is None) != (b.get(key) is None) for _i, a, b in ok)}
        known = [abs(d[key]) for d in diffs if d[key] is not None]
        stats['max_abs_difference'] = max(known) if known else None
        out['quantities'][key] = stats
        scale = abs(stats['built_in'].get('p50') or 0.0) or 1.0
        for (i, a, b), d in zip(ok, diffs, strict=True):
            # reached by one side only: the largest difference there is
            rel = math.inf if (a.get(key) is None) != (b.get(key) is None) else abs(d[key] or 0.0) / scale
            if rel > score.get(i, (0.0, '', 0.0))[0]:
                score[i] = (rel, key, d[key])
    worst = sorted(score.items(), key=lambda kv: -kv[1][0])[:WORST]
    out['differ_most'] = [{'index': i, 'key': key, 'difference': d, 'relative': rel} for i, (rel, key, d) in worst]
    return out


def _num(v: float | None, spec: str = '.4g') -> str:
    return '—' if v is None else f'{v:{spec}}'


def _cell(stats: dict[str, Any]) -> str:
    """p5 / p50 / p95 and the p50's interval."""
    lo, hi = stats['interval']['p50']
    above = stats.get('censored_above')
    p = [(_num(stats[k]) if stats[k] is not None or above is None else f'>{above:.4g}') for k in ('p5', 'p50', 'p95')]
    return f'{p[0]} / {p[1]} / {p[2]} [{_num(lo)}, {_num(hi)}]'


def paired_table(stats: dict[str, Any]) -> list[str]:
    """The paired report as text lines (study units: each key's own, as its name says)."""
    lines = [f'identical in {stats["identical"]} of {stats["compared"]} (truth digest of the flight software\'s sample '
             'equal to the built-in\'s)' + (f'; {stats["failed"]} pair(s) with a failed side left out'
                                            if stats['failed'] else '')]
    if not stats['quantities']:
        return lines
    width = max(len(k) for k in stats['quantities'])
    lines.append(f'{"quantity":<{width}}  built-in p5 / p50 / p95 [p50 95 % CI]      flight software p5 / p50 / p95 '
                 '[CI]         difference (fsw − built-in) p5 / p50 / p95 [CI]   max |Δ|')
    for key, q in stats['quantities'].items():
        one = f'  ({q["one_sided"]} reached by one side only)' if q['one_sided'] else ''
        lines.append(f'{key:<{width}}  {_cell(q["built_in"]):<40}  {_cell(q["flight_software"]):<40}  '
                     f'{_cell(q["difference"]):<44}  {_num(q["max_abs_difference"])}{one}')
    return lines


def timing(records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Over the samples' ``{'index', 'timing': {instance: report}}``: per instance, the median, 90th percentile and
    maximum over the samples of each of p50/p99/max ms, the overruns, and the slowest samples (module doc)."""
    out: dict[str, Any] = {}
    by_node: dict[str, list[tuple[int, dict[str, Any]]]] = {}
    for rec in records:
        for inst, rep in (rec.get('timing') or {}).items():
            if rep:
                by_node.setdefault(inst, []).append((rec['index'], rep))
    for inst, reps in by_node.items():
        node: dict[str, Any] = {'samples': len(reps), 'steps': sum(r['steps'] for _i, r in reps)}
        for figure in ('p50_ms', 'p99_ms', 'max_ms'):
            vals = np.array([r[figure] for _i, r in reps], dtype=float)
            node[figure] = {'median': percentile(vals, 50), 'p90': percentile(vals, 90), 'max': float(vals.max())}
        deadlines = {r['deadline_ms'] for _i, r in reps if 'deadline_ms' in r}
        if deadlines:
            over = [(i, r['over_deadline']) for i, r in reps if r.get('over_deadline')]
            node.update(deadline_ms=sorted(deadlines), over_deadline=sum(n for _i, n in over),
                        samples_over=len(over), most_over=sorted(over, key=lambda x: -x[1])[:WORST])
        node['slowest'] = [{'index': i, 'max_ms': r['max_ms'], 'p99_ms': r['p99_ms']}
                           for i, r in sorted(reps, key=lambda ir: -ir[1]['max_ms'])[:WORST]]
        out[inst] = node
    return out


def timing_table(stats: dict[str, Any]) -> list[str]:
    """The study's timing as text lines."""
    lines = []
    for inst, node in stats.items():
        lines.append(f'{inst}: step time over {node["samples"]} samples ({node["steps"]:,} steps; run monitor: last '
                     'input of step k → its outputs, DDS delivery included; this machine\'s, not the data\'s)')
        lines.append(f'  {"per sample":<12}{"median":>10}{"p90":>10}{"max":>10}   (over the samples)')
        for figure in ('p50_ms', 'p99_ms', 'max_ms'):
            f = node[figure]
            lines.append(f'  {figure:<12}{_num(f["median"], ".3f"):>10}{_num(f["p90"], ".3f"):>10}'
                         f'{_num(f["max"], ".3f"):>10}')
        if 'deadline_ms' in node:
            most = ', '.join(f'sample {i} ({n})' for i, n in node['most_over']) or 'none'
            lines.append(f'  deadline {"/".join(f"{d:g}" for d in node["deadline_ms"])} ms: {node["over_deadline"]:,} '
                         f'of {node["steps"]:,} steps over, in {node["samples_over"]} of {node["samples"]} samples '
                         f'(most: {most})')
        lines.append('  slowest samples: ' + ', '.join(f'sample {s["index"]} (max {s["max_ms"]:.3f} ms, p99 '
                                                        f'{s["p99_ms"]:.3f} ms)' for s in node['slowest']))
    return lines
