"""The documentation site (``acds docs``): Sphinx + MyST pages of ``docs/`` plus what is generated from the code.

Generated at build time, so the site cannot disagree with what runs: the CLI reference from the argument
parsers (:mod:`.cli_reference`), every shipped scenario's node contracts from the graph's declarations
(:mod:`.contracts`, the same generator as ``acds contract``), the API reference of the pure cores from their
docstrings (:mod:`.api`), and the mission pages' figures and numbers from real runs (:mod:`.figures`, cached
by scenario digest outside git).
"""
