"""Summary contributors: each module defines ``contribute(result, summary)`` and ``print_tables(summary)``."""
