"""EMFF analysis verbs (spec §10; seed 004 slides 40–47):

* ``acds emff-linearize SCENARIO [--review-actuators] [--json]``: linearise the scenario's spinning array
  about its steady spin (``acds_controller.formation_linear``: the free-space equations the graph flies,
  rotating frame, numerical Jacobian, centre of mass removed) and print the state dimension, the
  eigenvalues grouped as slide 42 groups them (beside the review's closed forms for two vehicles) and
  the controllability rank. The steady spin: law ``array_spin``/``lqr`` — the vehicles'
  ``array_position`` and ``spin_rate``; law ``spin_up`` — the pair at ``spin_separation`` along its
  initial baseline, ``spin_rate``. ``--review-actuators``: every vehicle with three orthogonal coils and
  three orthogonal wheels (slide 37) instead of the scenario's.
* ``acds emff-radius-sweep SCENARIO [--deviations-pct ...] [--json PATH]``: the review's nonlinear-vs-
  linear study (slides 45–47) for an ``lqr`` scenario: from each initial array-radius deviation, the
  scenario's graph (direct engine: the same steppers, em_driver and wheels included) and the linearised
  model under the same gain (u = −Kx held over each control period, RK4), their separations compared.
  The graph's coil currents start from zero (the em_driver's L/R lag), a transient the linear model does
  not have: the unperturbed run's separation is subtracted from each perturbed run's before comparing.

Every input is checked before anything runs: a bad one is one line, exit 2.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from acds_cli.arguments import UsageError, check_output_dir, check_output_file

#: The review's deviations (slides 46–47) and a finer grid, percent of the nominal array radius.
DEFAULT_DEVIATIONS_PCT = (0.001, 0.5, 1.0, 2.0, 3.0, 3.5, 4.0, 5.0, 6.0, 8.0)
#: The nonlinear and linear separations "diverge" once they differ by more than this fraction of the
#: initial deviation.
DIVERGENCE_FRACTION = 0.1


def _scenario(name: str) -> Any:
    from acds_common.scenario import load_scenario
    sc = load_scenario(name)
    if not sc.formation:
        raise UsageError(f'{name} is not a formation scenario (no vehicles list)')
    return sc


def _vehicles(sc: Any, review: bool) -> list[Any]:
    from acds_common.inertia import inertia_tensor
    from acds_controller.formation_linear import LinearVehicle
    out = []
    for v in sc.values['vehicles']:
        vh, wh = v['vehicle'], v['wheels']
        inertia = inertia_tensor(*v['spacecraft']['inertia']) * v['spacecraft']['inertia_scale']
        coils = np.eye(3) if review else np.array(vh['coil_axes'], dtype=float).reshape(-1, 3).T
        wheels = np.eye(3) if review else np.array(wh['torque_axes'], dtype=float).reshape(-1, 3).T
        out.append(LinearVehicle(v['name'], vh['mass'], inertia, coils, wheels))
    return out


def steady_spin(sc: Any) -> tuple[np.ndarray, float]:
    """(places (N, 3), rate) of the scenario's steady spin (module docstring); UsageError if it has none."""
    f = sc.values['formation']
    vehicles = sc.values['vehicles']
    if f['law'] in ('array_spin', 'lqr'):
        places = np.array([v['vehicle']['array_position'] for v in vehicles], dtype=float)
    elif f['law'] == 'spin_up':
        start = np.array([v['vehicle']['initial_position'] for v in vehicles], dtype=float)
        axis = (start[1] - start[0]) / np.linalg.norm(start[1] - start[0])
        places = np.array([-0.5, 0.5])[:, None] * f['spin_separation'] * axis[None, :]
    else:
        raise UsageError(f'formation.law {f["law"]!r} has no steady spin to linearise about (spin_up, array_spin, lqr)')
    if f['spin_rate'] == 0.0:
        raise UsageError('formation.spin_rate is 0: no steady spin to linearise about')
    return places, float(f['spin_rate'])


