"""Going to a landmark (thesis 4.2.2, eqns 11-12, A.10) in the simulator."""

import math

import numpy as np
import pytest

from abcwc.behaviours import GoToLandmark, ThesisGoToLandmark, distance_and_bearing
from abcwc.estimation import Odometry
from abcwc.sim.base import SimBase
from abcwc.sim.world import world_from_dict
from abcwc.types import Pose2D

OPEN = world_from_dict({"name": "open", "places": {"start": [0, 0, 0]},
                        "walls": [[[-10, -10], [10, -10], [10, 10], [-10, 10], [-10, -10]]]})
GOAL = (-2.0, 3.0)  # behind and to the left: needs a big turn first


def test_distance_and_bearing_wraps():
    rho, alpha = distance_and_bearing(Pose2D(0, 0, 3.0), (-1.0, -0.1))
    assert rho == pytest.approx(math.hypot(1, 0.1))
    assert abs(alpha) < 0.3  # not 2 pi - 0.24


def _drive(controller_class, **options):
    sim = SimBase(OPEN, errors="ideal", people=False)
    controller = controller_class(GOAL, Odometry(start=sim.pose), **options)
    log = sim.run(controller, 30.0)
    steps = np.hypot(*np.diff(log.pose[:, :2], axis=0).T)
    moving = np.flatnonzero(steps > 1e-5)
    error = math.hypot(log.pose[-1, 0] - GOAL[0], log.pose[-1, 1] - GOAL[1])
    return controller, error, log.distance_travelled(), log.t[moving[-1]]


def test_thesis_and_proportional_controllers_reach_the_goal():
    thesis, error_t, length_t, time_t = _drive(ThesisGoToLandmark)
    better, error_p, length_p, time_p = _drive(GoToLandmark)
    assert thesis.reached and better.reached
    assert error_t <= 0.5  # the thesis's tolerance (A.10)
    assert error_p <= 0.1  # a 0.1 m tolerance, stopping included
    assert time_p < time_t  # turns while driving instead of stopping to turn
    straight = math.hypot(*GOAL)
    assert length_p < 1.2 * straight and length_t < straight


def test_goal_is_validated():
    with pytest.raises(ValueError, match="goal"):
        GoToLandmark((float("nan"), 1.0), Odometry())
    with pytest.raises(ValueError, match="tolerance"):
        GoToLandmark((1.0, 1.0), Odometry(), tolerance=0)
