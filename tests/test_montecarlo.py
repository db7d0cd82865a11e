"""Monte Carlo dispersions (issue 11) on short runs: a sample's result is reproducible, the direct engine and the
graph agree on drawn samples, a 2-worker Dask cluster gives what one process gives, a killed worker loses
nothing, the CLI leaves its outputs and ``run --sample`` reruns a drawn sample, the paired sweep pairs its draws."""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from acds_common.scenario import load_scenario
from acds_runtime import dispersion_report as dr
from acds_runtime.montecarlo import HEARTBEAT_AT_CLOSE, closing_heartbeat, run_sample, run_samples
from acds_runtime.sampling import Sampler

ROOT = Path(__file__).resolve().parents[1]
BASE = 'heao_b_acquisition'
STEPS = 40


def _comparable(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k != 'wall_seconds'}


def run_acds(*args: str, timeout: float = 300, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    env = {'PATH': os.environ.get('PATH', '/usr/bin:/bin'),
           'ROS_LOG_DIR': '/tmp/acds_ros_log', 'HOME': os.environ.get('HOME', '/tmp')}
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=timeout, check=False)


@pytest.fixture(scope='module')
def texts() -> list[str]:
    sampler = Sampler(load_scenario(BASE), 5)
    return [sampler.draw(i).text for i in range(6)]


@pytest.fixture(scope='module')
def serial(texts) -> list[dict]:
    return run_samples(texts, steps=STEPS, jobs=1, progress=False)[0]


def test_the_same_sample_gives_the_same_result(serial):
    again = Sampler(load_scenario(BASE), 5).draw(2)
    assert _comparable(run_sample(again.text, 'direct', STEPS)) == _comparable(serial[2])
    assert len({s['truth_digest'] for s in serial}) == len(serial)  # the samples differ


def test_direct_engine_and_graph_agree_on_two_samples(texts, serial):
    for i in (0, 1):
        graph = run_sample(texts[i], 'graph', STEPS)
        assert 'error' not in graph, graph.get('error')
        assert _comparable(graph) == _comparable(serial[i]), f'sample {i}'


def test_a_two_worker_local_cluster_equals_one_process(texts, serial):
    got, execution = run_samples(texts, steps=STEPS, jobs=2, progress=False)
    assert (execution.where, execution.workers) == ('local cluster', 2)
    assert [_comparable(s) for s in got] == [_comparable(s) for s in serial]


def _profiler_on() -> bool:
    import dask
    return bool(dask.config.get('distributed.worker.profile.enabled'))


def test_the_local_cluster_workers_run_without_dasks_profiler():
    """Dask's profiler samples a worker's task thread every 10 ms for a dashboard the local cluster does not serve
    (~5 % of a sample's CPU): its workers run without it."""
    from acds_runtime.montecarlo import _connect

    client, cluster = _connect(2, None)
    try:
        assert list(client.run(_profiler_on).values()) == [False, False]
    finally:
        client.close()
        cluster.close()


def test_a_killed_worker_loses_no_sample(texts):
    """Kill one of two workers while it computes a sample (SIGKILL, as a lost host): the scheduler reruns its
    work elsewhere and the result set is complete, in order and identical to one process's — percentiles too."""
    from dask.distributed import Client, LocalCluster

    steps = 200
    reference = run_samples(texts, steps=steps, jobs=1, progress=False)[0]
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    killed: list[tuple[int, list]] = []

    def kill_a_busy_worker(_i: int, _summary: dict) -> None:
        if killed:
            return
        busy = [(w, keys) for w, keys in client.processing().items() if keys]
        if busy:
            address, keys = busy[0]
            pid = client.run(os.getpid, workers=[address])[address]
            os.kill(pid, signal.SIGKILL)
            killed.append((pid, list(keys)))

    try:
        with Client(cluster) as client:
            got, _ = run_samples(texts, steps=steps, scheduler=cluster.scheduler_address, progress=False,
                                 on_result=kill_a_busy_worker)
    finally:
        cluster.close()
    assert killed and killed[0][1], 'no worker was busy to kill'
    assert [_comparable(s) for s in got] == [_comparable(s) for s in reference]

    def stats(summaries):
        samples = [Sampler(load_scenario(BASE), 5).draw(i) for i in range(len(summaries))]
        return dr.percentiles([dr.make_row(s.index, s.scenario.name, s.drawn, s.geometry(), m)
                               for s, m in zip(samples, summaries, strict=True)], 5)
    assert stats(got) == stats(reference)


