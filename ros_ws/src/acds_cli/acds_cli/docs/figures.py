"""Sphinx extension: the ``acds-run`` directive puts a real run's figures and numbers on a page.

```{acds-run} SCENARIO
:until-min: 30
:figures: PLOT_NAME, OTHER_PLOT_NAME
```

runs the shipped scenario on the direct engine (bit-identical to the graph) with ``acds run``, and shows the
named plots of the run and the report it printed. Runs are cached by digest (the scenario's YAML, the files
beside it that it names, the run options) in the folder ``acds_run_cache`` (``runs/docs/figures`` outside
git), so a rebuild does not rerun them (``acds docs --rerun`` does, after a change to the code). A run that
fails, or a figure it did not make, is an error naming the page, the scenario and the error: the page shows
it, the build fails, and no page ships with a missing figure.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

LOG = logging.getLogger(__name__)

#: Run failures of this build ({docname: [line]}): ``acds docs`` prints them and exits non-zero.
FAILURES: list[str] = []


def scenario_digest(scenario: str, args: list[str]) -> str:
    """Digest of what a figure run depends on: the scenario's YAML and every YAML its ``extends`` reaches, the
    files beside each that it names, the options."""
    from acds_common.scenario import extends_chain, scenario_path

    h = hashlib.sha256()
    for path in extends_chain(scenario_path(scenario)):
        text = path.read_bytes()
        h.update(text)
        for other in sorted(path.parent.iterdir()):
            if other != path and other.is_file() and other.name.encode() in text:
                h.update(other.name.encode() + other.read_bytes())
    h.update(json.dumps(args).encode())
    return h.hexdigest()[:16]


def _cached(name: str, digest: str, argv: list[str], cache: Path, rerun: bool, outputs: list[str]) -> Path:
    """The cache folder ``name-digest`` of ``acds ARGV`` run to completion (running it first when needed).

    ``outputs``: files (relative to the folder) the command must have written. Raises RuntimeError naming the
    error when it fails (nothing is cached then).
    """
    folder = cache.resolve() / f'{name}-{digest}'
    if (folder / 'stdout.txt').exists() and not rerun:
        return folder
    tmp = folder.parent / f'.{folder.name}.partial'
    shutil.rmtree(tmp, ignore_errors=True)
    shutil.rmtree(folder, ignore_errors=True)
    tmp.mkdir(parents=True)
    argv = [a.replace('{out}', str(tmp)) for a in argv]
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', *argv], capture_output=True, text=True, check=False,
                          env=dict(os.environ), stdin=subprocess.DEVNULL, cwd=tmp)
    if proc.returncode != 0 or not all((tmp / o).exists() for o in outputs):
        lines = [ln for ln in (proc.stderr + proc.stdout).splitlines() if ln.strip()]
        shown = ' '.join(a.replace(str(tmp), 'OUT') for a in argv)
        raise RuntimeError(f'acds {shown} exited {proc.returncode}: {lines[-1] if lines else "no output"}')
    (tmp / 'stdout.txt').write_text(proc.stdout.replace(str(tmp), 'OUT'))
    tmp.rename(folder)
    return folder


def cached_run(scenario: str, args: list[str], cache: Path, rerun: bool = False) -> Path:
    """The cache folder of a finished direct-engine run of ``scenario`` with ``args`` (plots in ``run/plots``)."""
    argv = ['run', scenario, '--engine', 'direct', '--quiet', *args, '--run-dir', f'{{out}}/{scenario}',
            '--record', '{out}/bag', '--summary-json', '{out}/summary.json']
    folder = _cached(scenario, scenario_digest(scenario, args), argv, cache, rerun, ['summary.json'])
    shutil.rmtree(folder / 'bag', ignore_errors=True)  # the plots and numbers are kept, the bag is not needed
    return folder


def cached_output(argv: list[str], cache: Path, rerun: bool = False) -> Path:
    """The cache folder of ``acds ARGV`` (a design or study verb), digest of the command line."""
    return _cached(argv[0], hashlib.sha256(json.dumps(argv).encode()).hexdigest()[:16], argv, cache, rerun, [])


def _report(text: str) -> str:
    """The summary the run printed, without the run's own housekeeping lines (``[acds] ...``)."""
    return '\n'.join(ln for ln in text.splitlines() if not ln.startswith('[')).strip()


def _made(folder: Path, wanted: list[str]) -> dict[str, Path]:
    """{plot name: PNG} of what a cached command made; RuntimeError naming a wanted figure it did not make."""
    made = {p.stem: p for p in folder.rglob('*.png')}
    missing = [w for w in wanted if w not in made]
    if missing:
        raise RuntimeError(f'it made no figure {", ".join(missing)} (it made: {", ".join(sorted(made)) or "none"})')
    return made


