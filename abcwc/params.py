"""The chair's numbers, loaded once from ``data/chair.toml``.

Every dimension, rate and range of the Sterling Ruby that the library uses comes from
here (thesis table 2, sections 2.2.5, 4.1.3-4.1.5, 4.2.1 and appendix A.18). Nothing
else in ``abcwc`` hard-codes a chair number: pass a different :class:`ChairParams` to
the simulator or controllers to model another chair. Each sensor's spec names the
ROS frame id its readings carry (:attr:`ChairParams.sensors`).

:func:`load_navigation_params` reads ``data/navigation.toml``: the sonar avoider's
table 7 and the move_base, DWA planner and costmap settings of appendix A.17.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, fields
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from abcwc.description import DescriptionError, RobotDescription, load_urdf
from abcwc.paths import data_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass(frozen=True)
class RangeSensorParams:
    """A range sensor: frame id, rate (Hz), limits (m), noise (m, 1 sigma) and mounting."""

    rate_hz: float
    min_range: float
    max_range: float
    noise_std: float
    frame_id: str  # ROS frame id of its readings, e.g. "sonar_link"
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y (m), yaw (rad) in base_link
    height: float = 0.0  # m above the floor (from the URDF)
    beams: int = 1
    fov_deg: float = 0.0
    half_angle_deg: float = 0.0
    resolution: float = 0.0
    vertical_fov_deg: float = 0.0  # a camera's vertical field of view
    scan_height_px: int = 0  # rows of the depth image a fake laser scan takes
    image_height_px: int = 0

    @property
    def vertical_half_angle(self) -> float:
        """Half the vertical spread (rad) the sensor sees: a depth scan's band of
        ``scan_height_px`` of ``image_height_px`` rows (depthimage_to_laserscan) through
        a pinhole, ``atan(tan(vfov / 2) scan_height / image_height)``, a sonar's cone
        (``half_angle_deg``), or 0 for a planar lidar or a thin IR beam."""
        if self.scan_height_px:
            return math.atan(math.tan(math.radians(self.vertical_fov_deg) / 2)
                             * self.scan_height_px / self.image_height_px)
        return math.radians(self.half_angle_deg)


@dataclass(frozen=True)
class IrRingParams:
    """Six IR rangers on a ring, 60 degrees apart (thesis 2.2.5)."""

    rate_hz: float
    min_range: float
    max_range: float
    noise_std: float
    frame_ids: tuple[str, ...]  # ROS frame id of each ranger
    mount_poses: tuple[tuple[float, float, float], ...] = ()  # from the URDF
    height: float = 0.0  # m above the floor (from the URDF)
    count: int = 6

    def __post_init__(self) -> None:
        if len(self.frame_ids) != self.count:
            raise ValueError(f"the IR ring has {self.count} rangers but "
                             f"{len(self.frame_ids)} frame ids: {self.frame_ids!r}")
        if len(self.mount_poses) != self.count:
            raise ValueError(f"the IR ring has {self.count} rangers but "
                             f"{len(self.mount_poses)} mounts")

    @property
    def mounts(self) -> np.ndarray:
        """(count, 3): each ranger's ``x, y`` (m) and facing ``yaw`` (rad) in base_link,
        as the URDF places them (a ring on the base rod, 60 degrees apart)."""
        return np.array(self.mount_poses, dtype=float)


@dataclass(frozen=True)
class GyroParams:
    """Gyro z noise model: white noise per sample, turn-on bias, bias random walk.

    ``variant`` says where the numbers come from: ``"datasheet"`` (the MPU-9250's noise
    density and a published bias stability, see ``data/chair.toml`` and
    :func:`gyro_from_datasheet`) or ``"pessimistic"`` (chapter 09's "what if").
    """

    rate_hz: float
    noise_std: float  # rad/s, per sample
    bias_std: float  # rad/s
    bias_walk_std: float  # rad/s/sqrt(s)
    frame_id: str  # ROS frame id of the IMU, "imu_link"
    variant: str = "datasheet"


GYRO_VARIANTS = ("datasheet", "pessimistic")
"""The gyro models ``data/chair.toml`` describes (see :func:`load_params`)."""


def gyro_from_datasheet(noise_density_dps_rthz: float, bias_stability_dph: float,
                        bias_stability_tau: float, rate_hz: float) -> tuple[float, float]:
    """``(noise_std, bias_walk_std)`` from a gyro's datasheet / Allan-variance figures.

    White noise of density ``N`` (deg/s/sqrt(Hz)) sampled every ``dt = 1 / rate_hz`` s
    has std ``N / sqrt(dt)`` per sample (rad/s after conversion). A bias that wanders
    by ``B`` (deg/h, the bias stability read off the Allan deviation at ``tau`` s) is
    modelled as a random walk of ``B / sqrt(tau)`` (rad/s/sqrt(s)), whose std after
    ``tau`` seconds is ``B``.
    """
    for name, value in (("noise density", noise_density_dps_rthz),
                        ("bias stability", bias_stability_dph), ("tau", bias_stability_tau),
                        ("rate", rate_hz)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"gyro {name} must be a finite number > 0, got {value!r}")
    noise_std = math.radians(noise_density_dps_rthz) * math.sqrt(rate_hz)
    bias_walk_std = math.radians(bias_stability_dph / 3600.0) / math.sqrt(bias_stability_tau)
    return noise_std, bias_walk_std


def _gyro(table: dict[str, Any], variant: str) -> GyroParams:
    if variant not in GYRO_VARIANTS:
        raise ValueError(f"gyro variant {variant!r} unknown; allowed: {', '.join(GYRO_VARIANTS)}")
    noise_std, bias_walk_std = gyro_from_datasheet(
        table["noise_density_dps_rthz"], table["bias_stability_dph"],
        table["bias_stability_tau"], table["rate_hz"])
    values = dict(table, noise_std=noise_std, bias_walk_std=bias_walk_std, variant=variant)
    if variant != "datasheet":
        values.update(table[variant])
    return _pick(GyroParams, values)


@dataclass(frozen=True)
class ChairParams:
    """Geometry, drive, pot and sensor parameters of the chair (SI units)."""

    length: float
    width: float
    height: float
    mass_kg: float
    occupant_mass_kg: float
    axle_to_rear: float
    max_speed: float
    max_turn_rate: float
    drive_wheel_diameter: float
    wheel_base: float
    motor_time_constant: float
    command_delay: float
    encoder_wheel_diameter: float
    counts_per_encoder_turn: int
    pot_neutral: int
    pot_safe_min: int
    pot_safe_max: int
    pot_dead_band: int
    pot_full_scale_offset: int
    joystick_centre: int
    joystick_min: int
    joystick_max: int
    joystick_dead_band_low: int
    joystick_dead_band_high: int
    eqn1_offset: int
    eqn1_multiplier: float
    degrees_scale: float
    adc_max: int
    control_period: float
    watchdog_timeout: float
    gyro: GyroParams
    sonar: RangeSensorParams
    ir: IrRingParams
    depth_scan: RangeSensorParams
    lidar: RangeSensorParams

    @property
    def distance_per_count(self) -> float:
        """Ground travel per encoder count (m): pi * d_e / N_e (thesis 4.2.1)."""
        return math.pi * self.encoder_wheel_diameter / self.counts_per_encoder_turn

    @property
    def counts_per_wheel_turn(self) -> float:
        """Encoder counts per drive-wheel turn: N_e * d_w / d_e (4.2.1: about 1258)."""
        return (
            self.counts_per_encoder_turn
            * self.drive_wheel_diameter
            / self.encoder_wheel_diameter
        )

    @property
    def footprint(self) -> list[tuple[float, float]]:
        """The chair's outline in base_link (m), counter-clockwise from rear right."""
        rear, front = -self.axle_to_rear, self.length - self.axle_to_rear
        half = self.width / 2
        return [(rear, -half), (front, -half), (front, half), (rear, half)]

    @property
    def sensors(self) -> dict[str, GyroParams | RangeSensorParams | IrRingParams]:
        """Every sensor's spec keyed by the frame id its readings carry: ``imu_link``,
        ``sonar_link``, ``ir_0_link``..``ir_5_link`` (all six the ring's one spec),
        ``depth_scan_link``, ``lidar_link``. Derived from the named fields, so
        ``dataclasses.replace(params, lidar=...)`` changes it too."""
        specs: dict[str, GyroParams | RangeSensorParams | IrRingParams] = {
            self.gyro.frame_id: self.gyro, self.sonar.frame_id: self.sonar}
        specs.update({frame_id: self.ir for frame_id in self.ir.frame_ids})
        specs.update({self.depth_scan.frame_id: self.depth_scan,
                      self.lidar.frame_id: self.lidar})
        return specs

    @property
    def total_mass(self) -> float:
        """Chair plus occupant (kg)."""
        return self.mass_kg + self.occupant_mass_kg


def _pick(cls: type, table: dict[str, Any], **renames: str) -> Any:
    """Build dataclass ``cls`` from a TOML table, converting lists to tuples."""
    names = {f.name for f in fields(cls)}
    kwargs = {}
    for key, value in table.items():
        name = renames.get(key, key)
        if name in names:
            kwargs[name] = tuple(value) if isinstance(value, list) else value
    return cls(**kwargs)


def _geometry(description: RobotDescription, sensors: dict[str, Any]) -> dict[str, Any]:
    """The footprint, the drive wheels and every sensor's mount, from the URDF.

    The footprint is the ``chassis`` link's collision box; the wheel diameter and base
    are the ``left_wheel``/``right_wheel`` collision cylinders and joints; each sensor
    sits at the link named by its frame id.
    """
    chassis = description.links["chassis"].collision
    wheel = description.links["left_wheel"].collision
    if chassis is None or chassis.kind != "box" or wheel is None or wheel.kind != "cylinder":
        raise DescriptionError(f"{description.source}: the chair needs a chassis collision "
                               "box and left_wheel/right_wheel collision cylinders")
    centre_x = (description.transform("chassis") @ chassis.origin)[0, 3]
    left = description.mount("left_wheel")
    right = description.mount("right_wheel")
    geometry: dict[str, Any] = {
        "length": chassis.dimensions[0],
        "width": chassis.dimensions[1],
        "axle_to_rear": chassis.dimensions[0] / 2 - centre_x,
        "drive_wheel_diameter": 2 * wheel.dimensions[0],
        "wheel_base": left[1] - right[1],
    }
    for name in ("sonar", "depth_scan", "lidar"):
        frame = sensors[name]["frame_id"]
        sensors[name] = {**sensors[name], "mount": description.mount(frame),
                         "height": description.height(frame)}
    frames = sensors["ir"]["frame_ids"]
    heights = {round(description.height(f), 6) for f in frames}
    if len(heights) != 1:
        raise DescriptionError(f"{description.source}: the IR rangers sit at different "
                               f"heights {sorted(heights)}; the ring model needs one")
    sensors["ir"] = {**sensors["ir"], "height": heights.pop(),
                     "mount_poses": tuple(description.mount(f) for f in frames)}
    return geometry


def load_params(path: str | Path | None = None, gyro: str = "datasheet") -> ChairParams:
    """Read chair parameters from a TOML file (default ``data/chair.toml``) and the
    URDF it names (``[description] urdf``, beside it): the URDF gives the footprint,
    the drive wheels and every sensor's mount; the TOML file the rest.

    ``gyro`` picks the gyro model: ``"datasheet"`` (default) or ``"pessimistic"``.
    """
    path = Path(path) if path is not None else data_dir() / "chair.toml"
    with open(path, "rb") as handle:
        raw = tomllib.load(handle)
    sensors = dict(raw["sensors"])
    description = load_urdf(path.parent / raw["description"]["urdf"])
    flat: dict[str, Any] = {}
    flat.update(raw["body"])
    flat.update(_geometry(description, sensors))
    flat.update(raw["drive"])
    flat.update(raw["encoders"])
    flat.update({f"pot_{k}": v for k, v in raw["pots"].items()})
    for key, value in raw["joystick"].items():
        flat[key if key.startswith(("eqn1", "degrees", "adc")) else f"joystick_{key}"] = value
    flat["control_period"] = raw["control"]["period"]
    flat["watchdog_timeout"] = raw["control"]["watchdog_timeout"]
    flat["gyro"] = _gyro(sensors["gyro"], gyro)
    flat["ir"] = _pick(IrRingParams, sensors["ir"])
    for name in ("sonar", "depth_scan", "lidar"):
        flat[name] = _pick(RangeSensorParams, sensors[name])
    return _pick(ChairParams, flat)


@lru_cache(maxsize=1)
def default_params() -> ChairParams:
    """The Sterling Ruby's parameters from ``data/chair.toml`` (cached)."""
    return load_params()


# ------------------------------------------------------------------ navigation
@dataclass(frozen=True)
class SonarAvoidanceParams:
    """Table 7 / eqn 3 (4.1.6): sonar distance (m) -> turn angle (deg)."""

    turn_within: float  # m, no turn beyond this
    reverse_within: float  # m, reverse closer than this
    min_turn_deg: float  # at turn_within
    max_turn_deg: float  # at reverse_within
    turn_step_deg: float  # per step_distance closer
    step_distance: float  # m


@dataclass(frozen=True)
class MoveBaseParams:
    """move_base's own parameters (A.17 "Move_base params")."""

    controller_frequency: float  # Hz
    controller_patience: float  # s
    planner_frequency: float  # Hz
    planner_patience: float  # s
    oscillation_timeout: float  # s
    oscillation_distance: float  # m
    shutdown_costmaps: bool
    recovery_behavior_enabled: bool
    clearing_rotation_allowed: bool
    base_local_planner: str
    base_global_planner: str


@dataclass(frozen=True)
class LocalPlannerParams:
    """The DWA local planner's limits, scoring and sampling (A.17
    Base_local_planner_params; ROS names, m, s, rad)."""

    max_vel_x: float
    min_vel_x: float
    max_vel_y: float
    min_vel_y: float
    max_vel_theta: float
    min_in_place_vel_theta: float
    acc_lim_theta: float
    acc_lim_x: float
    acc_lim_y: float
    holonomic_robot: bool
    pdist_scale: float
    gdist_scale: float
    occdist_scale: float
    meter_scoring: bool
    heading_lookahead: float
    heading_scoring: bool
    heading_scoring_timestep: float
    oscillation_reset_dist: float
    publish_cost_grid_pc: bool
    prune_plan: bool
    sim_time: float
    sim_granularity: float
    angular_sim_granularity: float
    vx_samples: int
    vy_samples: int
    vtheta_samples: int
    dwa: bool
    simple_attractor: bool


@dataclass(frozen=True)
class GoalTolerance:
    """When a goal counts as reached (A.17): within ``xy`` m and ``yaw`` rad."""

    xy: float
    yaw: float
    latch_xy: bool


@dataclass(frozen=True)
class CostmapParams:
    """What both costmaps share (A.17 Costmap_common_params), m."""

    obstacle_range: float
    raytrace_range: float
    robot_radius: float
    inflation_radius: float
    min_obstacle_height: float


@dataclass(frozen=True)
class CostmapWindowParams:
    """One costmap's frame, rates (Hz), grid (m) and window (A.17 global/local costmap)."""

    global_frame: str
    robot_base_frame: str
    update_frequency: float
    publish_frequency: float
    resolution: float
    width: float
    height: float
    static_map: bool
    rolling_window: bool
    transform_tolerance: float
    sonar_no_readings_timeout: float | None = None  # s, local costmap's sonar layer


@dataclass(frozen=True)
class NavigationParams:
    """The navigation numbers of ``data/navigation.toml`` (thesis table 7 and A.17)."""

    sonar_avoidance: SonarAvoidanceParams
    move_base: MoveBaseParams
    local_planner: LocalPlannerParams
    goal_tolerance: GoalTolerance
    costmap: CostmapParams
    global_costmap: CostmapWindowParams
    local_costmap: CostmapWindowParams


def _table(cls: type, raw: dict[str, Any], name: str, path: Path) -> Any:
    """Build ``cls`` from TOML table ``name``: every key known, every required key there."""
    if name not in raw:
        raise ValueError(f"{path}: no [{name}] table")
    table = raw[name]
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ValueError(f"{path}: [{name}] has unknown keys {unknown}; allowed: {sorted(known)}")
    try:
        return cls(**table)
    except TypeError as error:
        raise ValueError(f"{path}: [{name}] is incomplete: {error}") from None


def load_navigation_params(path: str | Path | None = None) -> NavigationParams:
    """Read navigation parameters from a TOML file (default ``data/navigation.toml``)."""
    path = Path(path) if path is not None else data_dir() / "navigation.toml"
    with open(path, "rb") as handle:
        raw = tomllib.load(handle)
    classes = {"sonar_avoidance": SonarAvoidanceParams, "move_base": MoveBaseParams,
               "local_planner": LocalPlannerParams, "goal_tolerance": GoalTolerance,
               "costmap": CostmapParams, "global_costmap": CostmapWindowParams,
               "local_costmap": CostmapWindowParams}
    unknown = sorted(set(raw) - set(classes))
    if unknown:
        raise ValueError(f"{path}: unknown tables {unknown}; allowed: {sorted(classes)}")
    return NavigationParams(**{name: _table(cls, raw, name, path)
                               for name, cls in classes.items()})