def test_cli_outputs_and_run_sample_reruns_the_drawn_scenario(tmp_path):
    out = tmp_path / 'mc'
    vary = 'spacecraft.initial_rates_deg_s=uniform(0.116, 0.12)'
    proc = run_acds('montecarlo', BASE, '--runs', '3', '--jobs', '1', '--until-min', '0.25', '--vary', vary,
                    '--out', str(out), '--quiet')
    assert proc.returncode == 0, proc.stderr
    assert 'time on magnetics only' in proc.stdout and 'p95' in proc.stdout
    assert 'HEAO mode manager' not in proc.stderr  # the note is for scenarios without one
    for name in ('samples.csv', 'samples.json', 'percentiles.json', 'report.md', 'montecarlo.json',
                 'acquisition_time_min.png', 'orbit_dipole_inclination_deg.png'):
        assert (out / name).is_file(), name
    pct = json.loads((out / 'percentiles.json').read_text())
    assert {f'p{p}' for p in dr.PERCENTILES} <= set(pct['acquisition_time_min'])
    assert pct['acquisition_time_min']['censored'] == 3  # 15 s runs: no capture, counted, not dropped
    records = json.loads((out / 'samples.json').read_text())
    assert [r['index'] for r in records] == [0, 1, 2]
    assert 'spacecraft.initial_rates_deg_s' in records[2]['drawn']
    report = (out / 'report.md').read_text()
    assert '## Percentiles' in report and '](acquisition_time_min.png)' in report and 'Spearman' in report
    assert len((out / 'samples.csv').read_text().strip().splitlines()) == 4

    run_dir = tmp_path / 'rerun'
    proc = run_acds('run', BASE, '--sample', '1:2', '--vary', vary, '--until-min', '0.25', '--run-dir', str(run_dir),
                    '--summary-json', str(tmp_path / 'rerun.json'), '--quiet')
    assert proc.returncode == 0, proc.stderr
    rerun = json.loads((tmp_path / 'rerun.json').read_text())
    assert rerun['truth_digest'] == records[2]['summary']['truth_digest']
    assert rerun['scenario'] == records[2]['name'] == 'heao_b_acquisition_s1k2'
    assert (run_dir / 'sample.yaml').read_text().startswith('# Monte Carlo sample 2 of seed 1')
    assert (run_dir / 'bag').is_dir()

    proc = run_acds('pick-sample', str(out))  # every acquisition censored: the rule cannot apply
    assert proc.returncode == 2 and 'censored' in proc.stderr
    proc = run_acds('pick-sample', str(out), '--quantity', 'peak_moment_am2', '--percentile', '50')
    assert proc.returncode == 0, proc.stderr
    assert 'raan_deg:' in proc.stdout and 'case 4' in proc.stdout


