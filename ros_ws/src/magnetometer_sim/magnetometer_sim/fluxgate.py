"""Triaxial fluxgate magnetometer: two assemblies, coupling, residual field, faults (spec §5).

Seed: 002_heao_acds_study.txt §4.2.6 (Table 4-5), §4.2.7 (Fig. 4-11: per-axis
field voltages V_Bi and the zero-field bias voltage V_Bias), §4.3.1 (residual
body-fixed field 1 % of the maximum Earth field per axis; electromagnet →
magnetometer coupling eqs. 4-29 to 4-33, 5 % of the maximum Earth field on the
other two axes for a saturated magnet in acquisition) and §4.3.2 (cruise
coupling 8.75e-6 G per A·m² in each axis).

What the sensor sees (T, body axes): B_sensed = B_true + B_residual + Δ·M, with
M the electromagnets' achieved dipole (A·m², previous step) and Δ[i, j] the
coupling gain of the i-magnetometer to the j-magnet (the seed's δ_ij), T/(A·m²).

Volts ↔ field, per axis (b = B_sensed in gauss, V in volts):

    V = V_bias + k·(b + c·(b³ − b·b_fs²)) + accuracy error + noise,
    clipped to [0, 5] V, then quantised to steps of k·0.004 G = 0.01 V,

with k = 2.5 V/G, V_bias = 2.5 V (+ any bias-shift fault), b_fs = 1 G and
c = nonlinearity_frac/2. This end-point nonlinearity passes exactly through
0 V / 2.5 V / 5 V at −1 / 0 / +1 G; its slope k·(1 + c·(3b² − 1)) deviates from
k by −c at zero field and +2c = nonlinearity_frac (1 %) at full scale, so the
deviation never exceeds ±1 % of 2.5 V/G over ±1 G (Table 4-5). To invert
(what ``MagnetometerReading.field_t`` reports, the "naive reader"):
b ≈ (V − 2.5 V)/(2.5 V/G), i.e. about the NOMINAL bias; a reader that uses the
telemetered bias instead computes b ≈ (V − bias_volts)/(2.5 V/G), which removes
a bias-shift fault. Neither inversion undoes the nonlinearity (≤ 0.4 % of
reading, ≤ 0.0038 G at 1 G).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common import kernels, validation
from acds_common.commands import UNITS  # assembly names: active/standby pair
from acds_common.units import GAUSS_T
from acds_common.vec3 import ZERO, Vec3, mat3, mv

__all__ = [
    'MagnetometerError',
    'FluxgateAxisParams',
    'FluxgateAssembly',
    'Magnetometer',
    'MagnetometerReading',
    'FAULT_KINDS',
    'UNITS',
]

#: Fault kinds accepted by ``inject_fault``.
FAULT_KINDS = ('bias_shift', 'stuck_axis', 'dead_unit')


class MagnetometerError(ValueError):
    """Invalid input to the magnetometer model (the one exception of the magnetometer_sim package)."""


@dataclass(frozen=True)
class FluxgateAxisParams:
    """One fluxgate axis (Table 4-5). Units in the names; fields in gauss where the seed states them.

    bias_v: zero-field output, V (2.5). scale_v_per_g: 2.5 V/G.
    rail_low_v / rail_high_v: output rails, V (0 / 5).
    range_g: full scale ±range_g, G (1).
    nonlinearity_frac: peak slope deviation at full scale (0.01; sign selects
        expanding (+) or compressive (−) curvature; see the module docstring).
    resolution_g: output quantisation step, G (0.004 → 0.01 V).
    accuracy_frac_fs: accuracy bound, fraction of full scale (0.001 → ±0.001 G).
    accuracy_error_enabled: draw a fixed per-unit offset + scale error within the
        accuracy bound from the unit's seeded RNG (off by default).
    noise_std_g: white noise standard deviation, G (0: off).
    """

    bias_v: float = 2.5
    scale_v_per_g: float = 2.5
    rail_low_v: float = 0.0
    rail_high_v: float = 5.0
    range_g: float = 1.0
    nonlinearity_frac: float = 0.01
    resolution_g: float = 0.004
    accuracy_frac_fs: float = 0.001
    accuracy_error_enabled: bool = False
    noise_std_g: float = 0.0

    def __post_init__(self) -> None:
        for name in ('scale_v_per_g', 'range_g', 'resolution_g'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise MagnetometerError(f'FluxgateAxisParams.{name} must be finite and > 0, got {value!r}')
        for name in ('accuracy_frac_fs', 'noise_std_g'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise MagnetometerError(f'FluxgateAxisParams.{name} must be finite and >= 0, got {value!r}')
        if not (self.rail_low_v < self.bias_v < self.rail_high_v):
            raise MagnetometerError('FluxgateAxisParams: need rail_low_v < bias_v < rail_high_v')
        if not (math.isfinite(self.nonlinearity_frac) and abs(self.nonlinearity_frac) < 0.5):
            raise MagnetometerError(f'nonlinearity_frac must be finite with |value| < 0.5, '
                                    f'got {self.nonlinearity_frac!r}')

    @property
    def step_v(self) -> float:
        """Output quantisation step, V (resolution_g · scale_v_per_g)."""
        return self.resolution_g * self.scale_v_per_g

    def ideal_volts(self, b_g: np.ndarray) -> np.ndarray:
        """Noise-free, unclipped, unquantised output about the nominal bias, V, for fields b_g (G)."""
        c = 0.5 * self.nonlinearity_frac
        b = np.asarray(b_g, dtype=float)
        return self.bias_v + self.scale_v_per_g * (b + c * (b**3 - b * self.range_g**2))

    def variance_g2(self) -> float:
        """Per-axis reading variance, G²: quantisation (q²/12) + accuracy (uniform, a²/3) + noise."""
        accuracy_g = self.accuracy_frac_fs * self.range_g
        return self.resolution_g**2 / 12.0 + accuracy_g**2 / 3.0 + self.noise_std_g**2


@kernels.helper
def axis_volts(b_g: float, bias_v: float, curve: tuple[float, ...]) -> float:
    """One axis (module docstring): field ``b_g`` (G) → output volts about ``bias_v``, clipped to the rails,
    quantised; ``curve`` = (c, range_g², nominal bias, scale, rail low, rail high, step), V and G.

    ``b_g ** 3.0`` is the C library's ``pow`` both ways (Python turns ``** 3`` into the same call; numba would
    multiply instead, which differs in the last bit); ``round`` is round-half-even both ways.
    """
    c, range2, bias, scale, low, high, step = curve
    v = bias + scale * (b_g + c * (b_g ** 3.0 - b_g * range2)) - bias + bias_v
    v = low if v < low else high if v > high else v  # the rails
    return round(v / step) * step


@kernels.helper
def unit_volts(b_g: Vec3, bias_v: Vec3, curve: tuple[float, ...]) -> Vec3:
    """One assembly's three axes: :func:`axis_volts` of each field component (G) about its bias (V)."""
    return axis_volts(b_g[0], bias_v[0], curve), axis_volts(b_g[1], bias_v[1], curve), axis_volts(b_g[2], bias_v[2], curve)


