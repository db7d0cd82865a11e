"""``acds docs [--out DIR] [--rerun]``: build the documentation site and print where it is.

Sphinx + MyST over the checkout's ``docs/`` plus the pages generated from the code (the CLI reference, every
shipped scenario's node contracts, the API reference of the pure cores) and the mission pages' figures from
real runs, cached by scenario digest in ``runs/docs/figures`` (:mod:`acds_cli.docs`). Warnings are errors.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..arguments import check_output_dir
from ..workspace import workspace


def _docs(args: argparse.Namespace) -> int:
    from ..docs.build import build_site

    out = Path(args.out) if args.out else workspace() / 'runs' / 'docs'
    check_output_dir('--out', out)
    cache = Path(args.cache) if args.cache else workspace() / 'runs' / 'docs' / 'figures'
    result = build_site(out, cache, rerun=args.rerun, quiet=not args.verbose)
    if not result.ok:
        for line in result.problems or result.log.splitlines()[-20:]:
            print(f'acds docs: {line}', file=sys.stderr)
        print(f'acds docs: the site did not build cleanly ({len(result.problems)} problem(s) above)', file=sys.stderr)
        return 1
    print(result.html / 'index.html')
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``docs`` verb."""
    p = sub.add_parser('docs', help='build the documentation site (Sphinx) and print its path',
                       description='Build the documentation site into OUT/html (default runs/docs/html) and print '
                                   'the path of its front page: the pages of docs/, the CLI reference, every '
                                   'shipped scenario\'s node contracts and the API reference generated from the '
                                   'code, and the mission pages\' figures from real runs (cached by scenario '
                                   'digest). Warnings are errors; a figure whose run fails fails the build, naming '
                                   'the scenario and the error.')
    p.add_argument('--out', metavar='DIR', help='build folder (default runs/docs in the workspace): DIR/html, DIR/src')
    p.add_argument('--cache', metavar='DIR', help='figure runs cache (default runs/docs/figures in the workspace)')
    p.add_argument('--rerun', action='store_true', help='rerun every figure run (after a change to the code)')
    p.add_argument('--verbose', action='store_true', help="print Sphinx's output")
    p.set_defaults(func=_docs)
