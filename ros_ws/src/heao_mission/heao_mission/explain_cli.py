"""``acds explain-sample DIR K``: replay sample K of a Monte Carlo study with a bag and plots, and say why it did
not capture (or how it did) in the study's terms (seed 002 §4.3.1; spec §8).

The sample is drawn again from the study's seed and options (``montecarlo.json``, or the journal's study line of
an unfinished study), run through the process graph (``--engine direct``: the same bits in one process) into
``DIR/explain_K/`` with its bag and the usual plots, and its truth digest compared with the study's record of that
sample (the replay is that sample, or the line says it is not). Then the bag is read for what the acquisition
sequence acts through:

- the mode it stayed in (Mode 1A: rates not below the Mode 1B thresholds; Mode 1B: the capture test — body z
  within the capture cone of the sun line and every |ω_i| at or below the capture rate — never held at once);
- its wheel momentum against the wheels' capacity per axis (a wheel at its capacity cannot null the rates);
- its field geometry: the angle between the Earth field B and the wheel momentum h (the unloading torque M × B is
  perpendicular to B, so the part of h along B cannot be unloaded while the geometry lasts) and the orbit's
  inclination to the dipole axis (how far B turns in inertial space over an orbit).

``explanation.md`` in the replay folder keeps the words and the numbers; the verdict is printed.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
from acds_cli.arguments import UsageError, check_output_dir

#: |cos| of the B/h angle above which h counts as along the field (within 30° of ±B).
ALONG_B_COS = math.cos(math.radians(30.0))
#: A wheel axis counts as at its capacity from this share of it.
AT_CAPACITY = 0.999


def study_of(folder: Path) -> dict[str, Any]:
    """What a study ran (scenario, seed, user's --vary, --until-min, engine) from ``montecarlo.json`` or, for an
    unfinished study, its journal's study line; a folder that is neither is a UsageError (one line)."""
    from acds_runtime.journal import journaled_study

    try:
        spec = json.loads((folder / 'montecarlo.json').read_text())
        return {'scenario': spec['scenario_path'] if Path(spec['scenario_path']).exists() else spec['scenario'],
                'seed': spec['seed'], 'vary': spec['user_vary'], 'until_min': spec['until_min'], 'runs': spec['runs']}
    except (OSError, json.JSONDecodeError, KeyError):
        pass
    journaled = journaled_study(folder)
    if journaled is None or journaled[0].get('verb') != 'montecarlo':
        raise UsageError(f'{folder}: not a montecarlo output folder (no montecarlo.json nor a study journal)')
    study = journaled[0]
    return {'scenario': study['scenario'], 'seed': study['seed'], 'vary': study['vary'],
            'until_min': study['until_min'], 'runs': study['runs']}


def recorded_summary(folder: Path, index: int) -> dict[str, Any] | None:
    """The study's summary of sample ``index`` (its journal), None when the study has not run it."""
    from acds_runtime.journal import JOURNAL

    try:
        lines = (folder / JOURNAL).read_text().splitlines()[1:]
    except OSError:
        return None
    for line in lines:
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            continue
        if rec.get('index') == index and rec.get('case') == '':
            return rec['summary']
    return None


def replay(study: dict[str, Any], index: int, run_dir: Path, engine: str) -> dict[str, Any]:
    """Run the sample (``acds run SCENARIO --sample S:K``) with its bag and plots into ``run_dir``; its summary."""
    cmd = [sys.executable, '-m', 'acds_cli', 'run', str(study['scenario']), '--sample', f'{study["seed"]}:{index}',
           '--engine', engine, '--run-dir', str(run_dir), '--summary-json', str(run_dir / 'summary.json'), '--quiet']
    for v in study['vary']:
        cmd += ['--vary', v]
    if study['until_min'] is not None:
        cmd += ['--until-min', f'{study["until_min"]:g}']
    print(f'[explain-sample] replaying: {" ".join(cmd[2:])}', file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or ['(no output)']
        raise UsageError(f'sample {index}: the replay failed (exit {proc.returncode}): {tail[0]}')
    return json.loads((run_dir / 'summary.json').read_text())


# -------------------------------------------------------------------------------------- the bag's facts


def _segment_share(mask: np.ndarray) -> float:
    return float(mask.mean()) if len(mask) else 0.0


def facts_of(bag_path: Path, scenario: Any) -> dict[str, Any]:
    """What the acquisition acted through, from the bag (module doc): modes, capture test, wheels, field geometry."""
    from acds_cli.bag.plots import _common, _gather, _series, _v3, mode_of, odometry_values, run_context, sun_angle_deg
    from acds_common import topics, units
    from acds_common.mode_report import transitions
    from acds_runtime.bag.reader import open_bag

    from .heao_summary import Accumulator

    bag = open_bag(bag_path)
    ctx = run_context(bag)

    data = _gather(bag, {topics.TRUTH_ODOMETRY: odometry_values, topics.WHEEL_MOMENTUM: lambda m: _v3(m.vector),
                         topics.TRUTH_B_BODY: lambda m: _v3(m.magnetic_field)}, {topics.MODE: mode_of})
    stamps, values = data.get(topics.resolve(topics.MODE), ((), []))
    history = [(t / 1e9, *v) for t, v in zip(stamps, values, strict=True)]
    t_w, wq = _series(data, topics.TRUTH_ODOMETRY, 7)
    t_h, h = _series(data, topics.WHEEL_MOMENTUM)
    t_b, b = _series(data, topics.TRUTH_B_BODY)
    modes = ctx.section('ascs_mode_manager', 'modes')
    final_mode = history[-1][1] if history else None
    entered = next((t / 60 for t, m, _c, _k in reversed(history) if m != final_mode), None)
    entered = 0.0 if entered is None else next(t / 60 for t, m, _c, _k in history if m == final_mode and t / 60 >= entered)
    end_min = float(t_w[-1]) if len(t_w) else 0.0
    in_mode = t_w >= entered
    w_deg = np.degrees(wq[in_mode, :3])
    sun = ctx.sun_eci()
    angle = sun_angle_deg(wq[in_mode, 3:], sun) if sun is not None and in_mode.any() else np.zeros(0)
    cone, rate = math.degrees(modes['capture_cone']), math.degrees(modes['capture_rate'])
    thresholds = np.degrees(modes['rate_thresholds'])
    capacity = np.asarray(Accumulator(scenario).capacity)
    ih = t_h >= entered
    h_mode = h[ih]
    at_cap = np.abs(h_mode) >= capacity * AT_CAPACITY if len(h_mode) else np.zeros((0, 3), bool)
    # total body momentum H = I·ω + h at the field's stamps (the rigid body's inertia as the node ran it)
    spacecraft = ctx.section('rigid_body', 'spacecraft')
    from acds_common.inertia import inertia_tensor
    inertia = inertia_tensor(*spacecraft['inertia']) * spacecraft['inertia_scale']
    ib, iw = _common(t_b, t_w)
    big_h = wq[iw, :3] @ inertia.T
    _, ih2 = _common(t_w[iw], t_h)
    if len(ih2) == len(iw):
        big_h = big_h + h[ih2]
    keep = t_b[ib] >= entered
    geometry = _field_geometry(b[ib][keep], big_h[keep])
    geometry['h_at_entry_ftlbs'] = float(units.nms_to_ftlbs(np.linalg.norm(big_h[keep][0]))) if keep.any() else None
    in_cone = angle <= cone
    nulled = np.all(np.abs(w_deg) <= rate, axis=1) if len(w_deg) else np.zeros(0, bool)
    return {
        'final_mode': final_mode, 'entered_min': entered, 'end_min': end_min, 'events': transitions(history),
        'capture_cone_deg': cone, 'capture_rate_deg_s': rate, 'rate_thresholds_deg_s': thresholds.tolist(),
        'sun_angle_min_deg': float(angle.min()) if len(angle) else None,
        'sun_angle_final_deg': float(angle[-1]) if len(angle) else None,
        'share_in_cone': _segment_share(in_cone),
        'share_rates_nulled': _segment_share(nulled),
        'share_both': _segment_share(in_cone & nulled) if len(in_cone) == len(nulled) else 0.0,
        'rates_final_deg_s': w_deg[-1].tolist() if len(w_deg) else None,
        'rates_median_abs_deg_s': np.median(np.abs(w_deg), axis=0).tolist() if len(w_deg) else None,
        'capacity_ftlbs': units.nms_to_ftlbs(capacity).tolist(),
        'h_final_ftlbs': units.nms_to_ftlbs(h[-1]).tolist() if len(h) else None,
        'h_peak_ftlbs': units.nms_to_ftlbs(np.abs(h_mode).max(axis=0)).tolist() if len(h_mode) else None,
        'share_at_capacity': [_segment_share(at_cap[:, i]) for i in range(3)] if len(h_mode) else [0.0] * 3,
        **geometry,
    }


def _field_geometry(b: np.ndarray, big_h: np.ndarray) -> dict[str, Any]:
    """The body momentum H against the field B (body axes, same stamps): the share of the time H is within 30° of the
    field line, the median angle to it, and the median |H| and its part along B (ft-lb-sec)."""
    from acds_common import units

    nb, nh = np.linalg.norm(b, axis=1), np.linalg.norm(big_h, axis=1)
    ok = (nb > 0) & (nh > 0)
    if not ok.any():
        return {'share_h_along_b': 0.0, 'bh_angle_median_deg': None, 'h_median_ftlbs': None,
                'h_along_b_median_ftlbs': None}
    along = np.abs(np.einsum('ij,ij->i', b[ok], big_h[ok])) / nb[ok]
    cos = along / nh[ok]
    return {'share_h_along_b': float((cos >= ALONG_B_COS).mean()),
            'bh_angle_median_deg': float(np.degrees(np.arccos(np.clip(np.median(cos), 0.0, 1.0)))),
            'h_median_ftlbs': float(units.nms_to_ftlbs(np.median(nh[ok]))),
            'h_along_b_median_ftlbs': float(units.nms_to_ftlbs(np.median(along)))}


# ------------------------------------------------------------------------------------------ the words


def _axes(mask: list[bool]) -> str:
    return ', '.join(a for a, m in zip('xyz', mask, strict=True) if m)


def verdict(f: dict[str, Any], sat: list[bool]) -> str:
    """The cause in one sentence, from the facts (:func:`explain` gives the numbers)."""
    along = f['share_h_along_b'] >= 0.5
    if f['final_mode'] == 'mode_1a':
        cause = ('the body momentum stayed close to the field line, where the B × H law has no torque to reduce it'
                 if along else 'the magnetics alone did not bring the rates below the thresholds in the run')
        return f'Why, in short: it never left Mode 1A because {cause}.'
    parts = []
    if along:
        parts.append(f'the body momentum lay along the field line (within 30° of it {100 * f["share_h_along_b"]:.0f} % '
                     'of the time: the adverse alignment of Table 4-7 case 4, B ∥ H, reached here in flight), where the '
                     'magnetic torque M × B, perpendicular to B, cannot take it out of the wheels')
    if any(sat):
        entry = f['h_at_entry_ftlbs']
        parts.append(f'it entered Mode 1B on its rates (the transition test is on rates, not momentum) still carrying '
                     f'|H| = {entry or 0:.1f} ft-lb-sec, and what stayed exceeded the {_axes(sat)} wheel capacity '
                     f'({", ".join(f"{c:.1f}" for c, m in zip(f["capacity_ftlbs"], sat, strict=True) if m)} ft-lb-sec), '
                     'so the wheels saturated and the rates were never nulled')
    if not parts:
        parts.append('the capture test never held: ' + ('the rates were never nulled' if f['share_rates_nulled'] == 0
                                                         else 'z was never within the cone while the rates were nulled'))
    return 'Why, in short: it reached Mode 1B but not capture because ' + '; '.join(parts) + '.'


def explain(facts: dict[str, Any], geometry: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    """The verdict in the study's terms (module doc): one paragraph a fact, the cause first."""
    f = facts
    captured = summary.get('acquisition_time_min') is not None
    mode, span = f['final_mode'], f['end_min'] - f['entered_min']
    words = []
    if captured:
        return [f'It captured at {summary["acquisition_time_min"]:.1f} min (Mode 1B from '
                f'{summary.get("time_magnetics_only_min") or 0:.1f} min): nothing to explain beyond the plots.']
    if mode == 'mode_1a':
        above = [abs(w) > t for w, t in zip(f['rates_final_deg_s'], f['rate_thresholds_deg_s'], strict=True)]
        limits = ', '.join(f'{t:.3g}' for t in f['rate_thresholds_deg_s'])
        words.append(f'It stayed in Mode 1A (magnetics only, wheels off) for the whole {f["end_min"]:.0f} min: the body '
                     f'rates never all fell below the Mode 1B thresholds ({limits} deg/s); at the end |ω| = '
                     f'{", ".join(f"{abs(w):.3f}" for w in f["rates_final_deg_s"])} deg/s, '
                     f'above on {_axes(above) or "none"}.')
    else:
        words.append(f'It reached Mode 1B (wheels on the sun sensor, magnetics unloading) at {f["entered_min"]:.1f} min '
                     f'and stayed in it {span:.0f} min to the end of the run without capture: the capture test '
                     f'(z within {f["capture_cone_deg"]:.3g}° of the sun line and every |ω_i| ≤ {f["capture_rate_deg_s"]:.3g} '
                     f'deg/s) held at no step. z was inside the cone {100 * f["share_in_cone"]:.0f} % of that time '
                     f'(closest {f["sun_angle_min_deg"]:.1f}°, at the end {f["sun_angle_final_deg"]:.1f}°); the rates were '
                     f'nulled {100 * f["share_rates_nulled"]:.0f} % of it (median |ω| '
                     f'{", ".join(f"{w:.3f}" for w in f["rates_median_abs_deg_s"])} deg/s on x, y, z).')
    sat = [s > 0.0 for s in f['share_at_capacity']]
    words.insert(0, verdict(f, sat))
    if any(sat):
        shares = ', '.join(f'{100 * s:.0f} %' for s, m in zip(f['share_at_capacity'], sat, strict=True) if m)
        words.append(f'Its wheels were at their capacity ({", ".join(f"{c:.1f}" for c in f["capacity_ftlbs"])} ft-lb-sec '
                     f'per axis) on {_axes(sat)} for {shares} of that time (first at '
                     f'{summary.get("wheel_saturation_time_min") or 0:.1f} min): a wheel at its capacity gives no more '
                     'torque on its axis, so the sun loop cannot null the rate there.')
    else:
        words.append(f'Its wheels stayed below their capacity (peak |h| per axis '
                     f'{", ".join(f"{x:.1f}" for x in f["h_peak_ftlbs"] or (0, 0, 0))} of '
                     f'{", ".join(f"{c:.1f}" for c in f["capacity_ftlbs"])} ft-lb-sec).')
    words.append(f'Field geometry: the orbit was {geometry.get("orbit_dipole_inclination_deg", float("nan")):.1f}° from the '
                 f'dipole axis and the body momentum {geometry.get("initial_h_b_angle_deg", float("nan")):.0f}° from B at t0; '
                 f'in the final mode the body momentum H = I·ω + h (median {f["h_median_ftlbs"] or 0:.1f} ft-lb-sec) was '
                 f'within 30° of the field line {100 * f["share_h_along_b"]:.0f} % of the time (median angle '
                 f'{f["bh_angle_median_deg"] or 0:.0f}°, median part along B {f["h_along_b_median_ftlbs"] or 0:.1f} '
                 'ft-lb-sec): the magnetic torque M × B is perpendicular to B, so the part of H along B is not '
                 f'removed while the geometry lasts{"" if mode == "mode_1a" else " and stays in the wheels"}.')
    return words


def cmd_explain_sample(args: argparse.Namespace) -> int:
    """Replay, compare, read the bag, explain (module doc)."""
    from acds_common.scenario import load_scenario
    from acds_runtime.sampling import Sampler

    folder = Path(args.folder)
    study = study_of(folder)
    if not 0 <= args.index < study['runs']:
        raise UsageError(f'{args.index}: the study in {folder} has samples 0…{study["runs"] - 1}')
    run_dir = Path(args.run_dir) if args.run_dir else folder / f'explain_{args.index}'
    check_output_dir('--run-dir' if args.run_dir else 'replay folder', run_dir)
    if run_dir.exists() and any(run_dir.iterdir()):
        raise UsageError(f'{run_dir}: exists and is not empty (remove it, or give --run-dir)')
    sample = Sampler(load_scenario(study['scenario']), study['seed'], study['vary']).draw(args.index)
    recorded = recorded_summary(folder, args.index)
    summary = replay(study, args.index, run_dir, args.engine)
    if recorded is None:
        same = f'the study has no record of sample {args.index} yet'
    elif recorded.get('truth_digest') == summary.get('truth_digest'):
        same = f'the same truth digest as the study\'s sample {args.index} ({str(summary.get("truth_digest"))[:12]}…)'
    else:
        same = (f'NOT the study\'s sample: truth digest {str(summary.get("truth_digest"))[:12]}… against the study\'s '
                f'{str(recorded.get("truth_digest"))[:12]}… (the code or the scenario changed since)')
    facts = facts_of(run_dir / 'bag', sample.scenario)
    geometry = sample.geometry()
    words = explain(facts, geometry, summary)
    head = (f'Sample {args.index} of seed {study["seed"]} ({sample.scenario.name}), replayed on the {args.engine} engine: '
            f'{same}.')
    text = '\n\n'.join([head, *words])
    drawn = ', '.join(f'{k} = {json.dumps(v)}' for k, v in sample.drawn.items())
    (run_dir / 'explanation.md').write_text(
        f'# Why sample {args.index} did {"not " if summary.get("acquisition_time_min") is None else ""}capture\n\n{text}\n\n'
        f'Drawn: {drawn}\n\nGeometry at t0: {json.dumps(geometry)}\n\nFacts from the bag:\n\n```\n'
        f'{json.dumps(facts, indent=1, default=str)}\n```\n\nPlots: `plots/` (mode timeline, sun angle, responses, '
        'field/momentum angle); bag: `bag/`.\n')
    print(text)
    print(f'[explain-sample] {run_dir / "explanation.md"}; bag {run_dir / "bag"}; plots in {run_dir / "plots"}',
          file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``explain-sample`` verb."""
    p = sub.add_parser('explain-sample', help='replay one Monte Carlo sample with a bag and plots and say why it did '
                                              'not capture',
                       description='Draw sample K of the montecarlo study in DIR again, run it with a bag and plots '
                                   'into DIR/explain_K (the process graph by default), check it is the study\'s sample '
                                   '(truth digest) and say, from the bag, which mode it stayed in, its wheel momentum '
                                   'and its field geometry.')
    p.add_argument('folder', metavar='DIR', help='a montecarlo output folder (finished or interrupted)')
    p.add_argument('index', metavar='K', type=int, help='the sample index')
    p.add_argument('--engine', choices=('graph', 'direct'), default='graph',
                   help='graph (default: one process per node) or direct (one process, the same bits, faster)')
    p.add_argument('--run-dir', metavar='PATH', help='replay folder (default DIR/explain_K)')
    p.set_defaults(func=cmd_explain_sample)
