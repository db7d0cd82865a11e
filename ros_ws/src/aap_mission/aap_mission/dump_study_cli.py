"""``acds dump-report SCENARIO --k-sweep A:B:N`` and ``--mm-sweep KIND:A:B:N``: the seed-000 studies of the dump law
(§5's k range, §12's M_m estimation), run on the direct engine (:mod:`aap_mission.dump_study`); a table on stdout,
a plot and the rows as JSON."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np


def _f(x: float | None, spec: str) -> str:
    return '—' if x is None else format(x, spec)


def print_k_table(name: str, rows: list[dict[str, Any]]) -> None:
    """The k study, one line per k: the loop gains, then from the §5 initialisation and from H_s = 0."""
    print(f'k study (seed 000 §5) of {name}: each k flown from the §5 initialisation and from H_s = 0; "conv" = '
          f'orbits until the run from zero flies the same M_o and M_m (±5 %) as the initialised one')
    print(f'  {"k (seed)":>10} {"k·W gains":>13} {"conv":>5} | {"§5 init:":<8} {"|ΔH_s|":>8} {"H_s span":>9} '
          f'{"M_o":>8} {"M_m":>8} | {"from 0:":<7} {"|ΔH_s|":>8} {"H_s span":>9} {"M_o":>8} {"M_m":>8} '
          f'{"min-en M_o":>10}')
    for r in rows:
        gains = f'{r["loop_gain_min"]:.2f}…{r["loop_gain_max"]:.2f}'
        conv = '—' if r['orbits_to_converge_from_zero'] is None else str(r['orbits_to_converge_from_zero'])
        print(f'  {r["k_seed"]:>10.4g} {gains:>13} {conv:>5} | {"":<8} {_f(r["delta_H_s_ftlbs_init"], ".1f"):>8} '
              f'{_f(r["H_s_range_ftlbs_init"], ".1f"):>9} {_f(r["M_o_am2_init"], ".0f"):>8} '
              f'{_f(r["M_m_am2_init"], ".0f"):>8} | {"":<7} {_f(r["delta_H_s_ftlbs_zero"], ".1f"):>8} '
              f'{_f(r["H_s_range_ftlbs_zero"], ".1f"):>9} {_f(r["M_o_am2_zero"], ".0f"):>8} '
              f'{_f(r["M_m_am2_zero"], ".0f"):>8} {r["min_energy_M_o_am2"]:>10.0f}')
    print('  |ΔH_s|: largest per-orbit change of H_s, ft-lb-sec; H_s span: largest distance between two samples over the '
          'run; M_o, M_m in A·m², largest over the orbits (from 0: from convergence on); "—": the loop cannot converge')


def plot_k(name: str, rows: list[dict[str, Any]], out: Path) -> Path:
    """``k_sweep.png``: orbits to converge, |ΔH_s| and M_m against k, both initialisations, and the loop gains."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    k = np.array([r['k_seed'] for r in rows])
    fig, axs = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    axs[0].plot(k, [r['loop_gain_max'] for r in rows], 'o-', label='largest gain')
    axs[0].plot(k, [r['loop_gain_min'] for r in rows], 's-', label='smallest gain')
    axs[0].axhspan(0, 2, color='C2', alpha=0.12, label='converging range (0, 2)')
    axs[0].set_ylabel('eigenvalues of k·W')
    axs[0].legend(fontsize=8)
    for tag, label, marker in (('init', '§5 initialisation', 'o'), ('zero', 'from H_s = 0', 's')):
        axs[1].semilogy(k, [np.nan if r[f'delta_H_s_ftlbs_{tag}'] is None else r[f'delta_H_s_ftlbs_{tag}']
                            for r in rows], marker + '-', label=f'|ΔH_s| largest per orbit, {label}')
        axs[2].plot(k, [np.nan if r[f'M_m_am2_{tag}'] is None else r[f'M_m_am2_{tag}'] for r in rows], marker + '-',
                    label=f'M_m, {label}')
    conv = [np.nan if r['orbits_to_converge_from_zero'] is None else r['orbits_to_converge_from_zero'] for r in rows]
    twin = axs[2].twinx()
    twin.plot(k, conv, 'k^--', label='orbits to converge from 0')
    twin.set_ylabel('orbits to converge from 0')
    axs[1].set_ylabel('ft-lb-sec')
    axs[1].legend(fontsize=8)
    axs[2].set_ylabel('M_m, A·m²')
    axs[2].set_xlabel('k, amp-turn-m² per ft-lb-sec per Wb/m² (seed units)')
    axs[2].legend(fontsize=8, loc='upper left')
    twin.legend(fontsize=8, loc='upper right')
    for ax in axs:
        ax.grid(alpha=0.3, which='both')
    fig.suptitle(f'{name}: the k study (seed 000 §5)', fontsize=10)
    fig.tight_layout()
    path = out / 'k_sweep.png'
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


_SWEEP_LABEL = {'hb': '|H_b|, ft-lb-sec', 'iy_minus_iz': 'I_y − I_z, slug-ft²', 'iz_minus_ix': 'I_z − I_x, slug-ft²'}


