"""``acds montecarlo SCENARIO --runs N``: acquisition as a distribution; ``acds pick-sample DIR``: the baseline rule.

``montecarlo`` draws N samples of the open conditions (``acds_runtime.sampling``: attitude
uniform on SO(3), node RA, orbit phase and Greenwich angle uniform; ``--vary KEY=DIST`` adds or
replaces draws), runs each one on the direct engine (or ``--engine graph``), in this process
(``--jobs 1``), on a local Dask cluster (``--jobs J``) or on the user's (``--scheduler``), and
leaves in ``--out DIR``: ``samples.csv``, ``samples.json``, ``percentiles.json``, one PNG per
quantity, ``report.md`` and ``montecarlo.json`` (what was run, to rebuild any sample). It prints
the percentile table in study units. Exit 1 if a sample's run failed (listed, never dropped).

``pick-sample DIR`` applies the baseline rule to such a study: the sample whose acquisition time
is nearest the chosen percentile (default the 90th: a representative worst case, see the docs' Studies page),
printed with the scenario keys that set its conditions and, for Table 4-7 case 4, the H ∥ B attitude
on the same geometry.

``run SCENARIO --sample S:K [--vary ...]`` (``acds run``) reruns sample K of seed S through the full
graph with its bag; :func:`add_sample_options` and :func:`sample_for_run` are its pieces.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from acds_common.scenario import Scenario, ScenarioError

from ..arguments import UsageError, check_output_dir, positive_int, positive_minutes
from ..interrupts import interruption
from ..workspace import new_run_dir, workspace

#: The quantity and percentile of the baseline rule (docs: Studies, "Choosing the baseline's open conditions").
BASELINE_QUANTITY, BASELINE_PERCENTILE = 'acquisition_time_min', 90.0
#: What one sample leaves on disk, bytes: its journal line, its samples.json entry and its samples.csv row, twice over
#: what the main job's measure (1.5 + 2.0 + 0.5 kB; a sample with more mode changes writes more).
BYTES_PER_SAMPLE = 8_000
#: What a study leaves besides its samples, bytes: the PNGs, report.md, percentiles.json (0.4 MB measured).
BYTES_PER_STUDY = 2_000_000


def add_sample_options(p: argparse.ArgumentParser, *, run: bool) -> None:
    """``--vary KEY=DIST`` (repeatable) and, for ``run``, ``--sample S:K``."""
    if run:
        p.add_argument('--sample', metavar='S:K',
                       help='run sample K of seed S of SCENARIO (as `acds montecarlo` drew it) instead of SCENARIO')
    p.add_argument('--vary', action='append', default=[], metavar='KEY=DIST',
                   help='draw this scenario key from DIST (uniform(a,b), normal(mu,sigma), integers(a,b), choice(...), '
                        'fixed(v), so3(), h_parallel_b()); units as the key says, a vector key per component; '
                        'replaces the default draw of the same key')


def _sampler(base: Scenario, seed: int, vary: list[str], command: str = '') -> Any:
    from acds_runtime.sampling import Sampler, SamplingError

    try:
        return Sampler(base, seed, vary, command=command)
    except SamplingError as exc:
        raise UsageError(str(exc)) from None


def _draw(sampler: Any, index: int) -> Any:
    from acds_runtime.sampling import SamplingError

    try:
        return sampler.draw(index)
    except SamplingError as exc:
        raise UsageError(str(exc)) from None


def _preflight(sample: Any) -> None:
    """Pre-flight a sample (every stepper built), naming it rather than its temporary file."""
    from acds_runtime.preflight import preflight

    try:
        preflight(sample.scenario)
    except ScenarioError as exc:
        label = f'{sample.scenario.name} (sample {sample.seed}:{sample.index})'
        raise ScenarioError(str(exc).replace(str(sample.scenario.path), label)) from None


def rerun_command(scenario: str, seed: int, index: int | str, vary: list[str], until_min: float | None) -> str:
    """The ``acds run`` line that reruns one sample through the full graph."""
    parts = ['./scripts/acds', 'run', scenario, '--sample', f'{seed}:{index}']
    for v in vary:
        parts += ['--vary', v]
    if until_min is not None:
        parts += ['--until-min', f'{until_min:g}']
    return ' '.join(shlex.quote(p) if p != f'{seed}:{index}' else p for p in parts)


def sample_for_run(scenario: Scenario, args: argparse.Namespace) -> tuple[Scenario, str | None]:
    """``run --sample S:K``: the sample's scenario and its YAML text (None without ``--sample``)."""
    from acds_runtime.sampling import SamplingError, parse_sample_ref

    if args.sample is None:
        if args.vary:
            raise UsageError('--vary draws a sample: give --sample SEED:INDEX with it')
        return scenario, None
    try:
        seed, index = parse_sample_ref(args.sample)
    except SamplingError as exc:
        raise UsageError(str(exc)) from None
    sampler = _sampler(scenario, seed, args.vary,
                       rerun_command(args.scenario or scenario.name, seed, '{index}', args.vary, args.until_min))
    sample = _draw(sampler, index)
    _preflight(sample)
    print(f'[acds] sample {seed}:{index} of {scenario.name}:\n{sample.text}', file=sys.stderr, flush=True)
    return sample.scenario, sample.text


