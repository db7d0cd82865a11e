"""The 1-D airtrack's controllers (spec §10; seed 004 slides 52–55 "Experimental Validation: 1-D Airtrack").

The electromagnet's dipole μ_e (along the track, +x) is the input; the measurement is the separation x of
the slider from the electromagnet and its rate ẋ (the seed's ultrasound displacement sensor, here ideal).
The design model is the track as built, ``acds_common.airtrack.AirtrackPlant``:

* open loop (slide 55: "Constant current is applied to EM"): μ_e = μ_e0(x_ref), the equilibrium dipole at
  the commanded separation x_ref (``AirtrackOpenLoop``);
* LQR (slides 53–54: "Similar linearization, state-space analysis, and LQR control design to steady-state
  spin system"): μ_e = μ_e0(x_ref) − K (x − x_ref, ẋ), K from the plant's analytic linearisation at x_ref and
  Bryson weights Q = diag(1/Δx², 1/Δv²), R = 1/Δμ² (``airtrack_lqr_gain``; the Riccati solver is the
  formation LQR's, ``acds_controller.formation_linear.lqr_gain``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common.airtrack import AirtrackPlant

from acds_controller.formation_linear import lqr_gain
from acds_controller.magnetic_laws import ControllerError


@dataclass(frozen=True)
class BrysonScales:
    """The airtrack LQR's weights as Bryson scales (each weight is 1/scale²): ``position_m`` Δx,
    ``velocity_m_s`` Δv, ``dipole_am2`` Δμ; each > 0."""

    position_m: float
    velocity_m_s: float
    dipole_am2: float

    def __post_init__(self) -> None:
        for name in ('position_m', 'velocity_m_s', 'dipole_am2'):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ControllerError(f'the airtrack LQR scale {name} must be > 0 (its weight is 1/scale²), got {v}')


def airtrack_lqr_gain(plant: AirtrackPlant, separation_m: float, scales: BrysonScales) -> np.ndarray:
    """K (2,) of the LQR on (x − x_ref, ẋ) about the equilibrium at ``separation_m`` (module docstring)."""
    a, b = plant.linearised(separation_m)
    q = np.diag([1.0 / scales.position_m ** 2, 1.0 / scales.velocity_m_s ** 2])
    k, _ = lqr_gain(a, b, q, np.array([[1.0 / scales.dipole_am2 ** 2]]))
    return k[0]


class AirtrackOpenLoop:
    """The electromagnet at the constant dipole holding the slider at ``separation_m`` (module docstring)."""

    def __init__(self, plant: AirtrackPlant, separation_m: float) -> None:
        self.plant = plant
        self.separation_m = separation_m
        self.dipole0_am2 = plant.equilibrium_dipole_am2(separation_m)

    def dipole_am2(self, _x_m: float, _v_m_s: float) -> float:
        """μ_e for the measured separation and its rate: μ_e0(x_ref)."""
        return self.dipole0_am2


class AirtrackLqr(AirtrackOpenLoop):
    """μ_e0(x_ref) − K (x − x_ref, ẋ) (module docstring)."""

    def __init__(self, plant: AirtrackPlant, separation_m: float, scales: BrysonScales) -> None:
        super().__init__(plant, separation_m)
        self.gain = airtrack_lqr_gain(plant, separation_m, scales)

    def dipole_am2(self, x_m: float, v_m_s: float) -> float:
        """μ_e for the measured separation ``x_m`` and its rate ``v_m_s``."""
        return self.dipole0_am2 - float(self.gain @ np.array([x_m - self.separation_m, v_m_s]))

    def closed_loop_poles(self) -> np.ndarray:
        """Eigenvalues of A − B K of the linearised track."""
        a, b = self.plant.linearised(self.separation_m)
        return np.linalg.eigvals(a - b @ self.gain[None, :])
