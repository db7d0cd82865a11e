"""Mission plug-ins: what a package adds above its nodes (style guide, "a mission is a plug-in").

Beside its nodes (:data:`acds_common.graph.ENTRY_POINT_GROUP`), a package's setup.py names modules in these
entry-point groups, each group one protocol; the runtime and the CLI read "the installed packages' summaries,
plots and verbs" and name no mission:

* ``acds.summaries``: a run-summary section (:mod:`acds_runtime.summary`): ``applies(scenario)``,
  ``Accumulator(scenario)`` (``topics``, ``step(k, values)``, ``contribute(summary)``, optionally ``event_topics``
  with ``event(topic, value)``, and optionally :data:`STEP_BLOCK_ATTRIBUTE`), ``null_keys(summary)``,
  ``print_tables(summary)`` (the report lines) and :data:`KEYS_ATTRIBUTE`, the summary keys it contributes, and
  optionally :data:`STUDY_ROW_ATTRIBUTE`, the dispersion study's columns of a sample;
* ``acds.plots``: figures of ``acds plot`` (:mod:`acds_cli.bag.mission_plots`): ``applies(ctx)``, ``vectors(ctx)``,
  ``plot(kit)``;
* ``acds.verbs``: verbs of ``acds`` (:mod:`acds_cli.verbs`): ``register(subparsers)``.
* ``acds.limits``: limits the common figures and the live view draw beside a value (:func:`limits`):
  ``limits(params)``, from a run's node parameters.
* ``acds.study_budgets``: a paired sweep's budget of a case (:mod:`acds_cli.verbs.sweep`): ``applies(scenario)``,
  ``PAIRED_QUANTITIES``, ``study_budget(rows, scenario)``, ``study_budget_table(scenario_name, budget)``.

Modules of a group load in entry-point name order. Two packages that declare the same entry-point name in a
group, the same summary key or the same verb are a :class:`PluginConflict`: one line naming both packages,
raised before any process starts (``acds`` exits 2 on it).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib.metadata import entry_points
from types import ModuleType
from typing import Any

SUMMARIES, PLOTS, VERBS, LIMITS = 'acds.summaries', 'acds.plots', 'acds.verbs', 'acds.limits'
#: A paired sweep's per-case budgets (``acds sweep --runs N``).
STUDY_BUDGETS = 'acds.study_budgets'
#: The attribute of a summary module listing the top-level summary keys it contributes.
KEYS_ATTRIBUTE = 'SUMMARY_KEYS'
#: The optional function of a summary module giving a dispersion study's row columns from one sample's summary
#: (:func:`acds_runtime.dispersion_report.make_row`): ``study_row(summary) -> dict``.
STUDY_ROW_ATTRIBUTE = 'study_row'
#: The optional method of a summary module's ``Accumulator`` taking a block of steps at once
#: (:meth:`acds_runtime.summary.RunObserver.feed_block`): ``step_block(k0, columns)``, ``columns`` per topic it reads
#: the float64 rows of steps k0, k0 + 1, … (:class:`acds_common.cdr.RowLayout`; a topic without fixed layout, like the
#: mode, absent: no step of a block changes it). It must leave the accumulator as ``step(k, values)`` row by row would
#: (:mod:`acds_common.step_blocks`); without it the observer hands each step's values unflattened to ``step``.
STEP_BLOCK_ATTRIBUTE = 'step_block'


class PluginConflict(ValueError):
    """Two packages declare the same plug-in name, summary key or verb."""


@dataclass(frozen=True)
class Plugin:
    """One entry point of a plug-in group: its name, the distribution (package) declaring it, its module."""

    name: str
    package: str
    module: ModuleType


def _owner_check(what: str, owner: dict[str, str], name: str, package: str) -> None:
    if name in owner and owner[name] != package:
        raise PluginConflict(f'{what} {name!r} is declared by both {owner[name]} and {package}')
    owner[name] = package


@functools.cache
def plugins(group: str) -> tuple[Plugin, ...]:
    """The modules of entry-point ``group``, in name order (loaded once per process; conflicts raise)."""
    owner: dict[str, str] = {}
    found = []
    for ep in sorted(entry_points(group=group), key=lambda e: (e.name, e.dist.name if e.dist else '')):
        package = (ep.dist.name if ep.dist else ep.value.split('.')[0]).replace('-', '_')  # as ROS spells it
        _owner_check(f'{group} name', owner, ep.name, package)
        found.append(Plugin(ep.name, package, ep.load()))
    return tuple(found)


def modules(group: str) -> list[ModuleType]:
    """The modules of ``group`` (:func:`plugins`)."""
    return [p.module for p in plugins(group)]


def check_summary_keys(own: tuple[str, ...] = (), own_package: str = 'acds_runtime') -> None:
    """Raise :class:`PluginConflict` when two packages' summary modules (or one and ``own``, the runtime's
    common keys) declare the same summary key."""
    owner = dict.fromkeys(own, own_package)
    for plugin in plugins(SUMMARIES):
        for key in getattr(plugin.module, KEYS_ATTRIBUTE, ()):
            _owner_check('summary key', owner, key, plugin.package)


class VerbRegistry:
    """The subparsers a verb module's ``register`` sees: ``add_parser`` raises :class:`PluginConflict` when
    another package declared the verb (argparse would raise its own error, naming neither package)."""

    def __init__(self, subparsers: object) -> None:
        self._subparsers = subparsers
        self._owner: dict[str, str] = {}
        self.package = ''

    def add_parser(self, name: str, **kwargs: object) -> object:
        """``subparsers.add_parser`` of the verb module being registered, after the conflict check."""
        for verb in (name, *kwargs.get('aliases', ())):
            _owner_check('verb', self._owner, verb, self.package)
        return self._subparsers.add_parser(name, **kwargs)

    def __getattr__(self, name: str) -> object:
        """Everything else of the subparsers object, as it is."""
        return getattr(self._subparsers, name)

    def register(self, module: ModuleType, package: str) -> None:
        """Let ``module`` (of ``package``) register its verbs."""
        self.package = package
        module.register(self)


def limits(params: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The limits the :data:`LIMITS` plug-ins give a run from its node parameters (SI; a key absent: none applies):
    ``rate_thresholds`` (rad/s per body axis, the mode logic compares |ω_i| with them) and ``capture_cone`` (rad,
    body z to the sun line at capture)."""
    out: dict[str, Any] = {}
    for module in modules(LIMITS):
        out.update(module.limits(params))
    return out