def test_pick_sample_finds_a_study_of_a_relative_scenario_path_from_another_folder(tmp_path):
    """montecarlo.json keeps the scenario file's absolute path: pick-sample, run from elsewhere, redraws the sample
    from the user's own file (was: the relative path, then 'no scenario named mine')."""
    (tmp_path / 'mine.yaml').write_text(f'extends: {BASE}\nname: mine\n')
    proc = run_acds('montecarlo', 'mine.yaml', '--runs', '2', '--jobs', '1', '--until-min', '0.25', '--out', 'mc',
                    '--quiet', cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert json.loads((tmp_path / 'mc' / 'montecarlo.json').read_text())['scenario_path'] == str(tmp_path / 'mine.yaml')
    proc = run_acds('pick-sample', str(tmp_path / 'mc'), '--quantity', 'peak_moment_am2', '--percentile', '50')
    assert proc.returncode == 0, proc.stderr
    assert 'mine_s1k' in proc.stdout, proc.stdout


def test_bad_vary_is_one_line():
    proc = run_acds('montecarlo', BASE, '--runs', '2', '--vary', 'orbit.raan_deg=gauss(0,1)')
    assert proc.returncode == 2 and "unknown distribution 'gauss'" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_paired_sweep_has_every_case_and_its_interval(tmp_path):
    """N = 8 draws, 30 s runs from rates just above the Mode 1B thresholds (case 11 keeps its own 0.5 deg/s):
    the time on magnetics only is reached in most cases; the acquisition is censored in all."""
    out = tmp_path / 'sweep'
    proc = run_acds('sweep', 'table-4-7', '--runs', '8', '--seed', '2', '--jobs', '1', '--until-min', '0.5', '--vary',
                    'spacecraft.initial_rates_deg_s=uniform(0.1151, 0.1154)', '--out', str(out), '--quiet')
    assert proc.returncode == 0, proc.stderr
    result = json.loads((out / 'sweep.json').read_text())
    from acds_cli.verbs.sweep import GROUPS
    assert [c['scenario'] for c in result['cases']] == GROUPS['table-4-7']
    for case in result['cases']:
        assert case['n'] == 8 and case['scenario'] in proc.stdout
        for q in case['quantities'].values():
            assert len(q['ratio_ci90']) == 2 and q['pairs'] + q['pairs_dropped'] == 8
    mag = {c['scenario']: c['quantities']['time_magnetics_only_min'] for c in result['cases']}
    assert mag['heao_b_acquisition']['ratio_median'] == 1.0
    finite = [q for q in mag.values() if None not in q['ratio_ci90']]
    assert len(finite) >= 6
    for q in finite:
        assert q['ratio_ci90'][0] <= q['ratio_median'] <= q['ratio_ci90'][1]
    assert mag['heao_b_case11']['censored'] == 8  # 0.5 deg/s: no Mode 1B in 30 s
    assert mag['heao_b_case6']['median'] == 0.0  # wheels on from separation
    records = json.loads((out / 'samples.json').read_text())
    raan = {}
    for r in records:  # common random numbers: sample i is the same draw in every case
        raan.setdefault(r['index'], set()).add(r['drawn']['orbit.raan_deg'])
        if r['case'] == 'heao_b_case4':
            assert r['geometry']['initial_h_b_angle_deg'] < 1e-5
    assert all(len(v) == 1 for v in raan.values()) and len(raan) == 8


STUDY = ['montecarlo', BASE, '--runs', '6', '--jobs', '1', '--until-min', '5', '--quiet']


@pytest.fixture(scope='module')
def clean_study(tmp_path_factory) -> Path:
    """One uninterrupted study: what an interrupted and resumed one must give."""
    out = tmp_path_factory.mktemp('clean') / 'mc'
    proc = run_acds(*STUDY, '--out', str(out))
    assert proc.returncode == 0, proc.stderr
    return out


def _journal_lines(out: Path) -> int:
    try:
        return (out / 'samples.jsonl').read_bytes().count(b'\n') - 1
    except FileNotFoundError:
        return 0


def _interrupt_study(out: Path, sig: int, after: int) -> tuple[subprocess.Popen[str], str]:
    """Start the study into ``out``, send ``sig`` once ``after`` samples are kept; the process and its stderr."""
    import time

    env = {'PATH': os.environ.get('PATH', '/usr/bin:/bin'),
           'ROS_LOG_DIR': '/tmp/acds_ros_log', 'HOME': os.environ.get('HOME', '/tmp')}
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', *STUDY, '--out', str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while _journal_lines(out) < after and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)  # polling the journal on disk, not synchronising
    assert proc.poll() is None, f'the study ended before it could be interrupted: {proc.stderr.read()[-2000:]}'
    os.kill(proc.pid, sig)
    _, err = proc.communicate(timeout=120)
    return proc, err


@pytest.mark.slow
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGKILL], ids=['ctrl-c', 'sigkill'])
def test_an_interrupted_study_resumes_to_the_clean_result(tmp_path, clean_study, sig):
    """Interrupt the study once two samples are kept; ``--resume`` runs only the rest, and samples.csv and
    percentiles.json are byte for byte those of the uninterrupted study."""
    out = tmp_path / 'mc'
    proc, err = _interrupt_study(out, sig, 2)
    kept = _journal_lines(out)
    assert 2 <= kept < 6
    if sig == signal.SIGINT:
        assert proc.returncode == 130
        assert f'{kept} of 6 samples kept' in err and f'--resume {out}' in err, err
    assert not (out / 'samples.csv').exists()
    journal = (out / 'samples.jsonl').read_bytes()
    pick = run_acds('pick-sample', str(out))  # the baseline rule asked of the unfinished study: how to finish it
    assert pick.returncode == 2 and len(pick.stderr.strip().splitlines()) == 1, pick.stderr
    assert f'interrupted with {kept} of 6 samples finished' in pick.stderr and f' --resume {out}' in pick.stderr
    assert (out / 'samples.jsonl').read_bytes() == journal  # read, never cut
    resumed = run_acds(*STUDY, '--resume', str(out))
    assert resumed.returncode == 0, resumed.stderr
    assert f'resuming {out}: {kept} of 6 samples kept, {6 - kept} to run' in resumed.stderr
    for name in ('samples.csv', 'percentiles.json'):
        assert (out / name).read_bytes() == (clean_study / name).read_bytes(), name
    assert _journal_lines(out) == 6


def test_a_resume_with_another_run_length_names_the_option(clean_study):
    """--until-min is what the user changed: the refusal names it, not the step count it implies."""
    proc = run_acds(*STUDY[:-3], '--until-min', '4', '--quiet', '--resume', str(clean_study))
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f'acds montecarlo: error: --resume {clean_study}: the study there has until_min 5.0, this command 4.0']