def linearize(sc: Any, review: bool) -> dict[str, Any]:
    """The linearisation report of ``sc`` as a JSON-able dict."""
    from acds_controller.formation_linear import (
        SpinningArrayModel,
        controllability_rank,
        group_eigenvalues,
        review_two_vehicle_eigenvalues,
        spin_nominal,
    )
    from acds_controller.magnetic_laws import ControllerError
    vehicles = _vehicles(sc, review)
    places, rate = steady_spin(sc)
    try:
        nominal = spin_nominal(vehicles, places, rate)
        model = SpinningArrayModel(vehicles, nominal)
        a, b = model.reduced()
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    groups = group_eigenvalues(np.linalg.eigvals(a))
    out: dict[str, Any] = {
        'scenario': sc.name, 'vehicles': len(vehicles), 'rate_rad_s': rate,
        'actuators': 'review: 3 coils + 3 wheels per vehicle' if review else 'scenario',
        'model': 'free-space equations in the frame turning with the array; numerical Jacobian (central differences, '
                 'step 1e-5 of each scale); centre of mass removed; wheel momentum held (wheels as torque actuators)',
        'places_m': {v.name: p.tolist() for v, p in zip(vehicles, nominal.places_m, strict=True)},
        'nominal_dipoles_am2': {v.name: d.tolist() for v, d in zip(vehicles, nominal.dipoles_am2, strict=True)},
        'nominal_wheel_momentum_nms': {v.name: h.tolist() for v, h in zip(vehicles, nominal.wheel_h_nms, strict=True)},
        'state_dimension': a.shape[0], 'inputs': b.shape[1],
        'eigenvalues': {'zero': groups.zero, 'real_pairs': list(groups.real_pairs),
                        'imaginary_pairs': list(groups.imaginary_pairs),
                        'complex': [[z.real, z.imag] for z in groups.complex],
                        'real_unpaired': list(groups.real_unpaired)},
        'controllability_rank': controllability_rank(a, b),
    }
    if len(vehicles) == 2 and vehicles[0].mass_kg == vehicles[1].mass_kg:
        v = vehicles[0]
        r0 = float(np.linalg.norm(nominal.places_m[0]))
        out['review_closed_form'] = review_two_vehicle_eigenvalues(v.mass_kg, r0, rate, v.inertia_kg_m2[0, 0],
                                                                   v.inertia_kg_m2[2, 2])
    return out


def _print_linearization(r: dict[str, Any]) -> None:
    e = r['eigenvalues']
    print(f'emff-linearize {r["scenario"]}: {r["vehicles"]} vehicles spinning at {r["rate_rad_s"]:g} rad/s '
          f'(actuators: {r["actuators"]})')
    print(f'  model: {r["model"]}')
    for name, p in r['places_m'].items():
        dipole = np.round(r['nominal_dipoles_am2'][name], 1).tolist()
        print(f'  {name}: place {np.round(p, 4).tolist()} m, nominal dipole {dipole} A·m²,'
              f' wheels {np.round(r["nominal_wheel_momentum_nms"][name], 4).tolist()} N·m·s')
    print(f'  state dimension {r["state_dimension"]}, inputs {r["inputs"]}')
    print('  eigenvalues (slide 42 grouping):')
    print(f'    at the origin      {e["zero"]}')
    print(f'    real ± pairs       {", ".join(f"±{x:.6g}" for x in e["real_pairs"]) or "—"}')
    print(f'    imaginary pairs    {", ".join(f"±{x:.6g}i" for x in e["imaginary_pairs"]) or "—"}')
    print(f'    complex            {", ".join(f"{a:.4g}{b:+.4g}i" for a, b in e["complex"]) or "—"}')
    if e['real_unpaired']:
        print(f'    real, unpaired     {", ".join(f"{x:.6g}" for x in e["real_unpaired"])}')
    if 'review_closed_form' in r:
        c = r['review_closed_form']
        print('  review closed forms (slide 42; r0 = half the separation, I_rr = I_xx, I_zz):')
        for key, value in c.items():
            print(f'    {key:18s} {value:.6g}')
    print(f'  controllability rank {r["controllability_rank"]} of {r["state_dimension"]}')


