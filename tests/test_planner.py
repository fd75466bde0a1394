"""The global planner: A*, compiled and as plain Python, agrees with an independent reference."""

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra, shortest_path

from abcwc.navigation.costmap import FREE_SPACE, INSCRIBED, LETHAL, NO_INFORMATION, Costmap
from abcwc.navigation.planner import (
    COST_FACTOR,
    COST_NEUTRAL,
    NoPathError,
    astar_search,
    cell_weights,
    costs_to_goal,
    dijkstra_costs,
    plan,
    smooth,
)


def random_costmap(seed, size=24):
    rng = np.random.default_rng(seed)
    costmap = Costmap(0.1, size, size, default=FREE_SPACE)
    costmap.cost[rng.random(costmap.shape) < 0.08] = LETHAL
    costmap.inflate(0.05, 0.4)
    costmap.cost[rng.random(costmap.shape) < 0.03] = NO_INFORMATION
    costmap.cost[1, 1] = costmap.cost[size - 2, size - 2] = FREE_SPACE
    return costmap


NAVFN_UNKNOWN_WEIGHT = 253.0  # navfn.cpp's setCostmap: an unknown cell is COST_OBS - 1


def reference_weight(value):
    """navfn's weight of a cell of costmap ``value``, written out again: 50 + 0.8 cost
    below ``INSCRIBED``, 253 for an unknown cell, impassable from ``INSCRIBED`` up."""
    if value == NO_INFORMATION:
        return NAVFN_UNKNOWN_WEIGHT
    if value >= INSCRIBED:
        return math.inf
    return COST_NEUTRAL + COST_FACTOR * value


def neighbour_graph(weights):
    """A (cells, cells) CSR matrix of every 8-connected move between passable cells of
    the (height, width) ``weights``: its length in cells times the mean of the two
    weights, built here cell by cell."""
    height, width = weights.shape
    rows, cols, costs = [], [], []
    for r in range(height):
        for c in range(width):
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    rr, cc = r + dr, c + dc
                    if (dr or dc) and 0 <= rr < height and 0 <= cc < width:
                        step = math.hypot(dr, dc) * (weights[r, c] + weights[rr, cc]) / 2
                        if math.isfinite(step):
                            rows.append(r * width + c)
                            cols.append(rr * width + cc)
                            costs.append(step)
    return coo_matrix((costs, (rows, cols)), shape=(height * width,) * 2).tocsr()


def reference_cost(costmap, start, goal):
    """The least path cost by scipy's shortest_path on a graph built here cell by cell,
    with navfn's weights written out again."""
    weights = np.vectorize(reference_weight, otypes=[float])(costmap.cost.astype(int))
    distances = shortest_path(neighbour_graph(weights), method="J",
                              indices=start[0] * costmap.width + start[1])
    return distances[goal[0] * costmap.width + goal[1]]


def path_cost(costmap, cells):
    """A path's cost summed move by move (the planner's own rule, recomputed)."""
    cost = 0.0
    for (r0, c0), (r1, c1) in zip(cells[:-1], cells[1:]):
        assert max(abs(r1 - r0), abs(c1 - c0)) == 1  # 8-connected moves only
        w0, w1 = (reference_weight(int(costmap.cost[r, c])) for r, c in ((r0, c0), (r1, c1)))
        cost += math.hypot(r1 - r0, c1 - c0) * (w0 + w1) / 2
    return cost


def uncompiled_cost(costmap, start_cell, goal_cell, **options):
    """The same A* run line by line by Python (numba's ``py_func``)."""
    width = costmap.width
    cost, _ = astar_search.py_func(cell_weights(costmap, **options),
                                   start_cell[0] * width + start_cell[1],
                                   goal_cell[0] * width + goal_cell[1], COST_NEUTRAL)
    return cost


@pytest.mark.parametrize("seed, size", [(seed, 24) for seed in range(6)] + [(6, 90), (7, 90)])
def test_both_searches_find_the_least_cost_of_an_independent_reference(seed, size):
    costmap = random_costmap(seed, size)
    far = size - 2
    start, goal = costmap.cell_to_world(1, 1), costmap.cell_to_world(far, far)
    expected = reference_cost(costmap, (1, 1), (far, far))
    if not math.isfinite(expected):
        with pytest.raises(NoPathError):
            plan(costmap, start, goal)
        return
    path = plan(costmap, start, goal)
    assert path.cost == pytest.approx(expected, rel=1e-9)
    assert uncompiled_cost(costmap, (1, 1), (far, far)) == pytest.approx(expected, rel=1e-9)
    assert path_cost(costmap, path.cells) == pytest.approx(expected, rel=1e-9)
    assert tuple(path.cells[0]) == (1, 1) and tuple(path.cells[-1]) == (far, far)
    assert (costmap.cost[path.cells[:, 0], path.cells[:, 1]] != LETHAL).all()


