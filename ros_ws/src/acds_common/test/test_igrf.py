"""Tests of the IGRF option (acds_common.environment.IgrfField; spec §3 "a higher-order model (IGRF)")."""

from __future__ import annotations

import datetime
import math

import numpy as np
import ppigrf
import pytest
from acds_common import units
from acds_common.environment import (
    IGRF_TILE_M,
    IGRF_TILE_NODES,
    EnvironmentModelError,
    IgrfConfig,
    IgrfField,
    decimal_year_datetime,
)

#: (radius km, colatitude deg, east longitude deg, seconds after the epoch): low orbit over the
#: equator, high latitude in the southern hemisphere a day and a half later, SSS-A apogee (5.2 R_E).
POINTS = ((6371.2 + 417.0, 90.0, 30.0, 0.0),
          (6371.2 + 600.0, 165.0, -60.0, 1.5 * 86400.0),
          (5.2 * units.EARTH_RADIUS_M / 1e3, 60.0, 135.0, 3600.0))
EPOCH_YEAR = 2025.5
GREENWICH0 = 0.7


def _package_b_eci(r_km: float, colat_deg: float, lon_deg: float, t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """ppigrf's own value at the point, turned into ECI by hand: (position m, field T)."""
    date = decimal_year_datetime(EPOCH_YEAR) + datetime.timedelta(seconds=t_s)
    b_r, b_t, b_p = (float(np.ravel(c)[0]) for c in ppigrf.igrf_gc(r_km, colat_deg, lon_deg, date))
    th, ph = math.radians(colat_deg), math.radians(lon_deg) + GREENWICH0 + units.EARTH_RATE_RAD_S * t_s
    up = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    south = np.array([math.cos(th) * math.cos(ph), math.cos(th) * math.sin(ph), -math.sin(th)])
    east = np.array([-math.sin(ph), math.cos(ph), 0.0])
    return r_km * 1e3 * up, (b_r * up + b_t * south + b_p * east) * 1e-9


@pytest.mark.parametrize('point', POINTS)
def test_igrf_reproduces_ppigrf_at_three_points(point: tuple[float, float, float, float]) -> None:
    field = IgrfField(IgrfConfig(epoch_year=EPOCH_YEAR, greenwich_angle0_rad=GREENWICH0))
    r_eci, expected = _package_b_eci(*point)
    got = field.b_eci(r_eci, point[3])
    # ppigrf prints nT to 0.01 nT precision at best (the IGRF-14 coefficients' own); the cache must stay far below.
    assert np.max(np.abs(got - expected)) < 1e-3 * units.NANOTESLA_T
    assert 1e-9 < np.linalg.norm(expected) < 7e-5  # a real Earth field, not a unit slip


def test_igrf_cache_is_a_function_of_position_and_time_only() -> None:
    """The value at (r, t) is the same whatever was asked before, in this object or a fresh one."""
    field = IgrfField(IgrfConfig(epoch_year=EPOCH_YEAR))
    r, t = np.array([6.8e6, 1.2e6, -0.9e6]), 1234.5
    first = field.b_eci(r, t)
    for dx in np.linspace(-3 * IGRF_TILE_M, 3 * IGRF_TILE_M, 7):  # visit other tiles, then come back
        field.b_eci(r + np.array([dx, 0.0, 0.0]), t)
    assert np.array_equal(field.b_eci(r, t), first)
    assert np.array_equal(IgrfField(IgrfConfig(epoch_year=EPOCH_YEAR)).b_eci(r, t), first)


def test_igrf_is_continuous_across_a_tile_face_and_a_day() -> None:
    field = IgrfField(IgrfConfig(epoch_year=EPOCH_YEAR))
    offset = 0.5 * IGRF_TILE_M / (IGRF_TILE_NODES - 1)  # the lattice is offset by half a node spacing
    r = np.array([7 * IGRF_TILE_M + offset, 1.1e6, 0.4e6])
    eps = np.array([1e-3, 0.0, 0.0])
    a, b = field.b_ecef(r - eps, 100.0), field.b_ecef(r + eps, 100.0)
    assert np.max(np.abs(a - b)) < 1e-3 * units.NANOTESLA_T
    day = 86400.0
    assert np.max(np.abs(field.b_ecef(r, day - 1e-3) - field.b_ecef(r, day + 1e-3))) < 1e-3 * units.NANOTESLA_T


def test_igrf_cost_is_one_package_call_per_tile_along_an_orbit() -> None:
    from acds_common.environment import Orbit, OrbitConfig

    field = IgrfField(IgrfConfig(epoch_year=EPOCH_YEAR))
    orbit = Orbit(OrbitConfig())
    for t in np.arange(0.0, 600.0, 0.05):  # 10 minutes at 20 evaluations per second
        field.b_eci(orbit.position_velocity_eci(float(t))[0], float(t))
    # ~7.3 km/s through 1000 km tiles: a handful of ppigrf calls, not one per evaluation.
    assert 3 <= field.evaluations <= 12


def test_igrf_dates_outside_igrf14_are_refused() -> None:
    with pytest.raises(EnvironmentModelError, match='epoch_year'):
        IgrfConfig(epoch_year=2031.0)
    field = IgrfField(IgrfConfig(epoch_year=2029.99))
    with pytest.raises(EnvironmentModelError, match='IGRF-14 covers'):
        field.b_eci(np.array([7e6, 0.0, 0.0]), 30 * 86400.0)
    with pytest.raises(EnvironmentModelError, match='away from the Earth'):
        field.b_eci(np.zeros(3), 0.0)


def test_decimal_year() -> None:
    assert decimal_year_datetime(2025.0) == datetime.datetime(2025, 1, 1)
    assert decimal_year_datetime(2024.5) == datetime.datetime(2024, 7, 2)  # 2024 is a leap year: 183 days in
