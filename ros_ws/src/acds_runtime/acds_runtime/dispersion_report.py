"""Dispersion statistics and reports: percentiles with censoring, rank sensitivities, paired ratios (issue 11).

Rows. One per sample: its index and name, the drawn values (a vector key flattened to ``key[i]``),
the derived geometry at t0 (:func:`acds_runtime.sampling.initial_geometry`), and the run summary's
study columns in study units (minutes, ft-lb-sec, A·m²), as the summary plug-in that declares them reads them
(``study_row``, :data:`acds_common.plugins.STUDY_ROW_ATTRIBUTE`).

Censoring. A sample that has not reached an event when its run ends is *censored* at the run's
length, never dropped: for a time quantity its value is "> T" (T = the run's sim minutes), ordered
above every time that was reached. Percentiles use numpy's default ("linear", Hyndman–Fan type 7)
interpolation between order statistics with the censored values as +∞: a percentile whose
interpolation touches a censored value is not known and is reported as null (printed "> T", T the
shortest censoring time). The time quantities and their sample sets:

- time on magnetics only (separation → Mode 1B): every sample; censored if Mode 1B was not reached;
- acquisition time (separation → capture): every sample; censored if capture was not reached;
- time on wheels + magnetics (Mode 1B → capture): the samples that reached Mode 1B; censored if
  capture was not reached after it, at the run's length less its time on magnetics only.

Final stored wheel momentum is the Table 4-7 column *at capture*: its percentiles are over the
captured samples only (``n`` says how many). Peaks (wheel |h|, moment command) are over the whole
of every run. Failed runs (an error) are counted and listed, and take part in nothing.

Intervals. Each percentile has a percentile-bootstrap interval at :data:`CONFIDENCE_PCT` (the
samples that count resampled with replacement :data:`BOOTSTRAP_RESAMPLES` times from a generator
seeded by the study seed and the quantity, so a study's intervals are reproducible; censored values
stay +∞, so a bound that touches them is "> T"), and beside it the sample count that would make the
interval's full width the stated share of the percentile's value (``--target-width``, default
:data:`TARGET_WIDTH_PCT` %): a quantile estimate's error falls as 1/√n (its asymptotic variance is
p(1 − p)/(n f(x_p)²)), so n · (width / target)², rounded up.

Sensitivity. Spearman's rank correlation of acquisition time (and time on magnetics only) with each
drawn variable and each derived angle, censored samples ranked above every reached time (ties
averaged). With n samples, |ρ| > 1.96/√(n − 1) is unlikely (5 %) under no dependence. Drawn angles
(node RA, Greenwich angle, orbit phase) are circular: a ρ near 0 there does not exclude a
dependence; the derived geometry is what the physics acts through.

Paired ratios (common random numbers). For cases run on the same draws, the ratio case/reference of
each sample pair; the median ratio and a percentile-bootstrap 90 % interval (resampling the pairs,
:data:`BOOTSTRAP_RESAMPLES` times, from a generator seeded by the study seed). A pair where only the
case is censored has ratio +∞, only the reference censored 0 (the case was faster by an unknown
factor), both censored: dropped from the ratio and counted.
"""

from __future__ import annotations

import array
import csv
import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from acds_common.plugins import STUDY_ROW_ATTRIBUTE, SUMMARIES, modules

from .summary import summary_json

#: Percentiles reported for every quantity (the tails p0.1/p1/p99/p99.9 only where the samples allow:
#: :func:`samples_needed`).
PERCENTILES = (0.1, 1, 5, 10, 25, 50, 75, 90, 95, 99, 99.9)
#: Bootstrap resamples of the paired median ratio and of each percentile's interval.
BOOTSTRAP_RESAMPLES = 2000
#: Confidence of the interval on each percentile, %.
CONFIDENCE_PCT = 95.0
#: Default full width of the interval a study should reach, % of the percentile's value (module doc).
TARGET_WIDTH_PCT = 10.0
#: Spawn key of the bootstrap's generator under the study seed (sample streams use (index, ...)).
BOOTSTRAP_STREAM = 0xB0075
#: Time keys whose None means "not reached by the end of the run" (censored), and when the sample counts.
TIME_KEYS = ('time_magnetics_only_min', 'acquisition_time_min', 'time_wheels_magnetics_min')


