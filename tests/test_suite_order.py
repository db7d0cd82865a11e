"""The suite's scheduling hint (``conftest.py``): ``duration``-marked tests head the shares pytest-xdist first hands
its workers, the longest first, each on the worker with the least marked time so far."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location('repo_conftest', ROOT / 'conftest.py')
repo_conftest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(repo_conftest)


class Item(SimpleNamespace):
    def get_closest_marker(self, name):
        return SimpleNamespace(args=(self.seconds,)) if name == 'duration' and self.seconds else None


def test_shares_are_xdists_first_split():
    assert repo_conftest._shares(1475, 3) == [491, 492, 492]
    assert repo_conftest._shares(10, 4) == [2, 2, 3, 3]
    assert sum(repo_conftest._shares(7, 1)) == 7


def _order(items, workers):
    config = SimpleNamespace(workerinput={'workercount': workers})
    repo_conftest.pytest_collection_modifyitems(config, items)
    return [it.name for it in items]


def test_the_longest_head_the_shares_and_nothing_is_lost_or_doubled():
    items = [Item(name=f't{i}', seconds=0) for i in range(12)]
    items[11].seconds, items[5].seconds, items[7].seconds, items[2].seconds = 380, 130, 110, 50
    order = _order(items, 3)
    assert sorted(order) == sorted(f't{i}' for i in range(12))
    shares = [order[0:4], order[4:8], order[8:12]]
    assert [s[0] for s in shares] == ['t11', 't5', 't7']
    assert shares[2][1] == 't2'  # 110 s was the least marked time when the 50 s test came
    assert [n for n in order if n not in {'t11', 't5', 't7', 't2'}] == [f't{i}' for i in (0, 1, 3, 4, 6, 8, 9, 10)]


def test_without_xdist_the_marked_tests_come_first():
    items = [Item(name='a', seconds=0), Item(name='b', seconds=20), Item(name='c', seconds=0), Item(name='d', seconds=90)]
    assert _order(items, 1) == ['d', 'b', 'a', 'c']
