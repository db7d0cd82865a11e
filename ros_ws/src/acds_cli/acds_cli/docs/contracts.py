"""Every shipped scenario's node contracts (interface control documents), one page per node.

The same generator as ``acds contract SCENARIO --node NODE`` (:func:`acds_cli.verbs.contract.node_contract`
and :func:`~acds_cli.verbs.contract.markdown`): the site and the command print the same content.
"""

from __future__ import annotations

from pathlib import Path


def page_name(node: str) -> str:
    """A node instance's page file stem (a formation vehicle's ``vehicle/node`` as ``vehicle.node``)."""
    return node.replace('/', '.')


def write_contracts(out: Path) -> list[str]:
    """Write ``out/<scenario>/<node>.md`` and one index per scenario and for all; the scenario names."""
    from acds_common.scenario import list_scenarios, load_scenario

    from ..verbs.contract import markdown, scenario_contracts

    out.mkdir(parents=True, exist_ok=True)
    names = []
    index = ['# Interface control documents', '',
             'One contract per node of every shipped scenario, generated at build time from the declarations the '
             'graph is built from: what `./scripts/acds contract SCENARIO --node NODE` prints. A node you replace '
             'with your own (`acds run --external NODE`) implements its contract; '
             '[Flying your own flight software](../flight_software.md) says how.', '',
             '| scenario | nodes | description |', '| --- | --- | --- |']
    toc = []
    for name, description in list_scenarios():
        contracts = scenario_contracts(load_scenario(name))
        nodes = list(contracts)
        folder = out / name
        folder.mkdir(exist_ok=True)
        for node, contract in contracts.items():
            (folder / f'{page_name(node)}.md').write_text(markdown(contract))
        links = ', '.join(f'[{n}]({name}/{page_name(n)}.md)' for n in nodes)
        index.append(f'| `{name}` | {links} | {description.replace("|", "/")} |')
        toc += [f'{name}/{page_name(n)}' for n in nodes]
        names.append(name)
    index += ['', '```{toctree}', ':hidden:', ':maxdepth: 1', '', *toc, '```', '']
    (out / 'index.md').write_text('\n'.join(index))
    return names
