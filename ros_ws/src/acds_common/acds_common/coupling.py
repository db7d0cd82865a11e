"""Coupling Δ from the electromagnets into the magnetometer (spec §5; seed 002 §4.3.1, §4.3.2, eqs. 4-29 to 4-33).

B_sensed = B_true + B_residual + Δ·M, Δ[i, j] the gain of magnetometer axis i to magnet j in
T/(A·m²). Shared by the magnetometer (which senses it) and the controller (whose optional
coupling compensation subtracts exactly the modelled Δ·M).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from acds_common.units import GAUSS_T

#: Study's maximum Earth field at HEAO altitude, T (0.5 G at the magnetic pole, spec §3).
MAX_EARTH_FIELD_T = 0.5 * GAUSS_T


class CouplingError(ValueError):
    """A coupling description that is not a valid Δ (names what is wrong)."""


def coupling_cruise(gain_g_per_am2: float = 8.75e-6) -> np.ndarray:
    """Cruise coupling Δ, T/(A·m²): gain on the diagonal (seed §4.3.2: 8.75e-6 G/A·m² "in each axis").

    Read as each magnetometer axis sensing its own-axis magnet; at 2000 A·m² that is
    0.0175 G (3.5 % of a 0.5 G maximum Earth field).
    """
    return np.eye(3) * gain_g_per_am2 * GAUSS_T


def coupling_acquisition(signs: np.ndarray | Sequence[Sequence[float]] | None = None, fraction: float = 0.05,
                         max_earth_field_t: float = MAX_EARTH_FIELD_T,
                         saturated_moment_am2: float = 2000.0) -> np.ndarray:
    """Acquisition worst-case coupling Δ, T/(A·m²) (seed §4.3.1, Case 10).

    A saturated magnet (saturated_moment_am2) adds ``fraction`` of the maximum
    Earth field on the OTHER two magnetometer axes; the diagonal is zero.
    signs: 3×3 array of ±1 for Δ[i, j] (i magnetometer, j magnet; diagonal
    ignored), default all +1. The seed's eq. 4-33 argument finds δ_zx > 0,
    δ_yx < 0 destabilising, the torque argument the opposite; simulations found
    no universal worst case, so the pattern is a scenario choice.
    """
    s = np.ones((3, 3)) if signs is None else np.asarray(signs, dtype=float)
    if s.shape != (3, 3) or not np.all(np.isin(s[~np.eye(3, dtype=bool)], (-1.0, 1.0))):
        raise CouplingError('signs must be a 3x3 array with off-diagonal entries of +1 or -1')
    if not (fraction >= 0.0 and max_earth_field_t > 0.0 and saturated_moment_am2 > 0.0):
        raise CouplingError('fraction must be >= 0, max_earth_field_t and saturated_moment_am2 > 0')
    gain = fraction * max_earth_field_t / saturated_moment_am2
    delta = s * gain
    np.fill_diagonal(delta, 0.0)
    return delta


def coupling_from_section(section: dict[str, Any]) -> np.ndarray:
    """Δ (3×3, T/(A·m²)) for the section's ``coupling_preset``.

    none: zeros. cruise: 8.75e-6 G/(A·m²) on the diagonal (seed 002 §4.3.2).
    acquisition: 5 % of the 0.5 G maximum field for a 2000 A·m² magnet on the other two
    axes, signs from ``coupling_signs`` (row-major, sensor axis i, magnet j; §4.3.1).
    custom: ``coupling`` (row-major 3×3, T/(A·m²)).
    """
    preset = section['coupling_preset']
    if preset == 'none':
        return np.zeros((3, 3))
    if preset == 'cruise':
        return coupling_cruise()
    if preset == 'acquisition':
        return coupling_acquisition(np.asarray(section['coupling_signs'], dtype=float).reshape(3, 3))
    if preset == 'custom':
        return np.asarray(section['coupling'], dtype=float).reshape(3, 3)
    raise CouplingError(f'unknown coupling_preset {preset!r}; expected none, cruise, acquisition or custom')