# ------------------------------------------------------------------------------------- montecarlo


def _steps(scenario: Scenario, until_min: float | None) -> int | None:
    from acds_common.scenario import MAX_STEPS

    if until_min is None:
        return None
    steps = max(1, round(until_min * 60 / scenario.control_period_s))
    if steps > MAX_STEPS:
        raise UsageError(f'--until-min {until_min:g}: {steps:,} steps, more than the {MAX_STEPS:,} a run may have')
    return steps


def _run_length(scenario: Scenario, steps: int | None, samples: list[Any] | None = None) -> str:
    """How long each run is: its steps and control period (their ranges when the samples vary the period)."""
    runs = {s.length for s in samples or []} or {(scenario.total_steps(), scenario.control_period_s)}
    lengths = sorted({(steps if steps is not None else n, dt) for n, dt in runs}, key=lambda nd: nd[0] * nd[1])
    if len({dt for _, dt in lengths}) > 1:
        counts, periods = sorted(n for n, _ in lengths), sorted(dt for _, dt in lengths)
        text = (f'{counts[0]}–{counts[-1]} steps of {periods[0]:g}–{periods[-1]:g} s (control_period_s varied; '
                f'{lengths[0][0] * lengths[0][1] / 60:.1f}–{lengths[-1][0] * lengths[-1][1] / 60:.1f} min sim)')
    else:
        n, dt = lengths[0]
        text = f'{n} steps of {dt:g} s ({n * dt / 60:.1f} min sim)'
    if scenario.get('modes', 'stop_at_capture'):
        text += ', each run stopping at acquisition capture'
    return text


def draw_samples(base: Scenario, seed: int, runs: int, vary: list[str], command: str,
                 jobs: int = 1) -> tuple[Any, Any]:
    """The sampler and its ``runs`` samples as the study keeps them (``KeptSample``: each validated, then its
    Scenario let go; the first pre-flighted here: every stepper built), on disk (``SpooledSamples``: the study's
    memory does not grow with its samples); a large study's drawn in ``jobs`` processes
    (:func:`acds_runtime.sampling.kept_samples`)."""
    from contextlib import closing

    from acds_runtime.sampling import SamplingError, SpooledSamples, kept_samples

    sampler = _sampler(base, seed, vary, command)
    samples = SpooledSamples()
    first = _draw(sampler, 0)
    _preflight(first)
    samples.append(first.kept())
    try:
        with closing(kept_samples(sampler, 1, runs, jobs)) as rest:
            for sample in rest:
                samples.append(sample)
    except SamplingError as exc:
        raise UsageError(str(exc)) from None
    return sampler, samples


class Keyed(Mapping[tuple[str, int], Any]):
    """A study's samples by (case, index), read from each case's samples (``SpooledSamples``, sample k at
    position k) when asked: a view, so nothing is held twice."""

    def __init__(self, cases: dict[str, Sequence[Any]]) -> None:
        self.cases = cases

    def __getitem__(self, key: tuple[str, int]) -> Any:
        case, index = key
        if case not in self.cases or not 0 <= index < len(self.cases[case]):
            raise KeyError(key)
        return self.cases[case][index]

    def __iter__(self) -> Iterator[tuple[str, int]]:
        return ((case, index) for case, samples in self.cases.items() for index in range(len(samples)))

    def __len__(self) -> int:
        return sum(len(samples) for samples in self.cases.values())


