"""The CLI reference page, generated from the argument parsers (every verb, every option, its limits)."""

from __future__ import annotations

import argparse
import inspect
import re


def _value(value: object, name: str) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return name
    return f'{value:,}' if isinstance(value, int) else f'{value:g}'


def _limits(action: argparse.Action) -> str:
    """What an option accepts: its choices, or the first line of its type function's docstring (the limits)."""
    if action.choices:
        return 'one of ' + ', '.join(f'`{c}`' for c in action.choices)
    kind = action.type
    if kind is None:
        return '—' if action.nargs == 0 else 'text'
    doc = inspect.getdoc(kind) if callable(kind) and getattr(kind, '__module__', '') != 'builtins' else None
    if doc:
        names = getattr(kind, '__globals__', {})  # a limit the docstring names by its constant: its value
        return re.sub(r'\b[A-Z][A-Z0-9_]{2,}\b', lambda m: _value(names.get(m.group()), m.group()),
                      doc.splitlines()[0]).replace('|', '\\|')
    return getattr(kind, '__name__', str(kind))


def _cell(text: object) -> str:
    return str(text).replace('|', '\\|').replace('\n', ' ') if text not in (None, '') else '—'


def _options(parser: argparse.ArgumentParser) -> list[str]:
    rows = ['| option | argument | default | accepts | meaning |', '| --- | --- | --- | --- | --- |']
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        names = ', '.join(f'`{o}`' for o in action.option_strings) or f'`{action.dest}` (positional)'
        if action.nargs == 0:
            arg = '—'
        else:
            arg = f'`{action.metavar or action.dest.upper()}`' + (' …' if action.nargs in ('*', '+', argparse.REMAINDER)
                                                                   else ' (optional)' if action.nargs == '?' else '')
        default = '—' if action.default in (None, argparse.SUPPRESS, False) or action.nargs == 0 \
            else f'`{action.default}`'
        repeat = ' (repeatable)' if isinstance(action, argparse._AppendAction) else ''
        rows.append(f'| {names} | {arg} | {default} | {_cell(_limits(action))} | {_cell(action.help)}{repeat} |')
    return rows


def _verbs(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def cli_reference(parser: argparse.ArgumentParser) -> str:
    """The Markdown page: one section per verb (its description, usage and every option)."""
    verbs = _verbs(parser)
    lines = ['# Command-line reference', '',
             f'Generated from the argument parsers of `{parser.prog}` at build time. Every verb also answers '
             f'`./scripts/acds VERB --help`. Units are those an option names; "accepts" gives the limits the '
             'option checks before anything starts (a value outside them: one line, exit 2).', '',
             '| verb | what it does |', '| --- | --- |']
    helps = {a.dest: a.help for p in parser._actions if isinstance(p, argparse._SubParsersAction)
             for a in p._choices_actions}
    lines += [f'| [`{v}`](#acds-{v}) | {_cell(helps.get(v, ""))} |' for v in verbs]
    for name, sub in verbs.items():
        usage = sub.format_usage().strip().removeprefix('usage: ')
        sub_verbs = _verbs(sub)
        lines += ['', f'(acds-{name})=', f'## `acds {name}`', '', _cell(sub.description or helps.get(name, '')), '',
                  '```text', usage, '```', '', *_options(sub)]
        for sname, ssub in sub_verbs.items():
            lines += ['', f'### `acds {name} {sname}`', '', _cell(ssub.description or ''), '', '```text',
                      ssub.format_usage().strip().removeprefix('usage: '), '```', '', *_options(ssub)]
    return '\n'.join(lines) + '\n'
