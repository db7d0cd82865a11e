"""Magnetic CMG momentum dump of the AAP Workshop: the k·H_s × B law, its minimum-energy origin, and the per-orbit
bookkeeping and report (seed 000 §2, §3, §5, Appendix B).

Seed: ``000_aap_cmg_dump_levidow.txt``. Conventions: SI inside (B in T, body axes; momentum N·m·s; M in A·m²);
the torque on the vehicle is T = M × B (eq. 1); the CMGs hold the attitude, so over an orbit their momentum
changes by the bias H_b plus the magnetic torque's integral (§5): ΔH_s = H_b + ∫₀ᵀ M × B dt.

Laws (selected by :class:`DumpLawConfig` ``law``):

* ``'khb'``: M(t) = k H_s × B(t) (§3), H_s the CMG momentum sampled at the start of each orbit and held for it.
  The seed's k = 4e6 with H_s in ft-lb-sec, B in Wb/m², M in amp-turn-m²; in SI
  k_SI = 4e6 / 1.3558179 = 2.950e6 A·m² per (N·m·s·T), i.e. s⁻¹·T⁻² (:func:`k_to_si`).
  The torque k (H_s × B) × B = −k |B|² H_s⊥ opposes the part of H_s normal to B.
* ``'khb_shifted'``: M = k (H_s − H_0) × B (§3), which moves the region H_s settles in by H_0.
* ``'min_energy'``: eq. (3), M(t) = [(−∫₀ᵀ B̃²(t) dt)⁻¹ H_b] × B(t), the M of least ∫|M|² dt that dumps exactly
  H_b over the orbit (Appendix B), with B̃ the matrix of B × and B(t) over the coming orbit predicted on board.
  W = −∫ B̃² dt = ∫ (|B|² I − B Bᵀ) dt is positive definite unless B keeps one direction all orbit (B-4). The
  OCR copy of Appendix B lost the tildes ("∫ B² dt" in the λ line and in B-3); re-derived: λ =
  −2 (∫ B̃ B̃ᵀ dt)⁻¹ H_b = −2 W⁻¹ H_b, M = −B̃ᵀ λ / 2 = B × λ/2 = (W⁻¹ H_b) × B, which is eq. (3).

The sampled loop: with the unsaturated k·H_s × B law the orbit's magnetic momentum is ∫ M × B dt =
−k W (H_s − H_0), so the once-per-orbit samples obey H_{n+1} − H_0 = (I − k W_n)(H_n − H_0) + H_b. Its fixed
point k (H_s − H_0) = W⁻¹ H_b is eq. (3)'s bracket (§3: "the two solutions are identical"), and it is reached
only if every eigenvalue of k W lies in (0, 2) (:func:`loop_gains`); the report carries those gains per orbit.

The seed's k in its own units does not converge (issue 21, worked by hand from Appendix A): on the 220 nmi
orbit (T = 5,562.8 s) with B_0 = 0.26e-4 Wb/m², T·B_0² = 3.761e-6 T²·s, and W/(T·B_0²) has eigenvalues
0.36–1.45 as the dipole turns with the Earth (η_E), so with k_SI = 2.950e6 the gains k·W are 4.0–16.1: the
loop diverges for the whole of the seed's range 3e6–5e6. The field magnitude is the seed's (its own M_m =
12.5 H_b, which depends on W but not on k, is reproduced), and the sampling is its once per orbit; what
does not fit is k by a factor ≈ 10: the largest gain reaches 2 at k = 4.97e5 in the seed's units. A slip of
ten does not fit the memo's whole range (5e5: gains up to 2.04, no convergence); read with M in amp-turn-ft²
(÷ 10.764) the range 3–5e6 is 2.79–4.65e5, gains up to 1.14–1.89, all converging within a few orbits as the
memo says: the scenarios' literal case is 4e6 amp-turn-ft² per ft-lb-sec per Wb/m² (the unit
``aft2_per_ftlbs_t`` of ``controller.dump_gain``). The Workshop computer may instead derive k from the
loop-gain condition (:func:`loop_gain_k_seed`).

Variants of the k law flown in the seed: |M| limited to a fraction of the unconstrained maximum, direction
kept (§9, :func:`limit_magnitude`), and day-only dumping at a constant |M| in the direction of k H_s × B (§10,
:func:`constant_magnitude`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from acds_common.units import dump_gain_seed_to_si, nms_to_ftlbs

from acds_controller.magnetic_laws import ControllerError, as_vector3, check_gain, saturate

#: The seed's gain, amp-turn-m² per (ft-lb-sec · Wb/m²) (§5: "All data in this report are based on using k = 4 × 10^6").
K_SEED = 4e6
#: The range the seed found to converge from H_s = 0 "after a few orbits" (§5: "3 × 10^6 to 5 × 10^6").
K_SEED_RANGE = (3e6, 5e6)
LAWS = ('khb', 'khb_shifted', 'min_energy')
#: Default field samples per orbit for the minimum-energy prediction (trapezoid rule, closed interval).
PREDICTION_SAMPLES = 720


def k_to_si(k_seed: float) -> float:
    """The seed's k (amp-turn-m² per ft-lb-sec per Wb/m²) in SI, A·m²/(N·m·s·T) = s⁻¹·T⁻²: k / 1.3558179."""
    return dump_gain_seed_to_si(check_gain(k_seed, 'k (amp-turn-m² per ft-lb-sec per Wb/m²)', 0.0, 1e12))