def study_command(verb: list[str], args: argparse.Namespace) -> str:
    """The command line that makes this study again (from the parsed options, so it is exact)."""
    parts = ['./scripts/acds', *verb, '--runs', str(args.runs), '--seed', str(args.seed)]
    for v in args.vary:
        parts += ['--vary', v]
    if args.until_min is not None:
        parts += ['--until-min', f'{args.until_min:g}']
    if args.engine != 'direct':
        parts += ['--engine', args.engine]
    return ' '.join(shlex.quote(p) for p in parts)


def _execution_text(execution: Any) -> str:
    return f'{execution.where}, {execution.workers} worker(s), {execution.threads} thread(s){execution.mixed()}'


def study_folder(prefix: str, name: str, args: argparse.Namespace) -> Path:
    """The study's output folder: ``--resume DIR``, ``--out DIR`` or a new one under ``runs/``."""
    if args.resume:
        if args.out and Path(args.out).resolve() != Path(args.resume).resolve():
            raise UsageError(f'--out {args.out}: a resumed study writes into its own folder ({args.resume})')
        return Path(args.resume)
    out = Path(args.out) if args.out else _default_out(prefix, name, args.seed, args.runs)
    check_output_dir('--out' if args.out else 'output folder', out)
    return out


def check_disk(out: Path, runs: int) -> None:
    """Refuse, in one line before anything starts, a study whose ``runs`` samples the disk under ``out`` cannot
    hold (:data:`BYTES_PER_SAMPLE` each and :data:`BYTES_PER_STUDY`)."""
    import shutil

    where = next(p for p in (out, *out.resolve().parents) if p.exists())
    free = shutil.disk_usage(where).free
    need = runs * BYTES_PER_SAMPLE + BYTES_PER_STUDY
    if need > free:
        fit = max(0, (free - BYTES_PER_STUDY) // BYTES_PER_SAMPLE)
        raise UsageError(f'--runs {runs}: about {need / 1e6:,.1f} MB of output ({BYTES_PER_SAMPLE / 1e3:g} kB a sample) '
                         f'and {free / 1e6:,.1f} MB free under {where}: at most {fit:,} samples fit (free space, or '
                         'choose another --out)')


def open_journal(out: Path, study: dict[str, Any], samples: dict[tuple[str, int], Any], resume: bool) -> Any:
    """The study's journal (``acds_runtime.journal``), new or resumed; a mismatch is a UsageError (one line)."""
    from acds_runtime.journal import Journal, JournalError, samples_hash, text_hash

    hashes = {key: text_hash(samples[key].text) for key in samples}
    study = {**study, 'samples_hash': samples_hash(hashes.values())}
    try:
        return Journal(out, study, hashes, resume=resume)
    except JournalError as exc:
        raise UsageError(str(exc)) from None


class _Stop(BaseException):
    """SIGTERM / SIGHUP during a study: stop as Ctrl-C does (every finished sample is already kept)."""


def run_journaled(journal: Any, samples: dict[tuple[str, int], Any], args: argparse.Namespace, steps_of: Any,
                  verb: str, task_of: Any = None, after: Any = None) -> Any:
    """Run the samples the journal lacks (one batch per run length, ``steps_of(key)``, and per task, ``task_of(key,
    steps)``: the sample's runner, default the engine's), appending each as it finishes, then calling ``after(key,
    summary)`` (which may stop the study by raising); the execution, or None when every sample was kept already.
    Ctrl-C, SIGTERM or SIGHUP: print how many samples are kept and the resume command, exit 128 + the signal's
    number (130, 143, 129: :class:`SystemExit`, the CLI's convention)."""
    import signal

    from acds_runtime.montecarlo import MonteCarloError, run_samples

    todo = [key for key in samples if key not in journal.done]
    if journal.done:
        print(f'[{verb}] resuming {journal.path.parent}: {len(journal.done)} of {len(samples)} samples kept, '
              f'{len(todo)} to run', file=sys.stderr, flush=True)

    def stop(signum: int, _frame: Any) -> None:
        raise _Stop(signal.Signals(signum).name, signum)
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGHUP)}
    execution = None
    try:
        batches: dict[tuple[int | None, Any], list[tuple[str, int]]] = {}
        for key in todo:
            steps = steps_of(key)
            batches.setdefault((steps, None if task_of is None else task_of(key, steps)), []).append(key)

        def done(key: tuple[str, int], summary: dict[str, Any]) -> None:
            journal.record(key, summary)
            if after is not None:
                after(key, summary)
        for (steps, task), keys in batches.items():
            execution = run_samples(_Texts(samples, keys), engine=args.engine, steps=steps, jobs=args.jobs,
                                    scheduler=args.scheduler, progress=not args.quiet, task=task,
                                    allow_mixed=args.allow_mixed_workers, keep=False,
                                    on_result=lambda i, summary, keys=keys: done(keys[i], summary))[1]
    except MonteCarloError as exc:
        raise UsageError(str(exc)) from None
    except BaseException as caught:
        exc = interruption(caught, (KeyboardInterrupt, _Stop))
        if exc is None:
            raise
        why = 'Ctrl-C' if isinstance(exc, KeyboardInterrupt) else exc.args[0]
        signum = exc.args[1] if isinstance(exc, _Stop) else getattr(exc, 'signum', signal.SIGINT)
        print(f'\n[{verb}] interrupted ({why}): {journal.kept()} of {len(samples)} samples kept in '
              f'{journal.path}; continue with:\n  {journal.study["command"]} --resume {journal.path.parent}',
              file=sys.stderr, flush=True)
        raise SystemExit(128 + signum) from None
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        journal.close()
    for note in execution.notes if execution is not None else ():
        print(f'[{verb}] {note}', file=sys.stderr)
    return execution