@dataclass(frozen=True)
class Quantity:
    """A reported quantity: row key, label, study unit, which samples count, whether None means censored."""

    key: str
    label: str
    unit: str
    when: str  # 'all' | 'captured' | 'mode_1b'
    censored: bool


QUANTITIES = (
    Quantity('time_magnetics_only_min', 'time on magnetics only', 'min', 'all', True),
    Quantity('time_wheels_magnetics_min', 'time on wheels + magnetics', 'min', 'mode_1b', True),
    Quantity('acquisition_time_min', 'acquisition time', 'min', 'all', True),
    Quantity('final_wheel_momentum_ftlbs', 'final stored wheel momentum (at capture)', 'ft-lb-sec', 'captured',
             False),
    Quantity('peak_wheel_momentum_rss_ftlbs', 'peak wheel momentum |h|', 'ft-lb-sec', 'all', False),
    Quantity('peak_moment_am2', 'peak moment command (largest axis)', 'A·m²', 'all', False),
    Quantity('orbit_dipole_inclination_deg', 'orbit inclination to the dipole axis at t0', 'deg', 'all', False),
    Quantity('initial_h_b_angle_deg', 'angle between body momentum and B at t0', 'deg', 'all', False),
    Quantity('initial_sun_angle_deg', 'z-body to sun angle at t0', 'deg', 'all', False),
)
#: Quantities whose sensitivity to the drawn variables is reported.
SENSITIVITY_OF = ('acquisition_time_min', 'time_magnetics_only_min')


# ------------------------------------------------------------------------------------------ rows


def flatten(drawn: dict[str, Any]) -> dict[str, Any]:
    """Drawn values with each vector key split into ``key[i]`` columns."""
    out: dict[str, Any] = {}
    for key, value in drawn.items():
        if isinstance(value, list):
            out.update({f'{key}[{i}]': v for i, v in enumerate(value)})
        else:
            out[key] = value
    return out


def make_row(index: int, name: str, drawn: dict[str, Any], geometry: dict[str, Any],
             summary: dict[str, Any]) -> dict[str, Any]:
    """One sample's flat row (module doc): its index, name, draws and geometry, and the columns the summary plug-in
    that declares a study row (:data:`acds_common.plugins.STUDY_ROW_ATTRIBUTE`) reads from its summary."""
    row: dict[str, Any] = {'index': index, 'name': name, **flatten(drawn), **geometry}
    if 'error' in summary:
        row['error'] = summary['error']
        return row
    for module in modules(SUMMARIES):  # the summary's study columns, as the plug-in that declares them reads them
        if hasattr(module, STUDY_ROW_ATTRIBUTE):
            row.update(getattr(module, STUDY_ROW_ATTRIBUTE)(summary))
    return row


class Rows(Sequence[dict[str, Any]]):
    """The samples' rows (:func:`make_row`) held as columns: a column of floats (and None) as an array of float64,
    None as NaN (a row read from the journal has no NaN: JSON has none), any other column as a list; ``rows[i]``
    gives row ``i`` as :func:`make_row` made it (the same keys, values and types; its keys in the order the columns
    were first seen, so the rows' union of keys, ``samples.csv``'s header, is the same).
    About 0.5 kB a sample where a list of row dicts holds about 3 kB."""

    def __init__(self) -> None:
        self._columns: dict[str, Any] = {}
        #: Per float column, the rows that lack its key (a failed sample's row has no summary columns).
        self._absent: dict[str, set[int]] = {}
        self._n = 0

    def append(self, row: dict[str, Any]) -> None:
        """Add the next row."""
        for key, value in row.items():
            column = self._columns.get(key)
            if column is None:
                if _float(value):
                    column = self._columns[key] = array.array('d', [math.nan]) * self._n
                    self._absent[key] = set(range(self._n))
                else:
                    column = self._columns[key] = [_ABSENT] * self._n
            elif isinstance(column, array.array) and not _float(value):
                absent = self._absent.pop(key)
                column = self._columns[key] = [_ABSENT if i in absent else None if math.isnan(v) else v
                                               for i, v in enumerate(column)]
            column.append((math.nan if value is None else value) if isinstance(column, array.array) else value)
        for key, column in self._columns.items():
            if len(column) == self._n:  # a key this row lacks
                if isinstance(column, array.array):
                    column.append(math.nan)
                    self._absent[key].add(self._n)
                else:
                    column.append(_ABSENT)
        self._n += 1

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, i: int) -> dict[str, Any]:  # type: ignore[override]
        if not -self._n <= i < self._n:
            raise IndexError(i)
        i %= self._n
        row = {}
        for key, column in self._columns.items():
            v = column[i]
            if isinstance(column, array.array):
                if i not in self._absent[key]:
                    row[key] = None if math.isnan(v) else v
            elif v is not _ABSENT:
                row[key] = v
        return row


    def column(self, key: str) -> list[Any]:
        """Every row's value of ``key``, None where it is None or missing (``row.get(key)`` of each row)."""
        column = self._columns.get(key)
        if column is None:
            return [None] * self._n
        if isinstance(column, array.array):
            return [None if math.isnan(v) else v for v in column]
        return [None if v is _ABSENT else v for v in column]


