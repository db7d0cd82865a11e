"""Monte Carlo dispersions: run drawn samples on the direct engine or the graph, here or on Dask (issue 11).

One task per sample (:func:`run_sample`): its scenario as YAML text in, its run summary out —
nothing else crosses the wire, so a Dask worker needs only the project set up on its host
(``./scripts/acds setup``, the worker started from that ``.venv``). Results are kept by sample
index, so the set is complete and in order whatever ran where. A worker that dies mid-task has its
tasks rescheduled by the Dask scheduler on the workers left (up to
``distributed.scheduler.allowed-failures`` times, default 3; past that the sample is reported
failed, never dropped); a sample's run is deterministic (lockstep, seeded), so a retried sample
gives the result a single machine gives.

Every worker's numeric configuration (:mod:`acds_common.numeric_config`: Python, numpy and its SIMD dispatch,
OpenBLAS, the kernel compiler, the project's sources) is the client's, checked before samples are sent
(:func:`_check_workers`) and by each sample's task (:func:`run_checked_sample`, for a worker that joins later): a
worker that differs is refused in one line (:func:`refusal`), or accepted with ``allow_mixed`` and named in the
execution's notes, which the report's header carries.

``jobs=1`` without a scheduler runs the samples one after the other in this process (no Dask);
``jobs>1`` starts a ``LocalCluster`` of that many single-threaded worker processes; ``scheduler``
("tcp://host:8786") uses the user's cluster (``dask scheduler`` / ``dask worker``; docs: Studies).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .sampling import scenario_from_text

#: The engines a sample can run on: the direct engine (one process, bit-identical) or the per-process graph.
ENGINES = ('direct', 'graph')


class MonteCarloError(RuntimeError):
    """The samples cannot be run (cluster unreachable, a worker without the project); the message says which."""


def run_sample(text: str, engine: str = 'direct', steps: int | None = None) -> dict[str, Any]:
    """The task: run one sample's scenario (YAML text) for ``steps`` (default: its duration, or to
    capture) and return its run summary; a failed run (a diverging sample, a node that fails) returns
    ``{'scenario', 'error'}`` on every engine, so one sample never takes the study's others with it."""
    from .launcher import GraphRun, LaunchError

    scenario = scenario_from_text(text)
    try:
        if engine == 'direct':
            from .direct import DirectRun
            return DirectRun(scenario, steps=steps).run().summary
        if engine != 'graph':
            raise MonteCarloError(f'unknown engine {engine!r} (engines: {", ".join(ENGINES)})')
        with sample_folder() as tmp, GraphRun(scenario, tmp, steps=steps, echo=lambda _line: None) as graph:
            return graph.wait().summary
    except LaunchError as exc:
        return {'scenario': scenario.name, 'error': str(exc)}


#: Prefix of a graph sample's temporary run folder (in the temporary directory, ``TMPDIR``).
SAMPLE_DIR_PREFIX = 'acds_mc_'
#: The lock file a live sample holds (``flock``) in its folder: a folder whose lock nobody holds is a zombie.
_SAMPLE_LOCK = '.owner'


@contextlib.contextmanager
def sample_folder() -> Iterator[Path]:
    """A graph sample's run folder, locked while its process lives, removed when the sample ends."""
    import fcntl

    folder = Path(tempfile.mkdtemp(prefix=SAMPLE_DIR_PREFIX))
    try:
        with open(folder / _SAMPLE_LOCK, 'w') as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def clean_zombies(before: set[str] | None = None) -> tuple[list[str], list[Path]]:
    """Remove what graph samples of a study that was killed (its process, or a Dask worker) left: Fast DDS
    segments and ports in /dev/shm nobody holds (:func:`acds_runtime.shm.clean_run`: zombies only, among the
    entries not in ``before``, default every entry) and sample folders whose lock nobody holds (and not
    created in the last :data:`acds_runtime.shm.MIN_AGE_S`). Returns both lists."""
    from . import shm

    removed = shm.clean_run(set() if before is None else before)
    folders = []
    for folder in Path(tempfile.gettempdir()).glob(f'{SAMPLE_DIR_PREFIX}*'):
        lock = folder / _SAMPLE_LOCK
        try:
            young = time.time() - (lock if lock.exists() else folder).stat().st_mtime < shm.MIN_AGE_S
        except OSError:
            continue
        if folder.is_dir() and not young and not (lock.exists() and shm.lock_held(lock, probe=True)):
            shutil.rmtree(folder, ignore_errors=True)
            folders.append(folder)
    return removed, folders


