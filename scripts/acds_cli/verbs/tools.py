"""Verbs that run a core model's own tool (no ROS graph): duty-curve, mechanizations, torque-meter."""

from __future__ import annotations

import argparse


def _tool(main_path: str, prog: str):  # noqa: ANN202
    def run(args: argparse.Namespace) -> int:
        import importlib
        module, func = main_path.split(':')
        return getattr(importlib.import_module(module), func)(args.tool_args)
    return run


TOOLS = {
    'duty-curve': ('em_driver.duty_curve:main',
                   'bridge-switch duty cycle and switching frequency vs commanded current (Fig. 4-10)'),
    'mechanizations': ('ascs_mode_manager.mechanizations_tool:main',
                       'the four SSS spin-mode mechanizations in a rotating 0.3 G field (seed 001 Table 1)'),
    'torque-meter': ('ascs_mode_manager.torque_meter:main',
                     'the GSFC Mark VI torque-meter test of the SSS spin/attitude modes'),
}


def register(sub: argparse._SubParsersAction) -> None:
    """Add one verb per tool; the tool parses its own options (``VERB --help``)."""
    for verb, (main_path, text) in TOOLS.items():
        p = sub.add_parser(verb, help=text, description=text, add_help=False)
        p.add_argument('tool_args', nargs=argparse.REMAINDER)
        p.set_defaults(func=_tool(main_path, verb), passthrough=True)
