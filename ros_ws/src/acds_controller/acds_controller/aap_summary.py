"""AAP Workshop CMG dump report (seed 000 §5, Tables 1 and 2): ``dump_report`` in the summary, and its table.

Built from what the run recorded, one sample per control step k held over [t_k, t_k+1):

* M: the em_driver's step-average achieved dipole (``em_driver/dipole_avg`` step k; the controller's
  ``controller/moment_command`` when no em_driver is in the graph);
* B: the true field at the spacecraft (``truth/b_body`` step k), for the orbit's field gramian W (the loop
  gains, the minimum-energy M_o of Table 2 on the orbit's own field);
* ∫ M × B dt: ``truth/torque_magnetic`` of step k+1 (rigid_body's average of M × B_true over
  [t_k, t_k+1]); the gravity-gradient momentum likewise from ``truth/torque_gravity_gradient``;
* day or night: the sun sensor (``sensors/sun``, a zero vector in the Earth's shadow) at step k;
* H_s: the controller's ``controller/sampled_momentum`` (k); the CMG momentum ``wheels/momentum`` (k) for
  the last orbit's ΔH_s, the peak CMG momentum between samplings, and CMG saturation;
* the attitude error: ``truth/odometry`` against ``controller.target_quaternion_xyzw``.

``delta_H_s_ftlbs`` is the largest per-orbit |ΔH_s| (how the brief and :func:`dump_report` take it);
``H_s_range_ftlbs`` the largest distance between any two of the samples H_s,0 … H_s,N (the size of the
"small bounded region" H_s "varies within", §3) — the seed's "variation of H_S over 16 orbits" is either.

Orbits are counted from the ascending node with the on-board orbit's period, as the controller samples
H_s (:func:`orbit_clock`). The statistics are :class:`acds_controller.cmg_dump.OrbitAccumulator`'s (every
orbit that ran to its end; the last closes with the CMG momentum at the run's end), the report
:func:`acds_controller.cmg_dump.dump_report`'s (seed units: momenta in ft-lb-sec) plus, per orbit, the
gravity-gradient momentum, the peak CMG momentum and the largest attitude error.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.environment import orbit_from_section
from acds_common.units import dump_gain_si_to_seed, nms_to_ftlbs

from acds_controller.cmg_dump import OrbitAccumulator, OrbitClock, dump_report, loop_gain_warning
from acds_controller.configuration import build_workshop

DIPOLE, COMMAND, B_BODY, TORQUE, TORQUE_GG, SUN, H_S, CMG_H, ODOMETRY = (topics.resolve(t) for t in (
    topics.DIPOLE_AVG, topics.MOMENT_COMMAND, topics.TRUTH_B_BODY, topics.TRUTH_TORQUE_MAG, topics.TRUTH_TORQUE_GG,
    topics.SUN_SENSOR, topics.SAMPLED_MOMENTUM, topics.WHEEL_MOMENTUM, topics.TRUTH_ODOMETRY))


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = ('dump_report',)


def applies(scenario: Any) -> bool:
    """The dump report comes from runs of the Workshop computer (CMGs and the controller in the graph)."""
    return scenario.get('wheels', 'kind') == 'cmg' and 'acds_controller' in scenario.get('', 'nodes')


def null_keys(_summary: dict[str, Any]) -> None:
    """No keys of this module appear outside Workshop runs."""


def orbit_clock(scenario: Any) -> OrbitClock:
    """The orbit boundaries the controller samples H_s at: from the ascending node, one on-board period each."""
    orbit = orbit_from_section(scenario.values['orbit'])
    return OrbitClock(orbit.period_s, orbit.node_time_s())


def _angle_rad(q: tuple[float, ...], q_target: np.ndarray) -> float:
    """Rotation angle between two unit quaternions (x, y, z, w), rad."""
    return 2.0 * math.acos(min(1.0, abs(float(np.dot(q, q_target)))))


class Accumulator:
    """Streaming dump report: each step k is added once the torques of step k + 1 are in."""

    topics = (DIPOLE, COMMAND, B_BODY, TORQUE, TORQUE_GG, SUN, H_S, CMG_H, ODOMETRY)

    def __init__(self, scenario: Any) -> None:
        sc = scenario
        self.dt_s = sc.control_period_s
        self.clock = orbit_clock(sc)
        c = sc.values['controller']
        self.law = c['dump_law']
        # the law the controller flies: k from its gain rule, the §9 limit and §10 day |M| from its prediction
        computer = build_workshop(sc.values['spacecraft'], c, sc.values['orbit'], sc.values['earth'])[1]
        self.design = computer.design
        self.flown = None if computer.law is None else computer.law.cfg
        self.k_seed = dump_gain_si_to_seed(c['dump_gain']) if computer.cfg.dump is None else computer.cfg.dump.k_seed
        self.capacity_nms = sc.get('wheels', 'cmg_capacity')
        self.q_target = np.array(c['target_quaternion_xyzw'], dtype=float)
        self.q_target /= np.linalg.norm(self.q_target)
        # the loop gains k·W describe the linear k·H_s × B loop; the §10 day-only law flies a constant |M| instead
        day_only = self.flown is not None and self.flown.day_moment_am2 is not None
        self.orbits = OrbitAccumulator(self.clock, np.array(c['dump_bias_momentum']),
                                       None if self.law == 'none' or day_only else self.k_seed)
        self.extra: dict[int, dict[str, Any]] = {}
        self._prev: tuple[int, dict[str, Any]] | None = None  # step k waiting for the torques of k + 1
        self._last_h: tuple[int, np.ndarray] | None = None
        self.saturation_s: float | None = None

    def _orbit_extra(self, t_s: float) -> dict[str, Any]:
        return self.extra.setdefault(self.clock.index(t_s), {'gg': np.zeros(3), 'cmg_peak': 0.0, 'att_max': 0.0})

    def step(self, k: int, values: dict[str, Any]) -> None:
        """Step k's moment, field, light and momenta; closes step k − 1 with this step's torques."""
        torque, gg = values.get(TORQUE), values.get(TORQUE_GG)
        if self._prev is not None and self._prev[0] == k - 1 and torque is not None:
            t_prev, v = (k - 1) * self.dt_s, self._prev[1]
            self.orbits.add(t_prev, self.dt_s, v['m'], v['b'], v['day'], v['h_s'], np.array(torque), v['h'])
            if gg is not None:
                self._orbit_extra(t_prev)['gg'] += np.array(gg) * self.dt_s
        self._prev = None
        t = k * self.dt_s
        h = values.get(CMG_H)
        if h is not None:
            self._last_h = (k, np.array(h))
            extra = self._orbit_extra(t)
            size = float(np.linalg.norm(h))
            extra['cmg_peak'] = max(extra['cmg_peak'], size)
            if self.saturation_s is None and size >= self.capacity_nms * (1.0 - 1e-9):
                self.saturation_s = t
        odom = values.get(ODOMETRY)
        if odom is not None:
            extra = self._orbit_extra(t)
            extra['att_max'] = max(extra['att_max'], _angle_rad(odom.orientation, self.q_target))
        m = values.get(DIPOLE, values.get(COMMAND))
        b, h_s, sun = values.get(B_BODY), values.get(H_S), values.get(SUN)
        if m is not None and b is not None and h_s is not None and sun is not None and h is not None:
            self._prev = (k, {'m': np.array(m), 'b': np.array(b[0]), 'day': any(x != 0.0 for x in sun),
                              'h_s': np.array(h_s), 'h': np.array(h)})

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add ``dump_report``: the orbits' report, the law, and the CMG peak and saturation."""
        if self._last_h is not None:
            k, h = self._last_h
            self.orbits.finish(k * self.dt_s, h)
        report: dict[str, Any] = {'law': self.law, 'k_seed': self.k_seed, 'orbits': 0, 'H_s_range_ftlbs': None,
                                  'loop_gain_min': None, 'loop_gain_max': None, 'loop_converges': None,
                                  'per_orbit': []}
        if self.design is not None and self.flown is not None:
            report.update({
                'gain_rule': self.design.gain_rule,
                'predicted_loop_gains': list(self.design.predicted_gains),
                'predicted_unconstrained_M_m_am2': self.design.predicted_peak_am2,
                'moment_limit_am2': self.flown.moment_limit_am2,
                'day_moment_am2': self.flown.day_moment_am2,
                'profile': 'day_constant' if self.flown.day_moment_am2 is not None else 'day_night'})
        if self.orbits.stats:
            report.update(dump_report(self.orbits.stats))
            for row in report['per_orbit']:
                extra = self.extra.get(row['orbit'], {'gg': np.zeros(3), 'cmg_peak': 0.0, 'att_max': 0.0})
                row['gravity_gradient_momentum_ftlbs'] = [float(x) for x in nms_to_ftlbs(extra['gg'])]
                row['cmg_peak_ftlbs'] = float(nms_to_ftlbs(extra['cmg_peak']))
                row['attitude_error_max_deg'] = math.degrees(extra['att_max'])
            last = report['per_orbit'][-1]
            samples = np.array([r['H_s_ftlbs'] for r in report['per_orbit']]
                               + [np.add(last['H_s_ftlbs'], last['delta_H_s_vector_ftlbs'])])
            report['H_s_range_ftlbs'] = float(max(np.linalg.norm(samples - s, axis=1).max() for s in samples))
        peaks = [e['cmg_peak'] for e in self.extra.values()]
        report['cmg_peak_ftlbs'] = float(nms_to_ftlbs(max(peaks))) if peaks else None
        report['cmg_saturation_min'] = None if self.saturation_s is None else self.saturation_s / 60
        atts = [e['att_max'] for e in self.extra.values()]
        report['attitude_error_max_deg'] = math.degrees(max(atts)) if atts else None
        summary['dump_report'] = report


