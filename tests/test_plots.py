"""Plots an ACS engineer reads at a glance (issue 12 §5), from a bag of a short acquisition to capture.

Every time plot marks the mode transitions and the capture (labelled vertical lines at the
summary's times), the rate plots carry the Mode 1B thresholds, the moment plots ± the maximum
moment, the sun-angle plot the 10° capture cone; its curve (from the attitude and the scenario's
sun) agrees with arccos B33 of the truth direction cosines; titles name the scenario and the run;
``--format`` writes PNG, SVG or PDF.
"""

from __future__ import annotations

import dataclasses
import math

import matplotlib.pyplot as plt
import numpy as np
import pytest
from acds_cli.bag.plots import figures, make_plots
from acds_common import topics
from acds_common.scenario import load_scenario
from acds_runtime.bag.reader import open_bag
from acds_runtime.bag.writer import BagError, typestore
from acds_runtime.direct import DirectRun


@pytest.fixture(scope='module')
def acquisition(tmp_path_factory):
    """A direct-engine bag of heao_b_acquisition_short (Mode 1A → 1B → capture in ~200 steps) and its summary."""
    bag = tmp_path_factory.mktemp('plots') / 'bag'
    result = DirectRun(load_scenario('heao_b_acquisition_short'), record=bag).run()
    return bag, result.summary


def _event_lines(ax) -> list[float]:
    return sorted(line.get_xdata()[0] for line in ax.lines if line.get_label().startswith('_event'))


def _hline_levels(ax) -> set[float]:
    return {round(float(line.get_ydata()[0]), 9) for line in ax.lines
            if len(set(line.get_ydata())) == 1 and not line.get_label().startswith('_event')}


def test_every_time_plot_marks_transitions_capture_and_limits(acquisition):
    bag_path, summary = acquisition
    events = [tr['t_min'] for tr in summary['mode_transitions']]
    assert [tr['to'] for tr in summary['mode_transitions']] == ['mode_1b', 'capture']
    figs = dict(figures(open_bag(bag_path)))
    try:
        assert {'fig_4-14_direction_cosines', 'fig_4-15_roll_response', 'fig_4-16_pitch_response',
                'fig_4-17_yaw_response', 'fig_4-18_magnetics', 'sun_angle', 'mode_timeline'} <= set(figs)
        for stem, fig in figs.items():
            title = fig._suptitle.get_text()
            assert 'heao_b_acquisition_short' in title and f'run {bag_path.name}' in title, (stem, title)
            for ax in fig.axes:
                assert _event_lines(ax) == pytest.approx(events), stem
            labels = {t.get_text().strip() for t in fig.axes[0].texts}
            assert {'mode_1b', 'capture'} <= labels, (stem, labels)
        thresholds = (0.573, 0.115, 0.115)
        for stem, limit in zip(('fig_4-15_roll_response', 'fig_4-16_pitch_response', 'fig_4-17_yaw_response'),
                               thresholds, strict=True):
            rate_ax, *_, moment_ax = figs[stem].axes
            assert _hline_levels(rate_ax) == {limit, -limit}, stem
            assert _hline_levels(moment_ax) == {2000.0, -2000.0}, stem
        sun_ax = figs['sun_angle'].axes[0]
        assert _hline_levels(sun_ax) == {10.0}
        t_min, angle = (np.asarray(a) for a in (sun_ax.lines[0].get_xdata(), sun_ax.lines[0].get_ydata()))
        bag = open_bag(bag_path)
        b33 = np.array([typestore().deserialize_cdr(d, bag.types[topics.resolve(topics.TRUTH_SUN_COSINES)]).vector.z
                        for _t, d in ((t, d) for _topic, t, d in bag.messages([topics.TRUTH_SUN_COSINES]))])
        assert angle == pytest.approx(np.degrees(np.arccos(np.clip(b33, -1, 1))), abs=1e-6)
        at_capture = angle[np.argmin(np.abs(t_min - events[1]))]
        assert at_capture < 10.0, at_capture
        assert math.isclose(angle[0], 10.0, abs_tol=0.5)  # the scenario starts 10° off the sun
    finally:
        for fig in figs.values():
            plt.close(fig)


@pytest.mark.parametrize(('fmt', 'magic'), [('png', b'\x89PNG'), ('svg', b'<?xml'), ('pdf', b'%PDF')])
def test_plot_format(acquisition, tmp_path, fmt, magic):
    paths = make_plots(acquisition[0], tmp_path / fmt, fmt)
    assert paths and all(p.suffix == f'.{fmt}' and p.read_bytes().startswith(magic) for p in paths)


def test_unknown_format_is_refused_before_reading(tmp_path):
    with pytest.raises(BagError, match='choose one of png, svg, pdf'):
        make_plots(tmp_path / 'no_bag', tmp_path / 'out', 'jpg')
    assert not (tmp_path / 'out').exists()


