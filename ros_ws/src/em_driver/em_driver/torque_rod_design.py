"""Torque-rod design routine: the seed's procedure as a bounded minimum-mass search (spec §9; seed 003 "Design").

The seed's procedure ("Design Algorithm", steps 1–8): from V and P the minimum resistance
R = V²/P, the wire length l_w = R/W_w, turns n = l_w/(2πr_c), N_d, the moment, the mass, the
flux density, L and τ = L/R; then "vary l_c and r_c" until the design is optimal. Here:

* R = V²/P − R_bridge per winding (so the bus draws exactly P at full duty through the
  H-bridge of ``torque_rod.PwmDriverParams``); l_w = R/W_w per winding; two windings
  (the seed's redundancy constraint) wound together on the core. At fixed voltage the
  ampere-turns n·I = V/(2π r_mean W_w) do not depend on the wire length, so more wire
  (lower power) only adds mass: the power constraint is met with equality, and the wire
  mass is fixed by (V, P, AWG). What remains free is the core: length l_c and radius r_c.
* Objective: minimum total mass (wire + core). Constraints, each a normalised g ≤ 0:
  ``moment`` (dipole at full duty of one winding, with core saturation, ≥ the requirement),
  ``mass`` (≤ the limit), ``envelope`` (the rod's bounding box l_c × 2r_out × 2r_out fits the
  envelope in some orientation), ``saturation`` (core flux density at full current ≤ B_sat,
  unless ``allow_saturation``: then the achieved, saturated moment is what must meet the
  requirement) and ``power`` (V²/P above the bridge resistance).
* Search (bounded, deterministic, converging): l_c ∈ [min_core_length, largest envelope
  side], r_c ∈ [min_core_radius, half the second-largest side]; a 41 × 41 grid evaluated at
  once (numpy), then the box shrinks around the lightest feasible point (±2 cells) until it is
  below 1 µm; the incumbent only ever improves and every returned design is an evaluated,
  feasible point. The moment is non-monotonic in r_c (thick windings lower n·I), and the
  winding's layer count makes the functions only piecewise smooth, so a grid-refinement
  search is used rather than a gradient method; scipy is not needed for two bounded variables.
  When no grid point is feasible the largest constraint violation is minimised the same way
  first: a feasible set thinner than a cell is found there and then refined for mass.
* Infeasible requests raise :class:`InfeasibleDesignError` naming the binding constraint(s):
  each constraint is first checked alone over the box (e.g. ``mass``: even the thinnest
  core's rod, whose wire alone is fixed by V, P and AWG, is too heavy); if each is reachable
  alone, the ones still violated at the least-violating point of the box are named.

Why the seed's notebook diverges (reproduced with its own code and scipy's BFGS, start
(l_c, r_c) = (15, 2) mm): (1) ``mu_r = mu_c / mu_0`` with ``mu_c = 100000`` already relative
gives µ_r = 7.96e10 instead of 1e5 — physically wrong by 1/µ0, though numerically it hides
itself because the rod's apparent permeability is ≈ 1/N_d either way; (2) its analytic
∂N_d/∂l_c has a sign error (``3*l2 + 4*r2 − …`` where 3l² − 4r² − 2l² ln(l/r) is right), so the
supplied Jacobian disagrees with the merit function (∂f/∂l −0.01648 vs −0.01894 by finite
differences at the start point); (3) decisively, the problem it poses has no minimum: the
linear moment model lets an ever thinner core carry the moment (nothing bounds the core's
magnetisation), so the merit (mass/100 g)²/2 + (M/M_req − 1)²/2 keeps falling as r_c → 0,
and the unconstrained BFGS has no bounds to stop it. Its first step lands at
(16.2, 0.41) mm (moment 0.1535 A·m², 8.25 g of which 8.17 g is wire, a core magnetisation
µ0·M ≈ 23 T — thirty times any material's saturation), the second at (1288, −1741) mm, where
ln(l_c/r_c) is undefined: the merit is NaN and scipy stops with "precision loss". Fixing (1)
and (2) alone still walks to a negative radius. The seed's N_d formula also vanishes at
l/r = e and goes negative below, a pole of its moment formula. What makes the problem
well posed is the saturation constraint plus bounds — both are here.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from em_driver.bridge_switch import EmDriverError
from em_driver.torque_rod import (
    CORE_MATERIALS,
    MagnetWire,
    PwmDriverParams,
    TorqueRod,
    demagnetizing_factor_seed,
    magnet_wire,
    rod_properties,
)

__all__ = ['DesignRequest', 'TorqueRodDesign', 'InfeasibleDesignError', 'design_torque_rod', 'load_rod']

#: Constraints of the search (``power`` is met by construction once V²/P exceeds the bridge resistance).
CONSTRAINTS = ('moment', 'mass', 'envelope', 'saturation')
_GRID = 41
_TOL_M = 1e-6
_MAX_ROUNDS = 60


class InfeasibleDesignError(EmDriverError):
    """No rod meets the request; ``binding`` names the constraint(s) that cannot be met."""

    def __init__(self, message: str, binding: tuple[str, ...]) -> None:
        super().__init__(message)
        self.binding = binding


@dataclass(frozen=True)
class DesignRequest:
    """What the rod must do, SI (seed 003 "Constraints": 100 g, 0.5 W, 7.2 V, 0.1552 A·m², 35×35×25 mm).

    core: 'permalloy', 'permendur' or 'ck30'; awg: wire gauge (36); windings: 2 (redundancy);
    bridge_resistance_ohm: the H-bridge in the loop (PwmDriverParams' default);
    insulation_build_m: None = heavy build; allow_saturation: accept a core that saturates at
    full current (its saturated moment must still meet the requirement);
    min_core_radius_m, min_core_length_m: manufacturable lower bounds.
    """

    mass_max_kg: float = 0.100
    power_max_w: float = 0.5
    voltage_v: float = 7.2
    moment_min_am2: float = 0.1552
    envelope_m: tuple[float, float, float] = (0.035, 0.035, 0.025)
    core: str = 'permalloy'
    awg: int = 36
    windings: int = 2
    bridge_resistance_ohm: float = PwmDriverParams().bridge_resistance_ohm
    insulation_build_m: float | None = None
    allow_saturation: bool = False
    min_core_radius_m: float = 0.5e-3
    min_core_length_m: float = 2.0e-3

    def __post_init__(self) -> None:
        for name in ('mass_max_kg', 'power_max_w', 'voltage_v', 'moment_min_am2', 'min_core_radius_m',
                     'min_core_length_m'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise EmDriverError(f'DesignRequest.{name} must be a finite positive number, got {value!r}')
        if len(self.envelope_m) != 3 or not all(math.isfinite(x) and x > 0.0 for x in self.envelope_m):
            raise EmDriverError(f'DesignRequest.envelope_m must be three positive sizes, got {self.envelope_m!r}')
        if self.core not in CORE_MATERIALS:
            raise EmDriverError(f'unknown core {self.core!r}; expected one of {", ".join(CORE_MATERIALS)}')
        if self.windings not in (1, 2):
            raise EmDriverError(f'DesignRequest.windings must be 1 or 2, got {self.windings!r}')
        if not (math.isfinite(self.bridge_resistance_ohm) and self.bridge_resistance_ohm >= 0.0):
            raise EmDriverError(f'DesignRequest.bridge_resistance_ohm must be >= 0, got {self.bridge_resistance_ohm!r}')

    @property
    def wire(self) -> MagnetWire:
        return magnet_wire(self.awg, self.insulation_build_m)

    @property
    def coil_resistance_ohm(self) -> float:
        """R = V²/P − R_bridge per winding, Ω."""
        return self.voltage_v ** 2 / self.power_max_w - self.bridge_resistance_ohm

    @property
    def full_current_a(self) -> float:
        """Current at full duty, A (= P/V)."""
        return self.voltage_v / (self.coil_resistance_ohm + self.bridge_resistance_ohm)


@dataclass(frozen=True)
class TorqueRodDesign:
    """A design that meets its request. ``rod`` builds the driver model; the rest is for the report (SI)."""

    request: DesignRequest
    rod: TorqueRod
    mass_kg: float
    wire_mass_kg: float
    core_mass_kg: float
    power_w: float
    current_a: float
    moment_am2: float
    n_d: float
    n_d_seed: float
    flux_density_t: float
    core_saturates: bool
    outer_diameter_m: float
    tau_s: float
    search_rounds: int
    evaluations: int

    def to_json_dict(self) -> dict[str, Any]:
        """Flat JSON record, units in the keys (seed units: g, mm, A·m²)."""
        r, p = self.rod, self.rod.props
        return {
            'mass_g': self.mass_kg * 1e3, 'wire_mass_g': self.wire_mass_kg * 1e3, 'core_mass_g': self.core_mass_kg * 1e3,
            'power_w': self.power_w, 'voltage_v': self.request.voltage_v, 'current_a': self.current_a,
            'moment_am2': self.moment_am2, 'moment_required_am2': self.request.moment_min_am2,
            'core': r.material.name, 'core_relative_permeability': r.material.relative_permeability,
            'core_saturation_t': r.material.saturation_t,
            'core_length_mm': r.core_length_m * 1e3, 'core_radius_mm': r.core_radius_m * 1e3,
            'outer_diameter_mm': self.outer_diameter_m * 1e3, 'awg': r.wire.awg,
            'wire_insulated_diameter_mm': r.wire.insulated_diameter_m * 1e3,
            'wire_insulation_build_mm': (r.wire.insulated_diameter_m - r.wire.bare_diameter_m) * 1e3,
            'wire_ohm_per_m': r.wire.ohm_per_m,
            'windings': r.windings, 'wire_length_per_winding_m': r.wire_length_per_winding_m,
            'turns': p.turns, 'layers': p.layers, 'resistance_ohm': p.resistance_ohm,
            'bridge_resistance_ohm': self.request.bridge_resistance_ohm, 'inductance_h': p.inductance_h,
            'tau_s': self.tau_s, 'n_d': self.n_d, 'n_d_seed_formula': self.n_d_seed,
            'apparent_susceptibility': p.chi_app, 'flux_density_t': self.flux_density_t,
            'core_saturates': self.core_saturates, 'saturation_current_a': r.saturation_current_a,
            'search_rounds': self.search_rounds, 'evaluations': self.evaluations,
        }


def load_rod(record: dict[str, Any] | str | Path) -> TorqueRod:
    """The :class:`TorqueRod` of a design JSON record (a dict or a ``--json`` file)."""
    data = json.loads(Path(record).read_text()) if isinstance(record, str | Path) else record
    try:
        material = data['core']
        if material not in CORE_MATERIALS:
            raise EmDriverError(f'torque-rod design record: unknown core {material!r} '
                                f'(known: {", ".join(CORE_MATERIALS)})')
        wire = magnet_wire(int(data['awg']), data['wire_insulation_build_mm'] * 1e-3)
        return TorqueRod(data['core_length_mm'] * 1e-3, data['core_radius_mm'] * 1e-3, CORE_MATERIALS[material],
                         wire, data['wire_length_per_winding_m'], int(data['windings']))
    except KeyError as exc:
        raise EmDriverError(f'torque-rod design record lacks key {exc.args[0]!r}') from None


def _evaluate(req: DesignRequest, length: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(mass, {constraint: normalised g}) on arrays of (l_c, r_c); g ≤ 0 is satisfied."""
    wire = req.wire
    material = CORE_MATERIALS[req.core]
    r_coil = req.coil_resistance_ohm
    p = rod_properties(length, radius, material, wire, r_coil / wire.ohm_per_m, req.windings)
    i_full = req.full_current_a
    moment = p.air_moment_per_a * i_full + np.minimum(p.core_moment_per_a * i_full, p.core_max_moment_am2)
    env = np.sort(np.asarray(req.envelope_m)).reshape((3,) + (1,) * np.ndim(length))
    diameter = 2.0 * p.outer_radius_m
    box = np.sort(np.stack(np.broadcast_arrays(length, diameter, diameter)), axis=0)  # fits in some orientation
    g = {
        'moment': 1.0 - moment / req.moment_min_am2,
        'mass': p.mass_kg / req.mass_max_kg - 1.0,
        'envelope': np.max(box / env, axis=0) - 1.0,
        'saturation': (np.full(np.shape(length), -1.0) if req.allow_saturation
                       else p.flux_per_a_t * i_full / material.saturation_t - 1.0),
    }
    return p.mass_kg, g


def _bounds(req: DesignRequest) -> tuple[tuple[float, float], tuple[float, float]]:
    env = sorted(req.envelope_m)
    return (req.min_core_length_m, env[2]), (req.min_core_radius_m, env[1] / 2.0)


def _grid(box: tuple[tuple[float, float], tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    (l0, l1), (r0, r1) = box
    return np.meshgrid(np.linspace(l0, l1, _GRID), np.linspace(r0, r1, _GRID), indexing='ij')


def _shrink(box: tuple[tuple[float, float], tuple[float, float]], at: tuple[float, float],
            bounds: tuple[tuple[float, float], tuple[float, float]]) -> tuple[tuple[float, float], tuple[float, float]]:
    out = []
    for (lo, hi), x, (blo, bhi) in zip(box, at, bounds, strict=True):
        half = 2.0 * (hi - lo) / (_GRID - 1)
        out.append((max(blo, x - half), min(bhi, x + half)))
    return out[0], out[1]


def _search(req: DesignRequest, feasible_for: tuple[str, ...], minimise: str,
            start: tuple[float, float] | None = None) -> tuple[float, tuple[float, float], int, int]:
    """Minimise ``minimise`` ('objective' = the rod's mass, kg; 'violation' = the largest g of ``feasible_for``;
    or one constraint's name: its g)
    over the points that satisfy ``feasible_for`` (all points for 'violation'), by grid refinement.

    ``start``: a point known to qualify (the search then refines around the better of it and the grid).
    Returns (best value, (l_c, r_c), rounds, evaluations); the value is inf when no grid point qualifies.
    """
    bounds = _bounds(req)
    box = bounds
    best, best_at = math.inf, (math.nan, math.nan)
    if start is not None:
        mass, _ = _evaluate(req, np.array([start[0]]), np.array([start[1]]))
        best, best_at = float(mass[0]), start
    rounds = evaluations = 0
    while rounds < _MAX_ROUNDS:
        rounds += 1
        length, radius = _grid(box)
        evaluations += length.size
        mass, g = _evaluate(req, length, radius)
        worst = np.max(np.stack([g[c] for c in feasible_for]), axis=0) if feasible_for else np.full(length.shape, -1.0)
        if minimise == 'violation':
            value = worst
        else:
            value = np.where(worst <= 0.0, mass if minimise == 'objective' else g[minimise], np.inf)
        k = np.unravel_index(int(np.argmin(value)), value.shape)
        if value[k] < best:
            best, best_at = float(value[k]), (float(length[k]), float(radius[k]))
        if not math.isfinite(best):
            break
        box = _shrink(box, best_at, bounds)
        if max(box[0][1] - box[0][0], box[1][1] - box[1][0]) < _TOL_M:
            break
    return best, best_at, rounds, evaluations


def _explain(req: DesignRequest, name: str, least: float, context: str) -> str:
    """The best the bounds allow for one constraint (its least normalised violation ``least``), report units."""
    if name == 'mass':
        wire_kg = req.windings * req.coil_resistance_ohm / req.wire.ohm_per_m * req.wire.mass_per_m_kg
        return (f'mass: {context} the lightest rod weighs {(1.0 + least) * req.mass_max_kg * 1e3:.1f} g > '
                f'{req.mass_max_kg * 1e3:g} g (the wire alone is {wire_kg * 1e3:.1f} g: {req.windings} × '
                f'{req.coil_resistance_ohm:.1f} Ω of AWG {req.awg})')
    if name == 'moment':
        return (f'moment: {context} at most {(1.0 - least) * req.moment_min_am2:.4g} A·m² is reached at '
                f'{req.power_max_w:g} W and {req.voltage_v:g} V < {req.moment_min_am2:g} A·m² required')
    if name == 'saturation':
        b_sat = CORE_MATERIALS[req.core].saturation_t
        return (f'saturation: {context} the core flux density at full current is at least {(1.0 + least) * b_sat:.3g} T '
                f'> B_sat {b_sat:g} T ({req.core})')
    return f'envelope: {context} the rod and its winding exceed the envelope by {least * 100:.1f} %'


def _infeasible(req: DesignRequest) -> InfeasibleDesignError:
    """Name the binding constraints: those unreachable on their own, else those unreachable while the others hold."""
    alone = {c: _search(req, (), c)[0] for c in CONSTRAINTS}
    binding = [c for c in CONSTRAINTS if alone[c] > 0.0]
    if binding:
        detail = [_explain(req, c, alone[c], 'on its own,') for c in binding]
    else:
        given = {c: _search(req, tuple(o for o in CONSTRAINTS if o != c), c)[0] for c in CONSTRAINTS}
        binding = [c for c in CONSTRAINTS if 0.0 < given[c] < math.inf]
        detail = [_explain(req, c, given[c], 'with the other constraints met,') for c in binding]
        if not binding:
            _, at, _, _ = _search(req, CONSTRAINTS, 'violation')
            _, g = _evaluate(req, np.array([at[0]]), np.array([at[1]]))
            binding = [c for c in CONSTRAINTS if g[c][0] > 0.0]
            detail = [f'no two of them can be met together (least violation at l_c = {at[0] * 1e3:.2f} mm, '
                      f'r_c = {at[1] * 1e3:.3f} mm)']
    return InfeasibleDesignError(f'no torque rod meets the request; binding: {", ".join(binding)}. '
                                 + '; '.join(detail), tuple(binding))


def design_torque_rod(req: DesignRequest) -> TorqueRodDesign:
    """The minimum-mass rod meeting ``req`` (module docstring), or :class:`InfeasibleDesignError`."""
    if req.coil_resistance_ohm <= 0.0:
        raise InfeasibleDesignError(
            f'no torque rod meets the request; binding: power. V²/P = {req.voltage_v ** 2 / req.power_max_w:.3g} Ω '
            f'leaves nothing for the winding after the bridge’s {req.bridge_resistance_ohm:g} Ω', ('power',))
    best, (length, radius), rounds, evaluations = _search(req, CONSTRAINTS, 'objective')
    if not math.isfinite(best):  # no grid point feasible: the feasible set may be thinner than a grid cell
        violation, at, more_rounds, more = _search(req, CONSTRAINTS, 'violation')
        if violation > 0.0:
            raise _infeasible(req)
        best, (length, radius), rounds, evaluations = _search(req, CONSTRAINTS, 'objective', start=at)
        rounds, evaluations = rounds + more_rounds, evaluations + more
    rod = TorqueRod(length, radius, CORE_MATERIALS[req.core], req.wire, req.coil_resistance_ohm / req.wire.ohm_per_m,
                    req.windings)
    p = rod.props
    i_full = req.full_current_a
    b_full = rod.core_flux_density_t(i_full)
    return TorqueRodDesign(
        request=req, rod=rod, mass_kg=p.mass_kg, wire_mass_kg=p.wire_mass_kg, core_mass_kg=p.core_mass_kg,
        power_w=req.voltage_v * i_full, current_a=i_full, moment_am2=float(rod.moment_am2(i_full)), n_d=p.n_d,
        n_d_seed=demagnetizing_factor_seed(length, radius), flux_density_t=b_full,
        core_saturates=b_full > rod.material.saturation_t, outer_diameter_m=2.0 * p.outer_radius_m,
        tau_s=p.inductance_h / (p.resistance_ohm + req.bridge_resistance_ohm), search_rounds=rounds,
        evaluations=evaluations)