def print_mm_table(name: str, sweep: str, rows: list[dict[str, Any]], slopes: dict[str, float]) -> None:
    """The §12 sweep: M_m against the swept quantity, with the memo's rule beside it, and the fitted slopes."""
    from aap_mission.dump_study import SEED_MM_PER_HB

    print(f'M_m estimation (seed 000 §12) of {name}: {_SWEEP_LABEL[sweep]} swept, the law as the scenario flies it')
    print(f'  {_SWEEP_LABEL[sweep]:>20} {"|H_b|":>8} {"M_n":>8} {"M_d":>8} {"M_o":>8} {"M_m":>8} {"12.5·H_b":>9} '
          f'{"M_m/H_b":>8} {"|ΔH_s|":>8} {"k·W gains":>13}')
    for r in rows:
        print(f'  {r["value"]:>20,.0f} {r["H_b_ftlbs"]:>8.1f} {_f(r["M_n_am2"], ".0f"):>8} {_f(r["M_d_am2"], ".0f"):>8} '
              f'{r["M_o_am2"]:>8.0f} {r["M_m_am2"]:>8.0f} {r["seed_estimate_M_m_am2"]:>9.0f} '
              f'{r["M_m_am2"] / r["H_b_ftlbs"]:>8.2f} {_f(r["delta_H_s_ftlbs"], ".1f"):>8} '
              f'{_f(r["loop_gain_min"], ".2f")}…{_f(r["loop_gain_max"], ".2f")}')
    print(f'  fitted M_m = {slopes["hb_through_origin"]:.2f}·|H_b| (through the origin; least squares '
          f'{slopes["hb_ols"]:.2f}); the memo: {SEED_MM_PER_HB}·H_b')
    if sweep != 'hb':
        print(f'  against |{_SWEEP_LABEL[sweep]}|: slope {slopes["abs_value_ols"]:.4g} A·m² per slug-ft² (least squares); '
              f'the memo (45° OP, M_m = 12.5·(3π/2)·n·(I_z − I_x)): 0.0665')


def plot_mm(name: str, sweep: str, rows: list[dict[str, Any]], out: Path) -> Path:
    """``mm_sweep_<kind>.png``: M_m (and M_o) against the swept quantity, with the memo's 12.5·H_b."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    x = np.array([r['value'] for r in rows])
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.plot(x, [r['M_m_am2'] for r in rows], 'o-', label='M_m (emulator)')
    ax.plot(x, [r['M_o_am2'] for r in rows], 's-', label='M_o (emulator)')
    ax.plot(x, [r['seed_estimate_M_m_am2'] for r in rows], 'k--', label='memo §12: 12.5·|H_b|')
    ax.set_xlabel(_SWEEP_LABEL[sweep])
    ax.set_ylabel('A·m²')
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle(f'{name}: M_m estimation (seed 000 §12)', fontsize=10)
    fig.tight_layout()
    path = out / f'mm_sweep_{sweep}.png'
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def cmd_study(args: argparse.Namespace) -> int:
    """Run the k study or the §12 sweep of ``args.source``; print, plot, write JSON."""
    import json

    from acds_cli.arguments import check_output_file
    from acds_cli.workspace import new_run_dir, workspace
    from acds_common.scenario import ScenarioError
    from acds_runtime.bag.writer import BagError, check_out_dir
    from acds_runtime.launcher import LaunchError
    from acds_runtime.preflight import preflight

    from aap_mission import dump_study
    from aap_mission.dump_report import check_workshop

    def progress(text: str) -> None:
        print(f'[acds] {text}', file=sys.stderr, flush=True)

    try:
        if args.json:
            check_output_file('--json', Path(args.json))
        if args.k_sweep and args.mm_sweep:
            raise ScenarioError('--k-sweep and --mm-sweep are two studies: give one')
        base = dump_study.scenario_with_sets(args.source, args.set or [])
        check_workshop(base)
        preflight(base)
        kind = 'k_sweep' if args.k_sweep else 'mm_sweep'
        check_out_dir(Path(args.out) if args.out else workspace() / 'runs')
        if args.k_sweep:
            ks = dump_study.parse_range(args.k_sweep, '--k-sweep')
            if np.any(ks <= 0):
                raise ScenarioError(f'--k-sweep {args.k_sweep!r}: k must be positive')
            rows = dump_study.k_sweep(args.source, ks, args.steps, args.set, progress)
        else:
            sweep, _, span = args.mm_sweep.partition(':')
            if sweep not in dump_study.SWEEPS:
                raise ScenarioError(f'--mm-sweep {args.mm_sweep!r}: expected KIND:A:B:N, KIND one of '
                                    f'{", ".join(dump_study.SWEEPS)}')
            rows = dump_study.bias_sweep(args.source, sweep, dump_study.parse_range(span, '--mm-sweep'), args.steps,
                                         args.set, progress)
    except (ScenarioError, BagError, LaunchError) as exc:
        print(f'acds dump-report: {exc}', file=sys.stderr)
        return 2
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
    else:
        out = new_run_dir(f'{base.name}_{kind}')
    result: dict[str, Any] = {'scenario': base.name, 'study': kind, 'rows': rows}
    if args.k_sweep:
        print_k_table(base.name, rows)
        plot = plot_k(base.name, rows, out)
    else:
        hb = np.array([r['H_b_ftlbs'] for r in rows])
        mm = np.array([r['M_m_am2'] for r in rows])
        values = np.array([r['value'] for r in rows])
        origin, ols = dump_study.fitted_slope(hb, mm)
        slopes = {'hb_through_origin': origin, 'hb_ols': ols,
                  'abs_value_ols': float(np.polyfit(np.abs(values), mm, 1)[0]) if values.size > 1 else float('nan')}
        result['slopes'] = slopes
        print_mm_table(base.name, sweep, rows, slopes)
        plot = plot_mm(base.name, sweep, rows, out)
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + '\n')
        print(f'wrote {args.json}', file=sys.stderr)
    print(f'[acds] plot {plot}', file=sys.stderr)
    return 0
