"""A run's log: arrays that match the frames, and a lossless save/load."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from abcwc.log import CHANNELS, FORMAT_VERSION, LogFileError, LogRecorder, RunLog
from abcwc.params import load_params
from abcwc.sim import SimBase
from abcwc.types import LaserScan, PotCommand, Twist, make_frame


def test_log_records_commands_and_frames(tmp_path):
    chair = SimBase(seed=2, lidar=True)
    commands = [Twist(0.4, 0.1), PotCommand(190, 120), None]
    log = chair.run(lambda f: commands[int(f.t) % 3], 3.0)
    assert len(log) == 150
    np.testing.assert_allclose(log.t, np.arange(1, 151) * 0.02)
    assert np.isnan(log.cmd_twist[60:100]).all() and (log.cmd_pots[60:100] == [190, 120]).all()
    assert (log.cmd_pots[110:] == -1).all()  # nothing sent in the third second
    assert log.lidar is not None and log.lidar.ranges.shape == (31, 360)  # 10 Hz + t=0
    np.testing.assert_allclose(np.diff(log.lidar.stamps[1:]), 0.1)
    frame = chair.frame
    assert (log.ticks[-1] == [frame.ticks_left, frame.ticks_right]).all()
    path = log.save(tmp_path / "drive.npz")
    again = RunLog.load(path)
    for name in ("t", "ticks", "gyro_z", "sonar", "ir", "pots", "cmd_pots", "cmd_twist",
                 "pose", "flags", "collisions"):
        np.testing.assert_array_equal(getattr(again, name), getattr(log, name))
    np.testing.assert_array_equal(again.lidar.ranges, log.lidar.ranges)
    assert again.meta["world"] == "lab" and again.meta["seed"] == 2


def test_loading_a_log_of_another_format_is_refused(tmp_path):
    chair = SimBase()
    log = chair.drive(Twist(0.1, 0), 0.1)
    log.meta["format_version"] = 99
    path = tmp_path / "x.npz"
    np.savez(path, meta=np.array('{"format_version": 99}'), t=log.t)
    with pytest.raises(LogFileError, match=f"^{re.escape(str(path))}: log format 99"):
        RunLog.load(path)


def test_loading_a_missing_file_names_it(tmp_path):
    missing = tmp_path / "nowhere.npz"
    with pytest.raises(FileNotFoundError, match=f"^{re.escape(str(missing))}: no such file"):
        RunLog.load(missing)
    with pytest.raises(IsADirectoryError, match="a folder, not a RunLog file"):
        RunLog.load(tmp_path)


def _text(path: Path) -> None:
    path.write_text("t,x\n0.0,1.0\n")


def _empty(path: Path) -> None:
    path.write_bytes(b"")


def _broken_zip(path: Path) -> None:
    path.write_bytes(b"PK\x03\x04 and then nothing a zip file holds")


@pytest.mark.parametrize("write", [_text, _empty, _broken_zip])
def test_loading_a_file_that_is_not_an_npz_names_it(tmp_path, write):
    path = tmp_path / "drive.npz"
    write(path)
    with pytest.raises(LogFileError, match=f"^{re.escape(str(path))}: not an .npz file"):
        RunLog.load(path)


def test_loading_an_npy_array_names_it(tmp_path):
    path = tmp_path / "poses.npy"
    np.save(path, np.zeros((3, 3)))
    with pytest.raises(LogFileError, match=f"^{re.escape(str(path))}: a single NumPy array"):
        RunLog.load(path)


@pytest.mark.parametrize("arrays, problem", [
    ({"poses": np.zeros((3, 3)), "stamps": np.arange(3.0)},
     "an .npz without a RunLog's 'meta' \\(it holds poses, stamps\\)"),
    ({"meta": np.array("not json")}, "its 'meta' is not a RunLog's"),
    ({"meta": np.array("{}"), "format_version": np.array(2), "channels/x": np.arange(3.0)},
     "not a RunLog of format 2 .*time channel 't'"),
], ids=["other arrays", "meta not json", "no time channel"])
def test_loading_an_npz_that_is_not_a_runlog_names_it(tmp_path, arrays, problem):
    path = tmp_path / "other.npz"
    np.savez(path, **arrays)
    with pytest.raises(LogFileError, match=f"^{re.escape(str(path))}: {problem}"):
        RunLog.load(path)


V1_FIXTURE = Path(__file__).parent / "data" / "runlog_v1_lab_seed4.npz"


def _fixture_drive() -> RunLog:
    """The drive the v1 fixture recorded (1 s, lab, seed 4), recorded again now (with the
    gyro model of the time, today's "pessimistic" variant, and the bare chair of the
    time: no safety filter in the loop)."""
    chair = SimBase(seed=4, lidar=True, depth_scan=True, params=load_params(gyro="pessimistic"))
    return chair.drive(Twist(0.5, 0.3), 1.0, safety=None)


def test_a_version_1_file_still_loads_as_the_same_drive():
    with np.load(V1_FIXTURE) as raw:  # the fixture really is the old fixed-field format
        assert "ticks" in raw.files and "format_version" not in raw.files
    old = RunLog.load(V1_FIXTURE)
    now = _fixture_drive()
    assert old.meta["format_version"] == 1 and len(old) == len(now) == 50
    assert sorted(now.channels) == sorted(CHANNELS)
    # version 1 had every channel but the safety filter's two, which came later
    assert sorted(old.channels) == sorted(set(CHANNELS) - {"safety", "wanted_twist"})
    for name in old.channels:
        # the same to the last bits: the IR mounts now come from the URDF, whose ring
        # angles are wrapped to +-pi (cos(-120 deg) and cos(240 deg) differ in the 16th
        # digit)
        np.testing.assert_allclose(getattr(old, name), getattr(now, name), rtol=0,
                                   atol=1e-12, err_msg=name)
        assert getattr(old, name).dtype == getattr(now, name).dtype, name
    assert set(old.scans) == {"lidar_link", "depth_scan_link"}
    np.testing.assert_array_equal(old.lidar.ranges, now.lidar.ranges)
    np.testing.assert_array_equal(old.depth_scan.stamps, now.depth_scan.stamps)
    assert old.depth_scan.range_max == 4.0  # the Kinect's 4 m (chair.toml)


def test_save_writes_version_2_with_named_channels(tmp_path):
    log = _fixture_drive()
    path = log.save(tmp_path / "drive.npz")
    with np.load(path) as raw:
        assert int(raw["format_version"]) == 2 == FORMAT_VERSION
        assert "channels/ticks" in raw.files and "scans/lidar_link/ranges" in raw.files
        assert "ticks" not in raw.files
    again = RunLog.load(path)
    assert again.meta["format_version"] == 2 and again.meta["seed"] == 4
    for name, values in log.channels.items():
        np.testing.assert_array_equal(again.channels[name], values)
    np.testing.assert_array_equal(again.depth_scan.ranges, log.depth_scan.ranges)


def test_channels_read_as_attributes_and_replace_swaps_one():
    log = _fixture_drive()
    assert log.ticks is log.channels["ticks"] and log.pose.shape == (50, 3)
    assert "gyro_z" in dir(log)
    with pytest.raises(AttributeError, match="no channel or attribute 'speed'"):
        _ = log.speed
    blind = dataclasses.replace(log, pose=np.full_like(log.pose, np.nan))
    assert np.isnan(blind.pose).all() and np.isfinite(log.pose).all()
    assert blind.ticks is log.ticks and blind.meta is log.meta and blind.lidar is log.lidar


def test_every_channel_needs_one_row_per_stamp():
    with pytest.raises(ValueError, match="'ticks' has \\(3, 2\\) values; .* \\(4\\)"):
        RunLog(t=np.arange(4.0), ticks=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="time channel 't'"):
        RunLog(ticks=np.zeros((3, 2)))


def test_select_keeps_the_rows_asked_for_in_every_channel():
    log = _fixture_drive()
    late = log.t >= 0.5
    part = log.select(late)
    assert len(part) == 26 and part.t[0] == pytest.approx(0.5)
    for name, values in log.channels.items():
        np.testing.assert_array_equal(part.channels[name], values[late])


def test_readings_other_than_sonar_and_ir_are_recorded_by_frame_id():
    recorder = LogRecorder({"source": "test"})
    scan = LaserScan(-1.0, 1.0, 0.1, 5.0, np.array([1.0, 2.0, 3.0]), stamp=0.02)
    for k in range(3):
        readings = {"rear_sonar_link": 1.5 + k} if k != 1 else {}
        frame = make_frame(t=0.02 * (k + 1), readings=readings, sonar=2.0)
        frame.readings["rear_scan_link"] = scan  # the same scan every period: kept once
        recorder.add(frame, None, None)
    log = recorder.build()
    np.testing.assert_array_equal(log.rear_sonar_link, [1.5, np.nan, 3.5])
    assert log.scans["rear_scan_link"].ranges.shape == (1, 3)
    np.testing.assert_array_equal(log.sonar, [2.0, 2.0, 2.0])
    assert "sonar_link" not in log.channels and "ir_0_link" not in log.channels
    assert log.ir.shape == (3, 6)


def test_summary_of_an_empty_log_and_of_a_log_without_ground_truth():
    assert LogRecorder().build().summary() == "empty log: 0 rows"
    log = _fixture_drive()
    assert log.summary() == "1.0 s, 0.36 m driven, 0 collisions"
    blind = dataclasses.replace(log, pose=np.full_like(log.pose, np.nan))
    assert blind.summary() == "1.0 s, distance driven: unknown (no ground truth), 0 collisions"
    assert "nan" not in blind.summary()
