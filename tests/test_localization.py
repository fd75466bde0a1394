"""Map localisation against the simulator's ground truth: scan matches keep the EKF on
the map, a filter too sure of a wrong heading is reset by scans that keep disagreeing,
a filter far off says it is lost rather than taking fixes that do not fit, and a lost
chair finds its place by searching round its estimate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.estimation.ekf import ChairEkf
from abcwc.geometry import wrap_angle
from abcwc.navigation.localization import MapLocalizer, wall_points
from abcwc.sim import SimBase
from abcwc.types import Pose2D, Twist


def _drive(chair: SimBase, localizer: MapLocalizer, seconds: float) -> float:
    """Weave along the floor's corridor, steered by the true pose (the test's harness, not
    the localiser's business); the largest position error of the estimate (m)."""
    worst = 0.0
    for k in range(round(seconds / chair.period)):
        truth = chair.pose
        turn = -1.0 * (truth.y - 9.0) - 1.5 * truth.theta + 0.1 * math.sin(k / 60)
        chair.send(Twist(0.5, max(-0.4, min(0.4, turn))))
        localizer.observe(chair.step())
        truth, estimate = chair.pose, localizer.pose
        worst = max(worst, math.hypot(truth.x - estimate.x, truth.y - estimate.y))
    return worst


def test_wall_points_lie_on_the_walls_and_cover_them():
    walls = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 2.0]])
    points = wall_points(walls, spacing=0.1)
    assert len(points) == 11 + 21
    assert np.allclose(points[:11, 1], 0.0) and np.allclose(points[11:, 0], 1.0)
    assert np.max(np.diff(points[:11, 0])) <= 0.1 + 1e-12


def test_scan_matches_hold_the_estimate_where_odometry_alone_drifts():
    chair = SimBase("floor", seed=21, lidar=True, people=False)  # the worn chair
    with_map = MapLocalizer(wall_points(chair.world.walls), chair.pose)
    worst = _drive(chair, with_map, 40.0)
    chair = SimBase("floor", seed=21, lidar=True, people=False)
    blind = MapLocalizer(wall_points(chair.world.walls), chair.pose, match_interval=1e9)
    _drive(chair, blind, 40.0)
    truth, drifted = chair.pose, blind.pose
    assert with_map.accepted >= 60 and worst < 0.1
    assert math.hypot(truth.x - drifted.x, truth.y - drifted.y) > 2 * worst


def test_a_filter_sure_of_a_wrong_heading_is_reset_by_the_scans():
    chair = SimBase("floor", seed=22, lidar=True, people=False)
    start = chair.pose
    wrong = Pose2D(start.x, start.y, start.theta + 0.15)  # 8.6 degrees off, and sure of it
    ekf = ChairEkf(wrong, chair.params, start_std=(0.01, 0.01, 0.002))
    localizer = MapLocalizer(wall_points(chair.world.walls), start, ekf=ekf)
    _drive(chair, localizer, 8.0)
    assert localizer.relocalisations >= 1
    assert abs(wrap_angle(localizer.pose.theta - chair.pose.theta)) < 0.02
    assert not localizer.lost


def test_a_filter_far_off_the_map_says_it_is_lost():
    chair = SimBase("floor", seed=23, lidar=True, people=False)
    start = chair.pose
    ekf = ChairEkf(Pose2D(start.x + 6.0, start.y - 4.0, start.theta), chair.params)
    localizer = MapLocalizer(wall_points(chair.world.walls), start, ekf=ekf, lost_after=10)
    _drive(chair, localizer, 8.0)
    assert localizer.lost and localizer.accepted == 0


def test_bad_settings_are_refused():
    walls = SimBase("floor", people=False).world.walls
    with pytest.raises(ValueError, match="scan_frame"):
        MapLocalizer(wall_points(walls), Pose2D(2, 9, 0), scan_frame="sonar_link")
    with pytest.raises(ValueError, match="match_interval"):
        MapLocalizer(wall_points(walls), Pose2D(2, 9, 0), match_interval=math.nan)
    with pytest.raises(ValueError, match="spacing"):
        wall_points(walls, spacing=0.0)


def _kidnap(chair: SimBase, dx: float, dy: float, dtheta: float) -> None:
    """Move the simulated chair as a carer lifting and turning it would: its wheels turn
    no tick, so the filter keeps believing the old place (the kidnapped robot)."""
    chair.carry(dx, dy, dtheta)


