"""Parameters: sensors keyed by frame id, and the thesis's navigation numbers."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from abcwc.description import DescriptionError
from abcwc.params import (
    ChairParams,
    IrRingParams,
    NavigationParams,
    default_params,
    load_navigation_params,
    load_params,
)
from abcwc.paths import data_dir
from abcwc.sim import SimBase
from abcwc.types import DEPTH_SCAN_FRAME, IR_FRAMES, LIDAR_FRAME, SONAR_FRAME


def test_sensors_are_keyed_by_the_frame_ids_of_their_readings():
    p = default_params()
    assert list(p.sensors) == ["imu_link", SONAR_FRAME, *IR_FRAMES, DEPTH_SCAN_FRAME,
                               LIDAR_FRAME]
    assert p.sensors["imu_link"] is p.gyro and p.sensors["sonar_link"] is p.sonar
    assert all(p.sensors[f"ir_{k}_link"] is p.ir for k in range(6))
    assert p.sensors["depth_scan_link"] is p.depth_scan and p.sensors["lidar_link"] is p.lidar
    # table 3: the MB1013 reads 0.30..5.0 m; table 4: the Sharp IR 0.2..1.5 m
    assert (p.sensors["sonar_link"].min_range, p.sensors["sonar_link"].max_range) == (0.30, 5.0)
    assert (p.sensors["ir_3_link"].min_range, p.sensors["ir_3_link"].max_range) == (0.20, 1.50)


def test_every_simulated_reading_has_a_sensor_spec():
    chair = SimBase(seed=0, lidar=True, depth_scan=True, people=False)
    chair.run(lambda f: None, 0.1)
    assert set(chair.frame.readings) <= set(chair.params.sensors)


def test_replacing_a_sensor_changes_the_mapping_too():
    p = default_params()
    quiet = dataclasses.replace(p, lidar=dataclasses.replace(p.lidar, noise_std=0.0))
    assert quiet.sensors["lidar_link"].noise_std == 0.0 and p.sensors["lidar_link"].noise_std > 0


def test_an_ir_ring_needs_one_frame_id_and_one_mount_per_ranger():
    with pytest.raises(ValueError, match="6 rangers but 2 frame ids"):
        IrRingParams(10, 0.2, 1.5, 0.01, ("a", "b"))
    with pytest.raises(ValueError, match="6 rangers but 1 mounts"):
        IrRingParams(10, 0.2, 1.5, 0.01, tuple("abcdef"), ((0.0, 0.0, 0.0),))


def _chair_files(tmp_path, toml=lambda s: s, urdf=lambda s: s):
    (tmp_path / "chair.toml").write_text(toml((data_dir() / "chair.toml").read_text()))
    (tmp_path / "chair.urdf").write_text(urdf((data_dir() / "chair.urdf").read_text()))
    return tmp_path / "chair.toml"


def test_a_chair_file_names_its_frames_and_the_urdf_places_them(tmp_path):
    rename = lambda s: s.replace('"lidar_link"', '"laser"')  # noqa: E731
    p = load_params(_chair_files(tmp_path, rename, rename))
    assert isinstance(p, ChairParams) and "laser" in p.sensors and "lidar_link" not in p.sensors
    assert p.lidar.mount == pytest.approx((0.10, 0.0, 0.0)) and p.lidar.height == 0.35
    # a frame the TOML names that the URDF lacks is an error naming the frame
    with pytest.raises(DescriptionError, match="no link 'laser'"):
        (tmp_path / "toml_only").mkdir()
        load_params(_chair_files(tmp_path / "toml_only", rename))


def test_the_urdf_gives_the_footprint_wheels_and_mounts():
    """The numbers the library used to keep in chair.toml, now read from the URDF:
    thesis table 2 (610 x 482 mm, axle 0.16 m from the back), 4.2.1 (195 mm wheels),
    A.18 (440 mm wheel base), the six IR rangers 60 degrees apart on a 0.20 m ring."""
    p = load_params()
    assert (p.length, p.width) == (0.610, 0.482)
    assert p.axle_to_rear == pytest.approx(0.16, abs=1e-12)
    assert p.drive_wheel_diameter == pytest.approx(0.195) and p.wheel_base == pytest.approx(0.44)
    assert p.sonar.mount == pytest.approx((0.40, 0.0, 0.0))
    assert p.depth_scan.mount == pytest.approx((0.30, 0.0, 0.0))
    ring = p.ir.mounts
    centre = np.array([0.14, 0.0])
    np.testing.assert_allclose(np.hypot(*(ring[:, :2] - centre).T), 0.20)
    np.testing.assert_allclose(np.degrees(ring[:, 2]) % 360, 60.0 * np.arange(6), atol=1e-9)
    # each ranger faces straight out from the ring's centre
    outward = np.arctan2(ring[:, 1] - centre[1], ring[:, 0] - centre[0])
    np.testing.assert_allclose(np.cos(outward - ring[:, 2]), 1.0)


def test_a_chair_urdf_without_a_chassis_box_is_refused(tmp_path):
    no_box = lambda s: s.replace('<box size="0.610 0.482 0.30"/>',  # noqa: E731
                                 '<sphere radius="0.3"/>')
    with pytest.raises(DescriptionError, match="chassis collision box"):
        load_params(_chair_files(tmp_path, urdf=no_box))


def test_navigation_numbers_match_the_thesis():
    nav = load_navigation_params()
    assert isinstance(nav, NavigationParams)
    # appendix A.17, Base_local_planner_params and Costmap_common_params
    assert nav.goal_tolerance.xy == 0.5 and nav.goal_tolerance.yaw == 3.0
    assert nav.goal_tolerance.latch_xy is False
    assert nav.costmap.inflation_radius == 0.05 and nav.costmap.robot_radius == 0.5
    assert nav.costmap.obstacle_range == 3.0 and nav.costmap.raytrace_range == 3.0
    assert nav.local_planner.max_vel_x == 1.28 and nav.local_planner.max_vel_theta == 1.57
    assert nav.local_planner.acc_lim_x == 3.6 and nav.local_planner.sim_time == 1.0
    assert (nav.local_planner.vx_samples, nav.local_planner.vtheta_samples) == (8, 20)
    assert nav.local_planner.dwa is True
    assert nav.move_base.base_local_planner == "dwa_local_planner/DWAPlannerROS"
    assert nav.move_base.controller_frequency == 5.0 and nav.move_base.planner_patience == 5.0
    assert nav.global_costmap.resolution == 0.02 and nav.global_costmap.global_frame == "map"
    assert nav.local_costmap.rolling_window is True and nav.local_costmap.width == 5.0
    # table 7: 45 deg at 1000 mm, 5.625 deg more per 100 mm, 90 deg at 200 mm
    s = nav.sonar_avoidance
    assert (s.turn_within, s.reverse_within, s.min_turn_deg, s.max_turn_deg) == (1.0, 0.2, 45, 90)
    steps = round((s.turn_within - s.reverse_within) / s.step_distance)
    assert math.isclose(s.min_turn_deg + steps * s.turn_step_deg, s.max_turn_deg)


def test_navigation_params_are_frozen():
    nav = load_navigation_params()
    with pytest.raises(dataclasses.FrozenInstanceError):
        nav.goal_tolerance.xy = 0.1  # type: ignore[misc]


def test_a_navigation_file_with_a_typo_or_a_gap_is_refused(tmp_path):
    text = (data_dir() / "navigation.toml").read_text()
    path = tmp_path / "navigation.toml"
    path.write_text(text.replace("inflation_radius =", "inflation_radus ="))
    with pytest.raises(ValueError, match=r"\[costmap\] has unknown keys \['inflation_radus'\]"):
        load_navigation_params(path)
    path.write_text(text.replace("[goal_tolerance]", "[goal_tolerances]"))
    with pytest.raises(ValueError, match="unknown tables \\['goal_tolerances'\\]"):
        load_navigation_params(path)
    path.write_text(text.replace("xy = 0.5", "# xy = 0.5"))
    with pytest.raises(ValueError, match=r"\[goal_tolerance\] is incomplete"):
        load_navigation_params(path)


def test_internal_helpers_take_params_explicitly():
    from abcwc.checks.ch00 import reference_distance_ahead
    from abcwc.control.interface_board import joystick_state
    from abcwc.types import make_frame

    p = default_params()
    with pytest.raises(TypeError, match="params"):
        joystick_state(254, 254)  # type: ignore[call-arg]
    assert joystick_state(254, 254, p) == "neutral" and joystick_state(300, 254, p) == "deflected"
    with pytest.raises(TypeError, match="params"):
        reference_distance_ahead(make_frame(sonar=1.0))  # type: ignore[call-arg]
    assert reference_distance_ahead(make_frame(sonar=1.0), p) == pytest.approx(1.0 + 0.40)