def worker_configuration(dask_worker: Any = None) -> dict[str, str]:
    """This Dask worker's numeric configuration (:func:`acds_common.numeric_config.numeric_configuration`) and its
    address (``worker``); ``dask_worker``: the worker ``Client.run`` passes, else the one running this task."""
    from acds_common.numeric_config import numeric_configuration
    from dask.distributed import get_worker
    return {**numeric_configuration(), 'worker': (dask_worker or get_worker()).address}


def mixed_worker(config: dict[str, str], expected: dict[str, str]) -> tuple[str, str] | None:
    """How a worker's ``config`` differs from the client's ``expected``: (the worker and its host, the differences),
    or None when they agree."""
    from acds_common.numeric_config import differences

    diff = differences(expected, config, 'the client')
    return (f'worker {config["worker"]} on host {config["host"]}', '; '.join(diff)) if diff else None


def run_checked_sample(task: Callable[[str], dict[str, Any]], text: str, expected: dict[str, str], allow_mixed: bool
                       ) -> tuple[dict[str, Any] | None, tuple[str, str] | None]:
    """A Dask worker's task: (``task(text)``, the sample's summary, None) on a worker whose numeric configuration
    is the client's ``expected``; on another (:func:`mixed_worker`), (None, how it differs) without running the
    sample, or with ``allow_mixed`` (the summary, how it differs). Every worker is checked before the study sends
    samples (:func:`_check_workers`); this covers a worker that joined after that."""
    mixed = mixed_worker(worker_configuration(), expected)
    if mixed is not None and not allow_mixed:
        return None, mixed
    return task(text), mixed


#: What the user passes to accept workers whose numeric configuration differs from the client's.
ALLOW_MIXED_OPTION = '--allow-mixed-workers'


def refusal(mixed: tuple[str, str]) -> str:
    """The study's one line refusing a mixed worker (:func:`mixed_worker`)."""
    who, diff = mixed
    return (f'{who} differs from the client: {diff}; refused, its samples could differ in the last bits (start the '
            f'worker from the project\'s .venv, set up as here, or pass {ALLOW_MIXED_OPTION} to accept it)')


def kernel_build() -> str:
    """The build the samples' numbers come from, in one line: the compiler (numba, llvmlite), numpy, and one hash
    over the sources of the models and kernels (every node package, entry point ``acds.nodes``, and acds_common).
    A study resumed on another build would mix two arithmetics in one table, so the journal keeps it and a resume
    compares it (:mod:`acds_runtime.journal`)."""
    import importlib.util
    from importlib.metadata import entry_points, version

    packages = sorted({ep.value.split(':')[0].split('.')[0] for ep in entry_points(group='acds.nodes')} | {'acds_common'})
    h = hashlib.sha256()
    for name in packages:
        spec = importlib.util.find_spec(name)
        for root in spec.submodule_search_locations or () if spec else ():
            for path in sorted(Path(root).rglob('*.py')):
                h.update(f'{name}/{path.relative_to(root)}\0'.encode())
                h.update(path.read_bytes())
    return (f'numba {version("numba")}, llvmlite {version("llvmlite")}, numpy {version("numpy")}, '
            f'model sources {h.hexdigest()[:12]}')


def task_key(text: str, engine: str, steps: int | None) -> str:
    """The Dask key of a sample's task: the same inputs give the same key (and so the same result)."""
    return 'acds-sample-' + hashlib.sha256(f'{engine}\0{steps}\0{text}'.encode()).hexdigest()[:24]


