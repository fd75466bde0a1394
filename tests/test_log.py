"""A run's log: arrays that match the frames, and a lossless save/load."""

from __future__ import annotations

import numpy as np
import pytest

from abcwc.log import RunLog
from abcwc.sim import SimBase
from abcwc.types import PotCommand, Twist


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
    with pytest.raises(ValueError, match="format 99"):
        RunLog.load(path)