def pair_volts(b_a: Vec3, bias_a: Vec3, b_b: Vec3, bias_b: Vec3, curve: tuple[float, ...]) -> tuple[Vec3, Vec3]:
    """Both assemblies' axis volts (:func:`unit_volts`) in one call: the kernel (:mod:`acds_common.kernels`)
    :meth:`Magnetometer.read` runs every step, the noise already drawn (the units' numpy streams stay in Python)."""
    return unit_volts(b_a, bias_a, curve), unit_volts(b_b, bias_b, curve)


class MagnetometerReading:
    """One magnetometer sample (spec §5, Table 4-11 telemetry).

    volts: per-axis field voltages V_Bi, V (0…5).
    bias_volts: per-axis zero-field bias reference output, V (2.5 nominal).
    field_t: field the volts mean to a naive reader, T: (volts − 2.5 V)/(2.5 V/G)
        in gauss × 1e-4 (nominal bias and scale; see the module docstring).
    b_sensed_t: the field at the sensor the volts came from (truth + residual + Δ·M), T.
    active_unit: 'A' or 'B'.
    covariance_t2: 3×3 reading covariance, T² (diagonal, from resolution/accuracy/noise).

    The model computes float triples (``volts_xyz``, ``bias_xyz``, ``field_xyz``, ``b_sensed_xyz``
    and the row-major ``covariance9``: what the stepper publishes); the numpy attributes are built
    from them when read.
    """

    def __init__(self, volts_xyz: Vec3, bias_xyz: Vec3, field_xyz: Vec3, b_sensed_xyz: Vec3, active_unit: str,
                 covariance9: tuple[float, ...]) -> None:
        self.volts_xyz = volts_xyz
        self.bias_xyz = bias_xyz
        self.field_xyz = field_xyz
        self.b_sensed_xyz = b_sensed_xyz
        self.active_unit = active_unit
        self.covariance9 = covariance9

    @property
    def volts(self) -> np.ndarray:
        """Per-axis field voltages, V."""
        return np.array(self.volts_xyz)

    @property
    def bias_volts(self) -> np.ndarray:
        """Per-axis bias reference voltages, V."""
        return np.array(self.bias_xyz)

    @property
    def field_t(self) -> np.ndarray:
        """Field the volts mean to a naive reader, T."""
        return np.array(self.field_xyz)

    @property
    def b_sensed_t(self) -> np.ndarray:
        """Field at the sensor, T."""
        return np.array(self.b_sensed_xyz)

    @property
    def covariance_t2(self) -> np.ndarray:
        """3×3 reading covariance, T²."""
        return np.array(self.covariance9).reshape(3, 3)