class _Texts(Sequence[str]):
    """The scenario texts of ``keys``' samples, read when asked (``run_samples`` asks for each as it sends it)."""

    def __init__(self, samples: Mapping[tuple[str, int], Any], keys: list[tuple[str, int]]) -> None:
        self.samples, self.keys = samples, keys

    def __getitem__(self, i: int) -> str:  # type: ignore[override]
        return self.samples[self.keys[i]].text

    def __len__(self) -> int:
        return len(self.keys)


def records_of(samples: Iterable[Any], summaries: Iterable[dict[str, Any]]) -> Iterator[dict[str, Any]]:
    """Per sample: index, name, drawn values, geometry at t0, run summary (``samples.json``), one at a time (the
    samples and summaries may be read from disk as they are asked for)."""
    return ({'index': s.index, 'name': s.name, 'drawn': s.drawn, 'geometry': s.geometry(), 'summary': summary}
            for s, summary in zip(samples, summaries, strict=True))


def rows_of(records: Iterable[dict[str, Any]]) -> Any:
    """The flat rows of ``records`` (``dispersion_report.Rows``: held as columns)."""
    from acds_runtime.dispersion_report import Rows, make_row

    rows = Rows()
    for r in records:
        rows.append(make_row(r['index'], r['name'], r['drawn'], r['geometry'], r['summary']))
    return rows


def _default_out(prefix: str, name: str, seed: int, runs: int) -> Path:
    """A new study folder under runs/, created exclusively (a study started in the same second gets its own)."""
    check_output_dir('output folder', workspace() / 'runs')
    return new_run_dir(f'{prefix}_{name}_s{seed}_n{runs}')


def mark_complete(out: Path, spec: dict[str, Any], complete: bool) -> None:
    """Write ``montecarlo.json`` saying whether the report phase finished: ``complete: false`` from its start until its
    last file is written, so a study interrupted there (Ctrl-C, a crash) says it is incomplete and ``pick-sample``
    refuses it."""
    from acds_runtime.dispersion_report import write_json

    write_json(out / 'montecarlo.json', {**spec, 'complete': complete})


