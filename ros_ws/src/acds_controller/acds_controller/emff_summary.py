"""Formation (EMFF) summary: how well the pair held or spun, what it cost in dipole, current and wheel momentum.

Contributed when the scenario is a formation (spec §10; seed 004). Built from every vehicle's
``truth/odometry`` (formation frame), ``em_driver/dipole_avg`` (body, A·m²), ``em_driver/coil_current``
(body, A) and ``wheels/momentum`` (body, N·m·s), one sample per step:

* baseline ρ = r_b − r_a between the first two vehicles; ``hold``: the error |ρ − ρ_ref| at the end and
  the settling time, the last time the error was above 5 % of its initial value (the usual 5 % band);
  ``spin_up``: the array rate Ω = (ρ × ρ̇)·ẑ / |ρ|² and separation at the end, against the commanded
  rate and separation, and the dipole product |μ_a||μ_b| held over the run's last STEADY_WINDOW_S beside the
  slides 48–49 closed form 2π μ_red Ω² d⁵/(3μ0) at that rate and separation;
* per vehicle: peak |μ| and peak coil current, the resistive energy ∫ Σ I²R dt of its coil circuits, peak
  and final wheel momentum;
* ``planar`` and ``free_space``: the formation's total linear momentum Σ m v and angular momentum
  Σ (m r × v + R(I ω + h_wheel)) about the frame origin are constants of the motion (the coils' forces
  and torques are internal), so their largest drift over the run is a check of the integration; the
  angular drift is also given relative to the largest Σ (|m r × v| + |R(I ω + h_wheel)|) of the run.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.attitude import quat_to_dcm
from acds_common.inertia import inertia_tensor

from acds_controller.formation_array import linear_array_rate_rad_s, mission_efficiency
from acds_controller.formation_control import steady_spin_dipole_product_am4

#: This module summarises formations (``acds_runtime.summary``).
FORMATIONS = True
#: Settling band: a fraction of the initial baseline error.
SETTLING_BAND = 0.05
#: The steady dipole product is averaged over the run's last this many seconds.
STEADY_WINDOW_S = 30.0


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = ('formation',)


def applies(scenario: Any) -> bool:
    """Every formation run."""
    return scenario.formation


def null_keys(summary: dict[str, Any]) -> None:
    """``formation`` is null outside formation runs."""
    summary.setdefault('formation', None)


class _Vehicle:
    """One vehicle's streams and running peaks."""

    def __init__(self, scenario: Any, v: dict[str, Any]) -> None:
        name = v['name']
        self.name = name
        self.mass = v['vehicle']['mass']
        self.inertia = inertia_tensor(*v['spacecraft']['inertia']) * v['spacecraft']['inertia_scale']
        self.resistance = np.array(v['em_driver']['coil_resistance_ohm'])
        self.odometry, self.dipole, self.current, self.wheel_h = (topics.resolve(f'{name}/{t}') for t in (
            topics.TRUTH_ODOMETRY, topics.DIPOLE_AVG, topics.COIL_CURRENT, topics.WHEEL_MOMENTUM))
        self.peak_dipole = 0.0
        self.peak_current = 0.0
        self.energy = 0.0
        self.peak_h = 0.0
        self.final_h = 0.0
        self.final_rates = (0.0, 0.0, 0.0)
        self.place = {'array_position': np.array(v['vehicle']['array_position']),
                      'initial_position': np.array(v['vehicle']['initial_position'])}


