"""Tests of dynamics.cmg_model: ideal CMG momentum store with a spherical capacity (seed 000 §5)."""

from __future__ import annotations

import numpy as np
import pytest
from acds_common import units
from dynamics.cmg_model import SEED_CAPACITY_NMS, CmgConfig, ControlMomentGyros
from dynamics.errors import DynamicsError
from hypothesis import given, settings
from hypothesis import strategies as st

VEC = st.lists(st.floats(-50.0, 50.0), min_size=3, max_size=3).map(np.array)


def test_seed_capacity() -> None:
    assert units.nms_to_ftlbs(SEED_CAPACITY_NMS) == pytest.approx(12000.0)


@settings(max_examples=50)
@given(VEC, VEC)
def test_commanded_rate_is_delivered_inside_the_envelope(h0: np.ndarray, hdot: np.ndarray) -> None:
    cmg = ControlMomentGyros(CmgConfig(), h0 * 100.0)
    h_start, mean = cmg.step(hdot, 2.0)
    assert np.array_equal(h_start, h0 * 100.0)
    assert np.allclose(mean, hdot, rtol=1e-12, atol=1e-12)
    assert np.allclose(cmg.momentum_body_nms(), h0 * 100.0 + 2.0 * hdot, rtol=1e-12, atol=1e-9)


def test_no_momentum_beyond_capacity_in_the_saturating_direction() -> None:
    cap = 100.0
    cmg = ControlMomentGyros(CmgConfig(cap), np.array([0.0, 0.0, 99.0]))
    h_start, mean = cmg.step(np.array([0.0, 0.0, 5.0]), 1.0)  # would reach 104
    assert h_start[2] == 99.0 and mean == pytest.approx(np.array([0.0, 0.0, 1.0]))
    assert cmg.saturated()
    _, mean = cmg.step(np.array([0.0, 0.0, 5.0]), 1.0)  # at capacity, pushing outward: nothing
    assert np.allclose(mean, 0.0) and np.linalg.norm(cmg.momentum_body_nms()) == pytest.approx(cap)
    _, mean = cmg.step(np.array([3.0, 0.0, 0.0]), 0.01)  # tangential command still turns h
    assert mean[0] > 2.9 and np.linalg.norm(cmg.momentum_body_nms()) == pytest.approx(cap)
    _, mean = cmg.step(np.array([0.0, 0.0, -4.0]), 1.0)  # driving back in works in full
    assert mean == pytest.approx(np.array([0.0, 0.0, -4.0]), abs=1e-9)
    assert not cmg.saturated()


def test_bad_inputs_are_named() -> None:
    with pytest.raises(DynamicsError, match='beyond the CMG capacity'):
        ControlMomentGyros(CmgConfig(10.0), np.array([10.0, 1.0, 0.0]))
    with pytest.raises(DynamicsError, match='capacity_nms'):
        CmgConfig(0.0)
    with pytest.raises(DynamicsError, match='dt_s'):
        ControlMomentGyros(CmgConfig()).step(np.zeros(3), 0.0)
    with pytest.raises(DynamicsError, match='hdot_command_body_nm'):
        ControlMomentGyros(CmgConfig()).step(np.array([np.nan, 0.0, 0.0]), 1.0)
