"""Tests of dynamics.wheels_model (spec §4): square law, capacity, Table 4-6, 4-wheel cluster."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common import units
from dynamics.errors import DynamicsError
from dynamics.wheels_model import (
    DEFAULT_TORQUE_GAIN_NM_PER_V2,
    DEFAULT_WHEEL_CAPACITY_NMS,
    ReactionWheels,
    WheelsConfig,
    four_cant20_axes_body,
)
from hypothesis import given, settings
from hypothesis import strategies as st

K = DEFAULT_TORQUE_GAIN_NM_PER_V2
H_W = DEFAULT_WHEEL_CAPACITY_NMS
S20, C20 = math.sin(math.radians(20.0)), math.cos(math.radians(20.0))
#: Table 4-6 (seed 002), body-axis capacity / H_w.
TABLE_4_6 = {4: np.array([0.684, 1.328, 1.328]), 3: np.array([0.342, 0.664, 0.664])}
#: The same from the cluster geometry: per-axis lever of one wheel, |a_i| = (sin20, cos20 cos45, ...),
#: times 2 with four wheels (pairs share each box corner) and 1 with three.
GEOMETRY = {4: 2.0 * np.array([S20, C20 / math.sqrt(2.0), C20 / math.sqrt(2.0)]),
            3: np.array([S20, C20 / math.sqrt(2.0), C20 / math.sqrt(2.0)])}


def test_default_gain_gives_average_torque_at_v_sat() -> None:
    assert units.nms_to_ftlbs(K * 17.1 ** 2) == pytest.approx(0.117, rel=1e-12)


@settings(derandomize=True, max_examples=100)
@given(st.lists(st.floats(-40.0, 40.0), min_size=3, max_size=3))
def test_square_law_torque_with_voltage_clip(volts: list[float]) -> None:
    wheels = ReactionWheels(WheelsConfig())
    h_start, hdot = wheels.step(np.array(volts), 0.5)
    v = np.clip(volts, -17.1, 17.1)
    assert np.array_equal(h_start, np.zeros(3))
    assert np.allclose(hdot, K * v * np.abs(v), rtol=1e-12, atol=1e-18)
    assert np.allclose(wheels.momentum_body_nms(), 0.5 * hdot, rtol=1e-12, atol=1e-18)


def test_voltage_beyond_saturation_gives_no_more_torque() -> None:
    _, hdot_sat = ReactionWheels(WheelsConfig()).step(np.array([17.1, -17.1, 17.1]), 0.5)
    _, hdot_big = ReactionWheels(WheelsConfig()).step(np.array([100.0, -30.0, 17.2]), 0.5)
    assert np.array_equal(hdot_sat, hdot_big)
    assert hdot_sat[1] == pytest.approx(-K * 17.1 ** 2)


def test_capacity_reached_mid_step_and_driving_back_out() -> None:
    wheels = ReactionWheels(WheelsConfig())
    caps = wheels.wheel_capacities_nms()
    t_max = K * 17.1 ** 2
    gap = 0.3 * t_max  # 0.3 s of full torque left before the z wheel's capacity
    wheels = ReactionWheels(WheelsConfig(), h0_body_nms=np.array([0.0, 0.0, caps[2] - gap]))
    h_start, hdot = wheels.step(np.array([0.0, 0.0, 17.1]), 1.0)
    assert hdot[2] == pytest.approx(gap / 1.0, rel=1e-12)  # step average reduced, not t_max
    assert wheels.momentum_body_nms()[2] == caps[2]
    assert wheels.saturated()[2]
    _, hdot = wheels.step(np.array([0.0, 0.0, 17.1]), 0.5)
    assert hdot[2] == 0.0  # no more torque in the saturating direction
    _, hdot = wheels.step(np.array([0.0, 0.0, -10.0]), 0.5)
    assert hdot[2] == pytest.approx(-K * 100.0, rel=1e-12)  # out of saturation
    assert not wheels.saturated()[2]


def test_three_orthogonal_yaw_wheel_saturates_at_39_ft_lb_sec() -> None:
    wheels = ReactionWheels(WheelsConfig())
    caps_ftlbs = units.nms_to_ftlbs(wheels.wheel_capacities_nms())
    assert caps_ftlbs[2] == pytest.approx(39.0, rel=1e-12)
    assert units.nms_to_ftlbs(H_W) == pytest.approx(29.4, abs=0.1)
    assert np.allclose(wheels.capacity_per_axis_nms(), wheels.wheel_capacities_nms())
    three = ReactionWheels(WheelsConfig(orthogonal_equivalent_active_wheels=3))
    assert np.allclose(three.wheel_capacities_nms(), 0.5 * wheels.wheel_capacities_nms())


def test_four_cant20_axes_geometry() -> None:
    axes = four_cant20_axes_body()
    assert np.allclose(np.linalg.norm(axes, axis=0), 1.0)
    # Canted 20° from the Y-Z plane.
    assert np.allclose(np.degrees(np.arcsin(axes[0])), 20.0)
    # Projections on the Y-Z plane 90° apart, symmetric about Y and Z.
    ang = np.degrees(np.arctan2(axes[2], axes[1])) % 360.0
    assert np.allclose(np.diff(np.sort(ang)), 90.0)
    assert np.allclose(np.sort(np.abs(axes[1])), np.sort(np.abs(axes[2])))


@pytest.mark.parametrize("failed", [None, 0, 1, 2, 3])
def test_table_4_6_capacity_ratios(failed: int | None) -> None:
    active = 4 if failed is None else 3
    wheels = ReactionWheels(WheelsConfig(layout="four_cant20", failed_wheel=failed))
    ratio = wheels.capacity_per_axis_nms() / H_W
    assert np.allclose(ratio, GEOMETRY[active], rtol=1e-9)
    assert np.allclose(ratio, TABLE_4_6[active], rtol=0.01)
    # The three-orthogonal model built on the same column carries the same capacities.
    ortho = ReactionWheels(WheelsConfig(orthogonal_equivalent_active_wheels=active))
    assert np.allclose(ortho.capacity_per_axis_nms() / H_W, GEOMETRY[active], rtol=1e-9)


@pytest.mark.parametrize("failed", [None, 2])
def test_four_wheel_cluster_reproduces_body_torque(failed: int | None) -> None:
    wheels = ReactionWheels(WheelsConfig(layout="four_cant20", failed_wheel=failed))
    volts = np.array([6.0, -9.0, 4.0])
    _, hdot = wheels.step(volts, 0.5)
    assert np.allclose(hdot, K * volts * np.abs(volts), rtol=1e-10)
    if failed is not None:
        assert wheels.wheel_momenta_nms()[failed] == 0.0
        assert wheels.wheel_torques_nm()[failed] == 0.0
    assert np.allclose(wheels.wheel_axes_body() @ wheels.wheel_momenta_nms(), wheels.momentum_body_nms())


def test_four_wheel_torque_limit_keeps_direction() -> None:
    wheels = ReactionWheels(WheelsConfig(layout="four_cant20", failed_wheel=0))
    volts = np.array([17.1, 17.1, -17.1])
    _, hdot = wheels.step(volts, 0.5)
    request = K * volts * np.abs(volts)
    assert np.max(np.abs(wheels.wheel_torques_nm())) == pytest.approx(K * 17.1 ** 2)
    assert np.linalg.norm(hdot) < np.linalg.norm(request)
    assert np.allclose(hdot / np.linalg.norm(hdot), request / np.linalg.norm(request), atol=1e-12)


def test_config_validation() -> None:
    with pytest.raises(DynamicsError, match="layout"):
        WheelsConfig(layout="pyramid")
    with pytest.raises(DynamicsError, match="failed_wheel"):
        WheelsConfig(failed_wheel=1)
    with pytest.raises(DynamicsError, match="failed_wheel"):
        WheelsConfig(layout="four_cant20", failed_wheel=4)
    with pytest.raises(DynamicsError):
        WheelsConfig(v_sat_v=float("nan"))
    with pytest.raises(DynamicsError, match="capacit"):
        ReactionWheels(WheelsConfig(), h0_body_nms=np.array([0.0, 0.0, 60.0]))
    with pytest.raises(DynamicsError, match="dt_s"):
        ReactionWheels(WheelsConfig()).step(np.zeros(3), -1.0)