def cmd_montecarlo(args: argparse.Namespace) -> int:
    """Draw, run (appending each sample to the journal), summarise (module doc)."""
    from acds_common.scenario import load_scenario
    from acds_runtime import dispersion_report as dr

    study = _study_summary()

    base = load_scenario(args.scenario)
    from ..fsw_study import cmd_fsw_study, flown_by_user
    if flown_by_user(args, base):
        return cmd_fsw_study(args, base)
    args.engine = args.engine or 'direct'
    out = study_folder('montecarlo', base.name, args)
    check_disk(out, args.runs)
    steps = _steps(base, args.until_min)
    rerun = rerun_command(args.scenario, args.seed, '{index}', args.vary, args.until_min)
    sampler, samples = draw_samples(base, args.seed, args.runs, args.vary, rerun, args.jobs)
    variables = [v.text for v in sampler.variables]
    run_length = _run_length(base, steps, samples)
    command = study_command(['montecarlo', args.scenario], args)
    from acds_runtime.montecarlo import kernel_build

    keyed = Keyed({'': samples})
    journal = open_journal(out, {'verb': 'montecarlo', 'scenario': base.name, 'seed': args.seed, 'runs': args.runs,
                                 'vary': args.vary, 'engine': args.engine, 'until_min': args.until_min,
                                 'steps': steps, 'kernels': kernel_build(), 'command': command},
                           keyed, bool(args.resume))
    print(f'[montecarlo] {base.name}: {args.runs} samples of seed {args.seed} ({"; ".join(variables)}), '
          f'{run_length}, engine {args.engine}; output {out}', file=sys.stderr, flush=True)
    if not study.applies(base):
        print(f'[montecarlo] note: {base.name} {study.STUDY_NOT_APPLICABLE}; samples.json keeps each run\'s whole '
              'summary', file=sys.stderr, flush=True)
    t0 = time.monotonic()
    kept = len(journal.done)
    execution = run_journaled(journal, keyed, args, lambda _key: steps, 'montecarlo')
    wall = time.monotonic() - t0

    def records() -> Iterator[dict[str, Any]]:  # read from disk, one sample at a time (twice: rows, samples.json)
        return records_of(samples, (journal.done[('', s.index)] for s in samples))
    rows = rows_of(records())
    stats = dr.percentiles(rows, args.seed, args.target_width or dr.TARGET_WIDTH_PCT)
    sens = dr.sensitivity(rows, list(dr.flatten(samples[0].drawn)))
    where = _execution_text(execution) if execution is not None else 'nothing left to run'
    if kept:
        where += f'; {kept} sample(s) kept from an interrupted session'
    spec = {'scenario': base.name, 'scenario_path': str(base.path.resolve()), 'seed': args.seed, 'runs': args.runs,
            'vary': variables, 'user_vary': args.vary, 'engine': args.engine, 'until_min': args.until_min,
            'steps': steps, 'run_length': run_length, 'execution': where,
            'wall_seconds': wall, 'command': command, 'rerun': rerun}
    mark_complete(out, spec, False)
    dr.write_rows(out, rows, records())
    dr.write_json(out / 'percentiles.json', stats)
    plots = dr.plot_distributions(out, rows, stats)
    failures = _not_captured(base, out, rows, samples)
    report = dr.write_report(out, spec, rows, stats, sens, plots, failures)
    mark_complete(out, spec, True)
    print(f'\n== {base.name}: {args.runs} samples (seed {args.seed}), {run_length}; '
          f'{where}; {wall:.0f} s wall ==')
    print(dr.percentile_table(stats))
    top = sens.get('acquisition_time_min', {})
    if top:
        print('rank correlation of acquisition time with: ' +
              ', '.join(f'{k} {v:+.2f}' for k, v in list(top.items())[:4]))
    if failures:
        print('\n' + '\n'.join(failures))
    failed = [r for r in rows if 'error' in r]
    for r in failed:
        print(f'[montecarlo] sample {r["index"]} failed: {r["error"].splitlines()[0]}', file=sys.stderr)
    print(f'[montecarlo] {report}; samples.csv, samples.json, percentiles.json, {len(plots)} PNG(s) in {out}',
          file=sys.stderr)
    return 1 if failed else 0


def _study_summary() -> Any:
    """The summary plug-in that gives the dispersion report's columns (:data:`acds_common.plugins.STUDY_ROW_ATTRIBUTE`);
    its ``STUDY_NOT_APPLICABLE`` says what stays empty for a scenario it does not apply to."""
    from acds_common.plugins import STUDY_ROW_ATTRIBUTE, SUMMARIES, modules
    return next(m for m in modules(SUMMARIES) if hasattr(m, STUDY_ROW_ATTRIBUTE))