def cmd_linearize(args: argparse.Namespace) -> int:
    """Print (or --json) the linearisation of the scenario's steady spin."""
    report = linearize(_scenario(args.scenario), args.review_actuators)
    if args.json:
        print(json.dumps(report))
    else:
        _print_linearization(report)
    return 0


# ------------------------------------------------------------------------------ radius perturbation


def _deviations(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(x) for x in text.split(','))
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected comma-separated percentages, got {text!r}') from None
    if not values or not all(math.isfinite(v) and -50.0 < v < 50.0 and v != 0.0 for v in values):
        raise argparse.ArgumentTypeError(f'deviations must be non-zero percentages in (-50, 50), got {text!r}')
    return values


def perturbed_data(sc: Any, deviation: float) -> dict[str, Any]:
    """The scenario's YAML data with every vehicle started at (1 + deviation)·its array place, turning
    rigidly at the spin rate (velocities Ω ẑ × r, rates Ω ẑ)."""
    import copy

    data = copy.deepcopy(sc.raw)
    places, rate = steady_spin(sc)
    mass = np.array([v['vehicle']['mass'] for v in sc.values['vehicles']])
    centre = mass @ places / mass.sum()
    for item, place in zip(data['vehicles'], places, strict=True):
        r = centre + (1.0 + deviation) * (place - centre)
        vehicle = item.setdefault('vehicle', {})
        for key in [k for k in vehicle if k.startswith(('initial_position', 'initial_velocity'))]:
            del vehicle[key]
        vehicle['initial_position_m'] = r.tolist()
        vehicle['initial_velocity_m_s'] = np.cross([0.0, 0.0, rate], r).tolist()
    return data


def graph_positions(run_sc: Any) -> tuple[dict[str, np.ndarray], str | None]:
    """({vehicle: (steps, 3) positions, formation frame}, failure or None): the scenario's graph, direct engine
    (the graph's steppers in one process), every vehicle's truth odometry of every step it reached."""
    from acds_common import topics
    from acds_runtime.direct import DirectRun
    names = [v['name'] for v in run_sc.values['vehicles']]
    odometry = {topics.resolve(f'{n}/{topics.TRUTH_ODOMETRY}'): n for n in names}
    store: dict[str, list[np.ndarray]] = {n: [] for n in names}

    class Sink:
        def __init__(self, _params: Any) -> None:
            pass

        def __call__(self, topic: str, _data: Any, item: Any = None) -> None:
            if topic in odometry and item is not None:
                store[odometry[topic]].append(np.array(item.position))

        def close(self) -> None:
            pass

    failure = None
    try:
        DirectRun(run_sc, live=Sink).run()
    except Exception as exc:  # a run that fails (a collision, a diverged state) is a result here, not a crash
        failure = str(exc).splitlines()[0]
    steps = min(len(s) for s in store.values())
    return {n: np.array(store[n][:steps]).reshape(steps, 3) for n in names}, failure


def nonlinear_run(sc: Any, deviation: float, workdir: Any) -> tuple[np.ndarray, str | None]:
    """(separation of the first two vehicles per step, failure or None): the scenario's graph, direct engine."""
    import yaml
    from acds_common.scenario import load_scenario
    path = workdir / f'{sc.name}_{deviation:+.6g}.yaml'
    path.write_text(yaml.safe_dump(perturbed_data(sc, deviation)))
    positions, failure = graph_positions(load_scenario(str(path)))
    a, b = list(positions.values())[:2]
    return np.linalg.norm(b - a, axis=1), failure


