"""Sphinx configuration of the ACDS emulator's site (built by ``./scripts/acds docs``; MyST Markdown pages)."""

project = 'ACDS emulator'
author = 'ACDS emulator team'
copyright = 'ACDS emulator team'  # noqa: A001 (Sphinx's name)
extensions = ['myst_parser', 'sphinx.ext.autodoc', 'acds_cli.docs.figures']
source_suffix = {'.md': 'markdown'}
myst_enable_extensions = ['colon_fence', 'dollarmath']
myst_heading_anchors = 4
exclude_patterns = ['_build']
html_theme = 'alabaster'
html_title = 'ACDS emulator'
html_theme_options = {'description': 'Spacecraft magnetic attitude control on ROS 2 Jazzy', 'fixed_sidebar': True,
                      'page_width': '1180px', 'sidebar_width': '240px'}
html_show_sourcelink = False
html_static_path = ['_static']
html_css_files = ['acds.css']
smartquotes = False  # option names keep their two hyphens (--external)
html_copy_source = False
autodoc_member_order = 'bysource'
autodoc_typehints = 'none'
# Offline: no intersphinx, no remote images; every link inside the site is checked by the build (-W).


import re  # noqa: E402

#: A change-request reference in a docstring (the product's site names none): the reference and its sections.
_ISSUE = re.compile(r'\bissues? \d+(?:\s*(?:§\s?[\d.]+|item \d+)(?:,\s*§\s?[\d.]+)*)?')


def _without_issue_numbers(line):
    line = _ISSUE.sub('', line)
    line = re.sub(r'\s?\(\s*[;,:]?\s*\)', '', line)
    line = re.sub(r'\(\s*[;,:]\s*', '(', line)
    return re.sub(r'\s+\)', ')', line)


def _verbatim(_app, _what, _name, _obj, _options, lines):
    """The docstrings are plain text with Unicode maths (the house style), not reStructuredText: shown as written,
    less the change-request numbers the code cites."""
    if lines:
        lines[:] = ['::', '', *(f'   {_without_issue_numbers(line)}' for line in lines), '']


def setup(app):
    """Docstrings verbatim."""
    app.connect('autodoc-process-docstring', _verbatim)
