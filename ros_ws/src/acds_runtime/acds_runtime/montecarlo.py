"""Monte Carlo dispersions: run drawn samples on the direct engine or the graph, here or on Dask (issue 11).

One task per sample (:func:`run_sample`): its scenario as YAML text in, its run summary out —
nothing else crosses the wire, so a Dask worker needs only the project set up on its host
(``./scripts/acds setup``, the worker started from that ``.venv``). Results are kept by sample
index, so the set is complete and in order whatever ran where. A worker that dies mid-task has its
tasks rescheduled by the Dask scheduler on the workers left (up to
``distributed.scheduler.allowed-failures`` times, default 3; past that the sample is reported
failed, never dropped); a sample's run is deterministic (lockstep, seeded), so a retried sample
gives the result a single machine gives.

``jobs=1`` without a scheduler runs the samples one after the other in this process (no Dask);
``jobs>1`` starts a ``LocalCluster`` of that many single-threaded worker processes; ``scheduler``
("tcp://host:8786") uses the user's cluster (``dask scheduler`` / ``dask worker``; README).
"""

from __future__ import annotations

import hashlib
import sys
import tempfile
from collections.abc import Callable, Sequence
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
    capture) and return its run summary; a failed run returns ``{'scenario', 'error'}``."""
    from .launcher import GraphRun, LaunchError

    scenario = scenario_from_text(text)
    try:
        if engine == 'direct':
            from .direct import DirectRun
            return DirectRun(scenario, steps=steps).run().summary
        if engine != 'graph':
            raise MonteCarloError(f'unknown engine {engine!r} (engines: {", ".join(ENGINES)})')
        with tempfile.TemporaryDirectory(prefix='acds_mc_') as tmp, \
                GraphRun(scenario, Path(tmp), steps=steps, echo=lambda _line: None) as graph:
            return graph.wait().summary
    except LaunchError as exc:
        return {'scenario': scenario.name, 'error': str(exc)}


def _environment() -> dict[str, str]:
    """What a worker's results depend on besides the scenario: the interpreter and numpy versions."""
    import numpy

    import acds_runtime
    return {'python': sys.version.split()[0], 'numpy': numpy.__version__, 'acds_runtime': acds_runtime.__file__}


def task_key(text: str, engine: str, steps: int | None) -> str:
    """The Dask key of a sample's task: the same inputs give the same key (and so the same result)."""
    return 'acds-sample-' + hashlib.sha256(f'{engine}\0{steps}\0{text}'.encode()).hexdigest()[:24]


@dataclass
class Execution:
    """Where the samples ran: ``where`` ('in-process', 'local cluster', or the scheduler), worker count."""

    where: str
    workers: int
    threads: int
    notes: list[str] = field(default_factory=list)


def run_samples(texts: Sequence[str], *, engine: str = 'direct', steps: int | None = None, jobs: int = 1,
                scheduler: str | None = None, progress: bool = True,
                on_result: Callable[[int], None] | None = None) -> tuple[list[dict[str, Any]], Execution]:
    """Run every sample; its summaries in the order of ``texts``, and where they ran.

    ``on_result(done)`` is called after each finished sample (``done`` finished so far).
    """
    if engine not in ENGINES:
        raise MonteCarloError(f'unknown engine {engine!r} (engines: {", ".join(ENGINES)})')
    from tqdm import tqdm

    tty = sys.stderr.isatty()
    bar = tqdm(total=len(texts), desc='[montecarlo] samples', unit='run', file=sys.stderr, disable=not progress,
               mininterval=0.5 if tty else 10.0, ascii=not tty, dynamic_ncols=tty)
    try:
        if scheduler is None and jobs == 1:
            results = []
            for text in texts:
                results.append(run_sample(text, engine, steps))
                bar.update(1)
                if on_result is not None:
                    on_result(len(results))
            return results, Execution('in-process', 1, 1)
        return _run_dask(texts, engine, steps, jobs, scheduler, bar, on_result)
    finally:
        bar.close()


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


def _connect(jobs: int, scheduler: str | None) -> tuple[Any, Any]:
    """(client, cluster or None) for a local cluster of ``jobs`` workers or the user's ``scheduler``."""
    import logging

    from dask.distributed import Client, LocalCluster

    if scheduler is None:
        quiet_resource_tracker()
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR)
        return Client(cluster, set_as_default=False), cluster
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


def _check_workers(client: Any, notes: list[str]) -> None:
    """Every worker can import the project, and says which numpy it runs (a different one may round differently)."""
    try:
        envs = client.run(_environment)
    except Exception as exc:  # noqa: BLE001 (whatever a worker raises, the message is the report)
        raise MonteCarloError(f'a Dask worker cannot run samples ({type(exc).__name__}: {exc}); every worker host '
                              'needs the project set up (./scripts/acds setup) and the worker started from its '
                              '.venv') from None
    here = _environment()
    for address, env in sorted(envs.items()):
        if (env['python'], env['numpy']) != (here['python'], here['numpy']):
            notes.append(f'worker {address} runs Python {env["python"]} / numpy {env["numpy"]}, this machine '
                         f'{here["python"]} / {here["numpy"]}: results may differ in the last bits')


def _run_dask(texts: Sequence[str], engine: str, steps: int | None, jobs: int, scheduler: str | None, bar: Any,
              on_result: Callable[[int], None] | None) -> tuple[list[dict[str, Any]], Execution]:
    from dask.distributed import as_completed

    client, cluster = _connect(jobs, scheduler)
    try:
        notes: list[str] = []
        _check_workers(client, notes)
        info = client.scheduler_info()['workers']
        execution = Execution(scheduler or 'local cluster', len(info), sum(w.get('nthreads', 1) for w in info.values()),
                              notes)
        indices: dict[str, list[int]] = {}
        for i, text in enumerate(texts):
            indices.setdefault(task_key(text, engine, steps), []).append(i)
        futures = [client.submit(run_sample, texts[ix[0]], engine, steps, key=key, pure=False)
                   for key, ix in indices.items()]
        results: list[dict[str, Any] | None] = [None] * len(texts)
        done = 0
        for future in as_completed(futures, loop=client.loop):
            try:
                summary = future.result()
            except Exception as exc:  # noqa: BLE001 (a sample that failed on every try is reported, not dropped)
                summary = {'error': f'{type(exc).__name__}: {exc}'}
            for i in indices[future.key]:
                results[i] = summary
                done += 1
            bar.update(len(indices[future.key]))
            if on_result is not None:
                on_result(done)
        missing = [i for i, r in enumerate(results) if r is None]
        if missing:  # as_completed yields every future; this would be a Dask bug, said rather than hidden
            raise MonteCarloError(f'samples {missing} came back from no task')
        return [r for r in results if r is not None], execution
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