def test_a_resume_with_another_seed_is_refused(clean_study):
    proc = run_acds(*STUDY, '--seed', '2', '--resume', str(clean_study))
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f'acds montecarlo: error: --resume {clean_study}: the study there has seed 1, this command 2']


def test_a_local_worker_drops_only_its_heartbeat_error_as_the_scheduler_closes():
    """The message is the pinned Dask worker's own words; any other worker error still reaches the terminal."""
    import inspect

    import distributed.worker

    assert f'"{HEARTBEAT_AT_CLOSE}.' in inspect.getsource(distributed.worker)

    def record(msg: str) -> logging.LogRecord:
        return logging.LogRecord('distributed.worker', logging.ERROR, __file__, 1, msg, (), None)

    assert not closing_heartbeat(record(HEARTBEAT_AT_CLOSE + '.'))
    assert closing_heartbeat(record('Compute Failed'))
    assert closing_heartbeat(record('Failed to communicate with scheduler'))


@pytest.mark.slow
def test_ctrl_c_on_a_local_cluster_prints_no_worker_traceback(tmp_path):
    """Ctrl-C in a terminal reaches the whole foreground process group, the local cluster's worker processes
    too: the study stops with its one message and exit 130, and no worker prints a KeyboardInterrupt traceback."""
    import time

    out = tmp_path / 'mc'
    env = {'PATH': os.environ.get('PATH', '/usr/bin:/bin'),
           'ROS_LOG_DIR': '/tmp/acds_ros_log', 'HOME': os.environ.get('HOME', '/tmp')}
    proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'montecarlo', 'heao_b_acquisition_short', '--runs', '40',
                             '--jobs', '2', '--quiet', '--out', str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 300
    while _journal_lines(out) < 2 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)  # polling the journal on disk, not synchronising
    assert proc.poll() is None, f'the study ended before it could be interrupted: {proc.stderr.read()[-2000:]}'
    os.killpg(proc.pid, signal.SIGINT)  # what the terminal does on Ctrl-C: the whole process group
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert 'Traceback' not in err and 'KeyboardInterrupt' not in err, err
    assert f'--resume {out}' in err, err


@pytest.mark.slow
@pytest.mark.parametrize('sig', [signal.SIGTERM, signal.SIGHUP], ids=['sigterm', 'sighup'])
def test_a_study_stopped_by_a_signal_exits_128_plus_its_number(tmp_path, sig):
    """The CLI's convention (acds_cli.__main__, and ``run``): 143 for SIGTERM, 129 for SIGHUP, not Ctrl-C's 130."""
    out = tmp_path / 'mc'
    proc, err = _interrupt_study(out, sig, 1)
    assert proc.returncode == 128 + sig, err
    assert f'interrupted ({signal.Signals(sig).name})' in err and f'--resume {out}' in err, err


def test_a_resume_with_another_engine_is_refused(clean_study):
    proc = run_acds(*STUDY, '--engine', 'graph', '--resume', str(clean_study))
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f'acds montecarlo: error: --resume {clean_study}: the study there has engine "direct", this command "graph"']


def test_a_resume_on_another_build_of_the_kernels_names_it(clean_study, tmp_path):
    """A journal whose study ran on another numba (or other model sources) is refused in one line naming both."""
    import shutil

    out = tmp_path / 'mc'
    shutil.copytree(clean_study, out)
    journal = out / 'samples.jsonl'
    head, *rest = journal.read_text().splitlines(keepends=True)
    study = json.loads(head)
    ours = study['study']['kernels']
    study['study']['kernels'] = ours.replace('numba ', 'numba 0.0.0-', 1)
    journal.write_text(json.dumps(study) + '\n' + ''.join(rest[:2]))
    proc = run_acds(*STUDY, '--resume', str(out))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and 'the study there has kernels "numba 0.0.0-' in lines[0] and f'this command "{ours}"' in lines[0]


def test_runs_beyond_what_the_disk_holds_are_refused_before_anything_starts(tmp_path):
    out = tmp_path / 'mc'
    proc = run_acds('montecarlo', BASE, '--runs', str(10 ** 15), '--quiet', '--out', str(out))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and 'samples fit' in lines[0]
    assert lines[0].startswith(f'acds montecarlo: error: --runs {10 ** 15}: about ')
    assert not out.exists()