def _figures(directive: SphinxDirective, folder: Path, made: dict[str, Path], wanted: list[str],
             caption: str) -> list[nodes.Node]:
    """Figure nodes of the wanted plots, copied into the site's sources under ``_figures/<cache folder>/``."""
    target_dir = Path(directive.env.srcdir) / '_figures' / folder.name
    target_dir.mkdir(parents=True, exist_ok=True)
    out: list[nodes.Node] = []
    for name in wanted:
        shutil.copyfile(made[name], target_dir / f'{name}.png')
        out.append(nodes.figure('', nodes.image(uri=f'/_figures/{folder.name}/{name}.png', alt=name, width='100%'),
                                nodes.caption(text=f'{name}: {caption}')))
    return out


def _wanted(options: dict[str, str]) -> list[str]:
    return [f.strip() for f in re.split(r'[,\s]+', options.get('figures', '')) if f.strip()]


class AcdsRun(SphinxDirective):
    """``acds-run SCENARIO`` with ``:until-min:``, ``:steps:``, ``:figures:`` (plot names), ``:report:`` (yes/no)."""

    required_arguments = 1
    option_spec = {'until-min': directives.unchanged, 'steps': directives.unchanged,
                   'figures': directives.unchanged_required, 'report': directives.unchanged}

    def run(self) -> list[nodes.Node]:
        scenario = self.arguments[0]
        args: list[str] = []
        if 'until-min' in self.options:
            args += ['--until-min', self.options['until-min']]
        if 'steps' in self.options:
            args += ['--steps', self.options['steps']]
        wanted = _wanted(self.options)
        cfg = self.env.config
        try:
            folder = cached_run(scenario, args, Path(cfg.acds_run_cache), bool(cfg.acds_rerun))
            made = _made(folder, wanted)
        except (RuntimeError, OSError, ValueError) as exc:
            line = f'{self.env.docname}: figure run of scenario {scenario} failed: {exc}'
            FAILURES.append(line)
            LOG.error(line, location=self.get_location())
            return [nodes.error('', nodes.paragraph(text=f'Scenario {scenario}: the figure run failed: {exc}'))]
        until = f', until {self.options["until-min"]} min' if 'until-min' in self.options else ''
        out = _figures(self, folder, made, wanted, f'{scenario}{until}, direct engine (acds run)')
        if self.options.get('report', 'yes') != 'no':
            report = _report((folder / 'stdout.txt').read_text())
            command = f'acds run {scenario}{" " + " ".join(args) if args else ""} --engine direct'
            out.append(nodes.paragraph('', '', nodes.Text('What '), nodes.literal(text=command),
                                       nodes.Text(' printed for this page:')))
            out.append(nodes.literal_block(report, report, language='text'))
        return out


class AcdsOutput(SphinxDirective):
    """``acds-output VERB ARGS...``: what a design or study verb prints, from a real run at build time."""

    required_arguments = 1
    final_argument_whitespace = True
    option_spec = {'figures': directives.unchanged_required}

    def run(self) -> list[nodes.Node]:
        argv = self.arguments[0].split()
        wanted = _wanted(self.options)
        cfg = self.env.config
        try:
            folder = cached_output(argv, Path(cfg.acds_run_cache), bool(cfg.acds_rerun))
            made = _made(folder, wanted)
        except (RuntimeError, OSError) as exc:
            line = f'{self.env.docname}: output of acds {" ".join(argv)} failed: {exc}'
            FAILURES.append(line)
            LOG.error(line, location=self.get_location())
            return [nodes.error('', nodes.paragraph(text=f'acds {" ".join(argv)} failed: {exc}'))]
        text = (folder / 'stdout.txt').read_text().rstrip()
        command = 'acds ' + ' '.join(argv).replace('{out}', 'OUT')
        return [*_figures(self, folder, made, wanted, command),
                nodes.paragraph('', '', nodes.Text('What '), nodes.literal(text=command),
                                nodes.Text(' printed when this page was built:')),
                nodes.literal_block(text, text, language='text')]


def setup(app: Any) -> dict[str, Any]:
    """Register the directive and its configuration values."""
    app.add_config_value('acds_run_cache', 'runs/docs/figures', 'env')
    app.add_config_value('acds_rerun', False, 'env')
    app.add_directive('acds-run', AcdsRun)
    app.add_directive('acds-output', AcdsOutput)
    return {'parallel_read_safe': False, 'parallel_write_safe': True, 'version': '1'}
