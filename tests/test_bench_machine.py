"""``acds bench`` names the host it measured (Measurements: figures compare between hosts of one CPU model and one
SIMD level only; the same code ran ~40 % more CPU on an AMD EPYC without AVX-512)."""

from __future__ import annotations

import platform

from acds_cli.bench import cpu_model

CPUINFO = """processor\t: 0
vendor_id\t: AuthenticAMD
model name\t: AMD EPYC 9R14 96-Core Processor
cpu MHz\t\t: 2445.422

processor\t: 1
model name\t: AMD EPYC 9R14 96-Core Processor
"""


def test_the_cpu_model_is_read_from_cpuinfo():
    assert cpu_model(CPUINFO) == 'AMD EPYC 9R14 96-Core Processor'


def test_without_a_model_name_the_platform_says_it():
    assert cpu_model('processor\t: 0\nmodel name\t:   \n') == (platform.processor() or platform.machine() or 'unknown')
