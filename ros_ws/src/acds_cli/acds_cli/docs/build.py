"""Build the site: copy ``docs/`` to a source folder, generate the reference pages into it, run Sphinx.

Sphinx runs with warnings as errors (a broken link, a missing figure, a bad cross-reference fail the build),
in this process (no shell), into ``OUT/html``; the source folder ``OUT/src`` is rebuilt each time from the
checkout's ``docs/`` plus the generated pages, and the figure runs are cached in ``CACHE``.
"""

from __future__ import annotations

import io
import shutil
import warnings
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path


@dataclass
class BuildResult:
    """Where the site is, and why it failed when it did (Sphinx's warnings and errors, the failed runs)."""

    html: Path
    ok: bool
    problems: list[str]
    log: str


def checkout_root() -> Path:
    """The checkout whose ``docs/`` is built: the one the shipped scenarios come from."""
    from acds_common.scenario import SCENARIO_DIR

    return SCENARIO_DIR.resolve().parent


def generate(src: Path, root: Path) -> None:
    """The generated pages: the CLI reference, the contracts, the API reference."""
    from ..__main__ import build_parser
    from .api import write_api
    from .cli_reference import cli_reference
    from .contracts import write_contracts

    (src / 'reference').mkdir(parents=True, exist_ok=True)
    (src / 'reference' / 'cli.md').write_text(cli_reference(build_parser()))
    write_contracts(src / 'contracts')
    write_api(root / 'ros_ws' / 'src', src / 'reference' / 'api')


def build_site(out: Path, cache: Path, rerun: bool = False, quiet: bool = True, docs: Path | None = None,
               generated: bool = True) -> BuildResult:
    """Build the HTML site into ``out/html`` (warnings are errors); figure runs cached in ``cache``.

    ``docs``: the pages (default the checkout's ``docs/``); ``generated``: add the generated reference pages.
    """
    import os

    from sphinx.cmd.build import build_main
    from sphinx.deprecation import RemovedInSphinx11Warning

    from . import figures

    root = checkout_root()
    src, html = out / 'src', out / 'html'
    shutil.rmtree(src, ignore_errors=True)
    shutil.rmtree(out / 'doctrees', ignore_errors=True)  # every page read again (its figures come from the cache)
    shutil.copytree(docs or root / 'docs', src)
    if generated:
        generate(src, root)
    cache.mkdir(parents=True, exist_ok=True)
    figures.FAILURES.clear()
    buf = io.StringIO()
    argv = ['-b', 'html', '-W', '--keep-going', '-q', '-d', str(out / 'doctrees'), '-D', f'acds_run_cache={cache}',
            '-D', f'acds_rerun={int(rerun)}', '-j', '1', str(src), str(html)]
    os.environ.setdefault('COLUMNS', '110')  # the CLI reference's usage lines wrap at a fixed width
    with redirect_stdout(buf), redirect_stderr(buf), warnings.catch_warnings():
        warnings.simplefilter('ignore', RemovedInSphinx11Warning)  # myst-parser's use of Sphinx API on its way out
        code = build_main(argv)
    log = buf.getvalue()
    problems = list(figures.FAILURES) + [ln for ln in log.splitlines() if 'WARNING' in ln or 'ERROR' in ln]
    if not quiet:
        print(log, end='')
    return BuildResult(html, code == 0 and not figures.FAILURES, problems, log)