def _not_captured(base: Scenario, out: Path, rows: Sequence[dict[str, Any]], samples: Sequence[Any]) -> list[str]:
    """The samples that did not reach capture, with their drawn conditions (where the study's summary applies; markdown)."""
    from acds_runtime import dispersion_report as dr

    if not _study_summary().applies(base):
        return []
    explain = f'./scripts/acds explain-sample {shlex.quote(str(out))} {{index}}'
    return dr.not_captured_lines(rows, list(dr.flatten(samples[0].drawn)), explain)


# ------------------------------------------------------------------------------------ pick-sample


def cmd_pick_sample(args: argparse.Namespace) -> int:
    """Apply the baseline rule to a Monte Carlo folder (module doc)."""
    from acds_common.scenario import load_scenario
    from acds_runtime.dispersion_report import pick_sample
    from acds_runtime.journal import journaled_study
    from acds_runtime.sampling import h_parallel_b_attitude

    folder = Path(args.folder)
    journaled = None if (folder / 'montecarlo.json').exists() else journaled_study(folder)
    if journaled and journaled[0].get('verb') == 'montecarlo':  # the journal read only when there is no report
        study, kept = journaled
        raise UsageError(f'{folder}: the study was interrupted with {kept} of {study.get("runs")} samples finished '
                         f'(no report yet); finish it with {study.get("command")} --resume {folder}')
    try:
        spec = json.loads((folder / 'montecarlo.json').read_text())
        records = json.loads((folder / 'samples.json').read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise UsageError(f'{folder}: not a montecarlo output folder ({exc})') from None
    if 'fsw_command' in spec:
        raise UsageError(f'{folder}: a study flown by your own node (--external); the baseline rule picks from a '
                         'dispersion study of the built-in nodes (its report.md names the samples that differ most)')
    if spec.get('complete') is False:
        raise UsageError(f'{folder}: the study is incomplete (its report phase was interrupted: montecarlo.json says '
                         f'complete: false); finish it with {spec["command"]} --resume {folder}')
    rows = rows_of(records)
    try:
        index, target = pick_sample(rows, args.quantity, args.percentile)
    except ValueError as exc:
        raise UsageError(f'{folder}: {exc}') from None
    record = next(r for r in records if r['index'] == index)
    base = load_scenario(spec['scenario_path'] if Path(spec['scenario_path']).exists() else spec['scenario'])
    sample = _draw(_sampler(base, spec['seed'], spec['user_vary']), index)
    if sample.drawn != record['drawn']:
        raise UsageError(f'{folder}: sample {index} drawn now differs from the study\'s (the scenario file '
                         f'{base.path} or the sampler changed since)')
    row = next(r for r in rows if r['index'] == index)
    print(f'rule: the sample whose {args.quantity} is nearest the {args.percentile:g}th percentile of its '
          f'distribution over {spec["runs"]} samples of seed {spec["seed"]} ({target:.1f})')
    print(f'chosen: sample {index} ({record["name"]}): ' + ', '.join(
        f'{k} {row[k]:.1f}' for k in ('time_magnetics_only_min', 'time_wheels_magnetics_min', 'acquisition_time_min',
                                      'orbit_dipole_inclination_deg', 'initial_h_b_angle_deg')
        if row.get(k) is not None))
    print(f'rerun through the graph: {spec["rerun"].replace("{index}", str(index))}')
    print('\n# --- the open conditions, for the scenario file ---')
    print(f'# Open conditions (seed 002 §4.3.1 leaves them open): sample {index} of `{spec["command"]}`,')
    print(f'# the sample whose {args.quantity} is nearest the {args.percentile:g}th percentile ({target:.1f} min) '
          'of that distribution')
    print('# (rule: a representative worst case, docs: Studies, "Choosing the baseline\'s open conditions").')
    by_section: dict[str, dict[str, Any]] = {}
    for label, value in sample.drawn.items():
        section, _, key = label.rpartition('.')
        by_section.setdefault(section, {})[key] = value
    for section, keys in by_section.items():
        if section:
            print(f'{section}:')
        for key, value in keys.items():
            print(f'{"  " if section else ""}{key}: {json.dumps(value)}')
    print('\n# Table 4-7 case 4 on the same geometry (H0 = I·ω0 along B at t0):')
    print(f'#   spacecraft.initial_quaternion_xyzw: {json.dumps(h_parallel_b_attitude(sample.scenario))}')
    return 0


# --------------------------------------------------------------------------------------- register


def add_execution_options(p: argparse.ArgumentParser) -> None:
    """--runs/--seed/--jobs/--scheduler/--engine shared by ``montecarlo`` and the paired ``sweep``."""
    from acds_runtime.montecarlo import ALLOW_MIXED_OPTION, ENGINES

    p.add_argument('--seed', type=_seed, default=1, help='study seed (default 1); sample K is the same for every N')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='run on this Dask cluster (tcp://host:8786) instead of a local one')
    p.add_argument(ALLOW_MIXED_OPTION, action='store_true',
                   help='accept Dask workers whose numeric configuration (Python, numpy and its SIMD dispatch, OpenBLAS, '
                        'kernel compiler, project sources) differs from this machine\'s; the report names them')
    p.add_argument('--engine', choices=ENGINES, default='direct',
                   help='direct (default: one process, bit-identical to the graph) or graph (one process per node)')
    p.add_argument('--resume', metavar='DIR',
                   help='continue the interrupted study in DIR (same scenario, seed and options): run only the samples '
                        'its journal (samples.jsonl) lacks')