def test_long_series_are_gathered_at_a_common_stride_and_the_modes_whole(acquisition):
    """Bounded plotting memory: at most ~max_steps steps per numeric series, the same steps on every topic
    (series combine at common stamps), every mode message kept."""
    from acds_cli.bag.plots import _gather
    from acds_runtime.bag.reader import open_bag

    bag = open_bag(acquisition[0])
    vectors = {topics.GYRO: lambda m: [m.angular_velocity.x], topics.WHEEL_MOMENTUM: lambda m: [m.vector.x]}
    texts = {topics.MODE: lambda m: m.status[0].message if m.status else ''}
    full = _gather(bag, vectors, texts)
    part = _gather(bag, vectors, texts, max_steps=20)
    dt = bag.control_period_ns
    longest = max(bag.count(t) for t in vectors)
    stride = -(-longest // 20)
    assert stride > 1
    for topic in map(topics.resolve, vectors):
        kept = list(part[topic][0])
        assert kept == [t for t in full[topic][0] if (t // dt) % stride == 0]
        assert 0 < len(kept) <= 21
        assert list(part[topic][1]) == [v for t, v in zip(full[topic][0], full[topic][1], strict=True)
                                        if (t // dt) % stride == 0]
    gyro, wheels = (set(part[topics.resolve(t)][0]) for t in vectors)
    assert gyro & wheels, 'the kept steps are common to both series'
    mode = topics.resolve(topics.MODE)
    assert list(part[mode][0]) == list(full[mode][0]) and part[mode][1] == full[mode][1]


#: Each mission's figures, by the name its package gives its plug-in (entry-point group acds.plots).
MISSION_FIGURES = {'cold_gas': {'cold_gas_thruster_raster', 'cold_gas_propellant_pressure', 'cold_gas_rates_sun_angle'},
                   'formation': {'emff_formation_plane', 'emff_dipoles'}, 'sss': {'sss_spin_rate_torque'},
                   'torque_rod': {'torque_rod_detumble'}}


@pytest.mark.parametrize(('scenario', 'name', 'missions'), [
    ('sss_a_pass_test', 'spin_run', {'sss'}),  # an SSS run by any name
    ('heao_b_acquisition_short', 'sss_lookalike', set()),  # an 'sss…' name does not make an SSS run
    ('oresat_detumble', 'rods', {'torque_rod'}),
    ('heao_b_acquisition_cold_gas_short', 'gas', {'cold_gas'}),
    ('emff_testbed_hold', 'pair', {'formation'}),
])
def test_mission_plots_are_plugins_chosen_by_the_nodes_that_ran_not_the_scenario_name(tmp_path, scenario, name,
                                                                                        missions):
    from acds_cli.bag import mission_plots
    from acds_cli.bag.plots import run_context

    sc = dataclasses.replace(load_scenario(scenario), name=name)
    DirectRun(sc, steps=min(60, sc.total_steps()), record=tmp_path / 'bag').run()
    bag = open_bag(tmp_path / 'bag')
    names = {p.module: p.name for p in mission_plots.plugins()}
    assert {names[m] for m in mission_plots.chosen(run_context(bag))} == missions
    assert set(MISSION_FIGURES) == set(names.values())
    figs = dict(figures(bag))
    try:
        drawn = {mission for mission, stems in MISSION_FIGURES.items() if stems & set(figs)}
        assert drawn == missions, sorted(figs)
        for mission in missions:
            assert MISSION_FIGURES[mission] <= set(figs), (mission, sorted(figs))
            assert all(name in figs[stem]._suptitle.get_text() for stem in MISSION_FIGURES[mission])
    finally:
        for fig in figs.values():
            plt.close(fig)


def test_formation_plane_draws_vehicles_that_run_no_node(tmp_path):
    """The airtrack's slider is a passive vehicle (no node of its own): its track and the baseline length to the
    electromagnet are still drawn (before: only the electromagnet's dot, and an empty baseline panel)."""
    DirectRun(load_scenario('emff_airtrack_unstable_open_loop'), steps=20, record=tmp_path / 'bag').run()
    figs = dict(figures(open_bag(tmp_path / 'bag')))
    try:
        ax_xy, ax_d = figs['emff_formation_plane'].axes
        assert {line.get_label() for line in ax_xy.lines if not line.get_label().startswith('_')} == {'magnet',
                                                                                                     'slider'}
        assert ax_d.get_ylabel() == '|r_slider − r_magnet|, m'
        baseline = ax_d.lines[0].get_ydata()
        assert len(baseline) == 21 and baseline[0] == pytest.approx(0.45)  # the scenario's 0.45 m start
    finally:
        for fig in figs.values():
            plt.close(fig)


def test_direct_engine_run_titles_name_its_run_folder(tmp_path):
    """``acds run --engine direct``: the plots' titles name the run folder, as the graph's do (before: ``run bag``,
    the bag folder's name)."""
    import subprocess
    import sys
    from pathlib import Path

    run = tmp_path / 'my_run'
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'run', 'heao_b_acquisition_short', '--steps', '10',
                           '--engine', 'direct', '--quiet', '--run-dir', str(run)], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[1], timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    bag = open_bag(run / 'bag')
    assert bag.info.get('run_id') == 'my_run'
    figs = dict(figures(bag))
    try:
        assert all('— run my_run' in fig._suptitle.get_text() for fig in figs.values())
    finally:
        for fig in figs.values():
            plt.close(fig)