def _f(x: float | None, spec: str) -> str:
    return '—' if x is None else format(x, spec)


def print_tables(summary: dict[str, Any]) -> None:
    """The per-orbit dump report and the largest values (the seed's Tables 1 and 2), seed units."""
    report = summary.get('dump_report')
    if report is None:
        return
    print(f'\n  AAP Workshop CMG dump (seed 000): law {report["law"]}, k = {report["k_seed"]:.4g} amp-turn-m² per '
          f'ft-lb-sec per Wb/m² ({report.get("gain_rule", "stated")}); {report["orbits"]} complete orbit(s)')
    if report.get('moment_limit_am2') is not None:
        print(f'    |M| limited to {report["moment_limit_am2"]:.0f} A·m² (§9: a fraction of the predicted unconstrained '
              f'M_m {report["predicted_unconstrained_M_m_am2"]:.0f})')
    if report.get('day_moment_am2') is not None:
        print(f'    day-only dumping at constant |M| = {report["day_moment_am2"]:.0f} A·m² (§10: a multiple of the '
              f'predicted unconstrained M_m {report["predicted_unconstrained_M_m_am2"]:.0f}); no k·W gains: that '
              'law is not the linear k·H_s × B loop')
    warning = loop_gain_warning(report)
    if warning is not None:
        print(f'    {warning}')
    print(f'    {"orbit":>5} {"M_n":>9} {"M_d":>9} {"M_o":>9} {"M_m":>9} {"min-en M_o":>10} {"|H_s|":>9} '
          f'{"|ΔH_s|":>9} {"bias seen (x, y, z)":>27} {"k·W gains":>13} {"CMG peak":>9} {"att err":>7}')
    print(f'    {"":>5} {"A·m²":>9} {"A·m²":>9} {"A·m²":>9} {"A·m²":>9} {"A·m²":>10} {"ft-lb-s":>9} '
          f'{"ft-lb-s":>9} {"ft-lb-sec":>27} {"min…max":>13} {"ft-lb-s":>9} {"deg":>7}')
    for r in report['per_orbit']:
        gains = r.get('loop_gains')
        gain_text = '—' if gains is None else f'{gains[0]:.2f}…{gains[-1]:.2f}'
        bias = ', '.join(f'{x:.0f}' for x in r['bias_observed_ftlbs'])
        print(f'    {r["orbit"]:>5} {_f(r["M_n_am2"], ".0f"):>9} {_f(r["M_d_am2"], ".0f"):>9} {r["M_o_am2"]:>9.0f} '
              f'{r["M_m_am2"]:>9.0f} {r["min_energy_M_o_am2"]:>10.0f} {float(np.linalg.norm(r["H_s_ftlbs"])):>9.1f} '
              f'{r["delta_H_s_ftlbs"]:>9.1f} {bias:>27} {gain_text:>13} {r["cmg_peak_ftlbs"]:>9.0f} '
              f'{r["attitude_error_max_deg"]:>7.3f}')
    if report['orbits']:
        print(f'    largest over the orbits (Table 1): M_n {_f(report["M_n_am2"], ".0f")}  M_d '
              f'{_f(report["M_d_am2"], ".0f")}  M_o {report["M_o_am2"]:.0f}  M_m {report["M_m_am2"]:.0f} A·m²; '
              f'|ΔH_s| {report["delta_H_s_ftlbs"]:.1f} ft-lb-sec (largest per orbit; the samples H_s,n span '
              f'{report["H_s_range_ftlbs"]:.1f})')
        print(f'    minimum-energy solution, largest M_o (Table 2): {report["min_energy_M_o_am2"]:.0f} A·m²')
    print(f'    CMG momentum peak {_f(report["cmg_peak_ftlbs"], ".0f")} ft-lb-sec; saturation at '
          f'{_f(report["cmg_saturation_min"], ".1f")} min; largest attitude error '
          f'{_f(report["attitude_error_max_deg"], ".3f")} deg')
