"""Costmaps against costmap_2d's rules, worked out independently here cell by cell."""

import math

import numpy as np
import pytest

from abcwc.mapping.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from abcwc.mapping.map_io import load_map, save_map
from abcwc.navigation.costmap import (
    FREE_SPACE,
    INSCRIBED,
    LETHAL,
    NO_INFORMATION,
    Costmap,
    Footprint,
    chair_footprint,
    footprint_cells,
    footprint_cost,
    inflation_cost,
)
from abcwc.params import default_params
from abcwc.types import LaserScan


def reference_inflation(cost, resolution, inscribed, inflation, k, inflate_unknown=False):
    """costmap_2d's inflation layer written out per cell: the nearest lethal cell by brute
    force, computeCost as in inflation_layer.h, the unknown-cell rule of updateCosts."""
    out = cost.copy()
    lethal = np.argwhere(cost == LETHAL)
    reach = math.ceil(inflation / resolution)
    for r in range(cost.shape[0]):
        for c in range(cost.shape[1]):
            d_cells = min(math.hypot(r - lr, c - lc) for lr, lc in lethal)
            if d_cells > reach:
                continue
            if d_cells == 0:
                new = LETHAL
            elif d_cells * resolution <= inscribed:
                new = INSCRIBED
            else:
                new = int((INSCRIBED - 1) * math.exp(-k * (d_cells * resolution - inscribed)))
            old = cost[r, c]
            if old == NO_INFORMATION:
                if (new > FREE_SPACE) if inflate_unknown else (new >= INSCRIBED):
                    out[r, c] = new
            else:
                out[r, c] = max(old, new)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("inflate_unknown", [False, True])
def test_inflation_equals_costmap_2d_cell_by_cell(seed, inflate_unknown):
    rng = np.random.default_rng(seed)
    costmap = Costmap(0.05, 30, 24, default=FREE_SPACE)
    costmap.cost[rng.random(costmap.shape) < 0.02] = LETHAL
    costmap.cost[rng.random(costmap.shape) < 0.1] = NO_INFORMATION
    costmap.cost[3, 4] = LETHAL
    before = costmap.cost.copy()
    costmap.inflate(0.12, 0.55, 10.0, inflate_unknown=inflate_unknown)
    expected = reference_inflation(before, 0.05, 0.12, 0.55, 10.0, inflate_unknown)
    np.testing.assert_array_equal(costmap.cost, expected)
    assert (costmap.cost == INSCRIBED).any() and ((costmap.cost > 0) & (costmap.cost < 100)).any()


def test_inflation_cost_by_hand():
    """At 0.3 m with r_inscribed 0.1 m and k = 10: 252 e^-2 = 34.1 -> 34 (truncated)."""
    costs = inflation_cost(np.array([0.0, 0.05, 0.1, 0.3, 1.0]), 0.1, 10.0)
    assert costs.tolist() == [LETHAL, INSCRIBED, INSCRIBED, 34, 0]


def test_the_chairs_footprint_and_its_radii():
    """610 x 482 mm with the axle 160 mm from the back: the nearest edge is the back
    (0.16 m), the farthest corner the front one, hypot(0.45, 0.241)."""
    footprint = chair_footprint(default_params())
    assert footprint.inscribed_radius == pytest.approx(0.16)
    assert footprint.circumscribed_radius == pytest.approx(math.hypot(0.45, 0.241))
    padded = chair_footprint(default_params(), padding=0.05)
    assert padded.inscribed_radius == pytest.approx(0.21)
    with pytest.raises(ValueError, match="padding"):
        chair_footprint(default_params(), padding=-0.1)


