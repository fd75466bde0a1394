"""One estimator shape: ``observe(frame)``, then ``pose``. Every estimator has it, so any
of them steers any behaviour, and the EKF fed frame by frame is the EKF over the log."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.behaviours import GoToLandmark, GroundTruth, Status
from abcwc.estimation import (
    ChairEkf,
    EkfEstimator,
    GyroOdometry,
    Odometry,
    PoseEstimator,
    run_ekf,
)
from abcwc.navigation.localization import MapLocalizer, wall_points
from abcwc.sim import SimBase
from abcwc.types import Pose2D, Twist

START = Pose2D(2.0, 2.0, 0.0)


def _estimators(chair: SimBase) -> dict[str, PoseEstimator]:
    p = chair.params
    return {
        "Odometry": Odometry(p, start=START),
        "GyroOdometry": GyroOdometry(params=p, start=START),
        "EkfEstimator": EkfEstimator(ChairEkf(START, p)),
        "MapLocalizer": MapLocalizer(wall_points(chair.world.walls), START, p),
        "GroundTruth": GroundTruth(),
    }


@pytest.mark.parametrize("name", ["Odometry", "GyroOdometry", "EkfEstimator",
                                  "MapLocalizer", "GroundTruth"])
def test_every_estimator_steers_a_behaviour_to_its_goal(name):
    chair = SimBase("lab", seed=3, start=START, people=False, lidar=name == "MapLocalizer",
                    errors="ideal")
    estimator = _estimators(chair)[name]
    assert isinstance(estimator, PoseEstimator)
    goal = (5.0, 3.0)
    behaviour = GoToLandmark(goal, estimator, tolerance=0.1, max_speed=0.5)
    chair.run(behaviour, 20.0)
    assert behaviour.status is Status.SUCCEEDED, name
    truth = chair.pose
    assert math.hypot(truth.x - goal[0], truth.y - goal[1]) < 0.2, name
    assert math.hypot(estimator.pose.x - truth.x, estimator.pose.y - truth.y) < 0.1, name


def test_the_ekf_fed_frame_by_frame_is_the_ekf_over_the_log():
    chair = SimBase("lab", seed=4, start=START, people=False)
    frames = []
    log = chair.run(lambda frame: frames.append(frame) or Twist(0.5, 0.3), 8.0)
    frames = frames[1:] + [chair.read()]  # the frame after each period, as the log rows
    states, _ = run_ekf(log, ChairEkf(START, chair.params))
    fed = EkfEstimator(ChairEkf(START, chair.params))
    poses = []
    for frame in frames:
        fed.observe(frame)
        poses.append(fed.pose.as_array())
    np.testing.assert_allclose(np.array(poses)[:, :2], states[:, :2], atol=1e-12)


def test_an_estimator_refuses_frames_out_of_time_order():
    chair = SimBase("lab", seed=4, people=False)
    fed = EkfEstimator(ChairEkf(chair.pose, chair.params))
    later = chair.step()
    fed.observe(later)
    with pytest.raises(ValueError, match="time order"):
        fed.observe(later)
