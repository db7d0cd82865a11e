"""The 1-D EMFF airtrack as built: the slider's equation of motion, its equilibrium and its linearisation
(spec §10; seed 004 slides 52–55 "Experimental Validation: 1-D Airtrack").

A slider of mass m carrying a permanent magnet of dipole μ_p moves along the track axis x (frictionless,
the issue's "ideal" slider), coaxial with a fixed electromagnet of dipole μ_e at x = 0; both dipoles are
signed components along +x. The track is tilted by θ (signed: θ > 0 when it rises along +x, away from the
electromagnet), so gravity pulls the slider along it with −m g sin θ. With the far-field coaxial force
(slide 48; ``acds_common.dipole_field.coaxial_force_n``, c = 3μ0/(2π)):

    m ẍ = −c μ_e μ_p / x⁴ − m g sin θ     (aligned dipoles attract: the force points to the electromagnet)

* stable: repelling magnets (μ_e μ_p < 0), the track rising away from the electromagnet (θ > 0);
* unstable: attracting magnets (μ_e μ_p > 0), the track falling away from it (θ < 0) — slide 48's
  spinning pair, with the centrifugal force in place of gravity (slide 52: "unstable mode has dynamics
  nearly identical to a 1-DOF steady-state spinning cluster").

Equilibrium at x0: μ_e0 = m (−g sin θ) x0⁴/(c μ_p). Linearised about it (slides 53–54), state (δx, δẋ), input
δμ_e: δẍ = (4 c μ_e0 μ_p/(m x0⁵)) δx − (c μ_p/(m x0⁴)) δμ_e, poles ±i√(6μ0 |μ_e0 μ_p|/(π m x0⁵)) (stable) or
±√(…) (unstable), the slides' s = ±√(6 μ0 μ μ_p/(π m x0⁵)) (i in the stable case).

Shared by the core study (``dynamics.airtrack``) and the graph's airtrack controllers
(``acds_controller.airtrack_control``); the graph's dynamics fly the general dipole–dipole wrench in the
formation frame ``line`` (``dynamics.formation``), the same force on the axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acds_common.dipole_field import coaxial_force_n
from acds_common.units import STANDARD_GRAVITY_M_S2


@dataclass(frozen=True)
class AirtrackPlant:
    """The track as built (module docstring): slider ``mass_kg``, its permanent magnet's
    ``magnet_dipole_am2`` along +x (signed, ≠ 0), the track's ``tilt_rad`` (signed, ≠ 0, > 0 rising along +x).
    ValueError on anything else (no magnet or no tilt cannot hold the slider anywhere)."""

    mass_kg: float
    magnet_dipole_am2: float
    tilt_rad: float

    def __post_init__(self) -> None:
        values = (self.mass_kg, self.magnet_dipole_am2, self.tilt_rad)
        if not all(math.isfinite(v) for v in values) or self.mass_kg <= 0.0 or self.magnet_dipole_am2 == 0.0 \
                or self.tilt_rad == 0.0 or abs(self.tilt_rad) >= math.pi / 2:
            raise ValueError(f'the airtrack needs a slider mass > 0 kg, a magnet (dipole ≠ 0 A·m²) and a tilt '
                             f'0 < |θ| < 90° to hold the slider, got {self.mass_kg} kg, {self.magnet_dipole_am2} A·m², '
                             f'{self.tilt_rad} rad')

    @property
    def track_acceleration_m_s2(self) -> float:
        """Gravity along the track, −g sin θ, m/s²."""
        return -STANDARD_GRAVITY_M_S2 * math.sin(self.tilt_rad)

    def equilibrium_dipole_am2(self, separation_m: float) -> float:
        """The electromagnet's dipole (signed, along +x) holding the slider at ``separation_m``."""
        return self.mass_kg * self.track_acceleration_m_s2 / coaxial_force_n(1.0, self.magnet_dipole_am2, separation_m)

    def acceleration(self, x_m: float, dipole_am2: float) -> float:
        """ẍ of the slider at ``x_m`` (> 0) with the electromagnet at ``dipole_am2`` (module docstring)."""
        return -coaxial_force_n(dipole_am2, self.magnet_dipole_am2, x_m) / self.mass_kg + self.track_acceleration_m_s2

    def linearised(self, separation_m: float) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of (δx, δẋ) with input δμ_e about the equilibrium at ``separation_m`` (analytic)."""
        per_dipole = coaxial_force_n(1.0, self.magnet_dipole_am2, separation_m) / self.mass_kg
        stiffness = 4.0 * per_dipole * self.equilibrium_dipole_am2(separation_m) / separation_m
        return np.array([[0.0, 1.0], [stiffness, 0.0]]), np.array([[0.0], [-per_dipole]])
