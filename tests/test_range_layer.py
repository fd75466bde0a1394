"""The range sensor layer: range_sensor_layer's sensor model by hand, Bayes' rule, the
simulator's sonar marking a wall where the wall is, and a passing person forgotten."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.control.safety import RangeSensorRay, range_sensor_rays
from abcwc.mapping.grid import GridGeometry
from abcwc.navigation.costmap import FREE_SPACE, LETHAL, NO_INFORMATION, Costmap
from abcwc.navigation.range_layer import RangeSensorLayer, inverse_sensor_model
from abcwc.params import default_params
from abcwc.sim import SimBase
from abcwc.sim.world import box_world
from abcwc.types import Pose2D, Twist

SONAR = RangeSensorRay(np.zeros(3), math.radians(17.0), 0.3, 5.0)


def test_the_sensor_model_by_hand():
    half, band, phi_v, r = math.radians(17.0), 0.05, 1.2, 2.0
    b = band * r  # 0.1 m
    lam_at = 1 - (1 + math.tanh(2 * (2.0 - phi_v))) / 2  # on the axis, at the echo
    # at the echo on the axis: lambda (1/2 - 0) + 1/2
    assert inverse_sensor_model(r, np.array([2.0]), np.array([0.0]), half, band, phi_v)[0] \
        == pytest.approx(lam_at * 0.5 + 0.5)
    # well short of the echo, half-way to the cone's edge: (1 - lambda) / 2
    theta = half / 2
    lam = (1 - (1 + math.tanh(2 * (1.0 - phi_v))) / 2) * (1 - 0.25)
    assert inverse_sensor_model(r, np.array([1.0]), np.array([theta]), half, band, phi_v)[0] \
        == pytest.approx((1 - lam) / 2)
    # in the rising zone, r - 2b < phi < r - b
    phi = r - 1.5 * b
    lam = 1 - (1 + math.tanh(2 * (phi - phi_v))) / 2
    assert inverse_sensor_model(r, np.array([phi]), np.array([0.0]), half, band, phi_v)[0] \
        == pytest.approx(lam / 2 * 0.25 + (1 - lam) / 2)
    # beyond the echo, or outside the cone: no information
    p = inverse_sensor_model(r, np.array([r + 1.5 * b, 1.0]), np.array([0.0, half * 1.01]),
                             half, band, phi_v)
    assert p == pytest.approx([0.5, 0.5])


def test_readings_combine_by_range_sensor_layers_bayes_rule():
    """Two readings of the same cell: the layer's log-odds sum gives range_sensor_layer's
    ``prob_occ / (prob_occ + prob_not)``."""
    grid = GridGeometry(0.05, 120, 60, (0.0, -1.5, 0.0))
    layer = RangeSensorLayer(grid, saturation=1 - 1e-9)
    cell_rows, cell_cols = grid.world_to_cell(np.array([[1.0, 0.0], [0.5, 0.0]]))
    centres = grid.cell_to_world(cell_rows, cell_cols)
    sensor = (0.0, 0.0, 0.0)
    p = []
    for reading in (1.0, 1.01):
        phi = np.hypot(*centres.T)
        theta = np.arctan2(centres[:, 1], centres[:, 0])
        p.append(inverse_sensor_model(reading, phi, theta, SONAR.half_angle,
                                      layer.band, layer.phi_v))
        layer.add_reading(sensor, reading, SONAR)
    occupied = p[0] * p[1]
    expected = occupied / (occupied + (1 - p[0]) * (1 - p[1]))
    assert layer.probability[cell_rows, cell_cols] == pytest.approx(expected)
    assert expected[0] > 0.6 and expected[1] < 0.2  # the echo's cell likelier, the way clear


def test_a_passing_person_is_forgotten_and_a_wall_that_stays_is_kept():
    grid = GridGeometry(0.05, 120, 60, (0.0, -1.5, 0.0))
    layer = RangeSensorLayer(grid)
    rows, cols = grid.world_to_cell(np.array([[0.8, 0.0], [1.5, 0.0]]))
    person, wall = (rows[0], cols[0]), (rows[1], cols[1])
    for _ in range(5):  # a person walks through the cone: five echoes at 0.8 m
        layer.add_reading((0.0, 0.0, 0.0), 0.8, SONAR)
    assert layer.probability[person[0], person[1]] > layer.mark_threshold
    for _ in range(20):  # then the wall behind, 1.5 m away, two seconds at 10 Hz
        layer.add_reading((0.0, 0.0, 0.0), 1.5, SONAR)
    assert layer.probability[person[0], person[1]] < layer.clear_threshold
    assert layer.probability[wall[0], wall[1]] > layer.mark_threshold


def test_far_echoes_count_for_little():
    """range_sensor_layer's delta(phi): with phi_v 1.2 m an echo at 3 m barely moves a
    cell, one at 0.8 m moves it a long way (a sonar's far returns are its least sure)."""
    grid = GridGeometry(0.05, 120, 60, (0.0, -1.5, 0.0))
    near, far = RangeSensorLayer(grid), RangeSensorLayer(grid)
    near.add_reading((0.0, 0.0, 0.0), 0.8, SONAR)
    far.add_reading((0.0, 0.0, 0.0), 3.0, SONAR)
    assert near.probability.max() > 0.75 and 0.5 < far.probability.max() < 0.51


def test_nothing_in_range_clears_and_no_reading_changes_nothing():
    grid = GridGeometry(0.05, 120, 60, (0.0, -1.5, 0.0))
    layer = RangeSensorLayer(grid)
    for reading in (math.nan, -math.inf):
        layer.add_reading((0.0, 0.0, 0.0), reading, SONAR)
    assert not layer.log_odds.any()
    layer.add_reading((0.0, 0.0, 0.0), math.inf, SONAR)
    assert layer.log_odds.max() <= 0.0 and layer.log_odds.min() < 0.0


def test_update_costs_marks_but_never_clears_another_layers_obstacle():
    grid = Costmap(0.05, 120, 60, (0.0, -1.5, 0.0), default=NO_INFORMATION)
    layer = RangeSensorLayer(grid)
    for _ in range(5):
        layer.add_reading((0.0, 0.0, 0.0), 1.0, SONAR)
    wall_row, wall_col = (int(v[0]) for v in grid.world_to_cell(np.array([[1.0, 0.0]])))
    way_row, way_col = (int(v[0]) for v in grid.world_to_cell(np.array([[0.5, 0.0]])))
    grid.cost[way_row, way_col + 1] = LETHAL  # a wall the static map knows, in the cone
    layer.update_costs(grid)
    assert grid.cost[wall_row, wall_col] == LETHAL
    assert grid.cost[way_row, way_col] == FREE_SPACE
    assert grid.cost[way_row, way_col + 1] == LETHAL
    with pytest.raises(ValueError, match="resolution"):
        layer.update_costs(Costmap(0.1, 10, 10))
    with pytest.raises(ValueError, match="threshold"):
        RangeSensorLayer(grid, mark_threshold=0.4)


def test_the_simulators_sonar_and_ir_mark_the_wall_where_it_is():
    """The chair drives at a wall across an 8 m room, feeding the layer every sonar and
    IR reading as the navigator would (ground-truth poses: the sensor model is under test,
    not the localisation). Every marked cell lies on the wall, within the echo's zone; the
    wall straight ahead is marked; the floor the chair drove over is clear."""
    params = default_params()
    chair = SimBase(box_world(8.0, 6.0), seed=5, people=False,
                    start=Pose2D(1.0, 3.0, 0.0))
    layer = RangeSensorLayer(Costmap(0.05, 160, 120))
    rays = range_sensor_rays(params)
    frame = chair.step()
    while frame.truth.pose.x < 6.6:  # the sonar 1 m from the wall
        chair.send(Twist(0.4, 0.0))
        frame = chair.step()
        if round(frame.t / params.control_period) % 5 == 0:  # at the sonar's 10 Hz
            layer.add_frame(frame, frame.truth.pose, rays)
    costmap = Costmap.like(layer)
    layer.update_costs(costmap)
    rows, cols = np.nonzero(costmap.cost == LETHAL)
    marked = costmap.cell_to_world(rows, cols)
    assert len(marked) >= 5
    # the room's walls are x = 0, x = 8, y = 0, y = 6: each mark within the echo's zone
    # of one (the IR ring looks back and sideways too)
    to_wall = np.min(np.abs(np.column_stack([marked[:, 0], 8.0 - marked[:, 0],
                                             marked[:, 1], 6.0 - marked[:, 1]])), axis=1)
    assert to_wall.max() <= 0.15
    ahead = marked[(np.abs(marked[:, 1] - 3.0) < 0.15) & (marked[:, 0] > 7.5)]
    assert len(ahead)  # the wall straight ahead is seen
    clear_rows, clear_cols = costmap.world_to_cell(np.column_stack(
        [np.arange(1.5, 6.5, 0.25), np.full(20, 3.0)]))
    assert (costmap.cost[clear_rows, clear_cols] == FREE_SPACE).all()
