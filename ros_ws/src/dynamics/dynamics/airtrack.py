"""The 1-D EMFF airtrack (spec §10; seed 004 slides 48–55 "Experimental Validation: 1-D Airtrack").

"Nearly frictionless 1-dimensional airtrack ... fixed electromagnet, free magnet on slider, ultrasound
displacement sensor; can be set up in a stable or unstable configuration, depending on the tilt angle;
the unstable mode has dynamics nearly identical to a 1-DOF steady-state spinning cluster" (slide 52).

Model: ``acds_common.airtrack.AirtrackPlant`` (the slider's equation, its equilibrium and its
linearisation, shared with the airtrack controllers); the graph flies the same track as the formation
frame ``line`` (``dynamics.formation``). This module is the core study: a configuration designed from
its open-loop pole (``AirtrackConfig``) and an RK4 run of the slider under a control law (``simulate``).

Parameters (``AirtrackConfig``) are not in the seed (it gives the poles' form, the ~0.2 Hz closed-loop
oscillation, ~1 cm excursions and separations of 0.3–0.65 m in its plots); the defaults are stated
there. Integration: RK4, ``substeps`` per control period, the dipole held over it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common.airtrack import AirtrackPlant
from acds_common.dipole_field import coaxial_force_n
from acds_common.units import STANDARD_GRAVITY_M_S2

from dynamics.errors import DynamicsError


@dataclass(frozen=True)
class AirtrackConfig:
    """``configuration`` ('stable' or 'unstable'); slider ``mass_kg``; permanent magnet ``magnet_dipole_am2``;
    equilibrium separation ``separation_m``; ``open_loop_frequency_rad_s`` |s| of the open-loop poles, which
    sets the electromagnet's nominal dipole and the tilt; ``max_dipole_am2`` of the electromagnet.
    Defaults (not in the seed): a 1 kg slider, a 10 A·m² NdFeB magnet, 0.5 m, |s| = 0.5 rad/s, 2000 A·m²."""

    configuration: str = "stable"
    mass_kg: float = 1.0
    magnet_dipole_am2: float = 10.0
    separation_m: float = 0.5
    open_loop_frequency_rad_s: float = 0.5
    max_dipole_am2: float = 2000.0

    def __post_init__(self) -> None:
        if self.configuration not in ("stable", "unstable"):
            raise DynamicsError(f"AirtrackConfig.configuration must be 'stable' or 'unstable', got {self.configuration!r}")
        for name in ("mass_kg", "magnet_dipole_am2", "separation_m", "open_loop_frequency_rad_s", "max_dipole_am2"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise DynamicsError(f"AirtrackConfig.{name} must be > 0, got {v}")

    @property
    def sign(self) -> float:
        """+1 stable (repelling), −1 unstable (attracting)."""
        return 1.0 if self.configuration == "stable" else -1.0

    @property
    def nominal_dipole_am2(self) -> float:
        """μ_e at equilibrium: |s|² = 4 c μ_e μ_p /(m x0⁵)."""
        return (self.open_loop_frequency_rad_s ** 2 * self.mass_kg * self.separation_m
                / (4.0 * coaxial_force_n(1.0, self.magnet_dipole_am2, self.separation_m)))

    @property
    def tilt_rad(self) -> float:
        """|θ| of the track with m g sin|θ| = c μ_e μ_p / x0⁴."""
        return math.asin(coaxial_force_n(self.nominal_dipole_am2, self.magnet_dipole_am2, self.separation_m)
                         / (self.mass_kg * STANDARD_GRAVITY_M_S2))

    @property
    def plant(self) -> AirtrackPlant:
        """The track of this configuration, the electromagnet's dipole along +x: the magnet against it and the
        track rising away from it (stable) or the magnet along it and the track falling away (unstable)."""
        return AirtrackPlant(self.mass_kg, -self.sign * self.magnet_dipole_am2, self.sign * self.tilt_rad)


def simulate(cfg: AirtrackConfig, x0_m: float, v0_m_s: float, dipole_of: object, duration_s: float, dt_s: float,
             substeps: int = 10) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, x, μ_e) of the nonlinear slider from (``x0_m``, ``v0_m_s``); ``dipole_of(t, x, v)`` is the control
    law, sampled every ``dt_s`` and held, clipped to ±``max_dipole_am2``. Stops early (shorter arrays) if the
    slider reaches the electromagnet or leaves 10 × the equilibrium separation."""
    steps = int(round(duration_s / dt_s))
    t_out, x_out, mu_out = [0.0], [x0_m], []
    x, v = x0_m, v0_m_s
    h = dt_s / substeps
    plant = cfg.plant

    def acceleration(x_m: float, dipole_am2: float) -> float:
        if x_m <= 0.0:
            raise DynamicsError(f"the slider reached the electromagnet (x = {x_m:.4g} m)")
        return plant.acceleration(x_m, dipole_am2)

    for k in range(steps):
        mu = float(np.clip(dipole_of(k * dt_s, x, v), -cfg.max_dipole_am2, cfg.max_dipole_am2))  # type: ignore[operator]
        mu_out.append(mu)
        try:
            for _ in range(substeps):
                a1 = acceleration(x, mu)
                a2 = acceleration(x + 0.5 * h * v, mu)
                a3 = acceleration(x + 0.5 * h * (v + 0.5 * h * a1), mu)
                a4 = acceleration(x + h * (v + 0.5 * h * a2), mu)
                x, v = (x + h * v + h * h / 6.0 * (a1 + a2 + a3),
                        v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4))
        except DynamicsError:
            break
        t_out.append((k + 1) * dt_s)
        x_out.append(x)
        if not 0.0 < x < 10.0 * cfg.separation_m:
            break
    mu_out.append(mu_out[-1] if mu_out else 0.0)
    return np.array(t_out), np.array(x_out), np.array(mu_out[:len(t_out)])
