"""Is the EKF honest? Seeded Monte Carlo runs on the floor world, scored by the NEES.

The experiment behind issue-level figures and tests (Bar-Shalom, Li and Kirubarajan,
*Estimation with Applications to Tracking and Navigation*, 2001, ch. 5.4):

1. :func:`calibrate_worn_chair`: UMBmark (one square each way, Borenstein and Feng 1996)
   plus a straight-line scale on the worn chair in an open hall, then the corrected
   squares again; what they still miss per metre, ``E_max,syst / (4 L)``, is the
   odometry's residual relative error that :func:`~abcwc.estimation.ekf.noise_from_models`
   needs.
2. :func:`ekf_run`: one seed: stand still 2 s (the gyro-bias prior), drive the floor
   world's mixed route (:func:`abcwc.behaviours.floor_mixed_drive`, steered by ground
   truth so no estimator changes the path), and filter the log with a landmark fix every
   ``fix_every`` seconds.
3. :func:`ekf_monte_carlo`: many seeds (in parallel processes if asked); the NEES
   averaged over runs at every step, its mean over time, and the two-sided 95 %
   chi-square band for that many runs (:func:`~abcwc.estimation.ekf.nees_band`).

The fixes of step 2 come either from the simulator's truth with noise of
:data:`FIX_STD` (``fixes="truth"``), or from the chair's camera reading the floor's
fixed ArUco markers (``fixes="markers"``: :func:`record_marker_drive`, the drive and its
sightings kept on disk, the same drives chapter 10 records; each reading's range and
bearing is an update, :meth:`~abcwc.estimation.ekf.ChairEkf.update_landmark`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from abcwc.behaviours import FollowWaypoints, GroundTruth, floor_mixed_drive
from abcwc.estimation.ekf import (
    ChairEkf,
    gyro_bias_prior,
    nees,
    nees_band,
    noise_from_models,
    run_ekf,
)
from abcwc.estimation.odometry import odometry_from_log
from abcwc.estimation.umbmark import THESIS_SIDE, e_max_syst, umbmark_corrections
from abcwc.experiments.disk_cache import cached_on_disk
from abcwc.experiments.truth_fixes import absolute_fixes
from abcwc.experiments.umbmark_trials import calibrate_distance_scale, run_umbmark
from abcwc.log import RunLog
from abcwc.params import default_params
from abcwc.perception.markers import MarkerSighting, sight_markers
from abcwc.sim.base import SimBase
from abcwc.sim.world import box_world, load_world
from abcwc.types import CAMERA_FRAME, CameraImage, Pose2D, Twist

FIX_STD = (0.05, 0.05, 0.02)
"""m, m, rad: how good one landmark sighting is."""
STILL_SECONDS = 2.0
"""Standing still before each drive: the gyro-bias prior."""
HALL_SIZE = 20.0
"""m: the open square hall the UMBmark squares are driven in."""


@dataclass(frozen=True)
class OdometryCalibration:
    """UMBmark's result for the EKF: wheel factors, wheel base (m), residual (per metre)."""

    correction: tuple[float, float]
    wheel_base: float
    residual_rel: float


@dataclass(frozen=True)
class EkfRun:
    """One seeded drive: the NEES at every step and both final position errors (m)."""

    nees: np.ndarray
    ekf_final_error: float
    odometry_final_error: float


@dataclass(frozen=True)
class MonteCarloResult:
    """Many seeded drives, and the NEES band they are judged by."""

    runs: tuple[EkfRun, ...]
    seconds: float
    band: tuple[float, float]

    @property
    def average_nees(self) -> float:
        """The NEES averaged over runs at each step, then over time."""
        return float(np.mean([run.nees for run in self.runs], axis=0).mean())

    @property
    def inside_band(self) -> bool:
        low, high = self.band
        return low < self.average_nees < high

    def summary(self) -> str:
        ekf = np.array([run.ekf_final_error for run in self.runs])
        odo = np.array([run.odometry_final_error for run in self.runs])
        low, high = self.band
        return (f"{len(self.runs)} runs x {self.seconds:g} s: average NEES "
                f"{self.average_nees:.2f}, 95 % band [{low:.2f}, {high:.2f}] "
                f"({'inside' if self.inside_band else 'OUTSIDE'}); final error EKF mean "
                f"{ekf.mean():.3f} m (worst {ekf.max():.3f}), raw odometry mean "
                f"{odo.mean():.2f} m; worst EKF/odometry ratio {(ekf / odo).max():.3f}")


