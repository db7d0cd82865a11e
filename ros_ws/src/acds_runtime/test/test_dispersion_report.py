"""Dispersion statistics (issue 11): censoring-aware percentiles, rank correlation, paired bootstrap, the pick rule."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_runtime import dispersion_report as dr

INF = math.inf


def _row(i, mag, acq, sim=100.0, **kw):
    return {'index': i, 'name': f's{i}', 'time_magnetics_only_min': mag, 'acquisition_time_min': acq,
            'time_wheels_magnetics_min': None if mag is None or acq is None else acq - mag,
            'captured': acq is not None, 'mode_1b_reached': mag is not None, 'sim_minutes': sim,
            'final_wheel_momentum_ftlbs': 1.0 if acq else 9.0, **kw}


def test_percentiles_match_numpy_and_a_censored_tail_is_unknown():
    x = np.array([3.0, 1.0, 4.0, 1.5, 9.0, 2.6, 5.0])
    for p in dr.PERCENTILES:
        assert dr.percentile(x, p) == pytest.approx(np.percentile(x, p))
    cens = np.array([3.0, 1.0, 4.0, INF, INF])  # two not reached
    assert dr.percentile(cens, 50) == 4.0  # sorted 1, 3, 4, ∞, ∞
    assert dr.percentile(cens, 70) is None  # interpolates toward a censored value
    assert dr.percentile(np.array([]), 50) is None


def test_describe_counts_censored_and_uses_the_right_sample_sets():
    rows = [_row(0, 10.0, 50.0), _row(1, 20.0, None, sim=80.0), _row(2, None, None, sim=90.0), _row(3, 5.0, 30.0),
            {'index': 4, 'name': 's4', 'error': 'boom'}]
    acq = dr.describe(rows, dr.QUANTITIES[2], 1, 2)
    assert (acq['n'], acq['censored'], acq['censored_above']) == (4, 2, 80.0)
    assert acq['p25'] == pytest.approx(np.percentile([30, 50, 1e9, 1e9], 25))
    assert acq['p75'] is None
    wheels = dr.describe(rows, dr.QUANTITIES[1], 1, 1)  # only samples that reached Mode 1B
    assert (wheels['n'], wheels['censored']) == (3, 1)
    final_h = dr.describe(rows, dr.QUANTITIES[3], 1, 3)  # only captured samples
    assert (final_h['n'], final_h['p50']) == (2, 1.0)
    assert set(acq) >= {f'p{p}' for p in dr.PERCENTILES}


def test_time_on_wheels_is_censored_at_the_time_the_run_left_it_on_the_wheels():
    """Time on wheels + magnetics runs from Mode 1B: a run of T min that reached Mode 1B at t_1B and no capture
    has spent only T − t_1B on the wheels, so its "> bound" is that, not T (it said "> 40" of a sample that
    could not have had more than 33.2 min on the wheels)."""
    rows = [_row(0, 0.5, 24.0, sim=40.0), _row(1, 6.8, None, sim=40.0), _row(2, 1.2, None, sim=40.0)]
    wheels = dr.describe(rows, dr.QUANTITIES[1], 1, 1)
    assert (wheels['n'], wheels['censored']) == (3, 2)
    assert wheels['censored_above'] == pytest.approx(40.0 - 6.8)
    acq = dr.describe(rows, dr.QUANTITIES[2], 1, 2)  # separation → capture: the whole run
    assert acq['censored_above'] == 40.0


def test_spearman_ranks_ties_and_censored_values():
    x = np.arange(10.0)
    assert dr.spearman(x, x ** 3) == pytest.approx(1.0)
    assert dr.spearman(x, -x) == pytest.approx(-1.0)
    assert dr.spearman(x, np.ones(10)) is None
    y = np.array([1, 2, 3, 4, 5, 6, 7, 8, INF, INF])
    assert dr.spearman(x, y) == pytest.approx(np.corrcoef(x, [1, 2, 3, 4, 5, 6, 7, 8, 9.5, 9.5])[0, 1])
    assert list(dr.ranks(np.array([2.0, 1.0, 2.0]))) == [2.5, 1.0, 2.5]


def test_paired_ratio_and_its_bootstrap_interval():
    rng = np.random.default_rng(3)
    ref = rng.uniform(50, 150, 40)
    case = ref * 1.3 * rng.uniform(0.95, 1.05, 40)
    out = dr.paired_ratio(case, ref, seed=5)
    assert out['ratio_median'] == pytest.approx(np.median(case / ref))
    lo, hi = out['ratio_ci90']
    assert lo < out['ratio_median'] < hi and 1.25 < lo and hi < 1.35
    assert dr.paired_ratio(case, ref, seed=5) == out  # seeded
    cens = dr.paired_ratio(np.array([INF, 10.0, INF, 20.0]), np.array([INF, INF, 5.0, 10.0]), seed=1)
    assert (cens['pairs'], cens['pairs_dropped']) == (3, 1)  # both censored: dropped; the others ordered
    assert cens['ratio_median'] == 2.0  # sorted ratios 0, 2, ∞


def test_pick_sample_is_nearest_the_percentile():
    rows = [_row(i, 1.0, float(t)) for i, t in enumerate([40, 10, 30, 20, 50, 60, 70, 80, 90, 100])]
    index, target = dr.pick_sample(rows, 'acquisition_time_min', 90)
    assert target == pytest.approx(np.percentile([10, 20, 30, 40, 50, 60, 70, 80, 90, 100], 90))
    assert rows[index]['acquisition_time_min'] == 90.0
    rows[9] = _row(9, 1.0, None)
    rows[8] = _row(8, 1.0, None)
    with pytest.raises(ValueError, match='censored'):
        dr.pick_sample(rows, 'acquisition_time_min', 90)


def test_a_tail_percentile_needs_a_sample_beyond_it_on_each_side():
    """p1/p99 need 100 samples, p0.1/p99.9 1,000: with fewer they are null, named in too_few, and have no interval."""
    assert [dr.samples_needed(p) for p in (0.1, 1, 5, 50, 95, 99, 99.9)] == [1000, 100, 20, 2, 20, 100, 1000]
    rng = np.random.default_rng(3)
    rows = [_row(i, 10.0, float(x)) for i, x in enumerate(rng.uniform(50, 150, 150))]
    acq = dr.describe(rows, dr.QUANTITIES[2], 1, 2)
    assert acq['p1'] == pytest.approx(np.percentile([r['acquisition_time_min'] for r in rows], 1))
    assert acq['p0.1'] is None and acq['p99.9'] is None and acq['too_few'] == {'p0.1': 1000, 'p99.9': 1000}
    assert acq['interval']['p99.9'] == [None, None] and None not in acq['interval']['p99']
    table = dr.percentile_table({'acquisition_time_min': acq})
    assert 'n<1000' in table and 'p99.9' in table


def test_the_samples_not_captured_are_listed_with_a_wilson_interval():
    rows = [_row(0, 10.0, 50.0, **{'orbit.raan_deg': 3.0}), _row(1, 20.0, None, sim=480.0, final_mode='mode_1b',
                                                                  **{'orbit.raan_deg': 7.5}),
            {'index': 2, 'name': 's2', 'error': 'boom'}]
    assert [r['index'] for r in dr.not_captured(rows)] == [1]
    k, n, ci = dr.failure_rate(rows)
    assert (k, n) == (1, 2) and ci == pytest.approx(dr.wilson_interval(1, 2))
    lines = dr.not_captured_lines(rows, ['orbit.raan_deg'], 'explain {index}')
    assert lines[0].startswith('1 of 2 samples did not reach acquisition capture')
    assert lines[-1].startswith('| 1 | ') and '| mode_1b |' in lines[-1] and '`orbit.raan_deg` 7.5' in lines[-1]


def _study_rows() -> list[dict]:
    """Rows of every kind a study has: captured, censored, not reaching Mode 1B, failed first and later, an int
    column beside float ones, a string column, a key only some rows have."""
    rng = np.random.default_rng(7)
    rows = [{'index': 0, 'name': 's0', 'seed': 12, 'x': 0.5, 'error': 'boom'}]
    for i in range(1, 300):
        mag = None if i % 17 == 0 else float(rng.uniform(40, 300))
        acq = None if mag is None or i % 11 == 0 else mag + float(rng.uniform(5, 80))
        rows.append(_row(i, mag, acq, sim=480.0, seed=int(rng.integers(0, 2**31 - 1)), x=float(rng.uniform()),
                         final_mode='mode_1b' if acq is None else 'capture', orbit_dipole_inclination_deg=float(i % 33),
                         **({'wheel_saturation_time_min': 12.5} if i % 5 == 0 else {})))
    rows.insert(150, {'index': 300, 'name': 's300', 'seed': 3, 'x': 0.25, 'error': 'diverged'})
    return rows


def test_rows_held_as_columns_give_back_every_row_and_the_same_statistics(tmp_path):
    rows = _study_rows()
    table = dr.Rows()
    for row in rows:
        table.append(row)
    assert len(table) == len(rows)
    for i, row in enumerate(rows):  # the same keys, values and types (keys in the order the columns came)
        assert table[i] == row and {k: type(v) for k, v in table[i].items()} == {k: type(v) for k, v in row.items()}
    assert dr.percentiles(table, 1) == dr.percentiles(rows, 1)
    assert dr.sensitivity(table, ['x', 'seed']) == dr.sensitivity(rows, ['x', 'seed'])
    assert dr.failure_rate(table) == dr.failure_rate(rows)
    assert dr.not_captured_lines(table, ['x'], 'e {index}') == dr.not_captured_lines(rows, ['x'], 'e {index}')
    (tmp_path / 'a').mkdir()
    (tmp_path / 'b').mkdir()
    records = [{'index': r['index'], 'summary': {'v': r.get('x'), 'nan': math.nan}} for r in rows]
    dr.write_rows(tmp_path / 'a', rows, records)
    dr.write_rows(tmp_path / 'b', table, iter(records))  # records streamed
    for name in ('samples.csv', 'samples.json'):
        assert (tmp_path / 'a' / name).read_bytes() == (tmp_path / 'b' / name).read_bytes(), name
    dr.write_json(tmp_path / 'list.json', records)
    assert (tmp_path / 'list.json').read_bytes() == (tmp_path / 'a' / 'samples.json').read_bytes()
    dr.write_json_list(tmp_path / 'empty.json', iter(()))
    assert (tmp_path / 'empty.json').read_text() == '[]\n'


def test_the_bootstrap_in_blocks_gives_the_numbers_of_one_block(monkeypatch):
    rows = _study_rows()
    case, ref = np.sqrt(np.arange(1.0, 40.0)), np.arange(2.0, 41.0)
    whole, ratio = dr.percentiles(rows, 5), dr.paired_ratio(case, ref, 5)
    monkeypatch.setattr(dr, 'BOOTSTRAP_BLOCK', 1000)  # 3 resamples a block of 299 values, the last block short
    assert dr.percentiles(rows, 5) == whole
    assert dr.paired_ratio(case, ref, 5) == ratio