def _seed(text: str) -> int:
    from acds_runtime.sampling import MAX_SEED

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a whole number, got {text!r}') from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f'must be in [0, {MAX_SEED}], got {text}')
    return value


def _width(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None
    if not 0.0 < value <= 1000.0:
        raise argparse.ArgumentTypeError(f'must be in (0, 1000] %, got {text}')
    return value


def _percent(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None
    if not 0.0 <= value <= 100.0:
        raise argparse.ArgumentTypeError(f'must be in [0, 100], got {text}')
    return value


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``montecarlo`` and ``pick-sample`` verbs."""
    p = sub.add_parser('montecarlo', help='Monte Carlo dispersion of a scenario\'s open conditions (percentiles, '
                                          'plots, report)',
                       description='Draw --runs samples of SCENARIO\'s open conditions (attitude uniform on SO(3), '
                                   'node RA, orbit phase, Greenwich angle uniform on [0, 360) deg; --vary adds or '
                                   'replaces draws), run each, and write samples.csv/json, percentiles.json, PNGs and '
                                   'report.md into --out. --jobs 1 runs here; more start a local Dask cluster.')
    p.add_argument('scenario', metavar='SCENARIO', help='scenario name or path')
    p.add_argument('--runs', type=positive_int, required=True, help='number of samples')
    p.add_argument('--jobs', '-j', type=positive_int, default=2,
                   help='local Dask workers (default 2; 1: in this process, no Dask)')
    add_execution_options(p)
    add_sample_options(p, run=False)
    p.add_argument('--until-min', type=positive_minutes,
                   help='run every sample for this sim time instead of the scenario\'s duration, minutes (longer or '
                        'shorter; it still stops at capture; a sample not captured by then is censored)')
    p.add_argument('--out', metavar='DIR', help='output folder (default runs/montecarlo_<scenario>_s<seed>_n<N>_<time>)')
    p.add_argument('--target-width', type=_width, default=None, metavar='PCT',
                   help='report the samples each percentile needs for a confidence interval this wide, %% of its value '
                        '(default 10)')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    from ..fsw_study import add_fsw_options
    add_fsw_options(p)
    p.set_defaults(func=cmd_montecarlo, engine=None)  # direct; a study flown by your node: the graph

    p = sub.add_parser('pick-sample', help='the baseline rule: the sample nearest a percentile of a Monte Carlo study',
                       description='From a montecarlo --out folder, print the sample whose QUANTITY is nearest its '
                                   'PERCENTILE, its rerun command and the scenario keys that set its conditions.')
    p.add_argument('folder', metavar='DIR', help='a montecarlo output folder')
    p.add_argument('--quantity', default=BASELINE_QUANTITY, help=f'row key (default {BASELINE_QUANTITY})')
    p.add_argument('--percentile', type=_percent, default=BASELINE_PERCENTILE,
                   help=f'percentile in [0, 100] (default {BASELINE_PERCENTILE:g}: a representative worst case)')
    p.set_defaults(func=cmd_pick_sample)
