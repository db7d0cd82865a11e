"""The documentation site builds clean and every link and figure in it resolves, offline.

``acds docs``'s builder (:func:`acds_cli.docs.build.build_site`) runs Sphinx with warnings as errors over
``docs/`` plus the generated pages (CLI reference, every shipped scenario's node contracts, the pure cores'
API); the mission pages' figure runs are cached by scenario digest in the workspace's ``runs/docs/figures``
(outside git), so only the first build of a checkout runs them. Then every ``href`` and ``src`` of every page
that is not an outside address must name a file of the site, and its ``#fragment`` an id in that file.
"""

from __future__ import annotations

import html.parser
import re
import shutil
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from acds_cli.docs.build import build_site, checkout_root
from acds_cli.docs.contracts import page_name
from acds_cli.verbs.contract import markdown, node_contract

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / 'runs' / 'docs' / 'figures'
ISSUE_NUMBER = re.compile(r'\bissues? \d+', re.I)


class _Refs(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.refs: list[tuple[str, str]] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get('id'):
            self.ids.add(a['id'] or '')
        for key in ('href', 'src'):
            if a.get(key) and not (tag == 'link' and key == 'href' and a.get('rel') not in ('stylesheet', None)):
                self.refs.append((tag, a[key] or ''))


def _parse(path: Path) -> _Refs:
    p = _Refs()
    p.feed(path.read_text())
    return p


@pytest.mark.duration(133)
@pytest.mark.timeout(900)  # a fresh checkout's first build makes the figure runs (cached after)
def test_the_site_builds_clean_with_every_page_link_and_figure(tmp_path):
    """One build (a second worker would build it again), every check of the built site."""
    result = build_site(tmp_path, CACHE)
    assert result.ok, '\n'.join(result.problems or result.log.splitlines()[-30:])
    _every_internal_link_and_figure_resolves(tmp_path / 'html')
    _every_guide_and_reference_page(tmp_path / 'html')
    _contract_pages_are_what_acds_contract_prints(tmp_path / 'src')
    _no_issue_numbers(tmp_path)


def _every_internal_link_and_figure_resolves(html_dir: Path) -> None:
    pages = sorted(html_dir.rglob('*.html'))
    assert len(pages) > 40
    parsed = {p: _parse(p) for p in pages}
    broken = []
    images = 0
    for page, refs in parsed.items():
        for tag, ref in refs.refs:
            parts = urlsplit(ref)
            if parts.scheme or ref.startswith('mailto:'):
                continue
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if not target.is_file():
                broken.append(f'{page.relative_to(html_dir)}: {tag} {ref} (no such file)')
                continue
            images += tag == 'img'
            if parts.fragment and target.suffix == '.html':
                ids = parsed[target].ids if target in parsed else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f'{page.relative_to(html_dir)}: {ref} (no id {parts.fragment} there)')
    assert not broken, '\n'.join(broken[:30])
    assert images >= 12  # the mission pages' figures from real runs


def _every_guide_and_reference_page(html_dir: Path) -> None:
    for page in ('index', 'getting_started', 'flight_software', 'studies', 'record_replay', 'architecture',
                 'conventions', 'measurements', 'missions/heao', 'missions/sss', 'missions/aap', 'missions/oresat',
                 'missions/emff', 'reference/cli', 'contracts/index', 'reference/api/index'):
        assert (html_dir / f'{page}.html').is_file(), page
    cli = (html_dir / 'reference' / 'cli.html').read_text()
    for verb in ('run', 'montecarlo', 'contract', 'docs', 'sweep', 'plot'):
        assert f'id="acds-{verb}"' in cli, verb


def _contract_pages_are_what_acds_contract_prints(src: Path) -> None:
    from acds_common.scenario import load_scenario

    for name, node in (('oresat_detumble', 'acds_controller'), ('emff_testbed_hold', 'a/em_driver')):
        page = src / 'contracts' / name / f'{page_name(node)}.md'
        assert page.read_text() == markdown(node_contract(load_scenario(name), node))


def _no_issue_numbers(site: Path) -> None:
    readme = (ROOT / 'README.md').read_text()
    assert len(readme.splitlines()) <= 150
    pages = [*sorted((site / 'src').rglob('*.md')), *sorted((site / 'html').rglob('*.html'))]
    found = [f'{p}: {m}' for p in [ROOT / 'README.md', *pages] for m in ISSUE_NUMBER.findall(p.read_text())]
    assert not found, found[:20]


def test_a_figure_whose_run_fails_fails_the_build_naming_the_scenario_and_the_error(tmp_path):
    docs = tmp_path / 'docs'
    docs.mkdir()
    shutil.copy(checkout_root() / 'docs' / 'conf.py', docs)
    bad = tmp_path / 'broken_detumble.yaml'
    bad.write_text('extends: oresat_detumble\nname: broken_detumble\ncontroller:\n  max_moment_am2: -1\n')
    (docs / 'index.md').write_text(f'# Broken\n\n```{{acds-run}} {bad}\n:figures: torque_rod_detumble\n```\n')
    result = build_site(tmp_path / 'out', tmp_path / 'cache', docs=docs, generated=False)
    assert not result.ok
    line = next(p for p in result.problems if 'figure run of scenario' in p)
    assert line.startswith(f'index: figure run of scenario {bad} failed: acds run {bad} ')
    assert 'max_moment_am2' in line, line
    assert not (tmp_path / 'out' / 'html' / '_images').exists() or not list((tmp_path / 'out' / 'html' / '_images').iterdir())


def test_a_figure_runs_cache_key_follows_extends(tmp_path):
    """A figure run is cached by its scenario's digest: a change to the scenario it extends (or to a file beside
    that one which it names) is a new digest, so the page is not built from the run of the parent as it was."""
    from acds_cli.docs.figures import scenario_digest

    base, child = tmp_path / 'base.yaml', tmp_path / 'child.yaml'
    (tmp_path / 'rod.json').write_text('{"turns": 1}')
    base.write_text('extends: oresat_detumble\nname: base\nduration_min: 2\nrod_file: rod.json\n')
    child.write_text('extends: base\nname: child\n')
    before = scenario_digest(str(child), [])
    assert scenario_digest(str(child), []) == before
    (tmp_path / 'rod.json').write_text('{"turns": 2}')
    after_file = scenario_digest(str(child), [])
    base.write_text('extends: oresat_detumble\nname: base\nduration_min: 3\nrod_file: rod.json\n')
    after_base = scenario_digest(str(child), [])
    assert len({before, after_file, after_base}) == 3
    assert scenario_digest(str(child), ['--steps', '10']) != after_base
