"""The documentation's engineering figures come from the code: each is read back from its page and recomputed.

A figure a mission page states (the HEAO page's cold-gas minimum impulse bit, tank pressure, Isp limit, arms,
ideal impulse and Δv; the AAP page's reading of the memo's k) is found by the words around it and compared with
what the code computes, to the digits printed. Changing the code without the page, or the page without the
code, fails here; so does a retired figure coming back on any page or in the README.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from acds_common import units as u
from acds_common.thrusters import LAYOUTS, arrangement
from cold_gas.rcs import RcsConfig, ideal_vacuum_isp_limit_s, table_5_3_isp_s

ROOT = Path(__file__).resolve().parents[1]


def page(*parts: str) -> str:
    """A documentation page's text (or the README's) with every run of whitespace one space."""
    return ' '.join(ROOT.joinpath(*parts).read_text().split())


HEAO = page('docs', 'missions', 'heao.md')
AAP = page('docs', 'missions', 'aap.md')
EVERY_PAGE = [page(*p.relative_to(ROOT).parts) for p in sorted((ROOT / 'docs').rglob('*.md'))] + [page('README.md')]
#: HEAO-B inertia diagonal, Table 4-1 (slug-ft²), and the tip-off rate the sizing case nulls (§3.2).
HEAO_B_INERTIA_SLUG_FT2 = (1520.0, 7970.0, 7920.0)
TIP_OFF_RAD_S = math.radians(1.0)


def stated(pattern: str, text: str = HEAO) -> list[str]:
    """The groups of ``pattern`` (spaces match any run of whitespace) in a page (the HEAO page unless ``text``
    says otherwise); fails if it is not there."""
    m = re.search(pattern.replace(' ', r'\s+'), text)
    assert m, f'the page no longer states: {pattern}'
    return list(m.groups())


def ideal_damping_impulse_lbf_s(layout: str) -> float:
    """Σ thruster impulse to null the tip-off rate about every axis on a layout's arms (a couple's two thrusters
    each give its impulse), lbf·s."""
    arr = arrangement(*LAYOUTS[layout])
    return sum(u.SLUG_FT2_KG_M2 * i * TIP_OFF_RAD_S / arr.arm_m[2 * a] * len(arr.thrusters_of_axis[2 * a])
               for a, i in enumerate(HEAO_B_INERTIA_SLUG_FT2)) / u.LBF_N


def test_cold_gas_figures():
    cfg = RcsConfig(arrangement(*LAYOUTS['platform']))
    (bit,) = stated(r'minimum impulse bit 0.5 lbf × \(20 − 5 \+ 3\) ms = (\d\.\d+) lbf·s')
    assert bit == f'{cfg.minimum_impulse_bit_ns / u.LBF_N:.3f}'
    (psia,) = stated(r'isothermal blowdown at 293 K: (\d+) psia at load')
    assert psia == f'{cfg.tank_pressure_pa(cfg.load_mass_kg) / u.PSI_PA:.0f}'
    (limit,) = stated(r'infinite-expansion limit of N₂ at 293 K is (\d+\.\d) s')
    assert limit == f'{ideal_vacuum_isp_limit_s(293.0):.1f}'
    low, high = stated(r'impulse over its gas capacity is (\d+\.\d)–(\d+\.\d) lbf·s/lb')
    assert (low, high) == (f'{min(table_5_3_isp_s()):.1f}', f'{max(table_5_3_isp_s()):.1f}')


def test_thruster_arms_impulse_and_delta_v():
    arr = arrangement(*LAYOUTS['platform'])
    aft, side = stated(r'every thruster 95.94 in \((\d\.\d+) m\) aft of the mass centre.*?40.25 in \((\d\.\d+) m\) out')
    assert (aft, side) == (f'{arr.arm_m[2]:.3f}', f'{arr.arm_m[0] / 2:.3f}')
    assert stated(r'pitch by one radial thruster \(arm (\d\.\d+) m\)') == [f'{arr.arm_m[2]:.3f}']
    assert stated(r'yaw by the two tangential thrusters of one place \(2 × (\d\.\d+) m\)') == [f'{arr.arm_m[4] / 2:.3f}']
    assert stated(r'roll by one tangential thruster at each place \(2 × (\d\.\d+) m;') == [f'{arr.arm_m[0] / 2:.3f}']
    cfg = RcsConfig(arr)
    (step,) = stated(r"minimum impulse bit's rate step, at most (\d\.\d+) deg/s on the roll axis")
    roll_step = cfg.minimum_impulse_bit_ns * arr.arm_m[0] / (u.SLUG_FT2_KG_M2 * HEAO_B_INERTIA_SLUG_FT2[0])
    assert step == f'{math.degrees(roll_step):.4f}'
    assert all(cfg.minimum_impulse_bit_ns * arr.arm_m[2 * a] / (u.SLUG_FT2_KG_M2 * i) <= roll_step
               for a, i in enumerate(HEAO_B_INERTIA_SLUG_FT2))  # roll's is the largest
    (platform,) = stated(r'null 1 deg/s about every axis on these arms is (\d+\.\d\d) lbf·s')
    assert platform == f'{ideal_damping_impulse_lbf_s("platform"):.2f}'
    (outriggers,) = stated(r'one thruster per signed axis: (\d+\.\d\d) lbf·s\)')
    assert outriggers == f'{ideal_damping_impulse_lbf_s("outriggers"):.2f}'
    impulse, dv, lb, kg = stated(r"whole load's impulse, (\d+) N·s, is a Δv of (\d\.\d+) m/s on HEAO-B's (\d,\d+) lb, "
                                 r'(\d,\d+) kg, Table 4-1')
    total_ns = cfg.load_mass_kg * cfg.exhaust_velocity_m_s
    mass_kg = 6436 * u.LB_KG  # Table 4-1, HEAO-B weight
    assert (impulse, dv, lb, kg) == (f'{total_ns:.0f}', f'{total_ns / mass_kg:.2f}', '6,436', f'{mass_kg:,.0f}')


def test_the_memo_k_in_its_readings():
    """Seed 000 §5's k = 4e6 (and its range 3–5e6) in amp-turn-m² units under the amp-turn-ft² reading."""
    ft2 = u.FOOT_M ** 2
    k, lo, hi = stated(r'read in amp-turn-ft², k = 4×10⁶ is (\d\.\d+)×10⁵ and the range 3…5×10⁶ is '
                       r'(\d\.\d+)…(\d\.\d+)×10⁵', AAP)
    assert (k, lo, hi) == (f'{4e6 * ft2 / 1e5:.3f}', f'{3e6 * ft2 / 1e5:.2f}', f'{5e6 * ft2 / 1e5:.2f}')


@pytest.mark.parametrize('pattern', [r'minimum impulse bit 0\.018', r"whole load's Δv is ≈ 0\.4 m/s"])
def test_retired_figures_are_gone(pattern):
    assert not any(re.search(pattern, text) for text in EVERY_PAGE), f'a page still states the retired figure {pattern!r}'
