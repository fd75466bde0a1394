"""The range sensor layer: sonar and IR cones in a costmap, as ROS's range_sensor_layer.

A sonar does not see a point: it reports the nearest echo somewhere in a cone (the
MaxSonar's about 17 degrees each side of its axis). One reading says little; many, from
different places, say a lot. The layer keeps for every cell the probability that it is
occupied and folds each reading in with Bayes' rule, using range_sensor_layer's inverse
sensor model (Lu, ``range_sensor_layer/src/range_sensor_layer.cpp``, after Elfes, "Using
occupancy grids for mobile robot perception and navigation", IEEE Computer 22(6), 1989).

For a reading of range ``r`` and a cell at distance ``phi`` from the sensor and angle
``theta`` off its axis, with ``b = band * r`` (the width of the echo's zone)::

    gamma(theta) = 1 - (theta / half_angle)^2             (off-axis cells count less)
    delta(phi)   = 1 - (1 + tanh(2 (phi - phi_v))) / 2    (far readings count less)
    lambda       = gamma delta

    p(occupied | r) = (1 - lambda) / 2                                     phi < r - 2b
                    = lambda / 2 ((phi - (r - 2b)) / b)^2 + (1 - lambda) / 2   phi < r - b
                    = lambda (1/2 - ((r - phi) / b)^2 / 2) + 1/2               phi < r + b
                    = 1/2 (no information)                                 beyond

so cells well short of the echo become likelier free, cells at the echo likelier
occupied, both the more surely the nearer the axis and the sensor. Bayes' rule for
independent readings is a sum in log-odds (Thrun, Burgard and Fox, *Probabilistic
Robotics*, eq. 9.7)::

    l(cell) <- l(cell) + log(p / (1 - p))

A reading of ``inf`` (nothing within the maximum range) clears its cone out to the
maximum range (range_sensor_layer's ``clear_on_max_reading``); ``-inf`` (too close to
measure) and NaN (no reading) change nothing. An IR ranger is a narrow beam; the layer
gives every reading a cone at least ``min_half_angle`` wide.

:meth:`RangeSensorLayer.update_costs` writes the layer into a costmap as
range_sensor_layer's ``updateCosts`` does: ``LETHAL`` where the probability is above
``mark_threshold``; ``FREE_SPACE`` where it is below ``clear_threshold`` but only in
cells no other layer has an opinion on (unknown), so that a sonar that misses a wall
(sound reflected away from a smooth surface at a slant) cannot erase the wall.
Defaults are range_sensor_layer's: ``phi_v`` 1.2 m, ``mark_threshold`` 0.8,
``clear_threshold`` 0.2.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from abcwc.control.safety import RangeSensorRay
from abcwc.geometry import PoseLike, compose, wrap_angle
from abcwc.mapping.grid import GridGeometry
from abcwc.navigation.costmap import FREE_SPACE, LETHAL, NO_INFORMATION, Costmap
from abcwc.types import SensorFrame


def inverse_sensor_model(reading: float, phi: np.ndarray, theta: np.ndarray,
                         half_angle: float, band: float, phi_v: float) -> np.ndarray:
    """p(occupied) of cells at distance ``phi`` (m) and off-axis angle ``theta`` (rad)
    given a reading of ``reading`` m (module notes; range_sensor_layer's
    ``sensor_model``). Cells outside the cone or beyond the echo's zone get 0.5."""
    lam = (1.0 - (1.0 + np.tanh(2.0 * (phi - phi_v))) / 2.0) * np.where(
        np.abs(theta) <= half_angle, 1.0 - (theta / half_angle) ** 2, 0.0)
    b = band * reading
    short = (1.0 - lam) / 2.0
    rising = lam / 2.0 * ((phi - (reading - 2 * b)) / b) ** 2 + short
    peak = lam * (0.5 - 0.5 * ((reading - phi) / b) ** 2) + 0.5
    return np.select([phi < reading - 2 * b, phi < reading - b, phi < reading + b],
                     [short, rising, peak], 0.5)


