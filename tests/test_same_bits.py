"""Same bits on every worker (docs/studies.md, "Running it on a cluster"): the SIMD pin where the environment's Python starts,
and the numeric configuration checked, not assumed.

Real processes the documented way: a ``dask scheduler`` and ``dask worker --nworkers 2 --nthreads 1`` started from the
environment's ``bin`` with an environment that does not carry the pin (as a user's shell); 20 samples of
``heao_b_acquisition`` (30 min each) compared digest by digest with the local study (on an AVX-512 host an unpinned
worker gives another digest for sample 0 there, for 3 of the 20 over the full runs); a worker whose SIMD dispatch
differs refused in one line when it joins during a study and before a study sends samples; a graph whose node
processes differ from their launcher failing before step 0, naming the node.
"""

from __future__ import annotations

import csv
import os
import platform
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from acds_common import SIMD_PIN
from acds_common.numeric_config import numeric_configuration

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
BASE = 'heao_b_acquisition'
#: Where a worker's numeric configuration is asked (the environment's Python, numpy imported FIRST).
ASK = ('import numpy, json; from acds_common.numeric_config import numeric_configuration as c; '
       'print(json.dumps(c()))')

pytestmark = pytest.mark.skipif(platform.machine() not in ('x86_64', 'AMD64'), reason='the SIMD pin is x86-64 only')


def _avx512() -> bool:
    with open('/proc/cpuinfo') as fh:
        return any(line.startswith('flags') and 'avx512f' in line.split() for line in fh)


#: A user's setting that makes numpy dispatch to other kernels than the pinned process on this host: none disabled on an
#: AVX-512 host (the unpinned worker of the filed study), else the AVX2 ones disabled too.
OTHER_SIMD = '' if _avx512() else 'X86_V3 X86_V4 AVX512_ICL AVX512_SPR'


def user_env(**extra: str) -> dict[str, str]:
    """A user's shell: this environment without the pin's two variables (which this test process holds)."""
    env = {k: v for k, v in os.environ.items() if k not in SIMD_PIN}
    env.update(extra)
    return env


def free_port() -> int:
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def start_worker(scheduler: str, log: Path, **env: str) -> subprocess.Popen[bytes]:
    """``dask worker SCHEDULER --nworkers 2 --nthreads 1`` on the loopback, as docs/studies.md starts one."""
    with open(log, 'wb') as out:
        return subprocess.Popen([str(BIN / 'dask'), 'worker', scheduler, '--nworkers', '2', '--nthreads', '1',
                                 '--host', '127.0.0.1', '--no-dashboard'], stdout=out, stderr=subprocess.STDOUT,
                                env=user_env(**env), cwd=ROOT)


def stop(*procs: subprocess.Popen[bytes]) -> None:
    """SIGTERM (Dask closes its workers), SIGKILL after 30 s."""
    for proc in procs:
        proc.terminate()
    for proc in procs:
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def wait_for_workers(scheduler: str, n: int) -> list[str]:
    """The addresses of the scheduler's workers once it has ``n`` (Dask's own wait, 60 s, failing loudly)."""
    from dask.distributed import Client

    with Client(scheduler, timeout='30s', set_as_default=False) as client:
        client.wait_for_workers(n, timeout=60)
        return sorted(client.scheduler_info()['workers'])


@pytest.fixture(scope='module')
def scheduler(tmp_path_factory) -> Iterator[str]:
    """A ``dask scheduler`` process with a ``dask worker`` process of two single-threaded workers."""
    logs = tmp_path_factory.mktemp('dask')
    address = f'tcp://127.0.0.1:{free_port()}'
    with open(logs / 'scheduler.log', 'wb') as out:
        sched = subprocess.Popen([str(BIN / 'dask'), 'scheduler', '--host', '127.0.0.1', '--port',
                                  address.rpartition(':')[2], '--no-dashboard'], stdout=out, stderr=subprocess.STDOUT,
                                 env=user_env(), cwd=ROOT)
    worker = start_worker(address, logs / 'worker.log')
    try:
        wait_for_workers(address, 2)
        yield address
    finally:
        stop(worker, sched)


def acds(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(ROOT / 'scripts' / 'acds'), *args], capture_output=True, text=True, cwd=ROOT,
                          env=user_env(), timeout=600, check=False)


def digests(out: Path) -> dict[str, str]:
    with open(out / 'samples.csv') as fh:
        return {row['index']: row['truth_digest'] for row in csv.DictReader(fh)}


def test_the_pin_is_in_force_where_the_environments_python_starts():
    """A program that imports numpy before anything of the project (as ``dask worker`` does) dispatches to the
    pinned kernels; a user's own setting of the variables still wins."""
    pinned = numeric_configuration()
    got = subprocess.run([sys.executable, '-c', ASK], capture_output=True, text=True, env=user_env(), check=True)
    import json
    config = json.loads(got.stdout)
    assert (config['simd'], config['openblas']) == (pinned['simd'], pinned['openblas'])
    assert config['pin'] == ' '.join(f'{k}={v!r}' for k, v in SIMD_PIN.items())
    own = subprocess.run([sys.executable, '-c', ASK], capture_output=True, text=True,
                         env=user_env(NPY_DISABLE_CPU_FEATURES=OTHER_SIMD), check=True)
    assert json.loads(own.stdout)['simd'] != pinned['simd']
    assert f'NPY_DISABLE_CPU_FEATURES={OTHER_SIMD!r}' in json.loads(own.stdout)['pin']


