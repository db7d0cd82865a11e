"""Per-mission figures of ``acds plot``: plug-ins, as the run summaries are (:mod:`acds_common.plugins`).

A package declares its missions' figures in the entry-point group ``acds.plots`` (setup.py), each a module
that defines

* ``applies(ctx) -> bool``: whether the run is of its mission, decided from what the bag says ran — the
  nodes and the scenario sections they received (:class:`~acds_cli.bag.plots.RunContext`, the parameters
  the bag records) — never from the scenario's name;
* ``vectors(ctx) -> {topic: getter}``: the series it reads beyond the common ones (gathered in the one
  pass over the bag; a getter turns a message into a list of floats);
* ``plot(kit)``: its figures, drawn with the :class:`PlotKit`.

Adding a mission's figures is adding such a module to the mission's package and naming it in its setup.py;
:func:`chosen` finds it. The CLI names no mission.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
from acds_common.plugins import PLOTS, Plugin
from acds_common.plugins import plugins as declared


@dataclass
class PlotKit:
    """What a plug-in draws with: the run's context, its series, the common ones, matplotlib and ``finish``.

    ``series(topic, width)``: (t min, (n, width) values) of a gathered topic (empty arrays when absent).
    ``rates``: (t min, body rates rad/s (n, 3)) from the truth, else the gyro. ``sun_angle``: body z to the
    sun line per rate sample, deg (None without attitude or sun). ``dt_s``: the control period.
    ``finish(fig, axes, stem, title)``: marks the mode transitions on ``axes``, titles and keeps the figure.
    """

    ctx: Any
    series: Callable[[str, int], tuple[np.ndarray, np.ndarray]]
    rates: tuple[np.ndarray, np.ndarray]
    sun_angle: np.ndarray | None
    dt_s: float
    plt: Any
    finish: Callable[[Any, list[Any], str, str], None]


def plugins() -> tuple[Plugin, ...]:
    """Every mission-plot plug-in the installed packages declare, by name."""
    return declared(PLOTS)


def chosen(ctx: Any) -> list[ModuleType]:
    """The plug-in modules that apply to the run ``ctx`` describes."""
    return [p.module for p in plugins() if p.module.applies(ctx)]
