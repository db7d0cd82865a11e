"""Minimum-weight magnet and power-supply design for magnetic CMG momentum dumping (seed 000 §6–§12, App. C–E).

Seed: ``000_aap_cmg_dump_levidow.txt`` (Levidow, Bellcomm TM-69-1022-8). The seed writes its design
equations in mixed units with rounded numeric coefficients (1970, 1140, 6200, 10700, 0.461, 0.0767,
9310, 5380, 13500, 23300); here the same physics is written in SI and the coefficients follow from
1 in = 0.0254 m and μ0 (the unit tests check that they round to the seed's). Seed units appear only
in the report helpers at the bottom and in the ``size-magnet`` verb.

The design (Appendix D, E), for a magnet producing a moment M(t) whose orbital profile is summarised
by M_n, M_d (rms over orbital night and day) and M_m (maximum |M|):

* power ∝ |M|² for every structure (§6 eq. 5, D1, D10), so the night, day and peak load powers are
  P_n = P_m (M_n/M_m)², P_d = P_m (M_d/M_m)²;
* power-supply weight W_p = K_n P_n + K_d P_d + K_a P_m (Appendix C), hence W_p = P_m M_e²/M_m² with
  the equivalent moment M_e = (K_n M_n² + K_d M_d² + K_a M_m²)^½ (D5, D12);
* with c identical coils (c = 1 gimbaled, 3 fixed orthogonal), conductor mass W_c = c·N·ℓ·a·σ and
  P_m = (I_m N)² ℓ ρ / (N a) (D3, D13); minimising W_c + W_p over the product N·a gives
  N·a = (I_m N / M_m) · M_e · (ρ / (c σ))^½ and W_p = W_c at the optimum (D7, D16);
* air coil of diameter d (D1, D2): I_m N = M_m / A, A = π d²/4, turn length ℓ = π d;
* iron core (D3, D4; length/diameter Q, empirical α and D of the §7 chart, peak flux density B):
  core volume μ0 M_m / (α B), length ℓ_i = (4 Q² V / π)^⅓, diameter ℓ_i / Q, I_m N = B ℓ_i D / μ0,
  turn length ℓ = π ℓ_i / Q; total = 2 W_c + c × core weight;
* day dump at constant |M| (§10, Appendix E): no battery, M_n = 0 and M_d = M_m = M, so
  M_e = M (K_d + K_a)^½ — Appendix E's (K_a + 1/(K_s E_rd)) with K_d = 1/(E_rd K_s).

Formulas re-derived where the OCR copy is damaged (each checked by the derivation above and the
unit tests): eqs. (20), (21) and D4 print (ρ/σ)^½ in P_m and the conductor weight where the
dimensionally right (ρσ)^½ of D3 belongs; Appendix E1's conductor weight prints
M (K_a + 1/(K_s E_rd)) where the minimisation gives M (K_a + 1/(K_s E_rd))^½.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from acds_common import units

__all__ = [
    'MagnetSizingError', 'DumpMoments', 'PowerSupplyParams', 'Conductor', 'IronCore', 'MagnetDesign',
    'Winding', 'MODES', 'CORES', 'STRUCTURES', 'COPPER', 'ALUMINIUM', 'PERMALLOY_45_CHART', 'PERMALLOY_45_Q30',
    'SEED_POWER_SUPPLY', 'SEED_COIL_DIAMETER_M', 'SEED_B0_T', 'SEED_ALTITUDE_M', 'SEED_DAYLIGHT_DEG',
    'M_O_OVER_M_M', 'DAY_CONSTANT_FACTOR', 'circular_orbit_period_s', 'night_day_s', 'power_supply_constants',
    'equivalent_moment', 'design', 'approximate_moments', 'estimate_max_moment_am2',
    'estimate_max_moment_45op_am2', 'wind', 'air_coil_axis_field_t', 'with_power_supply_orbit',
]

MODES = ('day-night', 'day-constant')
CORES = ('air', 'iron')
#: Magnet structures of §6: one gimbaled coil, or three fixed orthogonal identical coils.
STRUCTURES = ('gimbaled', 'three_orthogonal')
_N_COILS = {'gimbaled': 1, 'three_orthogonal': 3}

#: Coil diameter of the Fig. 4 designs, m (§8: "twenty foot diameter coils ... fits within the Workshop skin").
SEED_COIL_DIAMETER_M = 20.0 * units.FOOT_M
#: Earth's field at the magnetic equator at 220 nmi, T (Appendix A: B_0 = 0.26e-4 Wb/m²); the §8 field table's B_0.
SEED_B0_T = 0.26e-4
#: Workshop orbit altitude, m (§5: "220 nm, 35° inclination orbit").
SEED_ALTITUDE_M = 220.0 * units.NMI_M
#: Orbital daylight arc, degrees (§10 "the 220° orbital day", §11 "220 nm, 220° daylight orbit"; sun in the orbit plane).
SEED_DAYLIGHT_DEG = 220.0
#: Mean ratio M_o/M_m seen in the seed's simulations (§11: "varied between 0.7 and 0.8, with a mean of 0.78").
M_O_OVER_M_M = 0.78
#: Constant |M| for day-only dumping relative to the day-and-night M_m (§10: "30% higher ... was found adequate").
DAY_CONSTANT_FACTOR = 1.3
#: §12 estimator: M_m = 12.5 H_b A·m² per ft-lb-sec for a bias in the orbital plane (POP, 45° OP), in A·m² per N·m·s.
ESTIMATE_AM2_PER_NMS = 12.5 / units.FT_LB_S_NMS
#: §12 estimator for 45° OP: M_m = 0.0665 (I_z − I_x) A·m² per slug-ft², in A·m² per kg·m².
ESTIMATE_45OP_AM2_PER_KGM2 = 0.0665 / units.SLUG_FT2_KG_M2

_WH_J = 3600.0


class MagnetSizingError(ValueError):
    """Invalid input to the magnet sizing equations (seed 000 §7–§12; raised by em_driver.magnet_sizing)."""


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise MagnetSizingError(f'{name} must be a finite number > 0, got {value!r}')
    return v


def _non_negative(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v < 0.0:
        raise MagnetSizingError(f'{name} must be a finite number >= 0, got {value!r}')
    return v


@dataclass(frozen=True)
class DumpMoments:
    """The orbital |M| profile the design needs (seed §5 Table 1 quantities), A·m².

    ``m_n_am2``, ``m_d_am2``, ``m_o_am2``: rms of |M| over orbital night, day and the whole orbit;
    ``m_m_am2``: maximum |M|. M_o does not enter the design equations (§7); it is carried for the report.
    """

    m_n_am2: float
    m_d_am2: float
    m_o_am2: float
    m_m_am2: float

    def __post_init__(self) -> None:
        for name in ('m_n_am2', 'm_d_am2', 'm_o_am2'):
            _non_negative(f'DumpMoments.{name}', getattr(self, name))
        m_m = _positive('DumpMoments.m_m_am2', self.m_m_am2)
        for name in ('m_n_am2', 'm_d_am2', 'm_o_am2'):
            if getattr(self, name) > m_m * (1.0 + 1e-9):
                raise MagnetSizingError(f'DumpMoments.{name} = {getattr(self, name)} A·m² exceeds the maximum '
                                        f'm_m_am2 = {m_m} A·m² (an rms cannot exceed the maximum)')


@dataclass(frozen=True)
class PowerSupplyParams:
    """Solar array + battery + control amplifier (Appendix C), SI.

    Seed values (Appendix C, "estimated values used in calculations"): E_rd = 0.82 (regulator ×
    distribution efficiency), E_b = 0.68 (battery), E_ch = 0.96 (charger), D = 0.3 (depth of
    discharge), K_b = 10 W·h/lb, K_s = 3 W/lb (solar array), K_a = 0.12 lb/W single channel and
    0.32 lb/W three channel (control amplifier). ``night_s``/``day_s``: T_n, T_d.
    """

    night_s: float
    day_s: float
    e_rd: float = 0.82
    e_b: float = 0.68
    e_ch: float = 0.96
    depth_of_discharge: float = 0.3
    battery_j_per_kg: float = 10.0 * _WH_J / units.LB_KG
    solar_w_per_kg: float = 3.0 / units.LB_KG
    amplifier_single_kg_per_w: float = 0.12 * units.LB_KG
    amplifier_three_kg_per_w: float = 0.32 * units.LB_KG

    def __post_init__(self) -> None:
        _non_negative('PowerSupplyParams.night_s', self.night_s)
        for name in ('day_s', 'battery_j_per_kg', 'solar_w_per_kg', 'amplifier_single_kg_per_w',
                     'amplifier_three_kg_per_w'):
            _positive(f'PowerSupplyParams.{name}', getattr(self, name))
        for name in ('e_rd', 'e_b', 'e_ch', 'depth_of_discharge'):
            v = _positive(f'PowerSupplyParams.{name}', getattr(self, name))
            if v > 1.0:
                raise MagnetSizingError(f'PowerSupplyParams.{name} is an efficiency or fraction in (0, 1], got {v}')

    def amplifier_kg_per_w(self, structure: str) -> float:
        """K_a: one amplifier channel for a gimbaled magnet, three for three magnets (§7)."""
        return self.amplifier_single_kg_per_w if _n_coils(structure) == 1 else self.amplifier_three_kg_per_w


def circular_orbit_period_s(altitude_m: float) -> float:
    """Period of a circular two-body orbit at ``altitude_m`` above ``units.EARTH_RADIUS_M``, s."""
    a = units.EARTH_RADIUS_M + _positive('altitude_m', altitude_m)
    return 2.0 * math.pi * math.sqrt(a ** 3 / units.EARTH_MU_M3_S2)


def night_day_s(altitude_m: float = SEED_ALTITUDE_M, daylight_deg: float = SEED_DAYLIGHT_DEG) -> tuple[float, float]:
    """(T_n, T_d), s: orbital night and day of a circular orbit with a ``daylight_deg`` daylight arc."""
    arc = float(daylight_deg)
    if not 0.0 < arc <= 360.0:
        raise MagnetSizingError(f'daylight_deg must be in (0, 360], got {daylight_deg!r}')
    period = circular_orbit_period_s(altitude_m)
    return period * (360.0 - arc) / 360.0, period * arc / 360.0


#: Appendix C power supply on the seed's 220 nmi orbit with a 220° day (T_n ≈ 36.0 min, T_d ≈ 56.7 min).
SEED_POWER_SUPPLY = PowerSupplyParams(*night_day_s())


def power_supply_constants(ps: PowerSupplyParams, structure: str) -> tuple[float, float, float]:
    """(K_n, K_d, K_a), kg/W: W_p = K_n P_n + K_d P_d + K_a P_m (Appendix C).

    K_n = (T_n/E_rd)·[1/(D K_b) + 1/(K_s E_b E_ch T_d)] (battery for the night plus the array that
    recharges it by day), K_d = 1/(E_rd K_s) (array powering the day load), K_a per amplifier channel.
    """
    k_n = ps.night_s / ps.e_rd * (1.0 / (ps.depth_of_discharge * ps.battery_j_per_kg)
                                  + 1.0 / (ps.solar_w_per_kg * ps.e_b * ps.e_ch * ps.day_s))
    k_d = 1.0 / (ps.e_rd * ps.solar_w_per_kg)
    return k_n, k_d, ps.amplifier_kg_per_w(structure)


@dataclass(frozen=True)
class Conductor:
    """Coil conductor: resistivity ρ (Ω·m) and density σ (kg/m³)."""

    name: str
    resistivity_ohm_m: float
    density_kg_m3: float

    def __post_init__(self) -> None:
        _positive(f'Conductor({self.name}).resistivity_ohm_m', self.resistivity_ohm_m)
        _positive(f'Conductor({self.name}).density_kg_m3', self.density_kg_m3)


#: Copper. ρ from the seed's own typical IOP coil (§8: 31 turns of #10 copper wire, conductor area
#: 0.008155 in², on a 20 ft diameter coil, "maximum current and voltage ... 10.1 amperes and 21.5 volts"):
#: ρ = (V/I)·a/(N·π·d) = 7.43e-7 Ω·in = 1.89e-8 Ω·m (annealed copper near 45 °C; the seed prints no ρ).
#: σ = 8.89 g/cm³ = 0.321 lb/in³, the annealed-copper standard density (not in the seed; its Fig. 4
#: copper weights and turns × area imply 0.32 lb/in³).
COPPER = Conductor(
    'copper',
    units.ohm_in_to_ohm_m((21.5 / 10.1) * 0.008155 / (31 * math.pi * 240.0)),
    8890.0,
)
#: Aluminium at the same temperature: 61 % of copper's conductivity (IACS grade EC aluminium) and
#: 2.70 g/cm³ (neither in the seed; §8 states only "a 30% savings in coil conductor and power supply
#: weight" for aluminium, which these give: (ρσ)^½ ratio 0.70).
ALUMINIUM = Conductor('aluminium', COPPER.resistivity_ohm_m / 0.61, 2700.0)


@dataclass(frozen=True)
class IronCore:
    """Iron core of length/diameter ``q`` with the empirical α and D of the §7 chart (ref. 1, Hart et al.).

    ``b_max_t``: maximum flux density established in the core, T; ``density_kg_m3``: σ_i.
    """

    name: str
    q: float
    alpha: float
    d_factor: float
    b_max_t: float
    density_kg_m3: float

    def __post_init__(self) -> None:
        for name in ('q', 'alpha', 'd_factor', 'b_max_t', 'density_kg_m3'):
            _positive(f'IronCore({self.name}).{name}', getattr(self, name))


#: 45 % nickel permalloy (Fig. 5) at 1 Wb/m² (§8: "operating at a maximum flux density of 1 weber/meter²").
#: The seed prints no σ_i: 0.30 lb/in³ (8.30 g/cm³) is what Fig. 5 implies (its printed core lengths,
#: diameters and weights give 0.29–0.30 lb/in³); handbook values for 45 % Ni–Fe are 8.2–8.3 g/cm³.
_PERMALLOY_45_DENSITY = units.lb_in3_to_kg_m3(0.30)
#: The §7 chart: (Q, α, D) = (20, 0.76, 0.0060), (30, 0.77, 0.0030), (40, 0.78, 0.0020).
PERMALLOY_45_CHART = {
    q: IronCore(f'45 Permalloy, Q = {q}', float(q), alpha, d, 1.0, _PERMALLOY_45_DENSITY)
    for q, alpha, d in ((20, 0.76, 0.0060), (30, 0.77, 0.0030), (40, 0.78, 0.0020))
}
#: Fig. 5's core: length/diameter 30.
PERMALLOY_45_Q30 = PERMALLOY_45_CHART[30]


def _n_coils(structure: str) -> int:
    if structure not in _N_COILS:
        raise MagnetSizingError(f'structure must be one of {STRUCTURES}, got {structure!r}')
    return _N_COILS[structure]


def equivalent_moment(moments: DumpMoments, mode: str, structure: str,
                      ps: PowerSupplyParams = SEED_POWER_SUPPLY,
                      day_constant_factor: float = DAY_CONSTANT_FACTOR) -> tuple[float, float, float, float]:
    """(M_e, M_design, night load fraction, day load fraction) for a dump mode (§7, §10; App. D, E).

    ``'day-night'`` (continuous dumping): M_e = (K_n M_n² + K_d M_d² + K_a M_m²)^½, M_design = M_m,
    load fractions (M_n/M_m)², (M_d/M_m)² of the peak power. ``'day-constant'`` (§10: dump only in
    daylight with constant |M| = ``day_constant_factor`` × M_m of day-and-night dumping, seed 1.3):
    M_e = M (K_d + K_a)^½, M_design = M, fractions 0 and 1. M_e is in A·m²·(kg/W)^½.
    """
    k_n, k_d, k_a = power_supply_constants(ps, structure)
    if mode == 'day-night':
        m_m = moments.m_m_am2
        m_e = math.sqrt(k_n * moments.m_n_am2 ** 2 + k_d * moments.m_d_am2 ** 2 + k_a * m_m ** 2)
        return m_e, m_m, (moments.m_n_am2 / m_m) ** 2, (moments.m_d_am2 / m_m) ** 2
    if mode == 'day-constant':
        m = _positive('day_constant_factor', day_constant_factor) * moments.m_m_am2
        return m * math.sqrt(k_d + k_a), m, 0.0, 1.0
    raise MagnetSizingError(f'mode must be one of {MODES}, got {mode!r}')


@dataclass(frozen=True)
class MagnetDesign:
    """One minimum-weight design (Fig. 4 / Fig. 5 rows), SI. Totals are over all coils of the structure.

    ``ampere_turns_a`` and ``turns_area_m2`` (N·a) are per coil; ``max_power_w`` is the peak load
    power; ``battery_kg``, ``solar_array_kg``, ``amplifier_kg`` sum to ``power_supply_kg``; for iron
    cores ``core_*`` give one core and ``core_kg`` all of them; ``coil_diameter_m`` is the air coil's
    (None for iron), ``turn_length_m`` the conductor length per turn.
    """

    mode: str
    core: str
    structure: str
    n_coils: int
    conductor: str
    moment_am2: float
    equivalent_moment: float
    ampere_turns_a: float
    turns_area_m2: float
    turn_length_m: float
    max_power_w: float
    night_power_w: float
    day_power_w: float
    conductor_kg: float
    battery_kg: float
    solar_array_kg: float
    amplifier_kg: float
    core_kg: float
    core_length_m: float | None
    core_diameter_m: float | None
    coil_diameter_m: float | None

    @property
    def power_supply_kg(self) -> float:
        """Solar array + battery + control amplifier, kg (Appendix C)."""
        return self.battery_kg + self.solar_array_kg + self.amplifier_kg

    @property
    def total_kg(self) -> float:
        """Conductor + power supply + iron cores, kg (insulation and winding forms excluded, as in the seed)."""
        return self.conductor_kg + self.power_supply_kg + self.core_kg

    @property
    def current_density_a_m2(self) -> float:
        """Peak conductor current density I_m N / (N a), A/m² (§8: about 800 A/in² gimbaled, 1200 three coils)."""
        return self.ampere_turns_a / self.turns_area_m2

    def centre_field_t(self) -> float:
        """Peak field at the centre of an air coil, T: μ0 I_m N / d (also for three coils, whatever M's direction)."""
        return air_coil_axis_field_t(self.ampere_turns_a, self._air_diameter(), 0.0)

    def axis_field_t(self, distance_m: float) -> float:
        """Peak field on the coil axis at ``distance_m`` from an air coil's centre, T (§8 table)."""
        return air_coil_axis_field_t(self.ampere_turns_a, self._air_diameter(), distance_m)

    def _air_diameter(self) -> float:
        if self.coil_diameter_m is None:
            raise MagnetSizingError('the coil field is given for air coils only (§8); this design has an iron core')
        return self.coil_diameter_m


def air_coil_axis_field_t(ampere_turns_a: float, diameter_m: float, distance_m: float) -> float:
    """Field on the axis of a thin circular coil, T: B = μ0 N I r² / (2 (r² + z²)^{3/2}), r = d/2."""
    r = 0.5 * _positive('diameter_m', diameter_m)
    z = float(distance_m)
    return units.MU0 * _non_negative('ampere_turns_a', ampere_turns_a) * r * r / (2.0 * (r * r + z * z) ** 1.5)


def design(moments: DumpMoments, mode: str, core: str, structure: str, *,
           coil_diameter_m: float = SEED_COIL_DIAMETER_M, conductor: Conductor = COPPER,
           iron: IronCore = PERMALLOY_45_Q30, ps: PowerSupplyParams = SEED_POWER_SUPPLY,
           day_constant_factor: float = DAY_CONSTANT_FACTOR) -> MagnetDesign:
    """Minimum total weight design of conductor + power supply (+ cores) for ``moments`` (§7, App. D, E).

    ``mode`` 'day-night' | 'day-constant'; ``core`` 'air' | 'iron'; ``structure`` 'gimbaled' |
    'three_orthogonal'; ``coil_diameter_m`` for air coils (seed 20 ft); ``iron`` the core material and
    shape (seed Fig. 5: 45 Permalloy, Q = 30, 1 Wb/m²).
    """
    c = _n_coils(structure)
    m_e, m_m, night_frac, day_frac = equivalent_moment(moments, mode, structure, ps, day_constant_factor)
    if core == 'air':
        d = _positive('coil_diameter_m', coil_diameter_m)
        ampere_turns = m_m / (math.pi * d * d / 4.0)
        turn_length = math.pi * d
        core_length = core_diameter = None
        core_kg = 0.0
    elif core == 'iron':
        volume = units.MU0 * m_m / (iron.alpha * iron.b_max_t)
        core_length = (4.0 * iron.q ** 2 * volume / math.pi) ** (1.0 / 3.0)
        core_diameter = core_length / iron.q
        ampere_turns = iron.b_max_t * core_length * iron.d_factor / units.MU0
        turn_length = math.pi * core_diameter
        core_kg = c * volume * iron.density_kg_m3
        d = None
    else:
        raise MagnetSizingError(f'core must be one of {CORES}, got {core!r}')
    rho, sigma = conductor.resistivity_ohm_m, conductor.density_kg_m3
    turns_area = ampere_turns / m_m * m_e * math.sqrt(rho / (c * sigma))
    max_power = ampere_turns ** 2 * turn_length * rho / turns_area
    p_n, p_d = max_power * night_frac, max_power * day_frac
    battery = p_n * ps.night_s / (ps.e_rd * ps.depth_of_discharge * ps.battery_j_per_kg)
    solar = (p_n * ps.night_s / (ps.e_b * ps.e_ch * ps.day_s) + p_d) / (ps.e_rd * ps.solar_w_per_kg)
    return MagnetDesign(
        mode=mode, core=core, structure=structure, n_coils=c, conductor=conductor.name, moment_am2=m_m,
        equivalent_moment=m_e, ampere_turns_a=ampere_turns, turns_area_m2=turns_area, turn_length_m=turn_length,
        max_power_w=max_power, night_power_w=p_n, day_power_w=p_d,
        conductor_kg=c * turns_area * turn_length * sigma, battery_kg=battery, solar_array_kg=solar,
        amplifier_kg=ps.amplifier_kg_per_w(structure) * max_power, core_kg=core_kg, core_length_m=core_length,
        core_diameter_m=core_diameter, coil_diameter_m=d)


def approximate_moments(m_m_am2: float, m_o_over_m_m: float = M_O_OVER_M_M) -> DumpMoments:
    """§11 approximation for day-and-night dumping: M_n ≈ M_d ≈ M_o = 0.78 M_m (two cycles of |M| per orbit)."""
    ratio = _positive('m_o_over_m_m', m_o_over_m_m)
    m_m = _positive('m_m_am2', m_m_am2)
    return DumpMoments(ratio * m_m, ratio * m_m, ratio * m_m, m_m)


def estimate_max_moment_am2(h_b_nms: float) -> float:
    """§12: M_m = 12.5 H_b (A·m², H_b in ft-lb-sec) when the bias momentum lies in the orbital plane (POP, 45° OP).

    ``h_b_nms``: magnitude of the summed bias momentum per orbit, N·m·s.
    """
    return ESTIMATE_AM2_PER_NMS * _positive('h_b_nms', h_b_nms)


def estimate_max_moment_45op_am2(iz_minus_ix_kgm2: float) -> float:
    """§12, 45° OP: M_m = 0.0665 (I_z − I_x) A·m² with the inertias in slug-ft² (gravity-gradient bias only)."""
    return ESTIMATE_45OP_AM2_PER_KGM2 * _positive('iz_minus_ix_kgm2', iz_minus_ix_kgm2)


@dataclass(frozen=True)
class Winding:
    """A coil wound with a chosen conductor area (§8: "either the maximum current, turns, or conductor area
    can be chosen"): turns (not rounded), peak current, resistance per coil and peak voltage per coil."""

    turns: float
    max_current_a: float
    resistance_ohm: float
    max_voltage_v: float


def wind(d: MagnetDesign, conductor_area_m2: float, conductor: Conductor = COPPER) -> Winding:
    """Turns N = (N a)/a, I_m = (I_m N)/N, R = N ℓ ρ / a, V_m = I_m R for one coil of design ``d``."""
    a = _positive('conductor_area_m2', conductor_area_m2)
    if conductor.name != d.conductor:
        raise MagnetSizingError(f'design {d.structure}/{d.core} is for {d.conductor}, not {conductor.name}')
    n = d.turns_area_m2 / a
    current = d.ampere_turns_a / n
    resistance = n * d.turn_length_m * conductor.resistivity_ohm_m / a
    return Winding(n, current, resistance, current * resistance)


def with_power_supply_orbit(ps: PowerSupplyParams, altitude_m: float, daylight_deg: float) -> PowerSupplyParams:
    """``ps`` with T_n and T_d of another circular orbit / daylight arc."""
    night, day = night_day_s(altitude_m, daylight_deg)
    return replace(ps, night_s=night, day_s=day)