def test_a_lost_chair_finds_its_place_again_by_searching_round_the_estimate():
    chair = SimBase("floor", seed=24, lidar=True, people=False)
    localizer = MapLocalizer(wall_points(chair.world.walls), chair.pose, lost_after=10)
    _drive(chair, localizer, 6.0)
    _kidnap(chair, 1.0, 0.5, 0.5)  # 1.1 m away, turned 29 degrees: beyond ICP's reach
    for _ in range(300):
        localizer.observe(chair.step())
        if localizer.lost:
            break
    assert localizer.lost  # the scans no longer fit where the filter says it is
    scan = chair.read().lidar
    assert localizer.recover(scan)
    truth, estimate = chair.pose, localizer.pose
    assert math.hypot(truth.x - estimate.x, truth.y - estimate.y) < 0.05
    assert abs(wrap_angle(truth.theta - estimate.theta)) < 0.02
    assert not localizer.lost


def test_a_chair_carried_out_of_the_search_window_stays_lost():
    chair = SimBase("floor", seed=25, lidar=True, people=False)
    localizer = MapLocalizer(wall_points(chair.world.walls), chair.pose)
    _kidnap(chair, 6.0, 0.0, 0.0)  # 6 m down the corridor: beyond the 2 m window
    for _ in range(25):  # a scan taken after the move
        chair.step()
    assert not localizer.recover(chair.read().lidar)


def test_a_person_beside_the_chair_hides_the_walls_but_does_not_make_it_lost():
    """Returns short of the map's walls are explained by things not on it (a person);
    only beams that reach through a wall say the estimate is wrong."""
    from abcwc.sim.world import world_from_dict

    floor = SimBase("floor", people=False).world
    beside = {"name": "beside", "path": [[2.3, 8.36], [2.31, 8.36]], "speed": 0.01,
              "radius": 0.25}  # standing 0.1 m from the chair's right side
    world = world_from_dict({
        "name": "floor+person", "walls": [[list(w[:2]), list(w[2:])] for w in floor.walls],
        "places": {"start": [2.0, 9.0, 0.0]}, "people": [beside]})
    chair = SimBase(world, seed=26, lidar=True)
    # a strict fit (85 % of the points on a wall) that the person's shadow fails
    localizer = MapLocalizer(wall_points(world.walls), chair.pose, lost_after=5,
                             min_fitness=0.85)
    for _ in range(round(10.0 / chair.period)):
        localizer.observe(chair.step())
    assert localizer.rejected >= 10 and localizer.accepted == 0  # every scan refused
    assert not localizer.lost  # but none reached through a wall
    truth = chair.pose
    from abcwc.geometry import transform_points

    points = transform_points(localizer.mount, chair.read().lidar.points())
    here = np.array([truth.x, truth.y, truth.theta])
    assert localizer.see_through_fraction(points, here) < localizer.see_through
    away = here + (0.0, 1.2, 0.0)  # 1.2 m north: across the corridor's wall
    assert localizer.see_through_fraction(points, away) > 0.2


def test_in_a_hall_whose_walls_are_out_of_reach_the_chair_dead_reckons_and_is_not_lost():
    """In the middle of a 40 m hall the 12 m lidar returns nothing: no scan can be
    matched, and none says the estimate is wrong (no beam reaches through a wall). The
    filter dead-reckons, and when a wall comes into reach the scans match again."""
    from abcwc.sim.world import box_world

    world = box_world(40.0, 40.0)
    chair = SimBase(world, seed=27, lidar=True, people=False)
    assert chair.params.lidar.max_range < 20.0  # every wall out of reach at the start
    localizer = MapLocalizer(wall_points(world.walls), chair.pose, lost_after=10)
    for _ in range(round(4.0 / chair.period)):
        localizer.observe(chair.step())
    assert localizer.accepted == 0 and localizer.rejected >= 10
    assert not localizer.lost
    for _ in range(round(22.0 / chair.period)):  # 10 m towards the east wall, at 0.5 m/s
        chair.send(Twist(0.5, 0.0))
        localizer.observe(chair.step())
    assert not localizer.lost and localizer.accepted >= 5  # the wall in reach: matched
    truth, estimate = chair.pose, localizer.pose
    assert math.hypot(truth.x - estimate.x, truth.y - estimate.y) < 0.1
