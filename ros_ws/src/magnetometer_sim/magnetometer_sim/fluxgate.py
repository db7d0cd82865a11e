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


@kernels.helper
def unit_field_g(b_sensed_t: Vec3, unit: tuple[Vec3, Vec3, bool], noise_g: Vec3) -> Vec3:
    """The field each axis of one assembly measures, G: ``b_sensed_t`` (T) with the unit's scale and offset errors
    and, when the unit is noisy, this sample's noise ``noise_g`` (drawn in Python from the unit's stream).
    ``unit``: (scale errors, offsets in G, noisy) (:attr:`FluxgateAssembly.unit`)."""
    (sx, sy, sz), (ox, oy, oz), noisy = unit
    bx = b_sensed_t[0] / GAUSS_T * (1.0 + sx) + ox
    by = b_sensed_t[1] / GAUSS_T * (1.0 + sy) + oy
    bz = b_sensed_t[2] / GAUSS_T * (1.0 + sz) + oz
    if noisy:
        return bx + noise_g[0], by + noise_g[1], bz + noise_g[2]
    return bx, by, bz


@kernels.helper
def unit_output(volts: Vec3, last_v: Vec3, faults: tuple[Vec3, Vec3, tuple[bool, bool, bool], bool]
                ) -> tuple[Vec3, Vec3, Vec3]:
    """(last volts, axis volts, bias volts) one assembly puts out for the axis volts of its field: a stuck axis
    repeats its last output ``last_v``, a dead unit gives 0 V. ``faults``: (axis biases, bias outputs, stuck
    axes, dead) (:attr:`FluxgateAssembly.faults`)."""
    _, bias_out, stuck, dead = faults
    held = (last_v[0] if stuck[0] else volts[0], last_v[1] if stuck[1] else volts[1],
            last_v[2] if stuck[2] else volts[2])
    if dead:
        return held, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return held, held, bias_out


@kernels.helper
def unit_sample(b_sensed_t: Vec3, noise_g: Vec3, unit: tuple[Vec3, Vec3, bool],
                faults: tuple[Vec3, Vec3, tuple[bool, bool, bool], bool], last_v: Vec3, curve: tuple[float, ...]
                ) -> tuple[Vec3, Vec3, Vec3]:
    """One assembly's sample of the field at the sensor (T): :func:`unit_field_g` → :func:`unit_volts` about
    the axis biases → :func:`unit_output`; returns (last volts, axis volts, bias volts)."""
    return unit_output(unit_volts(unit_field_g(b_sensed_t, unit, noise_g), faults[0], curve), last_v, faults)


