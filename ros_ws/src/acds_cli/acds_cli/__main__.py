"""``acds`` (``./scripts/acds`` in a checkout): one user entry, one verb per job. Every verb has ``--help``.

The verbs are the modules of :mod:`acds_cli.verbs` and those the installed packages declare in the entry-point
group ``acds.verbs`` (each with ``register(subparsers)``, :mod:`acds_common.plugins`), beside the few small ones
here (scenarios, test, setup, bench). A verb, plug-in name or summary key two packages declare: one line naming
both, exit 2, before any verb runs.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys

from acds_common.plugins import PLOTS, VERBS, PluginConflict, VerbRegistry, check_summary_keys, plugins
from acds_common.scenario import ScenarioError, list_scenarios

from .arguments import OneLineParser, UsageError, positive_int
from .bench import bench_steps
from .interrupts import interruption
from .workspace import workspace


def cmd_scenarios(_args: argparse.Namespace) -> int:
    """List the shipped scenarios."""
    for name, description in list_scenarios():
        print(f'{name:32s} {description}')
    return 0


def cmd_test(args: argparse.Namespace) -> int:
    """Lint, then run the whole test suite."""
    env = dict(os.environ)
    root = workspace()
    lint = subprocess.run([sys.executable, '-m', 'ruff', 'check', '--output-format', 'concise', str(root)],
                          cwd=root, check=False)
    if lint.returncode != 0:
        print('[acds] lint failed (ruff): fix the findings above', file=sys.stderr)
        return lint.returncode
    # worksteal: a worker that runs out takes queued tests from the others (the graph tests' lengths differ).
    cmd = [sys.executable, '-m', 'pytest', '-q', '-n', str(args.jobs), '--dist', 'worksteal', *args.pytest_args]
    return subprocess.run(cmd, cwd=root, env=env, check=False).returncode


def cmd_bench(args: argparse.Namespace) -> int:
    """Benchmark: graph lockstep steps/s, a bare rclpy chain with the same hops, core-only steps/s."""
    from .bench import main as bench_main
    return bench_main(args)


def build_parser() -> argparse.ArgumentParser:
    """The command-line surface (later verbs register here too)."""
    parser = OneLineParser(prog='acds', description=(
        'ACDS emulator of spacecraft magnetic attitude control: the missions are the installed packages\' '
        '(`acds scenarios` lists their scenarios).'))
    sub = parser.add_subparsers(dest='verb', metavar='VERB', required=True)

    registry = VerbRegistry(sub)
    for package, module in _verb_modules():
        registry.register(module, package)
    registry.package = 'acds_cli'
    p = registry.add_parser('scenarios', help='list the shipped scenarios', description='List the shipped scenarios.')
    p.set_defaults(func=cmd_scenarios)

    p = registry.add_parser('test', help='run the whole test suite (lint + pytest)',
                       description='Lint (ruff) and run every test (pytest). Extra args go to pytest.')
    p.add_argument('--jobs', '-j', type=positive_int, default=3,
                   help='parallel test workers (default 3: the graph tests wait on node processes, pauses and '
                        'timeouts part of their time, so a 2-core machine keeps a third worker busy)')
    p.add_argument('pytest_args', nargs=argparse.REMAINDER, help='passed to pytest')
    p.set_defaults(func=cmd_test)

    p = registry.add_parser('setup', help='only set up the virtual environment (idempotent)',
                       description='Create or refresh .venv (done by scripts/acds before any verb).')
    p.set_defaults(func=lambda _a: 0)

    p = registry.add_parser('bench', help='benchmark the lockstep graph against a bare rclpy chain',
                       description='Print graph lockstep steps/s, a bare rclpy chain with the same hops, their ratio, '
                                   'and core-only dynamics steps/s.')
    p.add_argument('--json', action='store_true', help='last line: one JSON object')
    p.add_argument('--steps', type=bench_steps, default=2000, help='steps per measurement (default 2000, at least 500)')
    p.set_defaults(func=cmd_bench)
    return parser


#: Entry-point group of verbs a workspace package adds (each names a module with ``register(subparsers)``).
VERB_ENTRY_POINTS = VERBS


def _verb_modules() -> list:
    """(package, module) of the verb groups in ``acds_cli/verbs/`` (one module each, with ``register(subparsers)``),
    then of the modules other packages declare in the entry-point group :data:`VERB_ENTRY_POINTS`, by name."""
    import importlib
    import pkgutil

    from . import verbs
    ordered = sorted(pkgutil.iter_modules(verbs.__path__), key=lambda m: (m.name != 'run', m.name))  # run first
    own = [('acds_cli', importlib.import_module(f'{verbs.__name__}.{m.name}')) for m in ordered]
    return own + [(p.package, p.module) for p in plugins(VERB_ENTRY_POINTS)]


class Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP (a closed terminal), raised in the main thread and handled like Ctrl-C."""

    def __init__(self, signum: int) -> None:
        super().__init__(f'signal {signum}')
        self.signum = signum


def _terminate(signum: int, _frame: object) -> None:
    raise Stopped(signum)


def parse(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """The verb and its arguments; ``acds test`` hands pytest every option it does not know itself
    (``acds test --durations=20 -k graph``: argparse's remainder alone stops at an option that comes first)."""
    args, unknown = parser.parse_known_args(argv)
    if unknown and args.verb != 'test':
        parser.parse_args(argv)  # the verb's own one-line usage error, exit 2
    if unknown:
        args.pytest_args = [*unknown, *args.pytest_args]
    return args


def main(argv: list[str] | None = None) -> int:
    """Parse the verb and run it; usage and scenario errors are one line, exit 2.

    SIGTERM and SIGHUP stop like Ctrl-C; a stopped verb exits 128 + the signal number
    (130 SIGINT, 143 SIGTERM, 129 SIGHUP), the shell convention. SIGINT is set to Ctrl-C's KeyboardInterrupt
    whatever the process inherited: Python leaves it ignored when the parent ignored it (a job started with
    ``&`` from a script, or a harness that ignores it), and a run would then never stop on it (measured: three
    interrupt tests ran on to their timeouts under such a harness).
    """
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _terminate)
    signal.signal(signal.SIGHUP, _terminate)
    try:  # the installed packages' plug-ins agree, before any verb (and any process) starts
        parser = build_parser()
        from acds_runtime.summary import COMMON_KEYS
        check_summary_keys(COMMON_KEYS)
        plugins(PLOTS)
    except PluginConflict as exc:
        print(f'acds: plug-in conflict: {exc}', file=sys.stderr)
        return 2
    args = parse(parser, argv)
    try:
        code = args.func(args)
        sys.stdout.flush()  # inside: a reader gone before the last write is the BrokenPipeError below
        return code
    except ScenarioError as exc:
        print(f'acds: scenario error: {exc}', file=sys.stderr)
        return 2
    except UsageError as exc:
        print(f'acds {args.verb}: error: {exc}', file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader of stdout left (``acds params ... | head``): nothing more to say, no traceback; the shell's
        # exit status of a writer killed by SIGPIPE. Python would flush stdout again at exit: point it at devnull.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + signal.SIGPIPE
    except BaseException as caught:
        exc = interruption(caught)
        if exc is None:
            raise
        signum = getattr(exc, 'signum', signal.SIGINT)
        print(f'\n[acds] stopped by {signal.Signals(signum).name}', file=sys.stderr)
        return 128 + signum


if __name__ == '__main__':
    sys.exit(main())
