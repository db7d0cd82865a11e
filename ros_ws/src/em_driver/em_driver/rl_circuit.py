"""Exact response of a series RL circuit between switching edges (spec §6: piecewise exponentials).

Between two switching events the circuit sees a constant voltage, so the current relaxes
exponentially toward its asymptote i_∞ = V/R with τ = L/R:

    i(t) = i_∞ + (i_0 − i_∞)·exp(−t/τ)
    ∫₀ᵗ i dt = i_∞·t + (i_0 − i_∞)·τ·(1 − exp(−t/τ))

Used by the HEAO bridge-switch driver (``bridge_switch``, seed 002 §4.2.5) and by the
CubeSat torque-rod PWM driver (``torque_rod``, seed 003). :func:`pwm_periods` adds n whole
periods of a fixed-duty PWM in closed form: each period maps its start current affinely
(i → a·i + b), so n periods are a geometric sum — exact, whatever n.

Currents in A, times in s; ``area`` is the charge ∫ i dt in A·s (C).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common import kernels

__all__ = ['segment', 'time_to_reach_s', 'PwmPeriods', 'pwm_periods', 'pwm_cumulative_charge']


@kernels.helper
def segment(i0_a: float, i_inf_a: float, tau_s: float, dt_s: float) -> tuple[float, float]:
    """(current at dt_s, ∫ i dt over [0, dt_s]) of one exponential segment from i0_a toward i_inf_a."""
    decay = math.exp(-dt_s / tau_s)
    return i_inf_a + (i0_a - i_inf_a) * decay, i_inf_a * dt_s + (i0_a - i_inf_a) * tau_s * (1.0 - decay)


@kernels.helper
def time_to_reach_s(i0_a: float, i_inf_a: float, target_a: float, tau_s: float) -> float:
    """Time for the segment from i0_a toward i_inf_a to reach target_a, s (math.inf if it never does)."""
    if i_inf_a != i0_a:
        ratio = (target_a - i_inf_a) / (i0_a - i_inf_a)
        if 0.0 < ratio <= 1.0:
            return -tau_s * math.log(ratio)
    return math.inf


@dataclass(frozen=True)
class PwmPeriods:
    """Result of n whole PWM periods (see :func:`pwm_periods`).

    end_current_a: current after the n periods, A.
    area_as: ∫ i dt over the n periods, A·s.
    area_on_as: ∫ i dt over the on-phases only, A·s (the bus delivers V·i only then).
    """

    end_current_a: float
    area_as: float
    area_on_as: float


def _period_map(i_on_a: float, tau_s: float, period_s: float, duty: float) -> tuple[float, float, float, float]:
    """(a, b, e_on, e_off) of one period: i_{k+1} = a·i_k + b; on-phase toward i_on_a, off-phase toward 0."""
    e_on = math.exp(-duty * period_s / tau_s)
    e_off = math.exp(-(1.0 - duty) * period_s / tau_s)
    return e_on * e_off, i_on_a * (1.0 - e_on) * e_off, e_on, e_off


def _pwm_totals(i0_a: float, i_on_a: float, tau_s: float, period_s: float, duty: float,
                n: np.ndarray | int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(i_n, on-phase charge, total charge) after n whole periods (n may be an array of counts).

    Σ_{k<n} i_k is geometric (1 − a = −expm1(−T/τ) keeps it accurate when T ≪ τ); each period's
    on- and off-phase charges are affine in its start current, so their sums follow from it.
    """
    a, b, e_on, e_off = _period_map(i_on_a, tau_s, period_s, duty)
    one_minus_a = -math.expm1(-period_s / tau_s)
    n_arr = np.asarray(n, dtype=float)
    g = -np.expm1(-n_arr * period_s / tau_s) / one_minus_a  # Σ_{k<n} a^k
    i_n = np.exp(-n_arr * period_s / tau_s) * i0_a + b * g
    sum_i = i0_a * g + b * (n_arr - g) / one_minus_a
    area_on = n_arr * i_on_a * duty * period_s + (sum_i - n_arr * i_on_a) * tau_s * (1.0 - e_on)
    sum_mid = n_arr * i_on_a + (sum_i - n_arr * i_on_a) * e_on  # Σ of the currents at the on→off edges
    return i_n, area_on, area_on + sum_mid * tau_s * (1.0 - e_off)


def pwm_periods(i0_a: float, i_on_a: float, tau_s: float, period_s: float, duty: float, n: int) -> PwmPeriods:
    """n whole periods of PWM, exactly: each period is on for duty·period_s (current → i_on_a), then off
    (slow decay: the coil shorted through the bridge, current → 0), both with τ = tau_s.

    The per-period map is affine, i_{k+1} = a·i_k + b with a = exp(−T/τ) and
    b = i_on·(1 − e_on)·e_off (e_on = exp(−D·T/τ), e_off = exp(−(1−D)·T/τ)), so the totals are
    geometric sums: no stepping through the periods.
    """
    if n < 0:
        raise ValueError(f'n must be >= 0 periods, got {n}')
    i_n, area_on, area = (float(x) for x in _pwm_totals(i0_a, i_on_a, tau_s, period_s, duty, n))
    return PwmPeriods(i_n, area, area_on)


def pwm_cumulative_charge(i0_a: float, i_on_a: float, tau_s: float, period_s: float, duty: float,
                          k: np.ndarray) -> np.ndarray:
    """∫ i dt from 0 to k·period_s for each whole-period count in the array ``k``, A·s (as :func:`pwm_periods`)."""
    return _pwm_totals(i0_a, i_on_a, tau_s, period_s, duty, k)[2]