class RangeSensorLayer(GridGeometry):
    """Occupancy probability from range cones over a grid (module notes).

    ``log_odds`` is (height, width) float, 0 (p = 0.5) where nothing is known.
    """

    def __init__(self, grid: GridGeometry, phi_v: float = 1.2, band: float | None = None,
                 mark_threshold: float = 0.8, clear_threshold: float = 0.2,
                 min_half_angle: float = math.radians(2.0), saturation: float = 0.99):
        super().__init__(grid.resolution, grid.width, grid.height, grid.origin)
        if not (0.0 < clear_threshold < 0.5 < mark_threshold < 1.0):
            raise ValueError(f"need 0 < clear_threshold < 0.5 < mark_threshold < 1, got "
                             f"{clear_threshold!r} and {mark_threshold!r}")
        for name, value in (("phi_v", phi_v), ("min_half_angle", min_half_angle)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        if not 0.5 < saturation < 1.0:
            raise ValueError(f"saturation must be a probability in (0.5, 1), got {saturation!r}")
        self.phi_v = phi_v
        self.band = grid.resolution if band is None else band  # as range_sensor_layer
        if not (math.isfinite(self.band) and self.band > 0):
            raise ValueError(f"band must be a finite fraction of the range > 0, got {band!r}")
        self.mark_threshold, self.clear_threshold = mark_threshold, clear_threshold
        self.min_half_angle = min_half_angle
        self.limit = math.log(saturation / (1.0 - saturation))
        self.log_odds = np.zeros(self.shape)

    @property
    def probability(self) -> np.ndarray:
        """(height, width): p(occupied) of each cell."""
        return 1.0 - 1.0 / (1.0 + np.exp(self.log_odds))

    def add_reading(self, sensor_pose: PoseLike, reading: float, ray: RangeSensorRay) -> None:
        """Fold one reading (m; REP 117's ``inf``, ``-inf`` and NaN as in the module notes)
        taken from ``sensor_pose`` (the sensor's pose in this grid's frame) into the layer.
        The cells of the cone's bounding box are all scored at once."""
        reading = float(reading)
        if math.isnan(reading) or reading == -math.inf:
            return
        clearing = reading == math.inf or reading >= ray.max_range
        r = ray.max_range if clearing else max(reading, ray.min_range)
        half_angle = max(ray.half_angle, self.min_half_angle)
        x, y, yaw = (float(v) for v in sensor_pose)
        reach = r * (1.0 + self.band) + self.resolution
        rows, cols = self._box(x - reach, y - reach, x + reach, y + reach)
        if rows.size == 0:
            return
        centres = self.cell_to_world(rows, cols)
        phi = np.hypot(centres[:, 0] - x, centres[:, 1] - y)
        theta = wrap_angle(np.arctan2(centres[:, 1] - y, centres[:, 0] - x) - yaw)
        p = inverse_sensor_model(r, phi, theta, half_angle, self.band, self.phi_v)
        if clearing:  # nothing echoed: only the free part of the model applies
            p = np.minimum(p, 0.5)
        p = np.clip(p, 1e-6, 1 - 1e-6)
        update = np.log(p / (1.0 - p))
        self.log_odds[rows, cols] = np.clip(self.log_odds[rows, cols] + update,
                                            -self.limit, self.limit)

    def decay(self, seconds: float, time_constant: float) -> None:
        """Let every cell's evidence fade towards no information: log-odds times
        ``exp(-seconds / time_constant)``. range_sensor_layer keeps a mark until a
        reading clears it, so a person who stood in the cone stays an obstacle after
        walking off; a mark that fades unless readings renew it follows a world that
        moves (observations decaying over time, as in Macenski et al., "Spatio-temporal
        voxel layer", Int. J. Adv. Robot. Syst., 2020)."""
        if not (math.isfinite(seconds) and seconds >= 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        if not (math.isfinite(time_constant) and time_constant > 0):
            raise ValueError(f"time_constant must be a finite number > 0 s, "
                             f"got {time_constant!r}")
        self.log_odds *= math.exp(-seconds / time_constant)

    def add_frame(self, frame: SensorFrame, pose: PoseLike,
                  rays: dict[str, RangeSensorRay], only: Iterable[str] | None = None) -> None:
        """Fold in every range reading of ``frame`` taken with the chair at ``pose`` (this
        grid's frame): each sensor's pose is ``pose (+) mount``. ``only`` picks frame ids."""
        for frame_id, ray in rays.items():
            if only is not None and frame_id not in only:
                continue
            reading = frame.readings.get(frame_id, math.nan)
            if isinstance(reading, (int, float)):
                self.add_reading(compose(pose, ray.mount), reading, ray)

    def update_costs(self, costmap: Costmap) -> None:
        """Write the layer into ``costmap`` (which may be any grid of the same resolution
        and frame, e.g. a rolling window): ``LETHAL`` above ``mark_threshold``;
        ``FREE_SPACE`` below ``clear_threshold`` in cells still ``NO_INFORMATION``."""
        if not math.isclose(costmap.resolution, self.resolution):
            raise ValueError(f"the costmap's resolution {costmap.resolution} m differs from "
                             f"the layer's {self.resolution} m")
        rows, cols = np.indices(costmap.shape)
        mine_rows, mine_cols = self.world_to_cell(costmap.cell_to_world(rows.ravel(),
                                                                        cols.ravel()))
        inside = self.contains(mine_rows, mine_cols)
        p = np.full(rows.size, 0.5)
        p[inside] = self.probability[mine_rows[inside], mine_cols[inside]]
        p = p.reshape(costmap.shape)
        costmap.cost[p > self.mark_threshold] = LETHAL
        clear = (p < self.clear_threshold) & (costmap.cost == NO_INFORMATION)
        costmap.cost[clear] = FREE_SPACE

    def _box(self, x0: float, y0: float, x1: float, y1: float) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns of this grid's cells in the box ``[x0, x1] x [y0, y1]`` (m)."""
        corners = self.to_cell_units(np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]]))
        (c0, r0), (c1, r1) = np.floor(corners.min(axis=0)), np.floor(corners.max(axis=0))
        r0, c0 = max(int(r0), 0), max(int(c0), 0)
        r1, c1 = min(int(r1), self.height - 1), min(int(c1), self.width - 1)
        if r1 < r0 or c1 < c0:
            return np.empty(0, dtype=int), np.empty(0, dtype=int)
        rows, cols = np.mgrid[r0:r1 + 1, c0:c1 + 1]
        return rows.ravel(), cols.ravel()
