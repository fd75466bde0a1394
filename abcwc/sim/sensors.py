"""Simulated sensors: encoders, gyro, sonar cone, IR ring, depth-camera scan, lidar.

Each sensor takes the chair's true pose and the world's geometry and returns what the
real part would report, with its own seeded noise stream. Range sensors ray-cast
every beam against every wall segment and person at once (:mod:`abcwc.sim.raycast`).
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.geometry import compose, transform_points
from abcwc.params import ChairParams, GyroParams, IrRingParams, RangeSensorParams
from abcwc.sim.raycast import cone_nearest_distance, ray_distances
from abcwc.types import LaserScan, Pose2D


class GaussianStream:
    """Standard normal samples drawn in blocks (one NumPy call per 4096 samples)."""

    def __init__(self, rng: np.random.Generator, width: int = 1, block: int = 4096):
        self._rng, self._width, self._block = rng, width, block
        self._buffer = np.zeros((0, width))
        self._index = 0

    def next(self) -> np.ndarray:
        """The next row of ``width`` samples."""
        if self._index >= len(self._buffer):
            self._buffer = self._rng.standard_normal((self._block, self._width))
            self._index = 0
        row = self._buffer[self._index]
        self._index += 1
        return row


class Encoders:
    """Wheel-on-wheel quadrature encoders, x1 decoding (thesis 4.2.1).

    A 62 mm encoder wheel of actual diameter ``k d_e`` rolls on each tyre and gives
    400 counts per turn, so it counts ``400 / (pi k d_e)`` per metre of tyre travel.
    """

    def __init__(self, params: ChairParams, scale_left: float, scale_right: float):
        per_turn = params.counts_per_encoder_turn
        circumference = math.pi * params.encoder_wheel_diameter
        self._per_metre = (per_turn / (circumference * scale_left),
                           per_turn / (circumference * scale_right))
        self.travel_left = 0.0  # tyre surface travel (m), signed
        self.travel_right = 0.0

    def advance(self, surface_left: float, surface_right: float, dt: float) -> None:
        """Roll the encoder wheels for ``dt`` seconds at the tyre surface speeds (m/s)."""
        self.travel_left += surface_left * dt
        self.travel_right += surface_right * dt

    @property
    def counts(self) -> tuple[int, int]:
        """Cumulative counts (left, right)."""
        return (math.floor(self.travel_left * self._per_metre[0] + 1e-9),
                math.floor(self.travel_right * self._per_metre[1] + 1e-9))


class Gyro:
    """Gyro z: true rate + turn-on bias + bias random walk + white noise (rad/s)."""

    def __init__(self, params: GyroParams, period: float, rng: np.random.Generator):
        self._noise = GaussianStream(rng, 2)
        self.frame_id = params.frame_id  # where its samples are taken ("imu_link")
        self.bias = float(rng.normal(0.0, params.bias_std))
        self._noise_std = params.noise_std
        self._walk_std = params.bias_walk_std * math.sqrt(period)

    def read(self, true_rate: float) -> float:
        """One sample (rad/s)."""
        white, walk = self._noise.next()
        self.bias += walk * self._walk_std
        return true_rate + self.bias + white * self._noise_std


class Sonar:
    """MaxSonar MB1013 (table 3): nearest return inside a +-17 degree cone, 0.30..5 m.

    Closer than 0.30 m it reports 0.30 m and with nothing in range 5.0 m, as the part
    does; readings are quantised to 1 mm.
    """

    def __init__(self, params: RangeSensorParams, rng: np.random.Generator):
        self.params = params
        self.frame_id = params.frame_id  # the SensorFrame.readings key of its range
        self._noise = GaussianStream(rng)
        self._half = math.radians(params.half_angle_deg)

    def read(self, pose: Pose2D, segments: np.ndarray, circles: np.ndarray) -> float:
        """One reading (m)."""
        p = self.params
        sensor = compose(pose, p.mount)  # x, y, heading in the world
        distance = cone_nearest_distance(sensor[:2], sensor[2], self._half, segments, circles)
        if math.isfinite(distance):
            distance += float(self._noise.next()[0]) * p.noise_std
        distance = min(max(distance, p.min_range), p.max_range)
        return round(distance / p.resolution) * p.resolution


class IrRing:
    """Six Sharp GP2Y0A02YK0F rangers 60 degrees apart (2.2.5, table 4).

    REP 117: ``inf`` when nothing is within 1.5 m, ``-inf`` when closer than 0.2 m.
    """

    def __init__(self, params: IrRingParams, rng: np.random.Generator):
        self.params = params
        self.frame_ids = params.frame_ids  # the SensorFrame.readings key of each ranger
        self._noise = GaussianStream(rng, params.count)
        self.mounts = params.mounts

    def read(self, pose: Pose2D, segments: np.ndarray, circles: np.ndarray) -> np.ndarray:
        """Six readings (m)."""
        p = self.params
        origins = transform_points(pose, self.mounts[:, :2])  # the rangers in the world
        out = ray_distances(origins, pose.theta + self.mounts[:, 2], segments, circles,
                            p.max_range + 4 * p.noise_std)
        out = out + self._noise.next() * p.noise_std
        out[out > p.max_range] = np.inf
        out[out < p.min_range] = -np.inf
        return out


class ScanSensor:
    """A planar scanner: the 360-degree lidar or the depth camera's fake laser scan.

    ``fov_deg`` 0 means a full turn (``beams`` evenly spaced from -pi); otherwise the
    beams span ``-fov/2..fov/2`` inclusive. With ``depth_noise`` the noise grows with
    range as a Kinect's does (Nguyen, Izadi and Lovell, 3DIMPVT 2012:
    sigma = 0.0012 + 0.0019 (d - 0.4)^2 m); otherwise it is ``noise_std``.
    ``noise_std`` 0 switches the noise off either way.
    Out of range: ``inf`` (no return) or ``-inf`` (closer than ``min_range``).
    """

    def __init__(self, params: RangeSensorParams, rng: np.random.Generator,
                 depth_noise: bool = False):
        self.params = params
        self.frame_id = params.frame_id  # the SensorFrame.readings key of its scans
        self._rng = rng
        self.depth_noise = depth_noise
        if params.fov_deg == 0:
            self.angle_min = -math.pi
            self.angle_increment = 2 * math.pi / params.beams
        else:
            fov = math.radians(params.fov_deg)
            self.angle_min = -fov / 2
            self.angle_increment = fov / (params.beams - 1)
        self.beam_angles = self.angle_min + self.angle_increment * np.arange(params.beams)

    def read(self, pose: Pose2D, segments: np.ndarray, circles: np.ndarray,
             stamp: float) -> LaserScan:
        """One scan."""
        p = self.params
        sensor = compose(pose, p.mount)  # x, y, heading in the world
        ranges = ray_distances(sensor[:2], sensor[2] + self.beam_angles, segments, circles,
                               p.max_range)
        finite = np.isfinite(ranges)
        if p.noise_std > 0:
            if self.depth_noise:
                sigma = 0.0012 + 0.0019 * (ranges[finite] - 0.4) ** 2
            else:
                sigma = p.noise_std
            ranges[finite] += self._rng.standard_normal(int(finite.sum())) * sigma
        ranges[ranges > p.max_range] = np.inf
        ranges[ranges < p.min_range] = -np.inf
        return LaserScan(self.angle_min, self.angle_increment, p.min_range, p.max_range,
                         ranges, stamp)