def test_a_static_layer_from_a_saved_map(tmp_path):
    cells = np.full((20, 30), FREE, dtype=np.int8)
    cells[:, 12] = OCCUPIED
    cells[15:, 20:] = UNKNOWN
    grid = OccupancyGrid.from_trinary(cells, 0.05, (-1.0, 2.0, 0.0))
    save_map(grid, tmp_path / "room.yaml")
    loaded = load_map(tmp_path / "room.yaml")
    costmap = Costmap.like(loaded)
    costmap.add_static(loaded.trinary())
    assert (costmap.cost[:, 12] == LETHAL).all()
    assert (costmap.cost[15:, 20:] == NO_INFORMATION).all()
    assert costmap.cost[0, 0] == FREE_SPACE
    untracked = Costmap.like(loaded)
    untracked.add_static(loaded.trinary(), track_unknown=False)
    assert (untracked.cost[15:, 20:] == FREE_SPACE).all()
    with pytest.raises(ValueError, match="cells"):
        costmap.add_static(cells[:10])


def scan_of(ranges, fov=math.pi, range_max=4.0):
    ranges = np.asarray(ranges, dtype=float)
    n = len(ranges)
    return LaserScan(angle_min=-fov / 2, angle_increment=fov / max(n - 1, 1),
                     range_min=0.1, range_max=range_max, ranges=ranges)


def test_a_scan_marks_its_return_and_clears_the_way():
    costmap = Costmap(0.1, 40, 40, origin=(-2.0, -2.0, 0.0))  # all unknown
    costmap.cost[20, 25] = LETHAL  # an old obstacle on the beam's way: cleared
    beam = LaserScan(angle_min=0.0, angle_increment=0.01, range_min=0.1, range_max=4.0,
                     ranges=np.array([1.55]))
    costmap.add_scan(beam, (0.0, 0.0, 0.0), obstacle_range=3.0, raytrace_range=3.0)
    row = costmap.cost[20]  # y in [0, 0.1): the beam's row
    assert row[35] == LETHAL  # x = 1.55 m lies in column 35
    assert (row[20:35] == FREE_SPACE).all()  # from the sensor's cell up to the hit
    assert (row[36:] == NO_INFORMATION).all() and costmap.cost[21, 25] == NO_INFORMATION
    far = LaserScan(angle_min=0.0, angle_increment=0.01, range_min=0.1, range_max=4.0,
                    ranges=np.array([3.5]))
    costmap.add_scan(far, (0.0, 0.35, 0.0), obstacle_range=3.0, raytrace_range=2.0)
    assert (costmap.cost[23, 20:40] != LETHAL).all()  # beyond obstacle_range: no mark
    assert (costmap.cost[23, 20:40] == FREE_SPACE).sum() == 20  # cleared to 2.0 m only
    with pytest.raises(ValueError, match="raytrace_range"):
        costmap.add_scan(far, (0.0, 0.0, 0.0), obstacle_range=3.0, raytrace_range=0.0)


def test_the_rolling_window_follows_the_chair_on_the_map_grid():
    window = Costmap.rolling_window((10.03, -4.51, 1.0), 5.0, 0.05)
    assert window.shape == (100, 100)
    assert window.origin.x == pytest.approx(7.5) and window.origin.y == pytest.approx(-7.05)
    rows, cols = window.world_to_cell(np.array([[10.03, -4.51]]))
    assert (rows[0], cols[0]) in {(49, 50), (50, 50), (49, 49), (50, 49)}
    with pytest.raises(ValueError, match="finite"):
        Costmap.rolling_window((math.nan, 0.0, 0.0), 5.0, 0.05)


def test_a_rolling_window_on_a_maps_lattice_shares_its_cells():
    """A map whose origin is off the multiples of the resolution (-0.475 m): windows
    on its lattice have every cell centre at a map cell's centre, so a cell is read
    from one map cell, not from whichever of two a boundary falls to."""
    grid = Costmap(0.05, 200, 200, (-0.475, -0.475, 0.0))
    for centre in [(3.01, 2.49, 0.3), (7.777, 1.234, -2.0)]:
        window = Costmap.rolling_window(centre, 5.0, 0.05, lattice=grid)
        rows, cols = np.indices(window.shape)
        in_cells = grid.to_cell_units(window.cell_to_world(rows.ravel(), cols.ravel()))
        assert np.allclose(in_cells % 1.0, 0.5)
        # on multiples of 0.05 m instead, every cell centre lies on a map cell boundary
        plain = Costmap.rolling_window(centre, 5.0, 0.05)
        fraction = grid.to_cell_units(plain.cell_to_world(rows.ravel(), cols.ravel())) % 1.0
        assert np.all(np.minimum(fraction, 1.0 - fraction) < 1e-6)
    on_lattice = Costmap(0.05, 200, 200, (-0.5, -0.5, 0.0))
    a = Costmap.rolling_window((10.03, -4.51, 1.0), 5.0, 0.05, lattice=on_lattice)
    assert a.origin == Costmap.rolling_window((10.03, -4.51, 1.0), 5.0, 0.05).origin
    with pytest.raises(ValueError, match="lattice must be axis-aligned"):
        Costmap.rolling_window((0.0, 0.0, 0.0), 5.0, 0.05,
                               lattice=Costmap(0.1, 10, 10, (0.0, 0.0, 0.0)))