def test_the_path_keeps_away_from_walls_where_it_can():
    """A 3 m wide corridor with a wall on one side: the path runs where the inflation is
    cheapest, not along the wall."""
    costmap = Costmap(0.05, 120, 60, default=FREE_SPACE)
    costmap.cost[0, :] = LETHAL
    costmap.inflate(0.16, 1.0, 3.0)
    path = plan(costmap, (0.5, 1.5), (5.5, 1.5))
    assert path.points[:, 1].min() > 1.0
    start, goal = (int(c) for c in path.cells[0]), (int(c) for c in path.cells[-1])
    assert uncompiled_cost(costmap, tuple(start), tuple(goal)) == pytest.approx(path.cost)


def test_smoothing_shortens_a_staircase_without_crossing_costlier_cells():
    costmap = Costmap(0.1, 40, 40, default=FREE_SPACE)
    costmap.cost[10:30, 20] = LETHAL
    costmap.inflate(0.1, 0.3)
    path = plan(costmap, (0.5, 2.0), (3.5, 2.2))
    smoothed = smooth(costmap, path)
    assert len(smoothed.cells) < len(path.cells) and smoothed.length <= path.length + 1e-9
    assert tuple(smoothed.cells[0]) == tuple(path.cells[0])
    assert tuple(smoothed.cells[-1]) == tuple(path.cells[-1])


def test_impossible_goals_say_why():
    costmap = Costmap(0.1, 30, 30, default=FREE_SPACE)
    costmap.cost[:, 15] = LETHAL  # a wall from edge to edge
    with pytest.raises(NoPathError, match="walled off"):
        plan(costmap, (0.5, 0.5), (2.5, 0.5))
    assert uncompiled_cost(costmap, (5, 5), (5, 25)) == math.inf
    with pytest.raises(NoPathError, match="in an obstacle"):
        plan(costmap, (0.5, 0.5), (1.55, 0.5))
    with pytest.raises(NoPathError, match="off the costmap"):
        plan(costmap, (0.5, 0.5), (9.0, 0.5))
    with pytest.raises(ValueError, match="finite"):
        plan(costmap, (math.nan, 0.5), (1.0, 0.5))
    costmap.cost[:, 15] = NO_INFORMATION
    assert plan(costmap, (0.5, 0.5), (2.5, 0.5)).cost > 0
    with pytest.raises(NoPathError):
        plan(costmap, (0.5, 0.5), (2.5, 0.5), allow_unknown=False)


def test_costs_to_goal_are_each_cells_least_plan_cost():
    """The progress check's map: from every cell, the cost A* finds to the goal (in free
    floor metres), and inf where the goal is walled off."""
    costmap = Costmap(0.05, 40, 30, default=0)
    costmap.cost[:, 20] = LETHAL
    costmap.cost[10:14, 20] = 0  # a door
    costmap.cost[25:, 30] = LETHAL
    costmap.cost[25, 30:] = LETHAL  # a walled-off corner
    costmap.inflate(0.1, 0.4)
    goal = (1.8, 0.3)
    costs = costs_to_goal(costmap, goal)
    rng = np.random.default_rng(3)
    for row, col in zip(rng.integers(0, 30, 25), rng.integers(0, 40, 25)):
        start = costmap.cell_to_world(np.array([row]), np.array([col]))[0]
        try:
            expected = plan(costmap, start, goal).cost * costmap.resolution / COST_NEUTRAL
        except NoPathError:
            expected = np.inf
        assert costs[row, col] == pytest.approx(expected, rel=1e-9)
    assert np.isinf(costs[27, 35])  # behind the corner's walls


def test_dijkstra_costs_are_the_least_costs_scipys_dijkstra_finds():
    rng = np.random.default_rng(24)
    weights = rng.uniform(50.0, 250.0, (12, 15))
    weights[rng.random(weights.shape) < 0.15] = np.inf
    weights[0, 0] = 50.0
    graph = neighbour_graph(weights)
    expected = dijkstra(graph, indices=0)
    assert np.allclose(dijkstra_costs(weights, 0).ravel(), expected)


def test_an_unknown_cell_weighs_navfns_253():
    """navfn's setCostmap writes an unknown cell it may cross as COST_OBS - 1 = 253, a
    weight dearer than any known passable cell (the dearest, cost 252, weighs 251.6)."""
    costmap = Costmap(0.1, 3, 1, (0.0, 0.0, 0.0))
    costmap.cost[:] = [[0, INSCRIBED - 1, NO_INFORMATION]]
    free, dearest, unknown = cell_weights(costmap)[0]
    assert (free, unknown) == (50.0, 253.0)
    assert dearest == pytest.approx(50 + 0.8 * 252) and dearest < unknown
    assert not np.isfinite(cell_weights(costmap, allow_unknown=False)[0, 2])