def calibrate_worn_chair(side: float = THESIS_SIDE) -> OdometryCalibration:
    """UMBmark + distance scale on the worn chair, and the residual they leave."""
    hall = box_world(HALL_SIZE, HALL_SIZE, centred=True, name="hall")

    def make(seed: int) -> SimBase:
        return SimBase(hall, seed=seed, errors="worn", people=False)

    cw, ccw = run_umbmark(make, runs=1, side=side)
    result = umbmark_corrections(cw, ccw, side, make(0).params.wheel_base)
    scale = calibrate_distance_scale(make(99), correction=result.correction)
    correction = (result.c_left * scale, result.c_right * scale)
    wheel_base = result.wheel_base * scale
    cw, ccw = run_umbmark(make, runs=1, side=side, correction=correction,
                          wheel_base=wheel_base)
    return OdometryCalibration(correction, wheel_base, e_max_syst(cw, ccw) / (4 * side))


def calibrated_filter(start: Pose2D, bias_prior: tuple[float, float],
                      calibration: OdometryCalibration, fix_every: float = 10.0,
                      **ekf_options: object) -> ChairEkf:
    """The filter for a drive from ``start``: UMBmark-corrected wheels, the gyro with
    ``bias_prior = (bias, std)`` (rad/s), and the wheels' residual spread over
    ``fix_every`` s between fixes. ``ekf_options`` go to
    :class:`~abcwc.estimation.ekf.ChairEkf`."""
    return ChairEkf(start, correction=calibration.correction,
                    wheel_base=calibration.wheel_base, gyro_bias=bias_prior[0],
                    gyro_bias_std=bias_prior[1],
                    noise=noise_from_models(residual_rel=calibration.residual_rel,
                                            horizon=fix_every), **ekf_options)


def filter_drive(log: RunLog, bias_prior: tuple[float, float],
                 calibration: OdometryCalibration, seed: int, fix_every: float = 10.0,
                 **ekf_options: object) -> tuple[np.ndarray, np.ndarray]:
    """Filter a simulated drive from its true start (:func:`calibrated_filter`) with a
    seeded landmark fix every ``fix_every`` s. Returns
    :func:`~abcwc.estimation.ekf.run_ekf`'s states and covariances."""
    ekf = calibrated_filter(Pose2D(*log.pose[0]), bias_prior, calibration, fix_every,
                            **ekf_options)
    fixes = absolute_fixes(log, fix_every, FIX_STD, seed=seed)
    return run_ekf(log, ekf, fixes, np.diag(np.square(FIX_STD)))


def record_with_sightings(chair: SimBase, controller: Callable, seconds: float
                          ) -> tuple[RunLog, dict[int, list[MarkerSighting]]]:
    """``chair.run(controller, seconds)`` with the camera on, and what it read of the
    world's fixed markers: ``{log row: sightings}``, each image's readings at the row
    whose time is the image's."""
    if chair.camera_mode is None:
        raise ValueError("the chair needs its camera: SimBase(..., camera='gray')")
    markers = {m.marker_id: m for m in chair.world.markers}
    seen: dict[float, list[MarkerSighting]] = {}
    last = [-math.inf]

    def looking(frame):
        image = frame.readings.get(CAMERA_FRAME)
        if isinstance(image, CameraImage) and image.stamp > last[0]:
            last[0] = image.stamp
            found = sight_markers(image, markers)
            if found:
                seen[frame.t] = found
        return controller(frame)

    log = chair.run(looking, seconds)
    rows = {float(t): k for k, t in enumerate(log.t)}
    return log, {rows[t]: found for t, found in seen.items() if t in rows}


