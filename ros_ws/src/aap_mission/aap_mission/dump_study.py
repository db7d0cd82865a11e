"""Studies of the AAP Workshop dump law on the direct engine (seed 000 §5, §12; issue 21).

* :func:`k_sweep`: the k study of §5. For each k (seed units, the law flown with ``dump_gain_rule: stated``) the
  scenario runs twice, from the §5 initialisation (``dump_h_s_init: min_energy``: k·H_s of the first orbit is
  eq. 3's bracket) and from H_s = 0 (``measured``, the CMGs empty). The seed's claim is that from H_s = 0 a k of
  3–5 × 10⁶ gives "after a few orbits, the same M(t) as when H_s had been properly initialized": the orbits to
  converge are counted as the first orbit from which every later orbit's M_o and M_m of the run from zero are
  within ``SAME_M_TOLERANCE`` of the initialised run's (the seed's "same M(t)"); none when the loop cannot
  converge (some orbit's loop gain outside (0, 2): both runs then grow into the coil limit, where they
  coincide for the wrong reason).
* :func:`bias_sweep`: the §12 estimation of M_m. The scenario's bias momentum, or the inertia difference that
  sets its gravity-gradient part, is varied, and M_m (the largest over the orbits) read from each run. The
  coils are the scenario's, scaled in moment per ampere (same R, L, supply: the same current waveform) so that
  no point saturates them (:func:`coil_scale`): §12 estimates the law's M_m, not a coil's limit.

Every run is a :class:`acds_runtime.direct.DirectRun` of the scenario with ``SECTION.KEY=VALUE`` overrides
(:func:`scenario_with_sets`); the rows are plain dicts (the CLI prints, plots and writes them).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import yaml
from acds_common import units
from acds_common.scenario import Scenario, ScenarioError, load_scenario, scenario_path
from acds_runtime.sampling import scenario_from_text

#: "The same M(t)" (§5): per-orbit M_o and M_m within this fraction of the initialised run's.
SAME_M_TOLERANCE = 0.05
#: The §12 sweeps scale the coils so that the memo's estimate 12.5·|H_b| is at most this fraction of the limit.
COIL_HEADROOM = 0.5
#: §12's rule of thumb: M_m = 12.5 H_b, A·m² per ft-lb-sec (bias in the orbital plane; 45° OP: 0.0665 (I_z − I_x)).
SEED_MM_PER_HB = 12.5
#: The sweeps §12 describes: which quantity is varied, by mode.
SWEEPS = ('hb', 'iy_minus_iz', 'iz_minus_ix')


def scenario_with_sets(name: str, sets: list[str]) -> Scenario:
    """The scenario with ``SECTION.KEY=VALUE`` (or top-level ``KEY=VALUE``) overrides (keys as in the YAML, with
    their unit), via a temporary file that extends it."""
    if not sets:
        return load_scenario(name)
    overlay: dict[str, Any] = {'extends': str(scenario_path(name).resolve())}
    for item in sets:
        key, sep, value = item.partition('=')
        section, dot, field = key.partition('.')
        if not sep or (dot and not field) or not section:
            raise ScenarioError(f'--set {item!r}: expected SECTION.KEY=VALUE (e.g. controller.dump_h_s_init=measured) '
                                'or KEY=VALUE for a top-level key (control_period_s=20)')
        if dot:
            overlay.setdefault(section, {})[field] = yaml.safe_load(value)
        else:
            overlay[section] = yaml.safe_load(value)
    return scenario_from_text(yaml.safe_dump(overlay, sort_keys=False), f'{name} with --set')


def parse_range(text: str, what: str) -> np.ndarray:
    """``A:B:N`` → N values from A to B inclusive (N ≥ 1; N = 1 gives A)."""
    parts = text.split(':')
    try:
        a, b, n = float(parts[0]), float(parts[1]), int(parts[2])
        if len(parts) != 3 or n < 1 or n > 200 or not (math.isfinite(a) and math.isfinite(b)):
            raise ValueError
    except (ValueError, IndexError) as exc:
        raise ScenarioError(f'{what} {text!r}: expected A:B:N (N from 1 to 200 values from A to B)') from exc
    return np.linspace(a, b, n)


def run_report(scenario: Scenario, steps: int | None = None) -> dict[str, Any]:
    """The dump report of one direct-engine run (no bag)."""
    from acds_runtime.direct import DirectRun

    return DirectRun(scenario, steps=steps).run().summary['dump_report']


def orbits_to_converge(zero: dict[str, Any], initialised: dict[str, Any],
                       tolerance: float = SAME_M_TOLERANCE) -> int | None:
    """Orbits after which the run from H_s = 0 flies "the same M(t)" as the initialised run (module docstring):
    the number of the first orbit from which every later orbit's M_o and M_m agree within ``tolerance``; None
    when the loop cannot converge or they never agree."""
    if not (zero.get('loop_converges') and initialised.get('loop_converges')):
        return None
    rows = list(zip(zero['per_orbit'], initialised['per_orbit'], strict=False))
    same = [all(abs(z[key] - i[key]) <= tolerance * i[key] for key in ('M_o_am2', 'M_m_am2')) for z, i in rows]
    for n in range(len(same)):
        if all(same[n:]):
            return n
    return None


def _largest_from(report: dict[str, Any], key: str, first: int) -> float | None:
    values = [r[key] for r in report['per_orbit'][first:] if r[key] is not None]
    return max(values) if values else None


def k_sweep(name: str, ks: np.ndarray, steps: int | None = None, sets: list[str] | None = None,
            progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """One row per k (seed units): both runs' orbits to converge, |ΔH_s| (largest per orbit, and the span of the
    H_s samples over the run), M_o and M_m (largest over the orbits; from H_s = 0 over the orbits from
    convergence on), the loop-gain range, and whether the loop converges."""
    rows = []
    for k in ks:
        reports = {}
        for init in ('min_energy', 'measured'):
            sc = scenario_with_sets(name, [*(sets or []), 'controller.dump_gain_rule=stated',
                                           f'controller.dump_gain_am2_per_ftlbs_t={float(k)!r}',
                                           f'controller.dump_h_s_init={init}'])
            if progress:
                progress(f'k = {k:.4g}, H_s init {init}')
            reports[init] = run_report(sc, steps)
        init_r, zero_r = reports['min_energy'], reports['measured']
        n_conv = orbits_to_converge(zero_r, init_r)
        rows.append({
            'k_seed': float(k), 'loop_gain_min': init_r['loop_gain_min'], 'loop_gain_max': init_r['loop_gain_max'],
            'loop_converges': bool(init_r['loop_converges'] and zero_r['loop_converges']),
            'orbits': init_r['orbits'], 'orbits_to_converge_from_zero': n_conv,
            **{f'{key}_{tag}': value for tag, r, first in (('init', init_r, 0), ('zero', zero_r, n_conv or 0))
               for key, value in (('delta_H_s_ftlbs', _largest_from(r, 'delta_H_s_ftlbs', first)),
                                  ('H_s_range_ftlbs', r['H_s_range_ftlbs']),
                                  ('M_o_am2', _largest_from(r, 'M_o_am2', first)),
                                  ('M_m_am2', _largest_from(r, 'M_m_am2', first)))},
            'min_energy_M_o_am2': init_r['min_energy_M_o_am2'],
        })
    return rows


def gravity_gradient_bias_ftlbs(scenario: Scenario, delta_i_slugft2: float) -> float:
    """(3π/2)·n·ΔI, ft-lb-sec per orbit: the gravity-gradient bias of an inertially held body whose orbit normal
    is 45° between two principal axes differing by ΔI (the IOP and 45° OP attitudes of the scenarios)."""
    from acds_common.environment import orbit_from_section

    n = 2.0 * math.pi / orbit_from_section(scenario.values['orbit']).period_s
    return 1.5 * math.pi * n * delta_i_slugft2


def coil_scale(scenario: Scenario, h_b_ftlbs: float) -> float:
    """Factor on the coils' moment per ampere (and limits) so that §12's 12.5·|H_b| is at most COIL_HEADROOM of the
    per-axis limit (1 when the scenario's coils already are)."""
    limit = min(scenario.get("em_driver", "coil_max_moment_am2"))
    return max(1.0, SEED_MM_PER_HB * h_b_ftlbs / (COIL_HEADROOM * limit))


def _fmt_list(v: np.ndarray) -> str:
    return '[' + ', '.join(f'{float(x)!r}' for x in v) + ']'


def bias_sweep_sets(scenario: Scenario, sweep: str, value: float) -> tuple[list[str], float]:
    """(the overrides, |H_b| in ft-lb-sec) of one §12 sweep point. ``hb``: |H_b| = ``value`` ft-lb-sec along the
    scenario's bias direction; ``iy_minus_iz``: I_y = I_z + ``value`` slug-ft² (IOP: the gravity-gradient bias
    along x, (3π/2)·n·(I_z − I_y)); ``iz_minus_ix``: I_x = I_z − ``value`` (45° OP: along z, (3π/2)·n·(I_y − I_x));
    the aerodynamic and other bias the scenario's disturbance holds stays as it is."""
    if sweep not in SWEEPS:
        raise ScenarioError(f'sweep {sweep!r}: choose one of {", ".join(SWEEPS)}')
    ft = units.nms_to_ftlbs
    disturbance = ft(np.array(scenario.get('disturbance', 'bias_momentum_per_orbit')))
    on_board = ft(np.array(scenario.get('controller', 'dump_bias_momentum')))
    inertia = np.array(scenario.get('spacecraft', 'inertia')) / units.SLUG_FT2_KG_M2
    sets = []
    if sweep == 'hb':
        size = float(np.linalg.norm(on_board))
        if size == 0.0:
            raise ScenarioError(f'{scenario.name}: no bias momentum (controller.dump_bias_momentum) to scale')
        h_b = on_board * (value / size)
        disturbance = disturbance + (h_b - on_board)
    elif sweep == 'iy_minus_iz':
        inertia[1] = inertia[2] + value
        h_b = disturbance + np.array([gravity_gradient_bias_ftlbs(scenario, inertia[2] - inertia[1]), 0.0, 0.0])
    else:
        inertia[0] = inertia[2] - value
        h_b = disturbance + np.array([0.0, 0.0, gravity_gradient_bias_ftlbs(scenario, inertia[1] - inertia[0])])
    if np.any(inertia[:3] <= 0.0):
        raise ScenarioError(f'sweep {sweep} = {value:g}: a principal moment of inertia would not be positive '
                            f'(I_x, I_y, I_z = {", ".join(f"{x:,.0f}" for x in inertia[:3])} slug-ft²)')
    size = float(np.linalg.norm(h_b))
    s = coil_scale(scenario, size)
    sets += [f'disturbance.bias_momentum_per_orbit_ft_lb_s={_fmt_list(disturbance)}',
             f'controller.dump_bias_momentum_ft_lb_s={_fmt_list(h_b)}',
             f'spacecraft.inertia_slug_ft2={_fmt_list(inertia)}',
             f'em_driver.coil_moment_per_amp_am2={_fmt_list(np.array(scenario.get("em_driver", "coil_moment_per_amp_am2")) * s)}',
             f'em_driver.coil_max_moment_am2={_fmt_list(np.array(scenario.get("em_driver", "coil_max_moment_am2")) * s)}',
             f'controller.max_moment_am2={scenario.get("controller", "max_moment_am2") * s!r}']
    return sets, size


def bias_sweep(name: str, sweep: str, values: np.ndarray, steps: int | None = None, sets: list[str] | None = None,
               progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """One row per swept value: |H_b|, the largest M_n, M_d, M_o, M_m over the orbits, the loop gains, and the
    memo's estimate 12.5·|H_b| beside it."""
    base = scenario_with_sets(name, sets or [])
    points = [bias_sweep_sets(base, sweep, float(v)) for v in values]  # every point checked before the first run
    rows = []
    for v, (point, h_b) in zip(values, points, strict=True):
        if progress:
            progress(f'{sweep} = {v:.6g} (|H_b| = {h_b:.1f} ft-lb-sec)')
        r = run_report(scenario_with_sets(name, [*(sets or []), *point]), steps)
        rows.append({'sweep': sweep, 'value': float(v), 'H_b_ftlbs': h_b, 'M_n_am2': r['M_n_am2'],
                     'M_d_am2': r['M_d_am2'], 'M_o_am2': r['M_o_am2'], 'M_m_am2': r['M_m_am2'],
                     'delta_H_s_ftlbs': r['delta_H_s_ftlbs'], 'loop_gain_min': r['loop_gain_min'],
                     'loop_gain_max': r['loop_gain_max'], 'loop_converges': r['loop_converges'],
                     'k_seed': r['k_seed'], 'seed_estimate_M_m_am2': SEED_MM_PER_HB * h_b})
    return rows


def fitted_slope(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(slope through the origin, ordinary least-squares slope) of y against x."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    through_origin = float(x @ y / (x @ x))
    return through_origin, float(np.polyfit(x, y, 1)[0]) if x.size > 1 else through_origin
