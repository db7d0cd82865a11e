"""Repository-wide pytest settings.

* hypothesis runs derandomized and without per-example deadlines (the suite runs on two loaded cores; deadlines
  there measure the machine, not the code);
* the suite's longest tests start first, one per worker: a test marked ``duration(seconds)`` (its measured length)
  is placed at the head of the share of tests pytest-xdist first hands a worker, the longest on the worker with the
  least so far. The real C3 (its own 300 s IDLE sleep) and the 60× CANopen master mostly wait on the wall clock;
  started last, either one was the suite's tail while the other workers stood idle.
"""

import pytest
from hypothesis import settings

settings.register_profile('acds', deadline=None, derandomize=True)
settings.load_profile('acds')


def _shares(total: int, workers: int) -> list[int]:
    """How many of ``total`` tests pytest-xdist's first distribution hands each of ``workers`` (worksteal and load
    split the queue in order: each idle worker gets the rest divided by the workers still to serve)."""
    sizes, left = [], total
    for i in range(workers):
        sizes.append(left // (workers - i))
        left -= sizes[-1]
    return sizes


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Put each ``duration``-marked test at the head of a worker's first share, longest first (every worker
    collects and orders alike, so the controller sees one order)."""
    def seconds(item: pytest.Item) -> float:
        return float(item.get_closest_marker('duration').args[0])

    long = sorted((it for it in items if it.get_closest_marker('duration')), key=seconds, reverse=True)
    if not long:
        return
    workers = int(getattr(config, 'workerinput', {}).get('workercount', 1))
    heads: list[list[pytest.Item]] = [[] for _ in range(workers)]
    load = [0.0] * workers
    for item in long:
        w = load.index(min(load))
        heads[w].append(item)
        load[w] += seconds(item)
    rest = iter(it for it in items if not it.get_closest_marker('duration'))
    ordered = []
    for head, size in zip(heads, _shares(len(items), workers), strict=True):
        ordered += head + [next(rest) for _ in range(max(0, size - len(head)))]
    items[:] = ordered + list(rest)