def linear_run(controller: Any, sc: Any, deviation: float, steps: int) -> np.ndarray:
    """Separation of the first two vehicles per step of the linearised array under the same gain (ZOH, RK4)."""
    from acds_controller.formation_control import Measurement
    places, rate = steady_spin(sc)
    nominal = controller.nominal.places_m
    mass = np.array([v.mass_kg for v in controller.vehicles])
    centre = mass @ places / mass.sum()
    measurements = []
    for place in places:
        r = centre + (1.0 + deviation) * (place - centre)
        measurements.append(Measurement(r, np.cross([0.0, 0.0, rate], r), np.eye(3), np.array([0.0, 0.0, rate]),
                                        np.zeros(3)))
    x = controller.state(0.0, measurements)
    a, b, k = controller.a, controller.b, controller.k
    dt = sc.control_period_s
    sub = 10
    h = dt / sub
    rho0 = nominal[1] - nominal[0]
    out = []
    for _ in range(steps):
        out.append(float(np.linalg.norm(rho0 + x[:3])))
        bu = b @ (-k @ x)
        for _ in range(sub):
            k1 = a @ x + bu
            k2 = a @ (x + 0.5 * h * k1) + bu
            k3 = a @ (x + 0.5 * h * k2) + bu
            k4 = a @ (x + h * k3) + bu
            x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(out)