class FluxgateAssembly:
    """One triaxial fluxgate assembly (sensor + electronics unit) with its faults (spec §5).

    params: one FluxgateAxisParams used for all three axes.
    seed: seeds this unit's RNG (accuracy error draw and noise).
    """

    def __init__(self, params: FluxgateAxisParams | None = None, seed: int = 0) -> None:
        self.params = FluxgateAxisParams() if params is None else params
        self._rng = np.random.default_rng(seed)
        p = self.params
        if p.accuracy_error_enabled:
            # Offset and scale errors each take up to half the ±0.1 % FS budget.
            half_g = 0.5 * p.accuracy_frac_fs * p.range_g
            self._offset_g = tuple(self._rng.uniform(-half_g, half_g, 3).tolist())
            self._scale_err = tuple((self._rng.uniform(-half_g, half_g, 3) / p.range_g).tolist())
        else:
            self._offset_g = (0.0, 0.0, 0.0)
            self._scale_err = (0.0, 0.0, 0.0)
        self._last_v = (p.bias_v, p.bias_v, p.bias_v)
        #: What :func:`axis_volts` reads every sample: the curve's constants (the same values as from the params).
        self.curve = (0.5 * p.nonlinearity_frac, p.range_g ** 2, p.bias_v, p.scale_v_per_g, p.rail_low_v,
                      p.rail_high_v, p.step_v)
        self.clear_faults()

    def clear_faults(self) -> None:
        """Remove every injected fault."""
        self._bias_shift_v = [0.0, 0.0, 0.0]
        self._stuck = [False, False, False]
        self._dead = False
        self._faults_changed()

    def _faults_changed(self) -> None:
        """What every sample reads of the faults, computed when they change: each axis's bias (V, nominal + shift),
        the bias output clipped to the rails (each as min(max(e, lo), hi)) and whether any axis is stuck."""
        p = self.params
        shift_x, shift_y, shift_z = self._bias_shift_v
        ex, ey, ez = p.bias_v + shift_x, p.bias_v + shift_y, p.bias_v + shift_z
        self.axis_bias_v = (ex, ey, ez)
        lo, hi = p.rail_low_v, p.rail_high_v
        self._bias_out = (lo if ex < lo else hi if ex > hi else ex, lo if ey < lo else hi if ey > hi else ey,
                          lo if ez < lo else hi if ez > hi else ez)
        self._any_stuck = any(self._stuck)

    def inject_fault(self, kind: str, axis: int | None = None, value: float | None = None) -> None:
        """Inject 'bias_shift' (value V, one axis or all), 'stuck_axis' (one axis or all) or 'dead_unit'."""
        axes = self._axes(axis)
        if kind == 'bias_shift':
            if value is None or not math.isfinite(value):
                raise MagnetometerError(f'bias_shift needs a finite value in volts, got {value!r}')
            for i in axes:
                self._bias_shift_v[i] += value
        elif kind == 'stuck_axis':
            for i in axes:
                self._stuck[i] = True
        elif kind == 'dead_unit':
            self._dead = True
        else:
            raise MagnetometerError(f'unknown magnetometer fault {kind!r}; expected one of {FAULT_KINDS}')
        self._faults_changed()

    def field_g(self, b_sensed_t: Sequence[float]) -> Vec3:
        """The field each axis measures, G: b_sensed_t (T) with the unit's scale and offset errors and this
        sample's noise (drawn from the unit's stream when noise_std_g > 0)."""
        (sx, sy, sz), (ox, oy, oz) = self._scale_err, self._offset_g
        bx = b_sensed_t[0] / GAUSS_T * (1.0 + sx) + ox
        by = b_sensed_t[1] / GAUSS_T * (1.0 + sy) + oy
        bz = b_sensed_t[2] / GAUSS_T * (1.0 + sz) + oz
        noise_std_g = self.params.noise_std_g
        if noise_std_g > 0.0:
            nx, ny, nz = self._rng.normal(0.0, noise_std_g, 3).tolist()
            return bx + nx, by + ny, bz + nz
        return bx, by, bz

    def output(self, volts: Vec3) -> tuple[Vec3, Vec3]:
        """(axis volts, bias volts) the unit puts out for the axis volts of its field (:func:`unit_volts`): a stuck
        axis repeats its last output, a dead unit gives 0 V."""
        if self._any_stuck:
            last, stuck = self._last_v, self._stuck
            volts = (last[0] if stuck[0] else volts[0], last[1] if stuck[1] else volts[1],
                     last[2] if stuck[2] else volts[2])
        self._last_v = volts
        if self._dead:
            return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        return volts, self._bias_out

    def sample_xyz(self, b_sensed_t: Sequence[float]) -> tuple[Vec3, Vec3]:
        """:meth:`sample` on a float triple: (axis volts, bias volts) as float triples."""
        return self.output(unit_volts(self.field_g(b_sensed_t), self.axis_bias_v, self.curve))

    def sample(self, b_sensed_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Output (axis volts, bias volts), V, for the field at the sensor b_sensed_t (T, body axes)."""
        volts, bias = self.sample_xyz(_check_xyz('b_sensed_t', b_sensed_t))
        return np.array(volts), np.array(bias)

    @staticmethod
    def _axes(axis: int | None) -> tuple[int, ...]:
        if axis is None:
            return (0, 1, 2)
        if axis not in (0, 1, 2):
            raise MagnetometerError(f'axis must be 0, 1, 2 (x, y, z) or None for all, got {axis!r}')
        return (axis,)


def _check_xyz(name: str, value: np.ndarray | Sequence[float]) -> Vec3:
    return validation.finite_xyz(name, value, MagnetometerError)


def _check_vec3(name: str, value: np.ndarray | Sequence[float]) -> np.ndarray:
    return validation.finite_vector3(name, value, MagnetometerError)


class Magnetometer:
    """Two fluxgate assemblies (active/standby) behind one transfer-assembly interface (spec §5).

    params: axis parameters for both units. seed: base RNG seed (unit A uses seed,
    unit B seed + 1). residual_field_t: body-fixed residual field, T (3-vector).
    coupling_t_per_am2: Δ, 3×3, T/(A·m²) (default zero; see ``coupling_cruise`` and
    ``coupling_acquisition``). Both units see the same field.
    """

    def __init__(self, params: FluxgateAxisParams | None = None, seed: int = 0,
                 residual_field_t: np.ndarray | Sequence[float] = (0.0, 0.0, 0.0),
                 coupling_t_per_am2: np.ndarray | None = None) -> None:
        self.units = {name: FluxgateAssembly(params, seed + k) for k, name in enumerate(UNITS)}
        self.residual_field_t = _check_vec3('residual_field_t', residual_field_t)
        delta = np.zeros((3, 3)) if coupling_t_per_am2 is None else np.asarray(coupling_t_per_am2, dtype=float)
        if delta.shape != (3, 3) or not np.all(np.isfinite(delta)):
            raise MagnetometerError(f'coupling_t_per_am2 must be a finite 3x3 matrix, got shape {delta.shape}')
        self.coupling_t_per_am2 = delta
        self._residual = tuple(self.residual_field_t.tolist())
        #: Each unit's reading covariance, row-major, T² (diagonal: resolution, accuracy, noise).
        self._covariance9 = {}
        for name, unit in self.units.items():
            var = unit.params.variance_g2() * GAUSS_T**2
            self._covariance9[name] = (var, 0.0, 0.0, 0.0, var, 0.0, 0.0, 0.0, var)
        self._delta = mat3(delta)
        self.active_unit = UNITS[0]
        #: The two assemblies in UNITS order and their volts kernel (one call a read; the units share ``params``,
        #: hence one curve).
        self._pair = (self.units[UNITS[0]], self.units[UNITS[1]])
        a, b = self._pair
        #: Bound to the one signature :meth:`read_xyz` calls it with (:func:`kernels.bound`), fixed by construction:
        #: :meth:`FluxgateAssembly.field_g` gives floats (a true division of every component), each axis bias is
        #: ``bias_v`` plus a float shift (0.0 or sums from 0.0), and the curve is unit A's, built once here.
        #: (The example fields are float triples, not ``field_g``'s: that would draw from the units' noise streams.)
        self._pair_volts = kernels.bound(pair_volts, ZERO, a.axis_bias_v, ZERO, b.axis_bias_v, a.curve)

    def select_unit(self, unit: str) -> None:
        """Make ``unit`` ('A' or 'B') the active assembly."""
        self._check_unit(unit)
        self.active_unit = unit

    def inject_fault(self, unit: str, kind: str, axis: int | None = None, value: float | None = None) -> None:
        """Fault one unit: 'bias_shift' (value in V), 'stuck_axis' (output frozen), 'dead_unit' (all 0 V)."""
        self._check_unit(unit)
        self.units[unit].inject_fault(kind, axis, value)

    def clear_faults(self, unit: str | None = None) -> None:
        """Clear the faults of one unit, or of both when unit is None."""
        if unit is not None:
            self._check_unit(unit)
        for name, assembly in self.units.items():
            if unit is None or name == unit:
                assembly.clear_faults()

    def read(self, b_true_body_t: np.ndarray | Sequence[float],
             em_dipole_am2: np.ndarray | Sequence[float] = (0.0, 0.0, 0.0)) -> MagnetometerReading:
        """Sample both units (standby keeps tracking) and report the active one.

        b_true_body_t: Earth field at the spacecraft, body axes, T.
        em_dipole_am2: the electromagnets' achieved dipole from the previous step, A·m².
        """
        return self.read_xyz(_check_xyz('b_true_body_t', b_true_body_t), _check_xyz('em_dipole_am2', em_dipole_am2))

    def read_xyz(self, b_true_xyz: Sequence[float], dipole_xyz: Sequence[float]) -> MagnetometerReading:
        """:meth:`read` on float triples already checked finite (the stepper's per-step path, spec §5)."""
        bx, by, bz = b_true_xyz
        rx, ry, rz = self._residual
        dx, dy, dz = mv(self._delta, dipole_xyz)
        b_sensed = (bx + rx + dx, by + ry + dy, bz + rz + dz)
        a, b = self._pair
        volts_a, volts_b = self._pair_volts(a.field_g(b_sensed), a.axis_bias_v, b.field_g(b_sensed), b.axis_bias_v,
                                              a.curve)
        sample_a, sample_b = a.output(volts_a), b.output(volts_b)
        volts, bias = sample_a if self.active_unit == UNITS[0] else sample_b
        p = self.units[self.active_unit].params
        field_t = ((volts[0] - p.bias_v) / p.scale_v_per_g * GAUSS_T, (volts[1] - p.bias_v) / p.scale_v_per_g * GAUSS_T,
                   (volts[2] - p.bias_v) / p.scale_v_per_g * GAUSS_T)
        return MagnetometerReading(volts, bias, field_t, b_sensed, self.active_unit, self._covariance9[self.active_unit])

    @staticmethod
    def _check_unit(unit: str) -> None:
        if unit not in UNITS:
            raise MagnetometerError(f'unit must be one of {UNITS}, got {unit!r}')
