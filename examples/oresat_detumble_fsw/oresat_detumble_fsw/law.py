"""The detumble law of OreSat's flight software, in plain Python (seed 003: "Purpose", "Mission Requirements").

M = −(k_ω/|B|²)(B × ω) = −(k_ω/|B|)(B̂ × ω), saturated per axis at the rods' moment, with the gain
k_ω = (4π/T_orb)(sin ξ + 1) J_min from the orbit period T_orb, the orbit's inclination ξ to the geomagnetic
equator and the smallest principal moment of inertia J_min. The field is read as a flight computer reads its
magnetometer: the sensor's volts and its bias reference through an ADC (``adc_bits`` over 0…5 V, nearest count),
2.5 V per gauss. Units: T, rad/s, A·m², kg·m², s.
"""

from __future__ import annotations

import math

#: The magnetometer interface: converter span (V) and the sensor's scale (V per gauss), 1 G = 1e-4 T.
FULL_SCALE_V = 5.0
SCALE_V_PER_GAUSS = 2.5
GAUSS_T = 1e-4


def detumble_gain(orbit_period_s: float, inclination_rad: float, j_min_kg_m2: float) -> float:
    """k_ω = (4π/T_orb)(sin ξ + 1) J_min, kg·m²/s."""
    return 4.0 * math.pi / orbit_period_s * (math.sin(inclination_rad) + 1.0) * j_min_kg_m2


class Magnetometer:
    """The field from the magnetometer's volts and bias volts, as the ADC sees them."""

    def __init__(self, adc_bits: int) -> None:
        self.lsb_v = FULL_SCALE_V / (1 << adc_bits)
        self.top = (1 << adc_bits) - 1

    def count_v(self, v: float) -> float:
        """One voltage at the nearest ADC count (0…2ⁿ−1), as that count's voltage."""
        count = math.floor(v / self.lsb_v + 0.5)
        return (0 if count < 0 else self.top if count > self.top else count) * self.lsb_v

    def field_t(self, volts: tuple[float, float, float], bias: tuple[float, float, float]) -> tuple[float, ...]:
        """B in the body frame, T."""
        return tuple((self.count_v(v) - self.count_v(b)) / SCALE_V_PER_GAUSS * GAUSS_T for v, b in zip(volts, bias, strict=True))


def detumble_moment(b_t: tuple[float, ...], omega: tuple[float, ...], k_omega: float,
                    max_moment_am2: float) -> tuple[float, float, float]:
    """The saturated rod dipole command, A·m² (zero without a field: its direction is undefined)."""
    bx, by, bz = b_t
    wx, wy, wz = omega
    b2 = bx * bx + by * by + bz * bz
    if not b2 > 0.0 or not all(math.isfinite(x) for x in (*b_t, *omega)):
        return 0.0, 0.0, 0.0
    g = -(k_omega / b2)
    m = (g * (by * wz - bz * wy), g * (bz * wx - bx * wz), g * (bx * wy - by * wx))
    lo = -max_moment_am2
    return tuple(lo if x < lo else max_moment_am2 if x > max_moment_am2 else x for x in m)
