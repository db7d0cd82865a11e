"""The 1-D EMFF airtrack (spec §10; seed 004 slides 48–55 "Experimental Validation: 1-D Airtrack").

"Nearly frictionless 1-dimensional airtrack ... fixed electromagnet, free magnet on slider, ultrasound
displacement sensor; can be set up in a stable or unstable configuration, depending on the tilt angle;
the unstable mode has dynamics nearly identical to a 1-DOF steady-state spinning cluster" (slide 52).

Model: a slider of mass m carrying a permanent magnet of dipole μ_p moves along the track axis x
(frictionless, the issue's "ideal" slider), coaxial with a fixed electromagnet of dipole μ_e at x = 0;
the track is tilted so that gravity pulls the slider along the track with m g sin θ. The far-field
coaxial force on the slider, x̂ component, is F = −σ c μ_e μ_p / x⁴ with c = 3μ0/(2π) (slide 48), σ = +1
when the dipoles attract (aligned) and −1 when they repel:

* stable: repelling magnets, gravity pushing the slider toward the electromagnet (tilt toward it):
  m ẍ = c μ_e μ_p/x⁴ − m g sin θ;
* unstable: attracting magnets, gravity pulling it away (tilt away):
  m ẍ = −c μ_e μ_p/x⁴ + m g sin θ — slide 48's spinning pair, with the centrifugal force in place of
  gravity.

Equilibrium at x0: m g sin θ = c μ_e μ_p / x0⁴. Linearised about it (slide 53): δẍ = ∓(4 c μ_e μ_p/(m x0⁵)) δx
+ (c μ_p/(m x0⁴))(±δμ_e): poles ±i√(6μ0 μ_e μ_p/(π m x0⁵)) (stable) or ±√(…) (unstable), as the slide.
The electromagnet's dipole is the input (current × its N·π·R²); the sensor is ideal (the slider's x).

Parameters (``AirtrackConfig``) are not in the seed (it gives the poles' form, the ~0.2 Hz closed-loop
oscillation, ~1 cm excursions and separations of 0.3–0.65 m in its plots); the defaults are stated
there. Integration: RK4, ``substeps`` per control period, the dipole held over it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dynamics.errors import DynamicsError

#: μ0, T·m/A.
MU0 = 4e-7 * math.pi
#: Standard gravity, m/s².
G0 = 9.80665


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
        """+1 stable (repelling), −1 unstable (attracting): the force's sign per unit c μ_e μ_p / x⁴."""
        return 1.0 if self.configuration == "stable" else -1.0

    @property
    def coupling(self) -> float:
        """c μ_p = 3μ0 μ_p/(2π), N·m⁴ per A·m² of the electromagnet."""
        return 3.0 * MU0 * self.magnet_dipole_am2 / (2.0 * math.pi)

    @property
    def nominal_dipole_am2(self) -> float:
        """μ_e at equilibrium: |s|² = 4 c μ_e μ_p /(m x0⁵)."""
        return self.open_loop_frequency_rad_s ** 2 * self.mass_kg * self.separation_m ** 5 / (4.0 * self.coupling)

    @property
    def tilt_rad(self) -> float:
        """Track tilt θ with m g sin θ = c μ_e μ_p / x0⁴."""
        return math.asin(self.coupling * self.nominal_dipole_am2 / (self.separation_m ** 4 * self.mass_kg * G0))


def equilibrium_dipole_am2(cfg: AirtrackConfig, separation_m: float) -> float:
    """The electromagnet's dipole holding the slider at ``separation_m`` (same tilt)."""
    return cfg.mass_kg * G0 * math.sin(cfg.tilt_rad) * separation_m ** 4 / cfg.coupling


def acceleration(cfg: AirtrackConfig, x_m: float, dipole_am2: float) -> float:
    """ẍ of the slider at ``x_m`` with the electromagnet at ``dipole_am2`` (module docstring)."""
    if x_m <= 0.0:
        raise DynamicsError(f"the slider reached the electromagnet (x = {x_m:.4g} m)")
    magnetic = cfg.sign * cfg.coupling * dipole_am2 / x_m ** 4
    return (magnetic - cfg.sign * cfg.mass_kg * G0 * math.sin(cfg.tilt_rad)) / cfg.mass_kg


def linearised(cfg: AirtrackConfig) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of (δx, δẋ) with input δμ_e about the equilibrium (module docstring, analytic)."""
    x0, mu = cfg.separation_m, cfg.nominal_dipole_am2
    stiffness = -cfg.sign * 4.0 * cfg.coupling * mu / (cfg.mass_kg * x0 ** 5)
    gain = cfg.sign * cfg.coupling / (cfg.mass_kg * x0 ** 4)
    return np.array([[0.0, 1.0], [stiffness, 0.0]]), np.array([[0.0], [gain]])


def simulate(cfg: AirtrackConfig, x0_m: float, v0_m_s: float, dipole_of: object, duration_s: float, dt_s: float,
             substeps: int = 10) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, x, μ_e) of the nonlinear slider from (``x0_m``, ``v0_m_s``); ``dipole_of(t, x, v)`` is the control
    law, sampled every ``dt_s`` and held, clipped to ±``max_dipole_am2``. Stops early (shorter arrays) if the
    slider reaches the electromagnet or leaves 10 × the equilibrium separation."""
    steps = int(round(duration_s / dt_s))
    t_out, x_out, mu_out = [0.0], [x0_m], []
    x, v = x0_m, v0_m_s
    h = dt_s / substeps
    for k in range(steps):
        mu = float(np.clip(dipole_of(k * dt_s, x, v), -cfg.max_dipole_am2, cfg.max_dipole_am2))  # type: ignore[operator]
        mu_out.append(mu)
        try:
            for _ in range(substeps):
                a1 = acceleration(cfg, x, mu)
                a2 = acceleration(cfg, x + 0.5 * h * v, mu)
                a3 = acceleration(cfg, x + 0.5 * h * (v + 0.5 * h * a1), mu)
                a4 = acceleration(cfg, x + h * (v + 0.5 * h * a2), mu)
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