#: A key a row does not have, in a list column.
_ABSENT = object()


def column(rows: Sequence[dict[str, Any]], key: str) -> list[Any]:
    """``row.get(key)`` of every row; from the column itself when the rows are :class:`Rows` (no row built)."""
    return rows.column(key) if isinstance(rows, Rows) else [row.get(key) for row in rows]


def ran(rows: Sequence[dict[str, Any]]) -> list[int]:
    """The positions of the rows whose sample ran (no ``error``: a failed run takes part in no statistic)."""
    return [i for i, e in enumerate(column(rows, 'error')) if e is None]


def _float(value: Any) -> bool:
    """A value a float64 column holds as it is: a float, or None."""
    return value is None or type(value) is float


def values_of(rows: Sequence[dict[str, Any]], q: Quantity) -> tuple[np.ndarray, list[float]]:
    """The quantity's values over the samples that count (module doc), +∞ for censored, and the
    censoring times (run minutes) of the censored ones."""
    value, captured, mode_1b, magnetics, run_min = (column(rows, key) for key in (
        q.key, 'captured', 'mode_1b_reached', 'time_magnetics_only_min', 'sim_minutes'))
    vals, censor_at = [], []
    for i in ran(rows):
        if q.when == 'captured' and not captured[i]:
            continue
        if q.when == 'mode_1b' and not mode_1b[i]:
            continue
        v = value[i]
        if v is None and q.censored:
            vals.append(math.inf)
            # known only to exceed the time the run had left for it: from Mode 1B for the time on the wheels
            start = (magnetics[i] or 0.0) if q.when == 'mode_1b' else 0.0
            censor_at.append(run_min[i] - start)
        elif v is not None:
            vals.append(float(v))
    return np.array(vals, dtype=float), censor_at


# ------------------------------------------------------------------------------------ statistics


def _interpolate(sorted_rows: np.ndarray, p: float) -> np.ndarray:
    """Type-7 percentile ``p`` of each row of a row-sorted 2-D array; +∞ where it touches a censored value."""
    n = sorted_rows.shape[1]
    h = (n - 1) * p / 100.0
    lo, hi = math.floor(h), math.ceil(h)
    a, b = sorted_rows[:, lo], sorted_rows[:, hi]
    with np.errstate(invalid='ignore'):
        out = a + (h - lo) * (b - a)
    return np.where(np.isinf(b), math.inf, out)


def percentile(values: np.ndarray, p: float) -> float | None:
    """Percentile ``p`` of ``values`` (+∞ = censored), None when not known (module doc) or no values."""
    if len(values) == 0:
        return None
    v = float(_interpolate(np.sort(values)[None, :], p)[0])
    return v if math.isfinite(v) else None


#: Resampled values the bootstrap holds at once (2 MB; with their indices and sorted copy ~6 MB): the resamples are
#: drawn and reduced in blocks of rows.
BOOTSTRAP_BLOCK = 2**18


