"""SensorFrame: range readings keyed by frame id, the named accessors over them, and
make_frame's chair-at-rest defaults."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from abcwc.params import default_params
from abcwc.sim import SimBase
from abcwc.types import (
    DEPTH_SCAN_FRAME,
    IR_FRAMES,
    LIDAR_FRAME,
    SONAR_FRAME,
    LaserScan,
    Pose2D,
    SimTruth,
    make_frame,
)


def _scan(n: int = 4) -> LaserScan:
    return LaserScan(-math.pi, 2 * math.pi / n, 0.15, 12.0, np.arange(1.0, n + 1.0))


def test_simulated_frame_keys_every_range_sensor_by_its_frame_id():
    chair = SimBase(seed=1, lidar=True, depth_scan=True, people=False)
    chair.run(lambda f: None, 0.2)  # every 10 Hz sensor has read by now
    frame = chair.frame
    assert list(frame.readings) == [SONAR_FRAME, *IR_FRAMES, LIDAR_FRAME, DEPTH_SCAN_FRAME]
    assert IR_FRAMES == tuple(f"ir_{k}_link" for k in range(6))
    assert frame.readings["sonar_link"] == frame.sonar
    np.testing.assert_array_equal(frame.ir, [frame.readings[f"ir_{k}_link"] for k in range(6)])
    assert frame.lidar is frame.readings["lidar_link"]
    assert frame.depth_scan is frame.readings["depth_scan_link"]
    assert len(frame.lidar.ranges) == 360 and len(frame.depth_scan.ranges) == 320


def test_a_frame_without_scanners_has_no_scan_readings():
    chair = SimBase(seed=1, people=False)
    frame = chair.step()
    assert frame.lidar is None and frame.depth_scan is None
    assert LIDAR_FRAME not in frame.readings and DEPTH_SCAN_FRAME not in frame.readings


def test_replace_changes_readings_of_the_copy_only():
    scan = _scan()
    frame = make_frame(t=1.0, sonar=2.0, lidar=scan, truth=SimTruth(Pose2D(1.0, 2.0, 0.5)))
    blind = dataclasses.replace(frame, truth=None)
    assert blind.truth is None and frame.truth.pose == Pose2D(1.0, 2.0, 0.5)
    assert blind.lidar is scan and blind.sonar == 2.0
    edited = dataclasses.replace(frame, sonar=0.6, ir=np.full(6, 0.4), lidar=None)
    assert edited.sonar == 0.6 and edited.lidar is None and LIDAR_FRAME not in edited.readings
    np.testing.assert_array_equal(edited.ir, np.full(6, 0.4))
    assert frame.sonar == 2.0 and frame.lidar is scan and np.isinf(frame.ir).all()


def test_ir_setter_replaces_the_whole_ring():
    frame = make_frame(ir=np.arange(6.0))
    frame.ir = np.array([0.5, 0.7])
    np.testing.assert_array_equal(frame.ir, [0.5, 0.7])
    assert "ir_2_link" not in frame.readings


def test_make_frame_is_a_chair_at_rest_in_open_space():
    p = default_params()
    frame = make_frame()
    assert frame.t == 0.0 and (frame.ticks_left, frame.ticks_right) == (0, 0)
    assert frame.gyro_z == 0.0 and frame.truth is None
    assert frame.sonar == p.sonar.max_range == 5.0  # the MB1013's "nothing ahead"
    assert frame.ir.shape == (6,) and np.isposinf(frame.ir).all()
    assert (frame.joystick_fb, frame.joystick_lr) == (254, 254)
    assert (frame.pot_fb, frame.pot_lr) == (128, 128)
    moved = make_frame(t=2.5, ticks_left=10, gyro_z=0.1, truth=SimTruth(Pose2D(1.0, 0.0, 0.0)))
    assert (moved.t, moved.ticks_left, moved.ticks_right, moved.gyro_z) == (2.5, 10, 0, 0.1)
    assert moved.truth == SimTruth(Pose2D(1.0, 0.0, 0.0), collisions=0)
    with pytest.raises(ValueError, match="SimTruth or None"):
        make_frame(truth=Pose2D(1.0, 0.0, 0.0))


def test_a_frame_without_a_sonar_reading_reads_nan():
    frame = make_frame()
    del frame.readings[SONAR_FRAME]
    assert math.isnan(frame.sonar)


def test_a_scan_reading_must_be_a_laser_scan():
    with pytest.raises(ValueError, match="lidar_link reading must be a LaserScan or None"):
        make_frame(lidar=np.ones(4))


def test_simulated_sensors_carry_the_frame_ids_their_readings_are_keyed_by():
    chair = SimBase(seed=1, lidar=True, depth_scan=True, people=False)
    chair.run(lambda f: None, 0.1)
    frame = chair.frame
    assert chair.gyro.frame_id == "imu_link"
    assert frame.readings[chair.sonar.frame_id] == frame.sonar
    assert [frame.readings[k] for k in chair.ir.frame_ids] == list(frame.ir)
    assert frame.readings[chair.lidar.frame_id] is frame.lidar
    assert frame.readings[chair.depth_camera.frame_id] is frame.depth_scan