class Accumulator:
    """Streaming formation summary (module docstring)."""

    def __init__(self, scenario: Any) -> None:
        self.dt_s = scenario.control_period_s
        f = scenario.values['formation']
        self.law, self.frame = f['law'], f['frame']
        self.reference = np.array(f['relative_position'])
        self.spin_rate, self.spin_separation = f['spin_rate'], f['spin_separation']
        self.vehicles = [_Vehicle(scenario, v) for v in scenario.values['vehicles']]
        self.topics = tuple(t for v in self.vehicles for t in (v.odometry, v.dipole, v.current, v.wheel_h))
        self.conserved = self.frame in ('planar', 'free_space')
        self.p0: np.ndarray | None = None
        self.l0: np.ndarray | None = None
        self.max_dp = 0.0
        self.max_dl = 0.0
        self.e0: float | None = None
        self.settled_after = 0.0
        self.final: dict[str, float] = {}
        self.l_scale = 0.0
        self.tail_products: deque[float] = deque(maxlen=max(1, round(STEADY_WINDOW_S / self.dt_s)))
        self.tail_dipoles: deque[np.ndarray] = deque(maxlen=max(1, round(STEADY_WINDOW_S / self.dt_s)))
        self.tail_array: deque[tuple[float, float]] = deque(maxlen=max(1, round(STEADY_WINDOW_S / self.dt_s)))
        self.radii: np.ndarray | None = None

    def step(self, k: int, values: dict[str, Any]) -> None:
        """One step of every vehicle."""
        t = k * self.dt_s
        states = []
        for v in self.vehicles:
            odom, wheel = values.get(v.odometry), values.get(v.wheel_h)
            dipole, current = values.get(v.dipole), values.get(v.current)
            if odom is None:
                return
            r, vel, omega = np.array(odom.position), np.array(odom.velocity), np.array(odom.angular)
            h = np.zeros(3) if wheel is None else np.array(wheel)
            states.append((v, r, vel, quat_to_dcm(odom.orientation), omega, h))
            v.final_rates = tuple(odom.angular)
            v.final_h = float(np.linalg.norm(h))
            v.peak_h = max(v.peak_h, v.final_h)
            if dipole is not None:
                v.peak_dipole = max(v.peak_dipole, float(np.linalg.norm(dipole)))
            if current is not None:
                i = np.array(current)
                v.peak_current = max(v.peak_current, float(np.max(np.abs(i))))
                v.energy += float(np.sum(i * i * v.resistance)) * self.dt_s
        if self.conserved:
            p = sum(v.mass * vel for v, _r, vel, _rot, _w, _h in states)
            parts = [(v.mass * np.cross(r, vel), rot @ (v.inertia @ w + h)) for v, r, vel, rot, w, h in states]
            ang = sum(orbital + spin for orbital, spin in parts)
            self.l_scale = max(self.l_scale, sum(float(np.linalg.norm(a) + np.linalg.norm(b)) for a, b in parts))
            if self.p0 is None:
                self.p0, self.l0 = p, ang
            self.max_dp = max(self.max_dp, float(np.linalg.norm(p - self.p0)))
            self.max_dl = max(self.max_dl, float(np.linalg.norm(ang - self.l0)))
        self._array_step(states, values)
        (_va, ra, va, _ra, _wa, _ha), (_vb, rb, vb, _rb, _wb, _hb) = states[:2]
        rho, rho_dot = rb - ra, vb - va
        d = float(np.linalg.norm(rho))
        error = float(np.linalg.norm(rho - self.reference))
        if self.e0 is None:
            self.e0 = error
        if error > SETTLING_BAND * self.e0:
            self.settled_after = t
        rate = float(np.cross(rho, rho_dot)[2]) / (d * d) if d > 0 else 0.0
        self.final = {'separation_m': d, 'position_error_m': error, 'array_rate_rad_s': rate, 't_s': t}
        dipoles = [values.get(v.dipole) for v in self.vehicles[:2]]
        if all(dp is not None for dp in dipoles):
            self.tail_products.append(float(np.prod([np.linalg.norm(dp) for dp in dipoles])))

    def _array_step(self, states: list[tuple], values: dict[str, Any]) -> None:
        """The array about its centre of mass: outer radius, rigid rotation rate, every vehicle's |μ|."""
        m = np.array([s[0].mass for s in states])
        pos = np.array([s[1] for s in states])
        vel = np.array([s[2] for s in states])
        rel, rel_v = pos - m @ pos / m.sum(), vel - m @ vel / m.sum()
        inertia_z = float(m @ np.sum(rel[:, :2] ** 2, axis=1))
        rate = float(m @ (rel[:, 0] * rel_v[:, 1] - rel[:, 1] * rel_v[:, 0])) / inertia_z if inertia_z > 0 else 0.0
        self.radii = np.linalg.norm(rel, axis=1)
        self.tail_array.append((float(self.radii.max()), rate))
        dipoles = [values.get(v.dipole) for v in self.vehicles]
        if all(dp is not None for dp in dipoles):
            self.tail_dipoles.append(np.array([np.linalg.norm(dp) for dp in dipoles]))

    def _array(self) -> dict[str, Any] | None:
        """Steady state of a spinning array over the last STEADY_WINDOW_S and slide 64's mission efficiency."""
        if not self.tail_array or not self.tail_dipoles or self.radii is None:
            return None
        radius, rate = (float(x) for x in np.mean(np.array(self.tail_array), axis=0))
        dipoles = np.mean(np.array(self.tail_dipoles), axis=0)
        masses = [v.mass for v in self.vehicles]
        mu_b = float(dipoles.max())
        out: dict[str, Any] = {'outer_radius_m': radius, 'rate_rad_s': rate,
                               'steady_dipoles_am2': {v.name: float(d) for v, d in zip(self.vehicles, dipoles, strict=True)},
                               'radii_m': {v.name: float(r) for v, r in zip(self.vehicles, self.radii, strict=True)},
                               'mission_efficiency': mission_efficiency(abs(rate), sum(masses), radius, mu_b) if mu_b else None,
                               'closed_form_mission_efficiency': None}
        x = self._line_positions()
        if x is not None and mu_b:
            closed_rate = linear_array_rate_rad_s(masses, x, mu_b)
            out.update(closed_form_rate_rad_s=closed_rate,
                       closed_form_mission_efficiency=mission_efficiency(closed_rate, sum(masses), radius, mu_b))
        return out

    def _line_positions(self) -> list[float] | None:
        """The vehicles' places along the array's line if it is one (array_position, else initial position)."""
        key = 'array_position' if self.law in ('array_spin', 'lqr') else 'initial_position'
        places = np.array([v.place[key] for v in self.vehicles])
        m = np.array([v.mass for v in self.vehicles])
        places -= m @ places / m.sum()
        far = int(np.argmax(np.linalg.norm(places, axis=1)))
        axis = places[far] / np.linalg.norm(places[far])
        along = places @ axis
        if np.linalg.norm(places - np.outer(along, axis)) > 1e-9 * float(np.abs(along).max()):
            return None
        return along.tolist()

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add ``formation``."""
        out: dict[str, Any] = {'law': self.law, 'frame': self.frame,
                               'final_separation_m': self.final.get('separation_m')}
        if self.law != 'hold':
            out['array'] = self._array()
        if self.law == 'hold':
            out.update(final_position_error_m=self.final.get('position_error_m'),
                       initial_position_error_m=self.e0,
                       settling_time_s=self.settled_after if self.e0 else 0.0)
        elif self.law == 'spin_up':
            rate, d = self.final.get('array_rate_rad_s'), self.final.get('separation_m')
            product = float(np.mean(self.tail_products)) if self.tail_products else None
            closed = None
            if rate is not None and d:
                m = [v.mass for v in self.vehicles[:2]]
                closed = steady_spin_dipole_product_am4(m[0], m[1], d, rate)
            out.update(final_array_rate_rad_s=rate, commanded_rate_rad_s=self.spin_rate,
                       commanded_separation_m=self.spin_separation, steady_dipole_product_am4=product,
                       closed_form_dipole_product_am4=closed,
                       dipole_product_ratio=product / closed if product and closed else None)
        if self.conserved:
            out.update(linear_momentum_drift_n_s=self.max_dp, angular_momentum_drift_nms=self.max_dl,
                       angular_momentum_drift_rel=self.max_dl / self.l_scale if self.l_scale else 0.0)
        out['vehicles'] = {v.name: {'peak_dipole_am2': v.peak_dipole, 'peak_coil_current_a': v.peak_current,
                                    'coil_energy_j': v.energy, 'peak_wheel_momentum_nms': v.peak_h,
                                    'final_wheel_momentum_nms': v.final_h,
                                    'final_rates_deg_s': [math.degrees(w) for w in v.final_rates]}
                           for v in self.vehicles}
        summary['formation'] = out


def _fmt(value: Any, spec: str = '.4g') -> str:
    return '—' if value is None else format(value, spec)


def print_tables(summary: dict[str, Any]) -> None:
    """The formation's baseline result and each vehicle's costs."""
    f = summary.get('formation')
    if not f:
        return
    print(f'\nFormation ({f["law"]}, {f["frame"]} frame): final separation {_fmt(f["final_separation_m"])} m')
    a = f.get('array')
    if a:
        print(f'  array: outer radius {_fmt(a["outer_radius_m"])} m, rate {_fmt(a["rate_rad_s"])} rad/s; steady |μ| '
              + ', '.join(f'{n} {d:.1f}' for n, d in a['steady_dipoles_am2'].items()) + ' A·m²')
        print(f'  mission efficiency J = ω/(m_array √c_o) {_fmt(a["mission_efficiency"])}; equal-dipole linear array '
              f'closed form {_fmt(a["closed_form_mission_efficiency"])} (rate {_fmt(a.get("closed_form_rate_rad_s"))} rad/s)')
    if f['law'] == 'hold':
        print(f'  baseline error {_fmt(f["initial_position_error_m"])} m → {_fmt(f["final_position_error_m"])} m; '
              f'within {SETTLING_BAND:.0%} of the initial error after {_fmt(f["settling_time_s"], ".1f")} s')
    elif f['law'] == 'spin_up':
        print(f'  array rate {_fmt(f["final_array_rate_rad_s"])} rad/s (commanded {_fmt(f["commanded_rate_rad_s"])})'
              f', separation commanded {_fmt(f["commanded_separation_m"])} m')
        print(f'  dipole product |μa||μb| {_fmt(f["steady_dipole_product_am4"])} (A·m²)² held vs closed form '
              f'{_fmt(f["closed_form_dipole_product_am4"])}: ratio {_fmt(f["dipole_product_ratio"], ".5f")}')
    if 'angular_momentum_drift_nms' in f:
        print(f'  conserved-quantity drift: linear {f["linear_momentum_drift_n_s"]:.3g} N·s, angular '
              f'{f["angular_momentum_drift_nms"]:.3g} N·m·s ({f["angular_momentum_drift_rel"]:.3g} relative)')
    print(f'  {"vehicle":8s} {"peak |μ| A·m²":>14s} {"peak I A":>9s} {"I²R energy J":>13s} {"peak |h| N·m·s":>15s} '
          f'{"final |h|":>10s}')
    for name, v in f['vehicles'].items():
        print(f'  {name:8s} {v["peak_dipole_am2"]:14.1f} {v["peak_coil_current_a"]:9.2f} {v["coil_energy_j"]:13.2f} '
              f'{v["peak_wheel_momentum_nms"]:15.4f} {v["final_wheel_momentum_nms"]:10.4f}')
