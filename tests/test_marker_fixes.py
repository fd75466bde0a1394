"""Fixed markers as the EKF's fixes: the range-bearing model and its Jacobian, the
camera's readings of the floor's markers against the simulator's truth, and the filter
fed by them (instead of fixes made from the truth) on seeded drives."""

import math

import numpy as np
import pytest

from abcwc.estimation.ekf import ChairEkf, nees_band, run_ekf
from abcwc.estimation.range_bearing import range_bearing
from abcwc.experiments.nees import MonteCarloResult, calibrate_worn_chair, ekf_run
from abcwc.geometry import compose
from abcwc.perception.markers import FixedMarker, MarkerSighting, sight_markers
from abcwc.sim.base import SimBase
from abcwc.sim.world import WorldError, world_from_dict
from abcwc.types import Pose2D, Twist


def test_range_and_bearing_worked_by_hand():
    """Chair at (1, 2) facing +y, sensor 0.3 m ahead: it sits at (1, 2.3) looking along
    +y. A landmark at (0, 5.3) is 3.162 m away (sqrt(1 + 9)), 18.43 deg to the left."""
    z, _ = range_bearing(np.array([1.0, 2.0, math.pi / 2]), (0.0, 5.3), (0.3, 0.0, 0.0))
    assert z[0] == pytest.approx(math.sqrt(10.0))
    assert z[1] == pytest.approx(math.atan2(1.0, 3.0))


def test_the_jacobian_is_the_models_derivative():
    rng = np.random.default_rng(2)
    for _ in range(20):
        state = np.concatenate([rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, 1),
                                rng.normal(size=3)])
        landmark = tuple(rng.uniform(-8, 8, 2))
        mount = (rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3), rng.uniform(-1, 1))
        _, jacobian = range_bearing(state, landmark, mount)
        numeric = np.zeros_like(jacobian)
        for j in range(len(state)):
            step = np.zeros(len(state))
            step[j] = 1e-6
            up, _ = range_bearing(state + step, landmark, mount)
            down, _ = range_bearing(state - step, landmark, mount)
            difference = up - down
            difference[1] = math.remainder(difference[1], math.tau)
            numeric[:, j] = difference / 2e-6
        assert np.allclose(jacobian, numeric, atol=1e-6)
    with pytest.raises(ValueError, match="at the sensor"):
        range_bearing(np.zeros(3), (0.3, 0.0), (0.3, 0.0, 0.0))


def test_a_sighting_pulls_the_estimate_to_the_truth_and_shrinks_its_covariance():
    """The filter thinks the chair is 0.4 m east of where it is; two markers read
    without noise from the true pose bring it back within 2 cm."""
    truth = Pose2D(2.0, 1.0, 0.3)
    mount = (0.3, 0.0, 0.0)
    ekf = ChairEkf(Pose2D(2.4, 1.0, 0.3), start_std=(0.3, 0.3, 0.05))
    before = np.trace(ekf.filter.P[:2, :2])
    for landmark in ((7.0, 3.0), (6.0, -2.0), (7.0, 3.0), (6.0, -2.0)):
        z, _ = range_bearing(np.array([truth.x, truth.y, truth.theta]), landmark, mount)
        ekf.update_landmark(tuple(z), landmark, mount, np.diag([0.02**2, 0.005**2]))
    assert math.hypot(ekf.pose.x - truth.x, ekf.pose.y - truth.y) < 0.02
    assert np.trace(ekf.filter.P[:2, :2]) < 0.01 * before
    with pytest.raises(ValueError, match="range > 0"):
        ekf.update_landmark((-1.0, 0.0), (7.0, 3.0), mount, np.eye(2))


def test_the_camera_reads_the_floors_markers_within_the_noise_it_claims():
    chair = SimBase("floor", seed=3, camera="gray", people=False)
    markers = {m.marker_id: m for m in chair.world.markers}
    mount = chair.params.depth_scan.mount
    read = 0
    for x, heading in ((5.0, math.pi), (3.5, math.pi), (34.0, 0.0), (30.0, 0.0)):
        chair = SimBase("floor", seed=3, camera="gray", people=False,
                        start=Pose2D(x, 9.0, heading))
        sensor = compose(chair.pose, mount)  # x, y, heading in the world
        origin, facing = sensor[:2], sensor[2]
        for seen in sight_markers(chair.render_camera(), markers):
            centre = markers[seen.marker_id].centre
            true_range = math.hypot(centre[0] - origin[0], centre[1] - origin[1])
            true_bearing = math.remainder(
                math.atan2(centre[1] - origin[1], centre[0] - origin[0]) - facing, math.tau)
            std = np.sqrt(np.diag(seen.covariance))
            assert abs(seen.range - true_range) < 2 * std[0]
            assert abs(math.remainder(seen.bearing - true_bearing, math.tau)) < 2 * std[1]
            read += 1
    assert read >= 4


def test_marker_entries_are_checked():
    base = {"name": "w", "walls": [[[0, 0], [4, 0]]], "places": {"start": [1, 1, 0]}}
    bad = [([{"id": 60, "at": [1, 2, 1], "facing": 0}], "marker_id"),
           ([{"id": 3, "at": [1, 2], "facing": 0}], "at must be"),
           ([{"id": 3, "at": [1, 2, 1]}], "must be an object"),
           ([{"id": 3, "at": [1, 2, 1], "facing": 0},
             {"id": 3, "at": [2, 2, 1], "facing": 0}], "each id once")]
    for markers, message in bad:
        with pytest.raises(WorldError, match=message):
            world_from_dict({**base, "markers": markers})
    assert FixedMarker(3, (1.0, 2.0, 1.0), 0.0).width == pytest.approx(0.3 * 8 / 6)


def test_run_ekf_needs_the_landmarks_for_its_sightings():
    chair = SimBase("floor", seed=0, people=False)
    log = chair.drive(Twist(0.0, 0.0), 0.2)
    sighting = MarkerSighting(3, 2.0, 0.1, 30.0, 0.0)
    with pytest.raises(ValueError, match="landmarks"):
        run_ekf(log, ChairEkf(chair.pose), sightings={1: [sighting]})


@pytest.fixture(scope="module")
def calibration():
    return calibrate_worn_chair()


def test_marker_fixes_keep_the_filter_near_the_truth_and_honest(calibration):
    """Four seeded minutes on the floor, fixes from the camera's marker readings only:
    the time-averaged NEES inside the chi-square band for four runs, and every final
    error a few centimetres where the raw odometry is off by over a metre. Seeds 1-4:
    chapter 10 records the same drives (``record_marker_drive``, kept on disk)."""
    runs = tuple(ekf_run(seed, 60.0, calibration, fixes="markers") for seed in (1, 2, 3, 4))
    result = MonteCarloResult(runs, 60.0, nees_band(4, dof=3))
    assert result.inside_band, result.summary()
    assert all(run.ekf_final_error < 0.05 for run in result.runs), result.summary()
    assert all(run.odometry_final_error > 0.3 for run in result.runs), result.summary()
