"""SSS per-perigee-pass report (spec §8; seed 001): ``perigee_passes`` in the summary, and its table.

Built from what the run monitor recorded, one sample per control step k over [t_k, t_k+1):

* pass mode: the ``pass_mode`` key of the mode manager's step-k ``mode`` status
  (spin | attitude | direct_attitude | off);
* torque: ``truth/torque_magnetic`` of step k+1 (rigid_body's average of M × B_true over [t_k, t_k+1]);
* spin rate: body z rate of ``truth/odometry`` step k; spin axis: the direction of the angular
  momentum I·ω in ECI (so nutation does not read as precession);
* power: bus voltage × the step-average coil currents, the currents being the em_driver's step-average
  achieved dipole (``em_driver/dipole_avg`` step k) divided by each coil's moment per ampere
  (``em_driver.coil_moment_per_amp``), bus = ``em_driver.supply_v``: P = E·Σ|I_i|, what a saturated
  constant-level drive draws from the bus.

The statistics are :class:`ascs_mode_manager.sss_ascs.PassAccumulator`'s. A pass still on when the run
ends is closed at the last step and flagged ``complete: false``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common import topics
from ascs_mode_manager.sss_ascs import PassAccumulator
from dynamics.rigid_body_model import inertia_tensor, quat_to_dcm

KEYS = ('on_time_min', 'avg_torque_dyne_cm', 'peak_torque_dyne_cm', 'ripple_pct', 'spin_rate_change_rpm',
        'precession_deg', 'energy_j', 'mode')


def _is_sss(result: Any) -> bool:
    sc = result.scenario
    return sc.get('modes', 'system') == 'sss' and 'ascs_mode_manager' in sc.get('', 'nodes')


def _step(msg: Any, dt_ns: int) -> int:
    stamp = msg.header.stamp
    return round((stamp.sec * 10**9 + stamp.nanosec) / dt_ns)


def _vec(msg: Any) -> np.ndarray:
    return np.array([msg.vector.x, msg.vector.y, msg.vector.z])


def _clean(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else value


def perigee_passes(result: Any) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """(passes, events) of an SSS run; each pass has :data:`KEYS` plus SI extras."""
    sc, mon = result.scenario, result.monitor
    dt_s = sc.control_period_s
    dt_ns = round(dt_s * 1e9)
    inertia = inertia_tensor(*sc.get('spacecraft', 'inertia')) * sc.get('spacecraft', 'inertia_scale')
    pass_mode: dict[int, str] = {}
    for msg in mon.messages(topics.MODE):
        values = {kv.key: kv.value for kv in msg.status[0].values} if msg.status else {}
        pass_mode[_step(msg, dt_ns)] = values.get('pass_mode', 'off')
    torque = {_step(m, dt_ns): _vec(m) for m in mon.messages(topics.TRUTH_TORQUE_MAG)}
    dipole = {_step(m, dt_ns): _vec(m) for m in mon.messages(topics.DIPOLE_AVG)}
    per_amp = np.array(sc.get('em_driver', 'coil_moment_per_amp_am2'))
    bus_v = sc.get('em_driver', 'supply_v')
    state: dict[int, tuple[float, np.ndarray]] = {}
    for m in mon.messages(topics.TRUTH_ODOMETRY):
        o, w = m.pose.pose.orientation, m.twist.twist.angular
        omega = np.array([w.x, w.y, w.z])
        h_eci = quat_to_dcm(np.array([o.x, o.y, o.z, o.w])) @ (inertia @ omega)
        state[_step(m, dt_ns)] = (float(omega[2]), h_eci)
    acc = PassAccumulator()
    last = max(state) if state else 0
    open_at_end = False
    for k in range(last):
        if k not in pass_mode or k + 1 not in torque:
            continue
        power = bus_v * float(np.sum(np.abs(dipole.get(k, np.zeros(3)) / per_amp)))
        rate, axis = state[k]
        acc.add(k * dt_s, torque[k + 1], rate, axis, power, pass_mode[k])
        open_at_end = pass_mode[k] != 'off'
    if open_at_end and last in state:  # close with the state after the last torquing step
        rate, axis = state[last]
        acc.add(last * dt_s, np.zeros(3), rate, axis, 0.0, 'off')
    passes = []
    for i, rep in enumerate(acc.reports):
        complete = not (open_at_end and i == len(acc.reports) - 1)
        passes.append({**{k: _clean(rep[k]) for k in KEYS},
                       'avg_torque_nm': rep['avg_torque_nm'], 'peak_torque_nm': rep['peak_torque_nm'],
                       't_start_s': rep['t_start_s'], 't_end_s': rep['t_end_s'], 'complete': complete})
    events = []
    for msg in mon.messages(topics.EVENTS):
        head = msg.data.split(' ', 2)
        kind = head[1] if len(head) > 1 else ''
        try:
            t_s = float(head[0].removeprefix('t='))
        except ValueError:
            t_s = math.nan
        events.append({'t_s': _clean(t_s), 'kind': kind, 'text': msg.data})
    return passes, events


def contribute(result: Any, summary: dict[str, Any]) -> None:
    """Add ``perigee_passes`` (and ``sss_events``) to the summary of an SSS run."""
    if not _is_sss(result):
        return
    passes, events = perigee_passes(result)
    summary['perigee_passes'] = passes
    summary['sss_events'] = events


def print_tables(summary: dict[str, Any]) -> None:
    """The per-pass report, torques in dyne-cm and N·m."""
    if 'perigee_passes' not in summary:
        return
    events = summary.get('sss_events', [])
    print('\n  SSS events:')
    for e in events:
        print(f'    {e["text"]}')
    if not events:
        print('    (none)')
    passes = summary['perigee_passes']
    print(f'\n  SSS perigee passes ({len(passes)}):')
    header = (f'    {"#":>2} {"mode":<15} {"start":>8} {"on-time":>8} {"avg torque":>21} {"peak torque":>21} '
              f'{"ripple":>7} {"d spin":>9} {"precess":>8} {"energy":>8}')
    units = (f'    {"":>2} {"":<15} {"min":>8} {"min":>8} {"dyne-cm":>10} {"N·m":>10} {"dyne-cm":>10} '
             f'{"N·m":>10} {"% rms":>7} {"rpm":>9} {"deg":>8} {"J":>8}')
    print(header)
    print(units)
    for i, p in enumerate(passes, 1):
        ripple = f'{p["ripple_pct"]:7.1f}' if p['ripple_pct'] is not None else f'{"n/a":>7}'
        note = '' if p['complete'] else '  (still on at the end of the run)'
        print(f'    {i:>2} {p["mode"]:<15} {p["t_start_s"] / 60:8.2f} {p["on_time_min"]:8.2f} '
              f'{p["avg_torque_dyne_cm"]:10.1f} {p["avg_torque_nm"]:10.3e} '
              f'{p["peak_torque_dyne_cm"]:10.1f} {p["peak_torque_nm"]:10.3e} {ripple} '
              f'{p["spin_rate_change_rpm"]:+9.4f} {p["precession_deg"]:8.3f} {p["energy_j"]:8.1f}{note}')
    if not passes:
        print('    (no pass: the spin-plane field never reached the polarity-sensing level while enabled)')