@pytest.mark.timeout(900)  # ~25 s on the idle 2-core machine; > 300 s beside four busy sessions (load 20)
def test_a_study_on_dask_workers_started_by_hand_gives_the_local_studys_digests(scheduler, tmp_path):
    """20 samples on the documented cluster and locally (``--jobs 2``), 30 min each (on this AVX-512 host an unpinned
    worker already differs in sample 0 there): the same digest for every sample and the same samples.csv, byte for
    byte."""
    study = ['montecarlo', BASE, '--runs', '20', '--until-min', '30', '--quiet']
    cluster = acds(*study, '--scheduler', scheduler, '--out', str(tmp_path / 'cluster'))
    assert cluster.returncode == 0, cluster.stderr
    assert 'MIXED' not in cluster.stdout
    local = acds(*study, '--jobs', '2', '--out', str(tmp_path / 'local'))
    assert local.returncode == 0, local.stderr
    here, there = digests(tmp_path / 'local'), digests(tmp_path / 'cluster')
    assert len(here) == 20
    assert {i: there[i] for i in here if there[i] != here[i]} == {}
    assert (tmp_path / 'cluster' / 'samples.csv').read_bytes() == (tmp_path / 'local' / 'samples.csv').read_bytes()


@pytest.mark.timeout(900)  # a Dask worker process started and three studies: 380 s beside four busy sessions
def test_a_worker_with_another_simd_dispatch_is_refused_in_one_line(scheduler, tmp_path):
    """A worker started with the user's own NPY_DISABLE_CPU_FEATURES. Joining during a study (after the check at its
    start), it is refused at its first sample, which it does not run; present when a study starts, the study refuses
    it before sending a sample, naming the worker, its host and the difference (exit 2, no sample kept);
    --allow-mixed-workers runs the study and its report's header names the worker."""
    from acds_common.scenario import load_scenario
    from acds_runtime.montecarlo import MonteCarloError, run_samples
    from acds_runtime.sampling import Sampler

    texts = [Sampler(load_scenario(BASE), 7).draw(i).text for i in range(40)]  # 20 s of work on 2 idle workers
    before = set(wait_for_workers(scheduler, 2))
    joined: list[subprocess.Popen[bytes]] = []

    def join_once(_i: int, _summary: dict) -> None:
        if not joined:
            joined.append(start_worker(scheduler, tmp_path / 'odd.log', NPY_DISABLE_CPU_FEATURES=OTHER_SIMD))
    try:
        with pytest.raises(MonteCarloError) as late:
            run_samples(texts, scheduler=scheduler, progress=False, on_result=join_once)
        odd = sorted(set(wait_for_workers(scheduler, 4)) - before)
        assert any(f'worker {w} on host {socket.gethostname()} differs from the client: numpy SIMD dispatch' in
                   str(late.value) for w in odd), str(late.value)

        study = ['montecarlo', BASE, '--runs', '2', '--until-min', '1', '--quiet', '--scheduler', scheduler]
        refused = acds(*study, '--out', str(tmp_path / 'refused'))
        assert refused.returncode == 2, refused.stderr
        line, = [ln for ln in refused.stderr.splitlines() if 'differs from the client' in ln]
        assert f'worker {odd[0]} on host {socket.gethostname()} differs from the client: numpy SIMD dispatch' in line
        assert f"NPY_DISABLE_CPU_FEATURES={OTHER_SIMD!r}" in line and '--allow-mixed-workers' in line
        assert not (tmp_path / 'refused' / 'samples.csv').exists()
        journal = tmp_path / 'refused' / 'samples.jsonl'
        assert not journal.exists() or len(journal.read_text().splitlines()) <= 1  # the study's line only

        accepted = acds(*study, '--allow-mixed-workers', '--out', str(tmp_path / 'accepted'))
        assert accepted.returncode == 0, accepted.stderr
        header = (tmp_path / 'accepted' / 'report.md').read_text()
        assert 'MIXED WORKERS accepted (--allow-mixed-workers)' in header and odd[0] in header
    finally:
        for proc in joined:
            stop(proc)


def test_a_node_process_with_another_simd_dispatch_fails_the_graph_before_step_0(monkeypatch):
    """The launcher hands its configuration to every node process; one whose dispatch differs (here: every node,
    given the user's own NPY_DISABLE_CPU_FEATURES the launcher's numpy did not load with) fails the run before
    step 0, naming the node and the difference."""
    from acds_common.scenario import load_scenario
    from acds_runtime.launcher import GraphRun, LaunchError

    monkeypatch.setenv('NPY_DISABLE_CPU_FEATURES', OTHER_SIMD)
    steps: list[int] = []
    with tempfile.TemporaryDirectory() as tmp, pytest.raises(LaunchError) as failed, \
            GraphRun(load_scenario(BASE), Path(tmp), steps=5, echo=lambda _line: None,
                     progress=lambda k, _n, _t: steps.append(k)) as graph:
        graph.wait()
    first = str(failed.value).splitlines()[0]
    assert 'died (exit code 2)' in first and "CONFIGURATION ERROR: numeric configuration on host" in first
    assert "differs from the launcher's: numpy SIMD dispatch" in first
    assert steps == []


def test_what_a_run_generates_under_pycache_is_not_a_project_source():
    """A fused loop a direct run composes (written under ``acds_runtime/__pycache__``) leaves the project-sources
    digest as it was: a launcher and its nodes agree whichever of them generated it first (was: a study's graph nodes
    refused to start once the study's own direct run had written a new one)."""
    import acds_runtime
    from acds_common import numeric_config

    before = numeric_config._sources_digest()
    generated = Path(acds_runtime.__file__).parent / '__pycache__' / 'fused_loops' / 'test_generated_probe.py'
    generated.parent.mkdir(parents=True, exist_ok=True)
    try:
        generated.write_text('# generated at run time\n')
        assert numeric_config._sources_digest() == before
    finally:
        generated.unlink()