def _bootstrap(values: np.ndarray, seed: int, stream: tuple[int, ...], ps: Sequence[float]) -> dict[float, np.ndarray]:
    """Percentile ``p`` (each of ``ps``, :func:`_interpolate`) of each of :data:`BOOTSTRAP_RESAMPLES` resamples of
    ``values`` (with replacement); seeded by the study seed under ``(BOOTSTRAP_STREAM, *stream)``. Drawn in blocks
    of rows (:data:`BOOTSTRAP_BLOCK` values each; the generator gives the same numbers in blocks as at once), so the
    memory does not grow as resamples × samples (10,000 samples: 160 MB of indices and as much of values)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(BOOTSTRAP_STREAM, *stream)))
    n = len(values)
    rows = max(1, BOOTSTRAP_BLOCK // max(n, 1))
    parts: dict[float, list[np.ndarray]] = {p: [] for p in ps}
    for start in range(0, BOOTSTRAP_RESAMPLES, rows):
        block = np.sort(values[rng.integers(n, size=(min(rows, BOOTSTRAP_RESAMPLES - start), n))], axis=1)
        for p in ps:
            parts[p].append(_interpolate(block, p))
    return {p: np.concatenate(v) for p, v in parts.items()}


def samples_for_width(n: int, interval: Sequence[float | None], value: float | None, target_pct: float) -> int | None:
    """Samples that would bring the interval's full width to ``target_pct`` % of ``value`` (1/√n, module doc)."""
    lo, hi = interval
    if lo is None or hi is None or value is None or value == 0 or hi == lo:  # hi == lo: one value, any n will do
        return None
    return max(2, math.ceil(n * ((hi - lo) / (target_pct / 100 * abs(value))) ** 2))


def samples_needed(p: float) -> int:
    """The fewest samples for which percentile ``p`` is an estimate and not the extreme sample: at least one
    sample on each side of it, n ≥ 100 / min(p, 100 − p) (p1 and p99: 100; p0.1 and p99.9: 1,000). Below that
    the type-7 value is only the smallest (largest) sample, and the bootstrap cannot see past it either."""
    return math.ceil(round(100.0 / min(p, 100.0 - p), 6))


def describe(rows: Sequence[dict[str, Any]], q: Quantity, seed: int, stream: int,
             target_pct: float = TARGET_WIDTH_PCT) -> dict[str, Any]:
    """``{"p0.1": …, "p1": …, …, "p99.9": …, "n", "censored", "censored_above", "unit", "too_few": {"p0.1": 1000, …},
    "interval": {"p5": [lo, hi], …}, "samples_for_width": {"p5": N, …}, "confidence_pct", "target_width_pct"}`` of
    one quantity (module doc). A percentile the samples do not allow (:func:`samples_needed`) is null, named in
    ``too_few`` with the samples it needs, and has no interval."""
    vals, censor_at = values_of(rows, q)
    allowed = [p for p in PERCENTILES if len(vals) >= samples_needed(p)]
    out: dict[str, Any] = {f'p{p}': percentile(vals, p) if p in allowed else None for p in PERCENTILES}
    out.update(n=len(vals), censored=len(censor_at), censored_above=min(censor_at) if censor_at else None,
               unit=q.unit, too_few={f'p{p}': samples_needed(p) for p in PERCENTILES if p not in allowed})
    tail = (100.0 - CONFIDENCE_PCT) / 2
    boot = _bootstrap(vals, seed, (stream,), allowed) if len(vals) else {}
    intervals: dict[str, list[float | None]] = {}
    for p in PERCENTILES:
        dist = boot.get(p, np.array([]))
        intervals[f'p{p}'] = [percentile(dist, tail), percentile(dist, 100.0 - tail)]
    out['interval'] = intervals
    out['samples_for_width'] = {k: samples_for_width(len(vals), v, out[k], target_pct) for k, v in intervals.items()}
    out.update(confidence_pct=CONFIDENCE_PCT, target_width_pct=target_pct)
    return out


def percentiles(rows: Sequence[dict[str, Any]], seed: int, target_pct: float = TARGET_WIDTH_PCT
                ) -> dict[str, dict[str, Any]]:
    """:func:`describe` of every quantity the rows have."""
    return {q.key: describe(rows, q, seed, i, target_pct) for i, q in enumerate(QUANTITIES)
            if any(q.key in r for r in rows)}


