"""A recorded drive replayed: the same commands at the same times give the same drive
on the simulator (judged against the run that was recorded), and a drive file or a
command list that is not one is refused."""

from __future__ import annotations

import numpy as np
import pytest

from abcwc.behaviours.base import Status
from abcwc.behaviours.recorded import RecordedDrive, read_drive
from abcwc.behaviours.waypoints import FollowWaypoints, GroundTruth
from abcwc.paths import data_dir
from abcwc.sim import SimBase


def test_a_replayed_drive_retraces_the_recorded_one():
    """A waypoint drive's commands, recorded at every frame and replayed on the same
    simulator (same seed and start), give the same true poses."""
    route = FollowWaypoints([(4.0, 9.0), (6.0, 8.6), (8.0, 9.2)], GroundTruth())
    recorded: list[tuple[float, float, float]] = []

    def recording(frame):
        command = route(frame)
        recorded.append((frame.t, command.v, command.w))
        return command

    first = SimBase("floor", seed=3, people=False)
    original = first.run(recording, 12.0)
    rows = np.array(recorded)
    rows[:, 0] -= rows[0, 0]
    rows = np.vstack([rows, [12.0, 0.0, 0.0]])
    drive = RecordedDrive(rows)
    again = SimBase("floor", seed=3, people=False).run(drive, 12.0)
    assert np.abs(np.asarray(again.pose) - np.asarray(original.pose)).max() < 1e-9
    assert original.pose[-1][0] > 6.0  # it drove the route


def test_each_command_holds_until_the_next_and_the_drive_ends_at_the_last():
    drive = RecordedDrive(np.array([[0.0, 0.4, 0.0], [1.0, 0.0, 0.5], [2.0, 0.0, 0.0]]))
    log = SimBase("floor", seed=4, people=False, errors="ideal").run(drive, 3.0)
    moved = np.hypot(*(log.pose[-1, :2] - log.pose[0, :2]))
    assert 0.1 < moved < 0.45  # at most 0.4 m/s for 1 s, ramped by the safety filter
    assert log.pose[-1, 2] - log.pose[0, 2] > 0.2  # then it turned left
    assert drive.status is Status.SUCCEEDED
    drive.reset()
    assert drive.running


def test_the_shipped_survey_is_a_drive():
    rows = read_drive(data_dir() / "drives" / "floor_survey.csv")
    assert rows.shape[1] == 3 and rows[0, 0] == 0.0 and rows[-1, 0] == 200.0
    assert (np.diff(rows[:, 0]) > 0).all() and np.abs(rows[:, 1]).max() <= 1.0


@pytest.mark.parametrize("rows, message", [
    (np.zeros((1, 3)), "K >= 2"),
    (np.zeros((3, 2)), "rows of t, v, w"),
    (np.array([[0.0, 0.1, 0.0], [0.0, 0.0, 0.0]]), "increase"),
    (np.array([[0.5, 0.1, 0.0], [1.0, 0.0, 0.0]]), "start at 0"),
    (np.array([[0.0, np.nan, 0.0], [1.0, 0.0, 0.0]]), "finite"),
])
def test_a_command_list_that_is_not_a_drive_is_refused(rows, message):
    with pytest.raises(ValueError, match=message):
        RecordedDrive(rows)


def test_a_file_without_the_header_is_refused(tmp_path):
    path = tmp_path / "drive.csv"
    path.write_text("# a comment\n0.0,0.1,0.0\n1.0,0.0,0.0\n")
    with pytest.raises(ValueError, match="t_s,v_m_per_s,w_rad_per_s"):
        read_drive(path)