@cached_on_disk  # a seeded drive with the camera on: minutes, kept on disk
def record_marker_drive(seed: int, seconds: float
                        ) -> tuple[RunLog, np.ndarray, dict[int, list[MarkerSighting]]]:
    """The worn chair on the floor world (seed ``seed``, no people, the camera on) stands
    still :data:`STILL_SECONDS` s, then drives the mixed route for ``seconds`` s, steered
    by the simulator's ground truth through its safety filter (the estimators only
    listen). Returns the :class:`~abcwc.log.RunLog` of it all, the simulator's true gyro
    bias (rad/s) inside each row's gyro sample, and what the camera read of the floor's
    fixed markers, ``{row: [MarkerSighting, ...]}`` (:func:`record_with_sightings`)."""
    chair = SimBase("floor", seed=seed, errors="worn", people=False, camera="gray")
    route = FollowWaypoints(floor_mixed_drive(), GroundTruth())
    biases = []

    def controller(frame):
        biases.append(chair.gyro.bias)  # the bias inside this frame's gyro sample
        return Twist(0.0, 0.0) if frame.t < STILL_SECONDS else route(frame)

    log, sightings = record_with_sightings(chair, controller, STILL_SECONDS + seconds)
    biases.append(chair.gyro.bias)
    return log, np.array(biases[1:]), sightings  # the first call saw the frame before row 0


def split_still(log: RunLog, sightings: dict[int, list[MarkerSighting]]
                ) -> tuple[np.ndarray, RunLog, dict[int, list[MarkerSighting]]]:
    """A :func:`record_marker_drive` recording's gyro samples taken standing still (rad/s),
    its drive from ``t = STILL_SECONDS`` on, and the drive's sightings numbered by the
    drive's rows."""
    moving = log.t >= STILL_SECONDS - 1e-9
    first = int(np.argmax(moving))
    return (log.gyro_z[~moving], log.select(moving),
            {row - first: seen for row, seen in sightings.items() if row >= first})


def ekf_run(seed: int, seconds: float, calibration: OdometryCalibration,
            fix_every: float = 10.0, fixes: str = "truth") -> EkfRun:
    """One seeded drive on the floor world, filtered; see the module docstring."""
    if fixes not in ("truth", "markers"):
        raise ValueError(f"fixes must be 'truth' or 'markers', got {fixes!r}")
    if fixes == "markers":
        recording, _, seen = record_marker_drive(seed, seconds)
        still, log, sightings = split_still(recording, seen)
        bias_prior = gyro_bias_prior(still)
    else:
        sim = SimBase("floor", seed=seed, errors="worn", people=False)
        bias_prior = gyro_bias_prior(sim.drive(Twist(0.0, 0.0), STILL_SECONDS).gyro_z)
        log = sim.run(FollowWaypoints(floor_mixed_drive(), GroundTruth()), seconds)
    if log.collisions[-1]:
        raise RuntimeError(f"seed {seed}: the route touched something; the drive is void")
    if fixes == "markers":
        ekf = calibrated_filter(Pose2D(*log.pose[0]), bias_prior, calibration, fix_every)
        landmarks = {m.marker_id: m.centre[:2] for m in load_world("floor").markers}
        states, covs = run_ekf(log, ekf, sightings=sightings, landmarks=landmarks,
                               mount=default_params().depth_scan.mount)
    else:
        states, covs = filter_drive(log, bias_prior, calibration, seed, fix_every)
    raw = odometry_from_log(log)
    return EkfRun(nees(log.pose, states, covs),
                  math.hypot(*(states[-1, :2] - log.pose[-1, :2])),
                  math.hypot(*(raw[-1, :2] - log.pose[-1, :2])))


def ekf_monte_carlo(runs: int, seconds: float, calibration: OdometryCalibration | None = None,
                    processes: int = 1, fix_every: float = 10.0,
                    fixes: str = "truth") -> MonteCarloResult:
    """Seeds ``0 .. runs - 1``, each :func:`ekf_run`; ``processes > 1`` runs them in parallel."""
    if not (isinstance(runs, int) and runs >= 1):
        raise ValueError(f"runs must be an integer >= 1, got {runs!r}")
    if not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"seconds must be a finite number > 0, got {seconds!r}")
    calibration = calibration or calibrate_worn_chair()
    args = [(seed, seconds, calibration, fix_every, fixes) for seed in range(runs)]
    if processes > 1:
        with ProcessPoolExecutor(processes) as pool:
            results = list(pool.map(ekf_run, *zip(*args)))
    else:
        results = [ekf_run(*a) for a in args]
    return MonteCarloResult(tuple(results), float(seconds), nees_band(runs, dof=3))
