"""The AAP Workshop CMG dump report of a recorded run (seed 000 §5), and its plot.

The report is the run summary's ``dump_report`` (:mod:`acds_controller.aap_summary`): the bag is read
read-only, in one streaming pass, by the same :class:`~acds_runtime.summary.RunObserver` the run monitor
and the direct engine feed, built from the scenario recorded in the bag, so a bag gives exactly the report
its run printed. The same pass keeps the few series the plot needs (|M| and orbital day per step, the
sampled H_s): the |M|(t) profile the seed's weights depend on (§5: "the wave shape of |M| vs time"), H_s at
each orbit's sample, and |ΔH_s| per orbit against |H_b| (the convergence when H_s starts from zero).
"""

from __future__ import annotations

from array import array
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from acds_common import topics, units
from acds_common.cdr import Codec
from acds_runtime.bag.reader import open_bag
from acds_runtime.bag.writer import BagError, check_out_dir

DIPOLE, COMMAND, SUN, H_S = (topics.resolve(t) for t in (topics.DIPOLE_AVG, topics.MOMENT_COMMAND, topics.SUN_SENSOR,
                                                          topics.SAMPLED_MOMENTUM))


@dataclass
class DumpSeries:
    """Per-step series for the plot: step times (s), |M| (A·m²), day (1/0)."""

    t_s: array = field(default_factory=lambda: array('d'))
    m_am2: array = field(default_factory=lambda: array('d'))
    day_t_s: array = field(default_factory=lambda: array('d'))
    day: array = field(default_factory=lambda: array('b'))


def check_workshop(scenario: Any, where: str = '') -> None:
    """BagError unless ``scenario`` is an AAP Workshop run (what the dump report reads)."""
    from acds_controller import aap_summary as aap

    if not aap.applies(scenario):
        raise BagError(f'{where}scenario {scenario.name} is not an AAP Workshop run (wheels.kind cmg with the '
                       'acds_controller): no dump report')


def report_from_bag(bag_path: Path | str) -> tuple[dict[str, Any], DumpSeries, Any]:
    """(the summary with ``dump_report``, the plot series, the recorded scenario) of a Workshop run's bag.

    Raises :class:`BagError` (one line) when the path is not a readable bag or the bag is not a Workshop run.
    """
    from acds_common.graph import build_graph
    from acds_common.parameters import node_parameters
    from acds_runtime.summary import RunObserver

    bag = open_bag(bag_path)
    scenario = bag.scenario()
    if scenario is None:
        raise BagError(f'bag {bag.path}: holds no scenario (not recorded by acds): cannot build the dump report')
    check_workshop(scenario, f'bag {bag.path}: ')
    steps = int(bag.info.get('steps', '0') or 0) or scenario.total_steps()
    observer = RunObserver(scenario, build_graph(node_parameters(scenario, steps)))
    moment = DIPOLE if bag.has(topics.DIPOLE_AVG) else COMMAND
    codecs = {t: Codec(topics.type_of(t)) for t in (moment, SUN)}
    series = DumpSeries()
    wanted = sorted({topics.resolve(t) for part in observer.parts for t in part.topics} | set(codecs))
    last_step = 0
    for topic, _t, data in bag.messages(wanted):
        observer.feed_raw(topic, data)
        codec = codecs.get(topic)
        if codec is None:
            continue
        t_ns, value = codec.decode(data)
        if topic == moment:
            series.t_s.append(t_ns / 1e9)
            series.m_am2.append(float(np.linalg.norm(value)))
            last_step = max(last_step, round(t_ns / (scenario.control_period_s * 1e9)))
        else:
            series.day_t_s.append(t_ns / 1e9)
            series.day.append(int(any(x != 0.0 for x in value)))
    summary = observer.summary(last_step, 0.0)
    return summary, series, scenario


def plot_dump(report: dict[str, Any], series: DumpSeries, scenario: Any, out_dir: Path) -> list[Path]:
    """Write ``dump_moment.png`` (|M|(t), nights shaded, orbit starts marked) and ``dump_h_s.png`` (H_s per
    orbit and |ΔH_s| against |H_b|); return the paths."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from acds_controller.aap_summary import orbit_clock

    check_out_dir(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    clock = orbit_clock(scenario)
    title = (f'{scenario.name}: law {report["law"]}, k = {report["k_seed"]:.3g} (seed units), '
             f'H_s init {scenario.get("controller", "dump_h_s_init")}')
    written = []

    t = np.asarray(series.t_s) / clock.period_s
    fig, ax = plt.subplots(figsize=(10, 3.8))
    ax.plot(t, np.asarray(series.m_am2), lw=0.7, color='C0', label='|M| achieved')
    day_t, day = np.asarray(series.day_t_s) / clock.period_s, np.asarray(series.day)
    if day.size:
        ax.fill_between(day_t, 0, 1, where=day == 0, step='post', color='0.85', transform=ax.get_xaxis_transform(),
                        label='orbital night')
    for row in report['per_orbit']:
        ax.axvline((row['t_start_s'] - clock.t0_s) / clock.period_s, color='0.6', lw=0.5)
    ax.set_xlabel('orbits from the first ascending node')
    ax.set_ylabel('|M|, A·m²')
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc='upper right')
    fig.suptitle(f'Dump moment magnitude |M|(t)\n{title}', fontsize=10)
    fig.tight_layout()
    written.append(out_dir / 'dump_moment.png')
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)

    rows = report['per_orbit']
    if rows:
        n = np.array([r['orbit'] for r in rows] + [rows[-1]['orbit'] + 1])  # and the sample after the last orbit
        h_s = np.array([r['H_s_ftlbs'] for r in rows] + [np.add(rows[-1]['H_s_ftlbs'],
                                                                rows[-1]['delta_H_s_vector_ftlbs'])])
        delta = np.array([r['delta_H_s_ftlbs'] for r in rows])
        h_b = float(units.nms_to_ftlbs(np.linalg.norm(scenario.get('controller', 'dump_bias_momentum'))))
        fig, axs = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
        for i, axis in enumerate('xyz'):
            axs[0].plot(n, h_s[:, i], 'o-', ms=3, lw=0.8, label=f'H_s,{axis}')
        axs[0].plot(n, np.linalg.norm(h_s, axis=1), 'k.--', lw=0.8, label='|H_s|')
        axs[0].set_ylabel('H_s sampled at the orbit start, ft-lb-sec')
        axs[0].legend(fontsize=8, ncol=4)
        axs[0].grid(alpha=0.3)
        axs[1].semilogy(n[:-1], np.maximum(delta, 1e-3), 'o-', ms=3, lw=0.8, label='|ΔH_s| over the orbit')
        if h_b > 0:
            axs[1].axhline(h_b, color='C3', lw=0.8, ls='--', label=f'|H_b| = {h_b:.0f}')
        axs[1].set_ylabel('ft-lb-sec')
        axs[1].set_xlabel('orbit')
        axs[1].legend(fontsize=8)
        axs[1].grid(alpha=0.3, which='both')
        fig.suptitle(f'Sampled CMG momentum H_s per orbit\n{title}', fontsize=10)
        fig.tight_layout()
        written.append(out_dir / 'dump_h_s.png')
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)
    return written