def khb_moment(h_s_nms: np.ndarray, b_t: np.ndarray, k_seed: float = K_SEED,
               h_0_nms: np.ndarray | None = None) -> np.ndarray:
    """M = k (H_s − H_0) × B, A·m² (§3); ``h_0_nms`` None for the plain law. Unsaturated, perpendicular to B."""
    h = as_vector3(h_s_nms, 'h_s_nms')
    if h_0_nms is not None:
        h = h - as_vector3(h_0_nms, 'h_0_nms')
    return k_to_si(k_seed) * np.cross(h, as_vector3(b_t, 'b_t'))


def _samples(b_body_t: np.ndarray, weights_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    b = np.asarray(b_body_t, dtype=float)
    w = np.asarray(weights_s, dtype=float)
    if b.ndim != 2 or b.shape[1] != 3 or w.shape != (b.shape[0],):
        raise ControllerError(f'field samples must be (N, 3) with N weights, got {b.shape} and {w.shape}')
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(w))) or np.any(w < 0.0):
        raise ControllerError('field samples and weights must be finite, weights >= 0')
    return b, w


def field_gramian(b_body_t: np.ndarray, weights_s: np.ndarray) -> np.ndarray:
    """W = −∫ B̃² dt = Σ w_k (|B_k|² I − B_k B_kᵀ), T²·s, from field samples (N, 3) and quadrature weights (s)."""
    b, w = _samples(b_body_t, weights_s)
    b2 = np.einsum('k,ki,ki->', w, b, b)
    return b2 * np.eye(3) - np.einsum('k,ki,kj->ij', w, b, b)


def trapezoid_weights(t_s: np.ndarray) -> np.ndarray:
    """Trapezoid-rule weights (s) over increasing sample times (a closed interval)."""
    t = np.asarray(t_s, dtype=float)
    dt = np.diff(t)
    if t.ndim != 1 or t.size < 2 or np.any(dt <= 0.0):
        raise ControllerError('sample times must be increasing, at least two')
    w = np.zeros_like(t)
    w[:-1] += 0.5 * dt
    w[1:] += 0.5 * dt
    return w


def hold_weights(t_s: np.ndarray) -> np.ndarray:
    """Zero-order-hold weights (s): sample k holds until sample k+1 (the last for the previous spacing)."""
    t = np.asarray(t_s, dtype=float)
    dt = np.diff(t)
    if t.ndim != 1 or t.size < 2 or np.any(dt <= 0.0):
        raise ControllerError('step times must be increasing, at least two')
    return np.append(dt, dt[-1])