def ranks(x: np.ndarray) -> np.ndarray:
    """Ranks 1…n, ties given their average rank (+∞ ties with +∞)."""
    order = np.argsort(x, kind='mergesort')
    r = np.empty(len(x))
    r[order] = np.arange(1, len(x) + 1)
    xs = x[order]
    start = 0
    for i in range(1, len(x) + 1):
        if i == len(x) or xs[i] != xs[start]:
            if i - start > 1:
                r[order[start:i]] = (start + 1 + i) / 2.0
            start = i
    return r


def spearman(x: np.ndarray, y: np.ndarray) -> float | None:
    """Spearman's ρ of two equal-length arrays (None when either is constant or n < 3)."""
    if len(x) < 3:
        return None
    rx, ry = ranks(np.asarray(x, float)), ranks(np.asarray(y, float))
    rx, ry = rx - rx.mean(), ry - ry.mean()
    den = math.sqrt(float(rx @ rx) * float(ry @ ry))
    return float(rx @ ry) / den if den > 0 else None


def sensitivity(rows: Sequence[dict[str, Any]], drawn_columns: Sequence[str]) -> dict[str, dict[str, float | None]]:
    """{quantity: {variable: ρ}} over the samples that ran (module doc), strongest first."""
    ok = ran(rows)
    geometry = [q.key for q in QUANTITIES if q.unit == 'deg']
    out: dict[str, dict[str, float | None]] = {}
    for target in SENSITIVITY_OF:
        t = column(rows, target)
        y = np.array([math.inf if t[i] is None else float(t[i]) for i in ok])
        rhos = {}
        for key in [*drawn_columns, *geometry]:
            x = column(rows, key)
            if all(isinstance(x[i], (int, float)) and not isinstance(x[i], bool) for i in ok):
                rho = spearman(np.array([float(x[i]) for i in ok]), y)
                if rho is not None:
                    rhos[key] = rho
        out[target] = dict(sorted(rhos.items(), key=lambda kv: -abs(kv[1])))
    return out


def paired_ratio(case: np.ndarray, ref: np.ndarray, seed: int) -> dict[str, Any]:
    """Median of the paired ratios case/ref (+∞ = censored) and its bootstrap 90 % interval (module doc)."""
    ratios = []
    dropped = 0
    for c, r in zip(case, ref, strict=True):
        if math.isinf(c) and math.isinf(r):
            dropped += 1
        elif math.isinf(c) or (r == 0 and c > 0):
            ratios.append(math.inf)
        elif math.isinf(r):
            ratios.append(0.0)
        else:
            ratios.append(1.0 if c == r == 0 else c / r)
    x = np.array(ratios)
    out: dict[str, Any] = {'ratio_median': percentile(x, 50), 'ratio_ci90': [None, None], 'pairs': len(x),
                           'pairs_dropped': dropped}
    if len(x):
        medians = _bootstrap(x, seed, (), (50,))[50]
        out['ratio_ci90'] = [percentile(medians, 5), percentile(medians, 95)]
    return out


def pick_sample(rows: Sequence[dict[str, Any]], key: str, p: float) -> tuple[int, float]:
    """The sample whose ``key`` is nearest its ``p``-th percentile (ties: the lowest index), and that value.

    Raises ValueError when the percentile is censored or there is no value.
    """
    q = next((q for q in QUANTITIES if q.key == key), None)
    if q is None:
        raise ValueError(f'unknown quantity {key!r} (known: {", ".join(q.key for q in QUANTITIES)})')
    target = percentile(values_of(rows, q)[0], p)
    if target is None:
        raise ValueError(f'the {p:g}th percentile of {key} is not known (censored: the runs ended before it; '
                         'run longer or pick a lower percentile)')
    best = min((r for r in rows if 'error' not in r and r.get(key) is not None),
               key=lambda r: (abs(float(r[key]) - target), r['index']))
    return best['index'], target