@dataclass
class Execution:
    """Where the samples ran: ``where`` ('in-process', 'local cluster', or the scheduler), worker count, and the
    workers accepted with another numeric configuration (``allow_mixed``): {how they differ: [worker on host]}."""

    where: str
    workers: int
    threads: int
    mixed_workers: dict[str, list[str]] = field(default_factory=dict)

    @property
    def notes(self) -> list[str]:
        """One line per difference among the accepted mixed workers, naming them."""
        return [f'accepted ({ALLOW_MIXED_OPTION}): {", ".join(who)} differ(s) from the client: {diff}'
                for diff, who in self.mixed_workers.items()]

    def mixed(self) -> str:
        """What a report's header adds for the mixed workers the user accepted: '' when there were none."""
        return ''.join(f'; MIXED WORKERS {note}' for note in self.notes)


def run_samples(texts: Sequence[str], *, engine: str = 'direct', steps: int | None = None, jobs: int = 1,
                scheduler: str | None = None, progress: bool = True,
                on_result: Callable[[int, dict[str, Any]], None] | None = None,
                task: Callable[[str], dict[str, Any]] | None = None, allow_mixed: bool = False, keep: bool = True
                ) -> tuple[list[dict[str, Any]], Execution]:
    """Run every sample; its summaries in the order of ``texts`` (none with ``keep=False``: a study that journals
    each as ``on_result`` gets it holds none of them), and where they ran.

    ``texts`` may be read lazily (a sequence whose items are read from disk when asked): each is asked for when its
    sample is sent, and at most :data:`IN_FLIGHT_PER_WORKER` samples per worker are sent ahead of the results, so
    neither this process nor the scheduler holds every sample's text.

    ``task(text)`` runs one sample (default :func:`run_sample` on ``engine`` for ``steps``; a flight-software
    study's, :func:`acds_runtime.flight_software.run_fsw_sample`, picklable for the Dask workers).

    ``on_result(i, summary)`` is called as each sample finishes (``i`` its position in ``texts``), in the
    order they finish. A Dask worker whose numeric configuration differs from this process's is refused
    (:class:`MonteCarloError`, one line) before any of its results is passed on, or with ``allow_mixed`` accepted
    and named in the execution's notes. On the graph engine, what killed studies left behind is removed first
    (:func:`clean_zombies`) and what this one's runs leave (an interrupted one too) at its end.
    """
    if engine not in ENGINES:
        raise MonteCarloError(f'unknown engine {engine!r} (engines: {", ".join(ENGINES)})')
    from tqdm import tqdm

    from . import shm

    before = None
    if engine == 'graph':
        clean_zombies()
        before = shm.snapshot()
    tty = sys.stderr.isatty()
    bar = tqdm(total=len(texts), desc='[montecarlo] samples', unit='run', file=sys.stderr, disable=not progress,
               mininterval=0.5 if tty else 10.0, ascii=not tty, dynamic_ncols=tty)
    try:
        if scheduler is None and jobs == 1:
            results = []
            for i in range(len(texts)):
                summary = run_sample(texts[i], engine, steps) if task is None else task(texts[i])
                if keep:
                    results.append(summary)
                bar.update(1)
                if on_result is not None:
                    on_result(i, summary)
            return results, Execution('in-process', 1, 1)
        return _run_dask(texts, engine, steps, jobs, scheduler, bar, on_result, task, allow_mixed, keep)
    finally:
        bar.close()
        if before is not None:  # the zombies of runs this study's end interrupted (live or young ones: next start)
            clean_zombies(before)


#: The resource tracker's report of the semaphores it unlinks after its parent died (-W syntax).
TRACKER_REPORT = 'ignore:resource_tracker:UserWarning:multiprocessing.resource_tracker'


def quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker without its report of "leaked semaphore objects" (issue 18 item 8).

    A local cluster's nannies hand each worker process two multiprocessing queues (three named
    semaphores each), which the tracker, shared by this process and its workers, unlinks when this
    process is SIGKILLed: nothing is left in /dev/shm, but it printed "There appear to be 12 leaked
    semaphore objects" (two workers) over the user's terminal. The tracker takes its warning filters
    from this interpreter's ``-W`` options when it starts, so the filter is added first; a tracker
    already running is left as it is.
    """
    from multiprocessing import resource_tracker

    if TRACKER_REPORT not in sys.warnoptions:
        sys.warnoptions.append(TRACKER_REPORT)
    resource_tracker.ensure_running()


#: What a local cluster's worker logs, with a traceback, when its heartbeat meets the scheduler closing: the study's
#: own end (the scheduler lives in the study's process), never news for the user.
HEARTBEAT_AT_CLOSE = 'Failed to communicate with scheduler during heartbeat'


def closing_heartbeat(record: Any) -> bool:
    """A ``logging`` filter of a local cluster's worker: False for :data:`HEARTBEAT_AT_CLOSE`, True for the rest."""
    return not str(record.msg).startswith(HEARTBEAT_AT_CLOSE)


def dask_setup(_worker: Any) -> None:
    """A local cluster's worker process (this module is its Dask preload) ignores SIGINT and does not report the
    scheduler closing at the study's end.

    The workers are in the terminal's foreground process group, so Ctrl-C reaches them as well as this
    process; each printed a KeyboardInterrupt traceback over the study's one-line message. The study
    stops them itself (it closes the cluster), as on SIGTERM. They start with SIGINT blocked
    (:func:`_connect`), so a Ctrl-C while they import is held, then discarded here; SIGINT is unblocked
    for the threads this one starts (a graph sample's nodes set their own handler and are stopped by it).
    A worker whose heartbeat was under way as the study closed the cluster printed a 30-line CommClosedError
    traceback after the study's report (seen on a loaded machine, ``montecarlo --jobs 2``): its logger drops
    that one message (:func:`closing_heartbeat`); a sample's own failure reaches the study as its result.
    """
    import logging
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    logging.getLogger('distributed.worker').addFilter(closing_heartbeat)