@kernels.helper
def magnetometer_sample(params: tuple, faults: tuple, last_v: tuple[Vec3, Vec3], b_true_t: Vec3, dipole_am2: Vec3,
                        noise_g: tuple[Vec3, Vec3], active: int) -> tuple[tuple[Vec3, Vec3], tuple[Vec3, ...]]:
    """Both assemblies' sample of one step (:meth:`Magnetometer.sample_xyz`, spec §5): the field at the sensor
    B_true + B_residual + Δ·M (T), each unit's :func:`unit_sample`, and the active unit's (``active``: 0 = A,
    1 = B) volts read back to field about the nominal bias and scale (T, the naive reader). ``params``:
    (residual T, Δ rows, curve, (unit A, unit B)); ``faults``, ``last_v``, ``noise_g``: per unit, A then B.
    Returns ((last volts A, last volts B), (volts, bias volts, field T, field at the sensor T)).

    A kernel (:mod:`acds_common.kernels`): one call a step samples the magnetometer, the noise already drawn
    (the units' numpy streams stay in Python).
    """
    residual, delta, curve, units = params
    dx, dy, dz = mv(delta, dipole_am2)
    b_sensed = (b_true_t[0] + residual[0] + dx, b_true_t[1] + residual[1] + dy, b_true_t[2] + residual[2] + dz)
    last_a, volts_a, bias_a = unit_sample(b_sensed, noise_g[0], units[0], faults[0], last_v[0], curve)
    last_b, volts_b, bias_b = unit_sample(b_sensed, noise_g[1], units[1], faults[1], last_v[1], curve)
    volts, bias = (volts_a, bias_a) if active == 0 else (volts_b, bias_b)
    bias_v, scale = curve[2], curve[3]
    field_t = ((volts[0] - bias_v) / scale * GAUSS_T, (volts[1] - bias_v) / scale * GAUSS_T,
               (volts[2] - bias_v) / scale * GAUSS_T)
    return (last_a, last_b), (volts, bias, field_t, b_sensed)


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
            offset_g = tuple(self._rng.uniform(-half_g, half_g, 3).tolist())
            scale_err = tuple((self._rng.uniform(-half_g, half_g, 3) / p.range_g).tolist())
        else:
            offset_g = (0.0, 0.0, 0.0)
            scale_err = (0.0, 0.0, 0.0)
        #: What :func:`unit_field_g` reads every sample: (scale errors, offsets in G, noisy).
        self.unit = (scale_err, offset_g, p.noise_std_g > 0.0)
        #: The state :func:`unit_output` carries from sample to sample: the last axis volts (a stuck axis's output).
        self.last_v = (float(p.bias_v),) * 3
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
        """What every sample reads of the faults (:attr:`faults`), computed when they change: each axis's bias
        (V, nominal + shift), the bias output clipped to the rails (each as min(max(e, lo), hi), in floats), the
        stuck axes and whether the unit is dead."""
        p = self.params
        shift_x, shift_y, shift_z = self._bias_shift_v
        ex, ey, ez = p.bias_v + shift_x, p.bias_v + shift_y, p.bias_v + shift_z
        lo, hi = float(p.rail_low_v), float(p.rail_high_v)
        bias_out = (lo if ex < lo else hi if ex > hi else ex, lo if ey < lo else hi if ey > hi else ey,
                    lo if ez < lo else hi if ez > hi else ez)
        #: (axis biases V, bias outputs V, stuck axes, dead): what :func:`unit_output` and :func:`unit_volts` read.
        self.faults = ((ex, ey, ez), bias_out, tuple(self._stuck), self._dead)

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

    def noise_g(self) -> Vec3:
        """This sample's noise, G: three draws from the unit's stream when noise_std_g > 0, else zeros (which
        :func:`unit_field_g` does not add)."""
        noise_std_g = self.params.noise_std_g
        if noise_std_g > 0.0:
            nx, ny, nz = self._rng.normal(0.0, noise_std_g, 3).tolist()
            return nx, ny, nz
        return ZERO

    def sample_xyz(self, b_sensed_t: Sequence[float]) -> tuple[Vec3, Vec3]:
        """:meth:`sample` on a float triple: (axis volts, bias volts) as float triples (:func:`unit_sample`)."""
        self.last_v, volts, bias = unit_sample(b_sensed_t, self.noise_g(), self.unit, self.faults, self.last_v,
                                               self.curve)
        return volts, bias

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
        #: Each unit's reading covariance in UNITS order, row-major, T² (diagonal: resolution, accuracy, noise).
        self._covariance9 = tuple((var, 0.0, 0.0, 0.0, var, 0.0, 0.0, 0.0, var)
                                  for var in (unit.params.variance_g2() * GAUSS_T**2 for unit in self.units.values()))
        self._active = 0  # the active unit's index in UNITS: what the kernel reads
        #: The two assemblies in UNITS order.
        self._pair = (self.units[UNITS[0]], self.units[UNITS[1]])
        a, b = self._pair
        #: What :func:`magnetometer_sample` reads every step (the units share ``params``, hence one curve).
        self._params = (self._residual, mat3(delta), a.curve, (a.unit, b.unit))
        #: Both units' noise when it is off: zeros, nothing drawn.
        self._quiet = (ZERO, ZERO)
        #: Bound to the one signature :meth:`sample_xyz` calls it with (:func:`kernels.bound`), fixed by construction:
        #: ``_params`` is built once here (the residual and Δ floats from float arrays, the curve unit A's, each unit
        #: tuple float triples from ``tolist`` or literals and a bool), each unit's ``faults`` is rebuilt only by
        #: ``_faults_changed`` (float biases: ``bias_v`` plus float shifts, rails made floats; bools), its
        #: ``last_v`` starts as floats and is then the kernel's own float output, the noise is ``ZERO`` or
        #: ``tolist`` floats, the field and dipole are made float tuples in :meth:`sample_xyz`, and ``_active`` is an int.
        self._sample = kernels.bound(magnetometer_sample, self._params, (a.faults, b.faults), (a.last_v, b.last_v),
                                     ZERO, ZERO, self._quiet, 0)

    def kernel_parts(self) -> tuple[tuple, tuple, int, tuple[Vec3, Vec3]] | None:
        """What a compiled caller needs to run :func:`magnetometer_sample` in place of :meth:`sample_xyz` (the direct
        engine's fused loop, :mod:`acds_common.fused`): the parameters, both units' faults, the active unit and the
        state (both units' last volts); None when the units draw noise (drawn here, in Python)."""
        a, b = self._pair
        if a.unit[2] or b.unit[2]:
            return None
        return self._params, (a.faults, b.faults), self._active, (a.last_v, b.last_v)

    def set_kernel_state(self, last_v: tuple[Vec3, Vec3]) -> None:
        """Both units' last volts (:meth:`kernel_parts`' state) after a compiled caller sampled."""
        a, b = self._pair
        a.last_v, b.last_v = last_v

    def select_unit(self, unit: str) -> None:
        """Make ``unit`` ('A' or 'B') the active assembly."""
        self._check_unit(unit)
        self._active = UNITS.index(unit)

    @property
    def active_unit(self) -> str:
        """The active assembly, 'A' or 'B'."""
        return UNITS[self._active]

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
        volts, bias, field_t, b_sensed = self.sample_xyz(b_true_xyz, dipole_xyz)
        return MagnetometerReading(volts, bias, field_t, b_sensed, self.active_unit, self.covariance9)

    def sample_xyz(self, b_true_xyz: Sequence[float], dipole_xyz: Sequence[float]) -> tuple[Vec3, Vec3, Vec3, Vec3]:
        """Both units sampled, the active one's (volts, bias volts, field to a naive reader T, field at the sensor T)
        as float triples (:func:`magnetometer_sample`, one kernel call; the noise drawn here, unit A's first)."""
        b0, b1, b2 = b_true_xyz
        d0, d1, d2 = dipole_xyz
        # The field and dipole come from other models and messages: the bound kernel takes tuples of three floats,
        # so anything else (ints, numpy scalars, lists) is made floats first, as the sums they enter would.
        if not (type(b_true_xyz) is tuple and type(dipole_xyz) is tuple and type(b0) is float and type(b1) is float
                and type(b2) is float and type(d0) is float and type(d1) is float and type(d2) is float):
            b_true_xyz, dipole_xyz = (float(b0), float(b1), float(b2)), (float(d0), float(d1), float(d2))
        a, b = self._pair
        noise = (a.noise_g(), b.noise_g()) if a.unit[2] else self._quiet  # the units share params: both or neither
        (a.last_v, b.last_v), out = self._sample(self._params, (a.faults, b.faults), (a.last_v, b.last_v), b_true_xyz,
                                                 dipole_xyz, noise, self._active)
        return out

    @property
    def covariance9(self) -> tuple[float, ...]:
        """The active unit's reading covariance, row-major, T²."""
        return self._covariance9[self._active]

    @staticmethod
    def _check_unit(unit: str) -> None:
        if unit not in UNITS:
            raise MagnetometerError(f'unit must be one of {UNITS}, got {unit!r}')