def radius_sweep(sc: Any, deviations_pct: tuple[float, ...]) -> list[dict[str, Any]]:
    """One row per deviation (module docstring)."""
    import tempfile

    from acds_controller.formation_lqr_step import lqr_controller
    from acds_controller.magnetic_laws import ControllerError

    def section(name: str, vehicle: str) -> dict[str, Any]:
        return next(v for v in sc.values['vehicles'] if v['name'] == vehicle)[name]

    names = [v['name'] for v in sc.values['vehicles']]
    try:
        controller = lqr_controller(sc.values['formation'], names, section)
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    d_nom = float(np.linalg.norm(controller.nominal.places_m[1] - controller.nominal.places_m[0]))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        baseline, base_failure = nonlinear_run(sc, 0.0, Path(tmp))
        if base_failure:
            raise UsageError(f'{sc.name}: the unperturbed run fails ({base_failure}): no study about it')
        for pct in deviations_pct:
            dev = pct / 100.0
            sep_nl, failure = nonlinear_run(sc, dev, Path(tmp))
            sep_lin = linear_run(controller, sc, dev, len(sep_nl))
            dd0 = abs(sep_nl[0] - d_nom)
            response = sep_nl - baseline[:len(sep_nl)] + d_nom  # the start-up transient of the coils removed
            gap = np.abs(response - sep_lin) / max(dd0, 1e-300)
            over = np.flatnonzero(gap > DIVERGENCE_FRACTION)
            tail = max(1, len(sep_nl) // 10)
            stable_nl = failure is None and float(np.abs(sep_nl[-tail:] - d_nom).max()) < dd0
            stable_lin = bool(np.all(np.isfinite(sep_lin))) and float(np.abs(sep_lin[-tail:] - d_nom).max()) < dd0
            rows.append({'deviation_pct': pct, 'steps': len(sep_nl), 'nonlinear_failure': failure,
                         'nonlinear_stable': bool(stable_nl), 'linear_stable': bool(stable_lin),
                         'nonlinear_peak_deviation_m': float(np.abs(sep_nl - d_nom).max()),
                         'linear_peak_deviation_m': float(np.abs(sep_lin - d_nom).max()),
                         'nonlinear_final_deviation_m': float(sep_nl[-1] - d_nom),
                         'linear_final_deviation_m': float(sep_lin[-1] - d_nom),
                         'startup_peak_m': float(np.abs(baseline - d_nom).max()),
                         'max_gap_fraction': float(gap.max()),
                         'diverge_at_s': float(over[0] * sc.control_period_s) if len(over) else None})
    return rows


def cmd_radius_sweep(args: argparse.Namespace) -> int:
    """Run the nonlinear-vs-linear study and print its table."""
    sc = _scenario(args.scenario)
    if sc.values['formation']['law'] != 'lqr':
        raise UsageError(f'{args.scenario}: formation.law must be lqr (the study runs the same LQR on both models)')
    if args.json:
        check_output_file('--json', Path(args.json))
    steady_spin(sc)
    rows = radius_sweep(sc, args.deviations_pct)
    print(f'emff-radius-sweep {sc.name}: {sc.duration_s():g} s per run; the unperturbed run\'s separation '
          f'(coil currents rising from 0: peak {rows[0]["startup_peak_m"]:.3g} m off) is subtracted from each run\'s; '
          f'"diverge" = that response and the linear model\'s differ by > {DIVERGENCE_FRACTION:.0%} of the initial '
          'deviation')
    print(f'  {"Δr0 %":>8s} {"nonlinear":>24s} {"linear":>8s} {"peak |Δd| nl/lin m":>22s} '
          f'{"final Δd nl/lin m":>24s} {"max gap":>9s} {"diverge at s":>12s}')
    for r in rows:
        nl = 'stable' if r['nonlinear_stable'] else ('FAILED' if r['nonlinear_failure'] else 'not settled')
        print(f'  {r["deviation_pct"]:8.4g} {nl:>24s} {"stable" if r["linear_stable"] else "unstable":>8s} '
              f'{r["nonlinear_peak_deviation_m"]:10.4g}/{r["linear_peak_deviation_m"]:<10.4g} '
              f'{r["nonlinear_final_deviation_m"]:11.3e}/{r["linear_final_deviation_m"]:<11.3e} '
              f'{r["max_gap_fraction"]:9.3g} {"—" if r["diverge_at_s"] is None else format(r["diverge_at_s"], ".1f"):>12s}')
        if r['nonlinear_failure']:
            print(f'           nonlinear run: {r["nonlinear_failure"]}')
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        with open(args.json, 'w') as fh:
            json.dump(rows, fh)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the EMFF analysis verbs."""
    text = 'linearise a formation scenario about its steady spin: eigenvalues, controllability (seed 004)'
    p = sub.add_parser('emff-linearize', help=text, description=text + '.')
    p.add_argument('scenario', help='scenario name or path (law spin_up, array_spin or lqr)')
    p.add_argument('--review-actuators', action='store_true',
                   help="three orthogonal coils and three wheels per vehicle (slide 37) instead of the scenario's")
    p.add_argument('--json', action='store_true', help='print one JSON object instead of the table')
    p.set_defaults(func=cmd_linearize)
    text = 'nonlinear graph vs linearised model under the same LQR from perturbed array radii (seed 004 slides 45–47)'
    p = sub.add_parser('emff-radius-sweep', help=text, description=text + '.')
    p.add_argument('scenario', help='an lqr formation scenario (e.g. emff_two_vehicle_lqr)')
    p.add_argument('--deviations-pct', type=_deviations, default=DEFAULT_DEVIATIONS_PCT,
                   help='initial radius deviations, percent, comma-separated (default '
                        f'{",".join(f"{d:g}" for d in DEFAULT_DEVIATIONS_PCT)})')
    p.add_argument('--json', metavar='PATH', help='write the rows as a JSON list')
    p.set_defaults(func=cmd_radius_sweep)
    _register_airtrack(sub)


# ------------------------------------------------------------------------------------------ airtrack


#: The airtrack scenarios ``emff-airtrack --graph`` flies, per configuration: (open loop, LQR).
AIRTRACK_SCENARIOS = {'stable': ('emff_airtrack_stable_open_loop', 'emff_airtrack_stable'),
                      'unstable': ('emff_airtrack_unstable_open_loop', 'emff_airtrack_unstable')}


def step_metrics(t: np.ndarray, x: np.ndarray, x_ref: float, step_m: float, duration_s: float) -> dict[str, Any]:
    """Overshoot (% of the step), range, 2 % settling time (None if the response ends outside the band or the run
    ended early) and, for a run that ended before ``duration_s``, when."""
    err = (x - x_ref) / step_m
    outside = np.flatnonzero(np.abs(err) > 0.02)
    ended = t[-1] < duration_s - 1e-9
    return {'overshoot_pct': float(max(0.0, err.max()) * 100.0), 'peak_m': float(x.max()), 'min_m': float(x.min()),
            'settling_time_2pct_s': None if ended or (len(outside) and outside[-1] == len(t) - 1)
            else (float(t[outside[-1] + 1]) if len(outside) else 0.0),
            'ended_at_s': float(t[-1]) if ended else None}


def _airtrack_row(configuration: str, plant: Any, lqr: Any, scales: Any, x_start: float, runs: tuple[Any, Any],
                  duration_s: float) -> dict[str, Any]:
    """One configuration's table row from its plant, LQR law, start and (open-loop, LQR) runs (t, x, μ or None)."""
    a, _b = plant.linearised(lqr.separation_m)
    step = lqr.separation_m - x_start
    return {'configuration': configuration, 'mass_kg': plant.mass_kg, 'magnet_dipole_am2': plant.magnet_dipole_am2,
            'separation_m': lqr.separation_m, 'tilt_deg': math.degrees(plant.tilt_rad),
            'nominal_dipole_am2': lqr.dipole0_am2, 'resting_dipole_am2': plant.equilibrium_dipole_am2(x_start),
            'step_m': step, 'gain': lqr.gain.tolist(),
            'weights': {'position_m': scales.position_m, 'velocity_m_s': scales.velocity_m_s,
                        'dipole_am2': scales.dipole_am2},
            'open_loop_poles': [[p.real, p.imag] for p in np.linalg.eigvals(a)],
            'closed_loop_poles': [[p.real, p.imag] for p in lqr.closed_loop_poles()],
            'open_loop': step_metrics(*runs[0][:2], lqr.separation_m, step, duration_s),
            'lqr': step_metrics(*runs[1][:2], lqr.separation_m, step, duration_s), '_runs': runs}


def airtrack_study(configuration: str, step_m: float, duration_s: float, dt_s: float, scales: tuple[float, float, float]
                   ) -> dict[str, Any]:
    """Step responses of one airtrack configuration, open loop and under LQR, of the core model
    (``dynamics.airtrack``): the commanded separation steps from x0 − ``step_m`` (where the slider rests) to x0
    at t = 0; the laws are the graph's (``acds_controller.airtrack_control``), Bryson ``scales`` (Δx, Δv, Δμ)."""
    from acds_controller.airtrack_control import AirtrackLqr, AirtrackOpenLoop, BrysonScales
    from dynamics.airtrack import AirtrackConfig, simulate
    cfg = AirtrackConfig(configuration=configuration)
    weights = BrysonScales(*scales)
    open_law, lqr = AirtrackOpenLoop(cfg.plant, cfg.separation_m), AirtrackLqr(cfg.plant, cfg.separation_m, weights)
    x_start = cfg.separation_m - step_m
    runs = tuple(simulate(cfg, x_start, 0.0, lambda _t, x, v, law=law: law.dipole_am2(x, v), duration_s, dt_s)
                 for law in (open_law, lqr))
    return _airtrack_row(configuration, cfg.plant, lqr, weights, x_start, runs, duration_s)


def airtrack_graph_study(configuration: str) -> dict[str, Any]:
    """The same step responses from the graph: the configuration's two shipped scenarios
    (``AIRTRACK_SCENARIOS``) on the direct engine, the separation x_slider − x_magnet of every step."""
    from acds_common.scenario import load_scenario
    from acds_controller.airtrack_control import AirtrackLqr
    from acds_controller.airtrack_step import airtrack_plant, bryson_scales
    runs, durations = [], []
    for name in AIRTRACK_SCENARIOS[configuration]:
        sc = load_scenario(name)
        positions, _failure = graph_positions(sc)  # a failed run is a shorter response (ended_at_s)
        magnet_v = next(v for v in sc.values['vehicles'] if v['nodes'])  # the slider runs no node (check_airtrack)
        slider_v = next(v for v in sc.values['vehicles'] if not v['nodes'])
        x = positions[slider_v['name']][:, 0] - positions[magnet_v['name']][:, 0]
        runs.append((np.arange(len(x)) * sc.control_period_s, x, None))
        durations.append(sc.duration_s())
    f = sc.values['formation']
    plant, scales = airtrack_plant(f, slider_v['vehicle'], slider_v['spacecraft']), bryson_scales(f)
    row = _airtrack_row(configuration, plant, AirtrackLqr(plant, f['airtrack_separation'], scales), scales,
                        float(runs[1][1][0]), (runs[0], runs[1]), durations[1])
    row['open_loop'] = step_metrics(*runs[0][:2], f['airtrack_separation'], row['step_m'], durations[0])
    row['scenarios'] = list(AIRTRACK_SCENARIOS[configuration])
    return row


def cmd_airtrack(args: argparse.Namespace) -> int:
    """Both airtrack configurations' step responses: table and plots."""
    from acds_controller.airtrack_control import BrysonScales
    from acds_controller.magnetic_laws import ControllerError
    scales = (args.weight_position_m, args.weight_velocity_m_s, args.weight_dipole_am2)
    try:
        BrysonScales(*scales)
    except ControllerError as exc:
        raise UsageError(f'--weight-*: {exc}') from None
    for name, value in (('--step-m', args.step_m), ('--duration-s', args.duration_s), ('--dt-s', args.dt_s)):
        if not (math.isfinite(value) and value > 0.0):
            raise UsageError(f'{name}: must be > 0, got {value:g}')
    if not args.graph:
        from acds_common.scenario import MAX_STEPS
        from dynamics.airtrack import AirtrackConfig
        steps = args.duration_s / args.dt_s
        if steps > MAX_STEPS:  # as a run's step count is bounded (it had no bound: --dt-s 1e-9 ran for hours)
            raise UsageError(f'--duration-s {args.duration_s:g} at --dt-s {args.dt_s:g}: {steps:,.0f} steps, more '
                             f'than the {MAX_STEPS:,} a run may have')
        x0 = min(AirtrackConfig(configuration=c).separation_m for c in ('stable', 'unstable'))
        if args.step_m >= x0:
            raise UsageError(f'--step-m: the slider starts at x0 − step = {x0 - args.step_m:g} m, off the track '
                             f'(x0 = {x0:g} m): must be < {x0:g}, got {args.step_m:g}')
    from acds_cli.workspace import workspace
    out_dir = Path(args.out) if args.out else workspace() / 'runs' / 'emff_airtrack'
    check_output_dir('--out' if args.out else 'plot folder', out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    rows = []
    for configuration in ('stable', 'unstable'):
        r = (airtrack_graph_study(configuration) if args.graph
             else airtrack_study(configuration, args.step_m, args.duration_s, args.dt_s, scales))
        (t_o, x_o, _), (t_c, x_c, mu_c) = r.pop('_runs')
        fig, axes = plt.subplots(1 if mu_c is None else 2, 1, figsize=(7, 4 if mu_c is None else 6), sharex=True,
                                 squeeze=False)
        ax = axes[0, 0]
        ax.plot(t_o, x_o, label='open loop')
        ax.plot(t_c, x_c, label='LQR')
        ax.axhline(r['separation_m'], color='k', lw=0.5)
        ax.set_ylabel('separation, m')
        source = 'graph, direct engine' if args.graph else 'core model'
        ax.set_title(f'EMFF airtrack, {configuration}: step {r["step_m"]:g} m ({source}; seed 004 slides 53–54)',
                     fontsize=10)
        ax.legend()
        if mu_c is not None:
            axes[1, 0].plot(t_c, mu_c, label='LQR electromagnet dipole')
            axes[1, 0].set_ylabel('μ_e, A·m²')
            axes[1, 0].legend()
        axes[-1, 0].set_xlabel('time, s')
        path = out_dir / f'airtrack_{configuration}{"_graph" if args.graph else ""}.png'
        fig.savefig(path, dpi=100)
        plt.close(fig)
        r['plot'] = str(path)
        rows.append(r)
    if args.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        print(f'airtrack {r["configuration"]}: m {r["mass_kg"]:g} kg, μ_p {r["magnet_dipole_am2"]:g} A·m², x0 '
              f'{r["separation_m"]:g} m, tilt {r["tilt_deg"]:.4f}°, μ_e0 {r["nominal_dipole_am2"]:.1f} A·m²'
              + (f' ({", ".join(r["scenarios"])})' if 'scenarios' in r else ''))
        print(f'  open-loop poles {", ".join(f"{a:+.4f}{b:+.4f}i" for a, b in r["open_loop_poles"])}; LQR K '
              f'{np.round(r["gain"], 2).tolist()} (Δx {r["weights"]["position_m"]:g} m, Δv {r["weights"]["velocity_m_s"]:g} '
              f'm/s, Δμ {r["weights"]["dipole_am2"]:g} A·m²) → poles '
              f'{", ".join(f"{a:+.4f}{b:+.4f}i" for a, b in r["closed_loop_poles"])}')
        for name in ('open_loop', 'lqr'):
            m = r[name]
            settle = '—' if m['settling_time_2pct_s'] is None else f'{m["settling_time_2pct_s"]:.1f} s'
            end = f', left the track at {m["ended_at_s"]:.1f} s' if m['ended_at_s'] is not None else ''
            print(f'  {name:9s} overshoot {m["overshoot_pct"]:7.1f} %, range {m["min_m"]:.4f}–{m["peak_m"]:.4f} m, '
                  f'2 % settling {settle}{end}')
        print(f'  plot {r["plot"]}')
    return 0


def _register_airtrack(sub: argparse._SubParsersAction) -> None:
    text = '1-D airtrack step responses, stable and unstable, open loop and LQR (seed 004 slides 48–55)'
    p = sub.add_parser('emff-airtrack', help=text, description=text + '.')
    p.add_argument('--step-m', type=float, default=0.05, help='setpoint step, m (default 0.05)')
    p.add_argument('--duration-s', type=float, default=60.0, help='response length, s (default 60)')
    p.add_argument('--dt-s', type=float, default=0.05, help='control period, s (default 0.05)')
    p.add_argument('--weight-position-m', type=float, default=0.01, help='Bryson scale of the position, m (default 0.01)')
    p.add_argument('--weight-velocity-m-s', type=float, default=0.01, help='Bryson scale of the velocity (default 0.01)')
    p.add_argument('--weight-dipole-am2', type=float, default=100.0, help='Bryson scale of the dipole (default 100)')
    p.add_argument('--out', help='folder for the plots (default runs/emff_airtrack in the workspace, as every '
                   'verb\'s runs/)')
    p.add_argument('--graph', action='store_true',
                   help='fly the shipped scenarios (emff_airtrack_stable[_open_loop], emff_airtrack_unstable[_open_loop]) '
                        'on the direct engine instead of the core model; the step, duration, period and weights are '
                        "then the scenarios' (the --step-m, --duration-s, --dt-s, --weight-* options are not used)")
    p.add_argument('--json', action='store_true', help='print one JSON list instead of the table')
    p.set_defaults(func=cmd_airtrack)