def _connect(jobs: int, scheduler: str | None) -> tuple[Any, Any]:
    """(client, cluster or None) for a local cluster of ``jobs`` workers or the user's ``scheduler``."""
    import logging

    import dask
    from dask.distributed import Client, LocalCluster

    if scheduler is None:
        import signal

        quiet_resource_tracker()
        # The cluster's event-loop thread, and so every worker process it starts (a restarted one too), has
        # SIGINT blocked until the worker's preload (dask_setup) ignores it; here a Ctrl-C meanwhile is held
        # and raised when the mask is restored, after which the cluster is closed.
        cluster = client = None
        try:
            blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            try:
                # Dask's statistical profiler samples each worker's task thread every 10 ms for a dashboard this
                # cluster does not serve: ~5 % of a sample's CPU (30 case-1 samples: 84.6-88.3 CPU s without it,
                # 89.6-91.6 with). The workers take the configuration their nannies are created with.
                with dask.config.set({'distributed.worker.profile.enabled': False}):
                    cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                           dashboard_address=None, silence_logs=logging.ERROR, preload=[__name__])
                client = Client(cluster, set_as_default=False)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
        except BaseException:
            if client is not None:
                client.close()
            if cluster is not None:
                cluster.close()
            raise
        return client, cluster
    try:
        client = Client(scheduler, timeout='20s', set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise MonteCarloError(f'--scheduler {scheduler}: cannot reach the Dask scheduler ({exc})') from None
    try:
        client.wait_for_workers(1, timeout=60)
    except TimeoutError:
        client.close()
        raise MonteCarloError(f'--scheduler {scheduler}: no worker joined within 60 s (start `dask worker '
                              f'{scheduler}` on hosts with the project set up)') from None
    return client, None


def _check_workers(client: Any, expected: dict[str, str], allow_mixed: bool, accepted: dict[str, list[str]]) -> None:
    """Every worker can import the project and has the client's numeric configuration ``expected``; one that
    differs is refused (:func:`_mixed`)."""
    try:
        configs = client.run(worker_configuration)
    except Exception as exc:  # noqa: BLE001 (whatever a worker raises, the message is the report)
        raise MonteCarloError(f'a Dask worker cannot run samples ({type(exc).__name__}: {exc}); every worker host '
                              'needs the project set up (./scripts/acds setup) and the worker started from its '
                              '.venv') from None
    for _address, config in sorted(configs.items()):
        _mixed(mixed_worker(config, expected), allow_mixed, accepted)


def _mixed(mixed: tuple[str, str] | None, allow_mixed: bool, accepted: dict[str, list[str]]) -> None:
    """Refuse a mixed worker (:class:`MonteCarloError`, :func:`refusal`), or with ``allow_mixed`` add it to
    ``accepted`` (:attr:`Execution.mixed_workers`)."""
    if mixed is None:
        return
    if not allow_mixed:
        raise MonteCarloError(refusal(mixed))
    who, diff = mixed
    if who not in accepted.setdefault(diff, []):
        accepted[diff].append(who)


#: Samples sent to the cluster ahead of the results, per worker thread: enough that no worker waits for its next
#: sample while this process journals a result, few enough that the texts in flight stay a few kB.
IN_FLIGHT_PER_WORKER = 4


def _run_dask(texts: Sequence[str], engine: str, steps: int | None, jobs: int, scheduler: str | None, bar: Any,
              on_result: Callable[[int, dict[str, Any]], None] | None,
              task: Callable[[str], dict[str, Any]] | None, allow_mixed: bool,
              keep: bool) -> tuple[list[dict[str, Any]], Execution]:
    from acds_common.numeric_config import numeric_configuration
    from dask.distributed import as_completed

    client, cluster = _connect(jobs, scheduler)
    try:
        accepted: dict[str, list[str]] = {}
        expected = numeric_configuration()
        _check_workers(client, expected, allow_mixed, accepted)
        info = client.scheduler_info()['workers']
        execution = Execution(scheduler or 'local cluster', len(info), sum(w.get('nthreads', 1) for w in info.values()),
                              accepted)
        work = task if task is not None else functools.partial(run_sample, engine=engine, steps=steps)
        pending = as_completed(loop=client.loop)
        indices: dict[str, list[int]] = {}  # the samples of each task in flight (equal texts: one task)
        ahead = max(1, execution.threads) * IN_FLIGHT_PER_WORKER
        sent = 0

        def send() -> None:
            nonlocal sent
            while len(indices) < ahead and sent < len(texts):
                text = texts[sent]
                key = task_key(text, engine if task is None else repr(task), steps)
                if key in indices:
                    indices[key].append(sent)
                else:
                    indices[key] = [sent]
                    pending.add(client.submit(run_checked_sample, work, text, expected, allow_mixed, key=key,
                                              pure=False))
                sent += 1
        send()
        results: list[dict[str, Any] | None] = [None] * len(texts) if keep else []
        came = bytearray(len(texts))
        for future in pending:
            try:
                summary, mixed = future.result()
            except Exception as exc:  # noqa: BLE001 (a sample that failed on every try is reported, not dropped)
                summary, mixed = {'error': f'{type(exc).__name__}: {exc}'}, None
            _mixed(mixed, allow_mixed, accepted)  # a worker that joined after the check: refused before its result is kept
            ix = indices.pop(future.key)
            future.release()  # read: the scheduler may forget it (a lost worker then recomputes nothing read)
            send()
            for i in ix:
                came[i] = 1
                if keep:
                    results[i] = summary
                if on_result is not None:
                    on_result(i, summary)
            bar.update(len(ix))
        missing = [i for i, c in enumerate(came) if not c]
        if missing:  # as_completed yields every future; this would be a Dask bug, said rather than hidden
            raise MonteCarloError(f'samples {missing} came back from no task')
        return [r for r in results if r is not None], execution
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