def wilson_interval(k: int, n: int, confidence_pct: float = CONFIDENCE_PCT) -> tuple[float, float] | None:
    """Wilson score interval of a proportion k/n at ``confidence_pct`` (None without draws).

    (p̂ + z²/2n ± z·√(p̂(1 − p̂)/n + z²/4n²)) / (1 + z²/n), z the two-sided normal quantile: unlike the normal
    approximation it stays within [0, 1] and is not empty at k = n.
    """
    if n <= 0:
        return None
    from statistics import NormalDist

    z = NormalDist().inv_cdf(0.5 + confidence_pct / 200.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


# ------------------------------------------------------------------------------- not captured


#: The columns that say a sample's conditions and outcome in the not-captured list (report and print).
NOT_CAPTURED_COLUMNS = (('orbit_dipole_inclination_deg', 'orbit to dipole axis, deg', '.1f'),
                        ('initial_h_b_angle_deg', 'H vs B at t0, deg', '.1f'),
                        ('initial_sun_angle_deg', 'z to sun at t0, deg', '.1f'),
                        ('time_magnetics_only_min', 'Mode 1B at, min', '.1f'),
                        ('peak_wheel_momentum_rss_ftlbs', 'peak |h|, ft-lb-sec', '.2f'),
                        ('wheel_saturation_time_min', 'wheel at capacity at, min', '.1f'),
                        ('final_mode', 'final mode', 's'),
                        ('sim_minutes', 'run, min', '.0f'))


def not_captured(rows: Sequence[dict[str, Any]]) -> Iterator[dict[str, Any]]:
    """The samples that ran and did not reach acquisition capture (censored in the acquisition time), by index;
    each row built as it is asked for (a short study's samples may all be censored)."""
    index = column(rows, 'index')
    hits = [i for i, r in enumerate(rows) if 'error' not in r and 'acquisition_time_min' in r and not r.get('captured')]
    return (rows[i] for i in sorted(hits, key=index.__getitem__))


def failure_rate(rows: Sequence[dict[str, Any]]) -> tuple[int, int, tuple[float, float] | None]:
    """Not captured k of n samples that ran, and the Wilson interval of k/n (:func:`wilson_interval`)."""
    counted = [r.get('captured') for r in rows if 'error' not in r and 'acquisition_time_min' in r]
    k = sum(not c for c in counted)
    return k, len(counted), wilson_interval(k, len(counted))


def not_captured_lines(rows: Sequence[dict[str, Any]], drawn_columns: Sequence[str], explain: str) -> list[str]:
    """Markdown: how many samples did not capture (with the Wilson interval), and one table row each with its drawn
    conditions, geometry at t0 and outcome; ``explain`` is the command that replays one (``{index}`` in it)."""
    k, n, ci = failure_rate(rows)
    if not n:
        return []
    lines = [f'{k} of {n} samples did not reach acquisition capture by the end of their run '
             f'({100 * k / n:.2f} %, {CONFIDENCE_PCT:g} % Wilson interval {100 * ci[0]:.2f}–{100 * ci[1]:.2f} %).']
    if not k:
        return lines
    lines += ['', f'Each can be replayed and explained: `{explain}`.', '']
    heads = [label for _, label, _ in NOT_CAPTURED_COLUMNS]
    lines += ['| sample | ' + ' | '.join(heads) + ' | drawn |', '|' + '---|' * (len(heads) + 2)]
    for r in not_captured(rows):
        cells = ['—' if r.get(key) is None else format(r[key], spec) for key, _, spec in NOT_CAPTURED_COLUMNS]
        drawn = ', '.join(f'`{c}` {r[c]:.4g}' if isinstance(r.get(c), float) else f'`{c}` {r.get(c)}'
                          for c in drawn_columns)
        lines.append(f'| {r["index"]} | ' + ' | '.join(cells) + f' | {drawn} |')
    return lines


# ----------------------------------------------------------------------------------------- output


def _fmt(v: float | None, above: float | None, spec: str = '.1f', needs: int | None = None) -> str:
    if needs is not None:  # the samples do not allow this percentile (samples_needed)
        return f'n<{needs}'
    if v is None:
        return f'>{above:.4g}' if above is not None else '—'
    return format(v, spec)


def percentile_table(stats: dict[str, dict[str, Any]]) -> str:
    """The percentile table in study units (text): per quantity its percentiles, their bootstrap intervals and
    the samples that would narrow each interval to the target width."""
    cell = 15
    head = f'{"quantity":44s} {"unit":9s} {"n":>5s} {"cens":>4s} ' + ' '.join(f'{"p" + str(p):>{cell}s}'
                                                                           for p in PERCENTILES)
    some = next(iter(stats.values()), {})
    lines = [f'each percentile, below it its {some.get("confidence_pct", CONFIDENCE_PCT):g} % bootstrap interval and '
             f'the samples for an interval {some.get("target_width_pct", TARGET_WIDTH_PCT):g} % of the value wide; '
             '"n<N": too few samples for that tail (it needs N: one sample beyond it on each side)',
             head, '-' * len(head)]
    labels = {q.key: q.label for q in QUANTITIES}
    pad = ' ' * (44 + 9 + 5 + 4 + 3)
    for key, s in stats.items():
        spec = '.0f' if s['unit'] == 'A·m²' else '.2f' if s['unit'] == 'ft-lb-sec' else '.1f'
        above, few = s['censored_above'], s.get('too_few', {})
        lines.append(f'{labels[key]:44s} {s["unit"]:9s} {s["n"]:5d} {s["censored"]:4d} ' +
                     ' '.join(f'{_fmt(s[f"p{p}"], above, spec, few.get(f"p{p}")):>{cell}s}' for p in PERCENTILES))
        lines.append(f'{"  interval":{len(pad) - 1}s} ' + ' '.join(
            f'{"—" if f"p{p}" in few else "[" + _fmt(lo, above, spec) + ", " + _fmt(hi, above, spec) + "]":>{cell}s}'
            for p, (lo, hi) in ((p, s['interval'][f'p{p}']) for p in PERCENTILES)))
        lines.append(f'{"  samples for the target width":{len(pad) - 1}s} ' + ' '.join(
            f'{_fmt(s["samples_for_width"][f"p{p}"], None, "d"):>{cell}s}' for p in PERCENTILES))
    return '\n'.join(lines)


def write_rows(out: Path, rows: Sequence[dict[str, Any]], records: Iterable[dict[str, Any]]) -> None:
    """``samples.csv`` (flat rows) and ``samples.json`` (per sample: drawn values, geometry, full summary), the
    records written one at a time as they come (:func:`write_json_list`)."""
    columns: dict[str, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    with open(out / 'samples.csv', 'w', newline='') as fh:
        writer = csv.DictWriter(fh, fieldnames=list(columns), restval='')
        writer.writeheader()
        for row in rows:
            writer.writerow({k: '' if v is None else v for k, v in row.items()})
    write_json_list(out / 'samples.json', records)


def plot_distributions(out: Path, rows: Sequence[dict[str, Any]], stats: dict[str, dict[str, Any]]) -> list[Path]:
    """One PNG per quantity: histogram of the values reached and the empirical CDF over all that count
    (censored samples raise no step: the CDF ends below 1 by their share); and acquisition time against
    the orbit's inclination to the dipole axis."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    paths = []
    for q in QUANTITIES:
        if q.key not in stats or stats[q.key]['n'] == 0:
            continue
        vals, censor_at = values_of(rows, q)
        reached = np.sort(vals[np.isfinite(vals)])
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
        ax1.hist(reached, bins=max(5, min(30, int(math.sqrt(len(vals))) * 2)), color='tab:blue', edgecolor='white')
        ax1.set_xlabel(f'{q.label} [{q.unit}]')
        ax1.set_ylabel('samples')
        title = f'{len(vals)} samples'
        if censor_at:
            title += f'; {len(censor_at)} not reached by {min(censor_at):.0f} min (censored, not shown)'
        ax1.set_title(title, fontsize=9)
        y = np.arange(1, len(reached) + 1) / len(vals)
        ax2.step(reached, y, where='post', color='tab:blue')
        for p in (10, 50, 90):
            v = stats[q.key][f'p{p}']
            if v is not None:
                ax2.axvline(v, color='grey', lw=0.8, ls='--')
                ax2.text(v, 0.02 + p / 200, f' p{p}', fontsize=8, color='grey')
        ax2.set_ylim(0, 1)
        ax2.set_xlabel(f'{q.label} [{q.unit}]')
        ax2.set_ylabel('fraction of samples ≤ x')
        ax2.grid(alpha=0.3)
        fig.suptitle(q.label)
        fig.tight_layout()
        path = out / f'{q.key}.png'
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    inclination, acquisition, run_min = (column(rows, key) for key in (
        'orbit_dipole_inclination_deg', 'acquisition_time_min', 'sim_minutes'))
    ok = [i for i in ran(rows) if inclination[i] is not None]
    if ok and any('acquisition_time_min' in rows[i] for i in ok):
        fig, ax = plt.subplots(figsize=(6, 4))
        reached = [i for i in ok if acquisition[i] is not None]
        ax.scatter([inclination[i] for i in reached], [acquisition[i] for i in reached], s=12, label='captured')
        cens = [i for i in ok if acquisition[i] is None]
        if cens:
            ax.scatter([inclination[i] for i in cens], [run_min[i] for i in cens], s=18,
                       marker='^', color='tab:red', label='not captured (at run end)')
        ax.set_xlabel('orbit inclination to the dipole axis at t0 [deg]')
        ax.set_ylabel('acquisition time [min]')
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        path = out / 'acquisition_vs_inclination.png'
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def write_report(out: Path, spec: dict[str, Any], rows: Sequence[dict[str, Any]], stats: dict[str, dict[str, Any]],
                 sens: dict[str, dict[str, float | None]], plots: Sequence[Path],
                 failures: Sequence[str] = ()) -> Path:
    """``report.md``: what was drawn and run, the percentile table, the samples not captured (``failures``:
    :func:`not_captured_lines`), the plots, the rank sensitivities."""
    n_ok = sum('error' not in r for r in rows)
    lines = [f'# Monte Carlo dispersion of `{spec["scenario"]}`', '',
             f'- command: `{spec["command"]}`',
             f'- samples: {spec["runs"]} (seed {spec["seed"]}), {n_ok} ran, {len(rows) - n_ok} failed; engine '
             f'{spec["engine"]}; {spec["execution"]}; wall time {spec["wall_seconds"]:.0f} s',
             f'- run length: {spec["run_length"]}',
             '- drawn: ' + '; '.join(f'`{v}`' for v in spec['vary']),
             '- a sample is reproducible alone: `' + spec['rerun'].replace('{index}', 'K') + '` (K the sample index)',
             '',
             '## Percentiles (study units)', '',
             'Censored samples (event not reached when the run ended) count as longer than every reached time; '
             'a percentile that falls among them reads "> T" (null in `percentiles.json`). Final wheel momentum '
             'is over the captured samples, time on wheels + magnetics over those that reached Mode 1B.', '',
             '```', percentile_table(stats), '```', '']
    failed = [r for r in rows if 'error' in r]
    if failed:
        lines += ['## Failed samples', ''] + [f'- sample {r["index"]}: {r["error"].splitlines()[0]}' for r in failed]
        lines.append('')
    if failures:
        lines += ['## Samples not captured', '', *failures, '']
    lines += ['## Distributions', ''] + [f'![{p.stem}]({p.name})' for p in plots] + ['']
    band = 1.96 / math.sqrt(max(n_ok - 1, 1))
    lines += ['## Sensitivity (Spearman rank correlation)', '',
              f'|ρ| above {band:.2f} (1.96/√(n−1), n = {n_ok}) is unlikely without a dependence. Drawn angles are '
              'circular, so ρ ≈ 0 there does not exclude one; the derived angles at t0 are what the physics acts '
              'through. Censored samples rank above every reached time.', '']
    for target, rhos in sens.items():
        lines += [f'### {target}', '', '| variable | ρ |', '|---|---|']
        lines += [f'| `{k}` | {v:+.3f} |' for k, v in rhos.items() if v is not None]
        if not rhos:
            lines.append('| (none: the quantity has one value over every sample, e.g. all censored) | |')
        lines.append('')
    path = out / 'report.md'
    path.write_text('\n'.join(lines))
    return path


def write_json(path: Path, obj: Any) -> None:
    """Strict JSON, indented (a non-finite number as null, as every summary file)."""
    path.write_text(summary_json(obj)[0])


def write_json_list(path: Path, items: Iterable[Any]) -> None:
    """:func:`write_json` of a list, the same bytes, written an item at a time: the items may come from disk one
    by one (a study's samples), never all held."""
    with open(path, 'w') as fh:
        fh.write('[')
        sep = '\n  '
        for item in items:
            fh.write(sep + summary_json(item)[0][:-1].replace('\n', '\n  '))
            sep = ',\n  '
        fh.write(']\n' if sep == '\n  ' else '\n]\n')