def test_the_report_lists_the_samples_not_captured_and_explain_sample_says_why(clean_study, tmp_path):
    """Five minutes are too short for any capture: every sample is listed (with its drawn conditions), and
    explain-sample replays one (direct engine: the same bits) into its folder, finds the study's truth digest and
    says which mode it stayed in, its wheels and its field geometry."""
    report = (clean_study / 'report.md').read_text()
    assert '## Samples not captured' in report
    assert '6 of 6 samples did not reach acquisition capture' in report and 'Wilson interval' in report
    assert all(f'\n| {k} | ' in report for k in range(6))
    run_dir = tmp_path / 'explain'
    proc = run_acds('explain-sample', str(clean_study), '2', '--engine', 'direct', '--run-dir', str(run_dir))
    assert proc.returncode == 0, proc.stderr
    assert 'the same truth digest as the study\'s sample 2' in proc.stdout
    assert 'it never left Mode 1A' in proc.stdout and 'Field geometry: the orbit was' in proc.stdout
    assert (run_dir / 'explanation.md').exists() and (run_dir / 'bag').is_dir()
    assert any((run_dir / 'plots').glob('mode_timeline.*'))
    bad = run_acds('explain-sample', str(clean_study), '6', '--engine', 'direct')
    assert bad.returncode == 2 and bad.stderr.strip().splitlines()[-1].endswith('has samples 0…5')


def test_a_sample_journaled_twice_counts_once(clean_study, tmp_path):
    """A worker lost after its result was journaled and rescheduled can only add a second line of the same sample
    (the same bits): a resume keeps the first and the table is the clean study's, byte for byte."""
    import shutil

    out = tmp_path / 'mc'
    shutil.copytree(clean_study, out)
    for name in ('samples.csv', 'percentiles.json'):
        (out / name).unlink()
    journal = out / 'samples.jsonl'
    lines = journal.read_text().splitlines(keepends=True)
    journal.write_text(''.join([*lines, lines[3], lines[1 + 4]]))
    proc = run_acds(*STUDY, '--resume', str(out))
    assert proc.returncode == 0, proc.stderr
    assert 'resuming' in proc.stderr and '6 of 6 samples kept, 0 to run' in proc.stderr
    for name in ('samples.csv', 'percentiles.json'):
        assert (out / name).read_bytes() == (clean_study / name).read_bytes(), name


#: Samples run before the study's memory is traced (its modules, kernels and caches loaded; its process's RSS reaches
#: its plateau after ~300), and samples traced.
WARM, SPAN = 200, 500

_GROWTH = f'''import gc, runpy, sys, tracemalloc
import acds_runtime.montecarlo as m
run_sample, done = m.run_sample, [0]
def counted(*args, **kwargs):
    out = run_sample(*args, **kwargs)
    done[0] += 1
    if done[0] in ({WARM}, {WARM + SPAN}):
        gc.collect()
        if done[0] == {WARM}:
            tracemalloc.start()
        else:
            print('grown_B', tracemalloc.get_traced_memory()[0], file=sys.stderr)
            tracemalloc.stop()
    return out
m.run_sample = counted
sys.argv = ['acds', *sys.argv[1:]]
runpy.run_module('acds_cli', run_name='__main__')
'''


@pytest.mark.slow
@pytest.mark.duration(30)
def test_a_studys_memory_does_not_grow_with_its_samples(tmp_path):
    """What a study (--jobs 1, in this process) still holds after 500 samples that it did not hold before them, the
    first 200 run (Python's allocations, traced): the journal's index of the samples done (~124 B a sample: resume
    needs it) and nothing of a sample's own. Measured 257 B a sample. Holding the samples, their summaries and row
    dicts, as the study once did, grew it by ~9 kB a sample; the fused loop's observer check, remembered by each
    sample's codec layout object (``id``), by ~2 kB (peak RSS +16 MB over 1,350 samples). Peak RSS itself varies by
    up to 10 MB between two runs of the same study (the allocator's), too much to see either."""
    env = {'PATH': os.environ.get('PATH', '/usr/bin:/bin'), 'ROS_LOG_DIR': '/tmp/acds_ros_log',
           'HOME': os.environ.get('HOME', '/tmp')}
    out = tmp_path / 'mc'
    proc = subprocess.run([sys.executable, '-c', _GROWTH, 'montecarlo', BASE, '--runs', str(WARM + SPAN), '--jobs', '1',
                           '--until-min', '0.05', '--quiet', '--out', str(out)],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=900, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (out / 'samples.csv').read_text().count('\n') == WARM + SPAN + 1
    grown = int(proc.stderr.rsplit('grown_B', 1)[1].split()[0])
    assert grown < 512 * SPAN, f'the study holds {grown} B more after {SPAN} samples ({grown / SPAN:.0f} B a sample)'