def test_the_footprint_over_an_obstacle_is_lethal():
    footprint = Footprint(np.array([[0.3, 0.2], [-0.1, 0.2], [-0.1, -0.2], [0.3, -0.2]]))
    costmap = Costmap(0.05, 60, 60, origin=(-1.5, -1.5, 0.0), default=FREE_SPACE)
    assert footprint_cost(costmap, footprint, (0.0, 0.0, 0.0)) == FREE_SPACE
    # a 0.4 m square off the grid lines overlaps 9 x 9 cells of 0.05 m: exactly those
    rows, cols = footprint_cells(costmap, footprint, (0.012, 0.013, 0.0))
    assert len(set(zip(rows.tolist(), cols.tolist()))) == 81
    costmap.cost[costmap.world_to_cell(np.array([0.25, -0.15]))] = LETHAL  # under a corner
    assert footprint_cost(costmap, footprint, (0.0, 0.0, 0.0)) == LETHAL
    assert footprint_cost(costmap, footprint, (0.0, 0.0, math.pi)) == FREE_SPACE  # turned away
    assert footprint_cost(costmap, footprint, (1.4, 0.0, 0.0)) == NO_INFORMATION  # off the map


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="resolution"):
        Costmap(-0.05, 10, 10)
    with pytest.raises(ValueError, match="default"):
        Costmap(0.05, 10, 10, default=7)
    costmap = Costmap(0.05, 10, 10)
    with pytest.raises(ValueError, match="inflation_radius"):
        costmap.inflate(0.3, 0.1)


def test_the_floor_world_costmap_keeps_the_chair_clear_at_its_places():
    """From the floor world's walls, inflated by the chair's own radii: the chair at each
    named place fits (no lethal cell under it), and placed across a wall it does not."""
    from abcwc.sim.world import load_world

    world = load_world("floor")
    footprint = chair_footprint(default_params())
    costmap = Costmap.from_walls(world.walls, 0.05)
    costmap.inflate(footprint.inscribed_radius, 0.6)
    for name, place in world.places.items():
        assert footprint_cost(costmap, footprint, place) < LETHAL, name
    x1, y1, x2, y2 = world.walls[0]
    on_wall = ((x1 + x2) / 2, (y1 + y2) / 2, 0.0)
    assert footprint_cost(costmap, footprint, on_wall) == LETHAL
    assert (costmap.cost == INSCRIBED).any()


def test_the_costmap_plot_colours_each_class(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from abcwc import viz

    costmap = Costmap(0.1, 20, 10, origin=(1.0, 2.0, 0.0))
    costmap.cost[:, :5] = FREE_SPACE
    costmap.cost[5, 5] = LETHAL
    costmap.inflate(0.1, 0.5)
    ax = viz.plot_costmap(costmap)
    image = ax.images[0]
    assert image.get_extent() == [1.0, 3.0, 2.0, 3.0]
    colours = viz.costmap_colours()
    assert colours(LETHAL)[:3] == (1.0, 0.0, 1.0) and colours(INSCRIBED)[:3] == (0.0, 1.0, 1.0)
    assert colours(FREE_SPACE)[3] == 0.0 and colours(NO_INFORMATION)[3] > 0