def min_energy_vector(w: np.ndarray, h_b_nms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(c, H_undumpable): c = W⁻¹ H_b (A·m²/T), eq. (3)'s bracket, and what no moment can dump (N·m·s).

    W is positive definite for any orbit off the magnetic equator (Appendix B); when B keeps one
    direction (W singular) c is the least-norm solution and H_b − W c is the component along B that
    "it would be impossible to dump" (§2).
    """
    wm = np.asarray(w, dtype=float)
    h_b = as_vector3(h_b_nms, 'h_b_nms')
    vals, vecs = np.linalg.eigh(wm)
    if vals[-1] <= 0.0:
        raise ControllerError('the field gramian is zero: no field over the orbit, nothing can be dumped')
    keep = vals > vals[-1] * 1e-9
    c = vecs[:, keep] @ ((vecs[:, keep].T @ h_b) / vals[keep])
    return c, h_b - wm @ c


def loop_gains(w: np.ndarray, k_seed: float = K_SEED) -> np.ndarray:
    """Eigenvalues of k W (dimensionless, ascending): the sampled k·H_s × B loop converges iff all are in (0, 2)."""
    return np.linalg.eigvalsh(k_to_si(k_seed) * np.asarray(w, dtype=float))


def loop_gain_k_seed(gramians: list[np.ndarray], largest_gain: float = 1.0) -> float:
    """k (seed units) whose largest loop gain over the given orbits' gramians is ``largest_gain``: the loop-gain
    condition of the sampled law, k = g / max_n λ_max(W_n) (g = 1: dead-beat on the fastest mode; any g in
    (0, 2) keeps that orbit's loop convergent, the slowest mode then has k λ_min(W_n))."""
    g = check_gain(largest_gain, 'largest loop gain', 1e-6, 2.0)
    peak = max(float(np.linalg.eigvalsh(np.asarray(w, dtype=float))[-1]) for w in gramians)
    if peak <= 0.0:
        raise ControllerError('the field gramian is zero: no loop gain can be set')
    return g / (k_to_si(1.0) * peak)


def limit_magnitude(m_am2: np.ndarray, limit_am2: float) -> np.ndarray:
    """M scaled down to |M| ≤ ``limit_am2``, its direction kept (§9: the limit is on M_m, the magnitude)."""
    m = as_vector3(m_am2, 'm_am2')
    size = float(np.linalg.norm(m))
    return m if size <= limit_am2 else m * (limit_am2 / size)


def constant_magnitude(m_am2: np.ndarray, size_am2: float) -> np.ndarray:
    """M of magnitude ``size_am2`` along ``m_am2`` (§10: constant |M|, direction from k H_s × B); zero when m is."""
    m = as_vector3(m_am2, 'm_am2')
    norm = float(np.linalg.norm(m))
    return np.zeros(3) if norm == 0.0 else m * (size_am2 / norm)


def min_energy_peak_am2(b_body_t: np.ndarray, weights_s: np.ndarray, h_b_nms: np.ndarray) -> float:
    """max_t |c × B(t)| with c = W⁻¹ H_b over the samples: M_m of eq. (3) on that orbit, A·m²."""
    b, w = _samples(b_body_t, weights_s)
    c, _ = min_energy_vector(field_gramian(b, w), h_b_nms)
    return float(np.max(np.linalg.norm(np.cross(c, b), axis=1)))


def proper_initial_h_s_nms(c: np.ndarray, k_seed: float = K_SEED, h_0_nms: np.ndarray | None = None) -> np.ndarray:
    """The §5 initialisation, k (H_s − H_0) = eq. (3)'s bracket c: then exactly H_b is dumped on the first orbit."""
    h = as_vector3(c, 'c') / k_to_si(k_seed)
    return h if h_0_nms is None else h + as_vector3(h_0_nms, 'h_0_nms')


@dataclass(frozen=True)
class OrbitClock:
    """Orbit boundaries t0 + n·T. A step belongs to orbit n = ⌊(t − t0)/T⌋ (a step at a boundary opens the next)."""

    period_s: float
    t0_s: float = 0.0

    def __post_init__(self) -> None:
        check_gain(self.period_s, 'orbit period_s', 1.0, 1e9)
        check_gain(self.t0_s, 't0_s', -1e12, 1e12)

    def index(self, t_s: float) -> int:
        """Orbit number of time ``t_s`` (tolerant of the last-bit rounding of step times k·Δt)."""
        return math.floor((float(t_s) - self.t0_s) / self.period_s + 1e-9)

    def start_s(self, n: int) -> float:
        """Start time of orbit ``n``, s."""
        return self.t0_s + n * self.period_s


class SampledMomentum:
    """H_s: the CMG momentum sampled at the first step of each orbit and held until the next (§3, §5)."""

    def __init__(self, clock: OrbitClock) -> None:
        self.clock = clock
        self._orbit: int | None = None
        self._h_s = np.zeros(3)

    def sample(self, t_s: float, h_cmg_nms: np.ndarray) -> np.ndarray:
        """H_s (N·m·s) for the step at ``t_s``; ``h_cmg_nms`` is the CMG momentum then (used only at a new orbit)."""
        n = self.clock.index(t_s)
        if self._orbit is None or n != self._orbit:
            if self._orbit is not None and n < self._orbit:
                raise ControllerError(f'time went back from orbit {self._orbit} to orbit {n} (t = {t_s} s)')
            self._h_s = as_vector3(h_cmg_nms, 'h_cmg_nms').copy()
            self._orbit = n
        return self._h_s.copy()


def predicted_orbit(predict_b_body_t: Callable[[float], np.ndarray], clock: OrbitClock, n: int,
                    samples: int = PREDICTION_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """(B (samples + 1, 3) in T, trapezoid weights in s) of orbit ``n`` from a field prediction."""
    t = np.linspace(clock.start_s(n), clock.start_s(n + 1), samples + 1)
    b = np.array([as_vector3(predict_b_body_t(float(x)), 'predicted field') for x in t])
    return b, trapezoid_weights(t)


@dataclass(frozen=True)
class DumpLawConfig:
    """Choice and parameters of the dump law (§3, §5).

    ``law``: 'khb' | 'khb_shifted' | 'min_energy'; ``k_seed``: k in the seed's units (4e6);
    ``h_0_nms``: H_0 of the shifted law, N·m·s; ``max_moment_am2``: per-axis magnet limit, A·m² (None: no
    limit; the seed's §5 runs are unconstrained); ``h_b_nms``: bias momentum per orbit that the minimum-energy
    law dumps (known in advance, §3), N·m·s; ``prediction_samples``: field samples per predicted orbit;
    ``moment_limit_am2``: limit on |M|, direction kept (§9; None: none); ``day_moment_am2``: day-only dumping
    at this constant |M| (§10; None: day and night dumping).
    """

    law: str = 'khb'
    k_seed: float = K_SEED
    h_0_nms: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_moment_am2: float | None = None
    h_b_nms: tuple[float, float, float] | None = None
    prediction_samples: int = PREDICTION_SAMPLES
    moment_limit_am2: float | None = None
    day_moment_am2: float | None = None

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ControllerError(f'DumpLawConfig.law must be one of {LAWS}, got {self.law!r}')
        k_to_si(self.k_seed)
        as_vector3(self.h_0_nms, 'DumpLawConfig.h_0_nms')
        if self.max_moment_am2 is not None:
            check_gain(self.max_moment_am2, 'DumpLawConfig.max_moment_am2', 1e-9, 1e12)
        for name in ('moment_limit_am2', 'day_moment_am2'):
            if getattr(self, name) is not None:
                check_gain(getattr(self, name), f'DumpLawConfig.{name}', 1e-9, 1e12)
        if self.law == 'min_energy' and self.h_b_nms is None:
            raise ControllerError("DumpLawConfig.law 'min_energy' needs h_b_nms, the bias momentum to dump per orbit")
        if self.h_b_nms is not None:
            as_vector3(self.h_b_nms, 'DumpLawConfig.h_b_nms')
        if int(self.prediction_samples) != self.prediction_samples or self.prediction_samples < 8:
            raise ControllerError(f'DumpLawConfig.prediction_samples must be an integer >= 8, got '
                                  f'{self.prediction_samples!r}')


class CmgDumpLaw:
    """The dump law as a stepper: ``step(t, H_s, B) -> M`` per control step (§3).

    ``predict_b_body_t``: the on-board prediction of the body-axis field (T) at a time (s), needed by
    'min_energy' only; at the first step of each orbit it is sampled over that orbit and eq. (3)'s
    bracket c_n = W_n⁻¹ H_b is fixed for the orbit. The k laws use the sampled H_s handed in (see
    :class:`SampledMomentum`); 'min_energy' ignores it.
    """

    def __init__(self, cfg: DumpLawConfig, clock: OrbitClock,
                 predict_b_body_t: Callable[[float], np.ndarray] | None = None) -> None:
        if cfg.law == 'min_energy' and predict_b_body_t is None:
            raise ControllerError("law 'min_energy' needs predict_b_body_t, the predicted field along the orbit")
        self.cfg, self.clock, self._predict = cfg, clock, predict_b_body_t
        self._orbit: int | None = None
        self._c = np.zeros(3)
        self._undumpable = np.zeros(3)
        self._unsaturated = np.zeros(3)

    @property
    def min_energy_vector(self) -> np.ndarray:
        """Eq. (3)'s bracket for the current orbit, A·m²/T ('min_energy' only; zeros before the first step)."""
        return self._c.copy()

    @property
    def undumpable_nms(self) -> np.ndarray:
        """Part of H_b the predicted field cannot dump this orbit, N·m·s ('min_energy' only)."""
        return self._undumpable.copy()

    @property
    def unsaturated_am2(self) -> np.ndarray:
        """The last step's moment before the per-axis limit, A·m²."""
        return self._unsaturated.copy()

    def predicted_gramian(self, n: int) -> np.ndarray:
        """W of orbit ``n`` from the prediction (trapezoid rule over ``prediction_samples`` intervals), T²·s."""
        if self._predict is None:
            raise ControllerError('no field prediction was given to this law')
        return field_gramian(*predicted_orbit(self._predict, self.clock, n, self.cfg.prediction_samples))

    def step(self, t_s: float, h_s_nms: np.ndarray, b_body_t: np.ndarray, day: bool = True) -> np.ndarray:
        """Moment command M (A·m², body, per-axis limited) for the step at ``t_s`` with sampled H_s and measured B;
        ``day``: the vehicle is in orbital daylight (only day-only dumping, §10, looks at it: zero at night)."""
        b = as_vector3(b_body_t, 'b_body_t')
        cfg = self.cfg
        if cfg.law == 'min_energy':
            n = self.clock.index(t_s)
            if n != self._orbit:
                self._c, self._undumpable = min_energy_vector(self.predicted_gramian(n), cfg.h_b_nms)
                self._orbit = n
            m = np.cross(self._c, b)
        else:
            m = khb_moment(h_s_nms, b, cfg.k_seed, cfg.h_0_nms if cfg.law == 'khb_shifted' else None)
        if cfg.day_moment_am2 is not None:
            m = constant_magnitude(m, cfg.day_moment_am2) if day else np.zeros(3)
        if cfg.moment_limit_am2 is not None:
            m = limit_magnitude(m, cfg.moment_limit_am2)
        self._unsaturated = m
        return m if cfg.max_moment_am2 is None else saturate(m, cfg.max_moment_am2)


# ----------------------------------------------------------------------------------------------- report


@dataclass(frozen=True)
class OrbitStats:
    """The seed's per-orbit quantities (§5, Tables 1 and 2), SI. None where an orbit has no night or day samples."""

    orbit: int
    t_start_s: float
    duration_s: float
    night_s: float
    day_s: float
    m_n_am2: float | None
    m_d_am2: float | None
    m_o_am2: float
    m_m_am2: float
    h_s_nms: np.ndarray
    delta_h_s_nms: np.ndarray
    magnetic_momentum_nms: np.ndarray
    min_energy_m_o_am2: float
    loop_gains: np.ndarray | None

    @property
    def bias_observed_nms(self) -> np.ndarray:
        """ΔH_s − ∫ M × B dt: the bias the CMGs took this orbit (equals H_b under ideal attitude hold)."""
        return self.delta_h_s_nms - self.magnetic_momentum_nms


def _rms(total_m2_s: float, duration_s: float) -> float | None:
    """Time-weighted rms from ∫|M|² dt over a stretch, None over an empty stretch (e.g. no orbital night)."""
    return None if duration_s == 0.0 else math.sqrt(total_m2_s / duration_s)


class _OpenOrbit:
    """The running sums of the orbit being accumulated (what its :class:`OrbitStats` needs, nothing more)."""

    def __init__(self, n: int, t_s: float, h_s_nms: np.ndarray, h_store_nms: np.ndarray | None) -> None:
        self.n, self.t_start_s = n, t_s
        self.h_s_nms, self.h_store_nms = h_s_nms.copy(), None if h_store_nms is None else h_store_nms.copy()
        self.w = {True: 0.0, False: 0.0}  # day → seconds
        self.m2 = {True: 0.0, False: 0.0}  # day → ∫|M|² dt
        self.m2_max = 0.0
        self.gram = np.zeros((3, 3))
        self.magnetic = np.zeros(3)
        self.last_w = 0.0

    def add(self, w: float, m: np.ndarray, b: np.ndarray, day: bool, torque: np.ndarray) -> None:
        m2 = float(m @ m)
        self.last_w = w
        self.w[day] += w
        self.m2[day] += w * m2
        self.m2_max = max(self.m2_max, m2)
        self.gram += w * (float(b @ b) * np.eye(3) - np.outer(b, b))
        self.magnetic += w * torque

    def close(self, delta_h_s_nms: np.ndarray, h_b_nms: np.ndarray, k_seed: float | None) -> OrbitStats:
        duration = self.w[True] + self.w[False]
        c, _ = min_energy_vector(self.gram, h_b_nms)
        return OrbitStats(
            orbit=self.n, t_start_s=self.t_start_s, duration_s=duration, night_s=self.w[False], day_s=self.w[True],
            m_n_am2=_rms(self.m2[False], self.w[False]), m_d_am2=_rms(self.m2[True], self.w[True]),
            m_o_am2=math.sqrt((self.m2[True] + self.m2[False]) / duration), m_m_am2=math.sqrt(self.m2_max),
            h_s_nms=self.h_s_nms, delta_h_s_nms=np.asarray(delta_h_s_nms, dtype=float),
            magnetic_momentum_nms=self.magnetic.copy(),
            # ∫ |c × B|² dt = cᵀ W c with the same weights: eq. (3)'s M_o on this orbit's own field
            min_energy_m_o_am2=math.sqrt(max(0.0, float(c @ self.gram @ c)) / duration),
            loop_gains=None if k_seed is None else loop_gains(self.gram, k_seed))


class OrbitAccumulator:
    """Streaming per-orbit statistics over control steps, in bounded memory (what :func:`orbit_stats` does on arrays).

    ``clock``: the orbit boundaries; ``h_b_nms``: the bias momentum per orbit the minimum-energy comparison
    dumps (Table 2, on each orbit's own field); ``k_seed``: when given, each orbit carries the sampled loop's
    gains (eigenvalues of k W). Feed :meth:`add` once per control step in time order; an orbit is closed
    (its :class:`OrbitStats` appended to :attr:`stats`) by the first step of a later orbit, whose H_s sample
    gives ΔH_s, or at the end by :meth:`finish`.
    """

    def __init__(self, clock: OrbitClock, h_b_nms: np.ndarray, k_seed: float | None = None) -> None:
        self.clock = clock
        self.h_b_nms = as_vector3(h_b_nms, 'h_b_nms')
        self.k_seed = k_seed
        self.stats: list[OrbitStats] = []
        self._open: _OpenOrbit | None = None

    def add(self, t_s: float, weight_s: float, m_am2: np.ndarray, b_body_t: np.ndarray, day: bool,
            h_s_nms: np.ndarray, torque_nm: np.ndarray | None = None, h_store_nms: np.ndarray | None = None) -> None:
        """One control step at ``t_s`` held for ``weight_s`` s: moment M (A·m²), field B (T), orbital day or not,
        the H_s the step used (N·m·s); ``torque_nm`` the step's mean magnetic torque (default M × B);
        ``h_store_nms`` the CMG momentum at the step (lets :meth:`finish` close the last orbit)."""
        n = self.clock.index(t_s)
        h_s = as_vector3(h_s_nms, 'h_s_nms')
        m, b = as_vector3(m_am2, 'm_am2'), as_vector3(b_body_t, 'b_body_t')
        if self._open is not None and n != self._open.n:
            if n < self._open.n:
                raise ControllerError(f'time went back from orbit {self._open.n} to orbit {n} (t = {t_s} s)')
            self.stats.append(self._open.close(h_s - self._open.h_s_nms, self.h_b_nms, self.k_seed))
            self._open = None
        if self._open is None:
            self._open = _OpenOrbit(n, float(t_s), h_s, None if h_store_nms is None else as_vector3(h_store_nms,
                                                                                                   'h_store_nms'))
        self._open.add(float(weight_s), m, b, bool(day), np.cross(m, b) if torque_nm is None
                       else as_vector3(torque_nm, 'torque_nm'))

    def finish(self, t_end_s: float, h_store_end_nms: np.ndarray) -> None:
        """Close the open orbit at the end of the data if it ran to its end (within half a step of the boundary,
        the data's last step being held to ``t_end_s``): ΔH_s from the CMG momentum at the end."""
        o = self._open
        if o is None or o.h_store_nms is None:
            return
        if t_end_s >= self.clock.start_s(o.n + 1) - 0.5 * o.last_w:
            self.stats.append(o.close(as_vector3(h_store_end_nms, 'h_store_end_nms') - o.h_store_nms, self.h_b_nms,
                                      self.k_seed))
        self._open = None


def orbit_stats(t_s: np.ndarray, m_am2: np.ndarray, b_body_t: np.ndarray, day: np.ndarray, h_s_nms: np.ndarray,
                clock: OrbitClock, h_b_nms: np.ndarray, k_seed: float | None = None) -> list[OrbitStats]:
    """Per-orbit statistics over per-step arrays (one row per control step, M held over the step).

    ``t_s`` (N,) step times; ``m_am2`` (N, 3) moment produced; ``b_body_t`` (N, 3) field; ``day`` (N,) True in
    orbital day; ``h_s_nms`` (N, 3) the sampled H_s each step used; ``h_b_nms`` the bias momentum per orbit
    (for the minimum-energy comparison of Table 2, evaluated on each orbit's own field); ``k_seed``: when
    given, each orbit also carries the sampled loop's gains (eigenvalues of k W). Only orbits followed by a
    sample of the next orbit (so that ΔH_s is known) are reported. Zero-order-hold weights (:func:`hold_weights`).
    """
    t = np.asarray(t_s, dtype=float)
    m = np.asarray(m_am2, dtype=float)
    b = np.asarray(b_body_t, dtype=float)
    dayv = np.asarray(day, dtype=bool)
    hs = np.asarray(h_s_nms, dtype=float)
    n_steps = t.shape[0]
    for name, arr, shape in (('m_am2', m, (n_steps, 3)), ('b_body_t', b, (n_steps, 3)), ('day', dayv, (n_steps,)),
                             ('h_s_nms', hs, (n_steps, 3))):
        if arr.shape != shape:
            raise ControllerError(f'{name} must have shape {shape} to match t_s, got {arr.shape}')
    acc = OrbitAccumulator(clock, h_b_nms, k_seed)
    for row in zip(t, hold_weights(t), m, b, dayv, hs, strict=True):
        acc.add(*row)
    return acc.stats


def _largest(values: list[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return max(present) if present else None


def dump_report(stats: list[OrbitStats]) -> dict[str, Any]:
    """JSON-ready report: the largest M_n, M_d, M_o, M_m (A·m²), |ΔH_s| (ft-lb-sec) and minimum-energy M_o over the
    orbits, as the seed's Tables 1 and 2 take them, plus ``per_orbit`` (momenta in ft-lb-sec, the seed's unit)."""
    if not stats:
        raise ControllerError('no complete orbit in the data: the report needs the first step of the orbit after')

    def vec(v: np.ndarray) -> list[float]:
        return [float(x) for x in nms_to_ftlbs(v)]

    per_orbit = []
    for s in stats:
        row: dict[str, Any] = {
            'orbit': s.orbit, 't_start_s': s.t_start_s, 'duration_s': s.duration_s, 'night_s': s.night_s,
            'day_s': s.day_s, 'M_n_am2': s.m_n_am2, 'M_d_am2': s.m_d_am2, 'M_o_am2': s.m_o_am2, 'M_m_am2': s.m_m_am2,
            'H_s_ftlbs': vec(s.h_s_nms), 'delta_H_s_ftlbs': float(nms_to_ftlbs(np.linalg.norm(s.delta_h_s_nms))),
            'delta_H_s_vector_ftlbs': vec(s.delta_h_s_nms), 'magnetic_dump_ftlbs': vec(s.magnetic_momentum_nms),
            'bias_observed_ftlbs': vec(s.bias_observed_nms), 'min_energy_M_o_am2': s.min_energy_m_o_am2,
        }
        if s.loop_gains is not None:
            row['loop_gains'] = [float(x) for x in s.loop_gains]
        per_orbit.append(row)
    gains = [g for s in stats if s.loop_gains is not None for g in (float(s.loop_gains[0]), float(s.loop_gains[-1]))]
    return {
        'orbits': len(stats),
        'loop_gain_min': min(gains) if gains else None,
        'loop_gain_max': max(gains) if gains else None,
        'loop_converges': None if not gains else bool(0.0 < min(gains) and max(gains) < 2.0),
        'M_n_am2': _largest([s.m_n_am2 for s in stats]),
        'M_d_am2': _largest([s.m_d_am2 for s in stats]),
        'M_o_am2': _largest([s.m_o_am2 for s in stats]),
        'M_m_am2': _largest([s.m_m_am2 for s in stats]),
        'delta_H_s_ftlbs': _largest([r['delta_H_s_ftlbs'] for r in per_orbit]),
        'min_energy_M_o_am2': _largest([s.min_energy_m_o_am2 for s in stats]),
        'per_orbit': per_orbit,
    }


def loop_gain_warning(report: dict[str, Any]) -> str | None:
    """One line when some orbit's loop gain (eigenvalue of k W) leaves (0, 2), so that H_s cannot converge
    (module docstring); None when every gain is inside or the law has no loop gain."""
    if report.get('loop_converges') is not False:
        return None
    return (f'WARNING: the sampled k·H_s × B loop cannot converge: loop gains (eigenvalues of k·W) '
            f'{report["loop_gain_min"]:.3g}…{report["loop_gain_max"]:.3g} leave (0, 2) with k = '
            f'{report.get("k_seed", float("nan")):.4g} (seed units); H_s grows until the coils or the CMGs saturate')
