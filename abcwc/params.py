"""The chair's numbers, loaded once from ``data/chair.toml``.

Every dimension, rate and range of the Sterling Ruby that the library uses comes from
here (thesis table 2, sections 2.2.5, 4.1.3-4.1.5, 4.2.1 and appendix A.18). Nothing
else in ``abcwc`` hard-codes a chair number: pass a different :class:`ChairParams` to
the simulator or controllers to model another chair.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, fields
from functools import lru_cache
from pathlib import Path
from typing import Any

from abcwc.paths import data_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass(frozen=True)
class RangeSensorParams:
    """A range sensor: rate (Hz), limits (m), noise (m, 1 sigma) and mounting."""

    rate_hz: float
    min_range: float
    max_range: float
    noise_std: float
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y (m), yaw (rad) in base_link
    beams: int = 1
    fov_deg: float = 0.0
    half_angle_deg: float = 0.0
    resolution: float = 0.0


@dataclass(frozen=True)
class IrRingParams:
    """Six IR rangers on a ring, 60 degrees apart (thesis 2.2.5)."""

    rate_hz: float
    min_range: float
    max_range: float
    noise_std: float
    ring_radius: float
    ring_centre: tuple[float, float]
    first_angle_deg: float
    count: int = 6


@dataclass(frozen=True)
class GyroParams:
    """Gyro z noise model: white noise per sample, turn-on bias, bias random walk."""

    rate_hz: float
    noise_std: float  # rad/s
    bias_std: float  # rad/s
    bias_walk_std: float  # rad/s/sqrt(s)


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


def load_params(path: str | Path | None = None) -> ChairParams:
    """Read chair parameters from a TOML file (default ``data/chair.toml``)."""
    path = Path(path) if path is not None else data_dir() / "chair.toml"
    with open(path, "rb") as handle:
        raw = tomllib.load(handle)
    sensors = raw["sensors"]
    flat: dict[str, Any] = {}
    flat.update(raw["body"])
    flat.update(raw["drive"])
    flat.update(raw["encoders"])
    flat.update({f"pot_{k}": v for k, v in raw["pots"].items()})
    for key, value in raw["joystick"].items():
        flat[key if key.startswith(("eqn1", "degrees", "adc")) else f"joystick_{key}"] = value
    flat["control_period"] = raw["control"]["period"]
    flat["watchdog_timeout"] = raw["control"]["watchdog_timeout"]
    flat["gyro"] = _pick(GyroParams, sensors["gyro"])
    flat["ir"] = _pick(IrRingParams, sensors["ir"])
    for name in ("sonar", "depth_scan", "lidar"):
        flat[name] = _pick(RangeSensorParams, sensors[name])
    return _pick(ChairParams, flat)


@lru_cache(maxsize=1)
def default_params() -> ChairParams:
    """The Sterling Ruby's parameters from ``data/chair.toml`` (cached)."""
    return load_params()
