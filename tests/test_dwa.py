"""The DWA local planner: exact arcs, the dynamic window, and no trajectory into a wall."""

import math
from dataclasses import replace

import numpy as np
import pytest

from abcwc.geometry import transform_points
from abcwc.navigation.costmap import FREE_SPACE, LETHAL, Costmap, chair_footprint, footprint_cost
from abcwc.navigation.dwa import DwaPlanner, covering_circles, roll_out
from abcwc.params import default_params, load_navigation_params

FOOTPRINT = chair_footprint(default_params())


def test_roll_out_follows_the_exact_arc():
    """Against a fine Euler integration of the unicycle, and the straight line at w = 0."""
    samples = np.array([[0.5, 0.5], [0.8, 0.0], [-0.3, -1.2]])
    poses = roll_out((1.0, 2.0, 0.3), samples, 1.0, 40)
    for (v, w), trajectory in zip(samples, poses):
        x, y, th = 1.0, 2.0, 0.3
        dt = 1e-5
        for _ in range(100_000):
            x, y, th = x + v * math.cos(th) * dt, y + v * math.sin(th) * dt, th + w * dt
        assert trajectory[-1] == pytest.approx([x, y, th], abs=2e-5)
    assert np.allclose(poses[1, :, 2], 0.3)  # straight: the heading never changes


def test_the_window_holds_what_one_cycle_can_reach():
    planner = DwaPlanner(FOOTPRINT)
    samples = planner.window((0.0, 0.0))
    lp, period = planner.local, 1.0 / planner.frequency  # A.17: 5 Hz
    assert len(samples) == lp.vx_samples * lp.vtheta_samples == 160
    assert np.abs(samples[:, 0]).max() == pytest.approx(lp.acc_lim_x * period)  # 0.72 m/s
    assert np.abs(samples[:, 1]).max() == pytest.approx(lp.acc_lim_theta * period)  # 0.3
    fast = planner.window((1.2, 1.5))
    assert fast[:, 0].max() == pytest.approx(lp.max_vel_x)  # clipped at 1.28 m/s
    assert fast[:, 1].max() == pytest.approx(lp.max_vel_theta)
    with pytest.raises(ValueError, match="velocity"):
        planner.window((math.nan, 0.0))


def test_the_covering_circles_cover_the_footprint():
    centres, radius = covering_circles(FOOTPRINT)
    rng = np.random.default_rng(0)
    xs, ys = FOOTPRINT.polygon[:, 0], FOOTPRINT.polygon[:, 1]
    points = np.column_stack([rng.uniform(xs.min(), xs.max(), 2000),
                              rng.uniform(ys.min(), ys.max(), 2000)])
    nearest = np.min(np.hypot(points[:, None, 0] - centres[:, 0],
                              points[:, None, 1] - centres[:, 1]), axis=1)
    assert (nearest <= radius + 1e-12).all()


def corridor(wall_x=None):
    """A 5 x 5 m window around the origin: walls 1 m to each side, and one across at
    ``wall_x`` if given; inflated for the chair."""
    costmap = Costmap.rolling_window((0.0, 0.0, 0.0), 5.0, 0.05, default=FREE_SPACE)
    xs = np.linspace(-2.4, 2.4, 200)
    for y in (-1.0, 1.0):
        costmap.cost[costmap.world_to_cell(np.column_stack([xs, np.full_like(xs, y)]))] = LETHAL
    if wall_x is not None:
        ys = np.linspace(-1.0, 1.0, 80)
        costmap.cost[costmap.world_to_cell(np.column_stack([np.full_like(ys, wall_x), ys]))] = \
            LETHAL
    costmap.inflate(FOOTPRINT.inscribed_radius, 0.6)
    return costmap


PATH = np.column_stack([np.linspace(0.0, 2.4, 60), np.zeros(60)])
# the navigator's limits (NavigatorSettings): never backwards, 0.8 m/s, 0.8 m/s^2, 0.8 rad/s
NAVIGATOR_LIMITS = replace(load_navigation_params().local_planner, min_vel_x=0.0,
                           max_vel_x=0.8, acc_lim_x=0.8, max_vel_theta=0.8)


def test_it_follows_the_path_down_a_clear_corridor():
    result = DwaPlanner(FOOTPRINT).plan(corridor(), (0.0, 0.0, 0.0), (0.5, 0.0), PATH)
    assert not result.stuck and result.command.v > 0.8 and abs(result.command.w) < 0.1
    assert abs(result.poses[result.best, -1, 1]) < 0.05
    total = result.terms["path"] + result.terms["goal"] + result.terms["occupancy"]
    assert np.allclose(total[result.valid], result.cost[result.valid])
    lp = DwaPlanner(FOOTPRINT).local  # the occupancy term is the scale times the worst cell
    assert result.terms["occupancy"].max() <= lp.occdist_scale * 254


def test_no_chosen_trajectory_touches_the_wall_ahead():
    """A wall 1.2 m ahead: the trajectories into it are dropped, and the one chosen keeps
    the exact footprint off every lethal cell at every point (costmap's own check)."""
    costmap = corridor(wall_x=1.2)
    planner = DwaPlanner(FOOTPRINT)
    result = planner.plan(costmap, (0.0, 0.0, 0.0), (0.8, 0.0), PATH)
    assert not result.valid.all() and result.valid.any()
    for pose in result.poses[result.best]:
        assert footprint_cost(costmap, FOOTPRINT, pose) < LETHAL
    # every trajectory the planner calls valid passes the exact check too
    for k in np.flatnonzero(result.valid):
        assert max(footprint_cost(costmap, FOOTPRINT, p) for p in result.poses[k][::5]) < LETHAL


def test_boxed_in_it_stops_and_says_stuck():
    costmap = corridor(wall_x=0.5)
    costmap.cost[costmap.world_to_cell(np.array([[-0.35, y] for y in np.linspace(-1, 1, 80)]))] \
        = LETHAL
    result = DwaPlanner(FOOTPRINT).plan(costmap, (0.0, 0.0, 0.0), (0.0, 0.0), PATH)
    assert result.stuck and result.command.v == 0.0 and result.command.w == 0.0


def test_bad_paths_are_refused():
    planner = DwaPlanner(FOOTPRINT)
    with pytest.raises(ValueError, match="path"):
        planner.plan(corridor(), (0.0, 0.0, 0.0), (0.0, 0.0), np.empty((0, 2)))
    with pytest.raises(ValueError, match="path"):
        planner.plan(corridor(), (0.0, 0.0, 0.0), (0.0, 0.0), [[0.0, math.inf]])


def test_people_are_judged_by_where_the_chair_can_still_stop():
    """A person standing 2 m straight ahead: the gap the people check reports for
    driving straight at v equals the closed form of holding v for one control period and
    the braking delay, then braking at acc_lim_x, i.e. stopping after
    v (period + delay) + v^2 / (2 a) metres."""
    delay = 0.4
    planner = DwaPlanner(FOOTPRINT, braking_delay=delay)
    lp, period = planner.local, 1.0 / planner.frequency
    person = np.array([[2.0, 0.0, 0.0, 0.0, 0.25]])
    samples = np.array([[0.0, 0.0], [0.3, 0.0], [0.6, 0.0]])
    gaps = planner.people_gap((0.0, 0.0, 0.0), samples, person, horizon=4.0, dt=0.001)
    circles, _ = covering_circles(FOOTPRINT)
    front = circles[:, 0].max()  # the foremost covering circle, on the chair's axis
    for (v, _), gap in zip(samples, gaps):
        stop = v * (period + delay) + v**2 / (2 * lp.acc_lim_x)
        assert gap == pytest.approx(2.0 - stop - front - 0.25 - planner._radius, abs=2e-3)
    # a longer braking delay leaves less room: the same sample is judged nearer
    quick = DwaPlanner(FOOTPRINT).people_gap((0.0, 0.0, 0.0), samples, person, 4.0, 0.001)
    assert quick[2] - gaps[2] == pytest.approx(0.6 * delay, abs=2e-3)


def test_the_decision_plot_draws_every_roll_out_and_marks_the_chosen_one():
    import matplotlib

    matplotlib.use("Agg")
    from abcwc import viz

    costmap = corridor(wall_x=1.2)
    result = DwaPlanner(FOOTPRINT).plan(costmap, (0.0, 0.0, 0.0), (0.5, 0.0), PATH)
    ax = viz.plot_dwa(result)
    lines = [line for line in ax.lines if len(line.get_xdata()) > 1]
    assert len(lines) == len(result.samples) + 1  # every roll-out, then the chosen again
    dropped = [line for line in lines if line.get_linestyle() == "--"]
    assert len(dropped) == int((~result.valid).sum()) > 0
    chosen = lines[-1]
    assert np.allclose(chosen.get_xdata(), result.poses[result.best, :, 0])


def test_a_chair_already_too_near_may_not_swing_a_corner_into_what_it_touches():
    """An obstacle where the front-right corner will be after turning left 0.25 rad on
    the spot, inside the front covering circle: the turn takes the circles away from it
    (the rule "never nearer" alone would allow it) but sweeps the corner through it; the
    outline check refuses it."""
    costmap = Costmap.rolling_window((0.0, 0.0, 0.0), 3.0, 0.05, default=FREE_SPACE)
    corner = FOOTPRINT.polygon[np.argmax(FOOTPRINT.polygon[:, 0] - FOOTPRINT.polygon[:, 1])]
    rows, cols = costmap.world_to_cell(transform_points((0.0, 0.0, 0.25), corner[None]))
    costmap.cost[rows, cols] = LETHAL
    planner = DwaPlanner(FOOTPRINT)
    turn = np.array([[0.0, 0.5]])
    check = planner.check(costmap, (0.0, 0.0, 0.0), turn)
    circles = check.clearance.min(axis=0)[0]  # the nearest circle at every step
    assert circles[0] < planner._radius  # noqa: SLF001 - the circle already overlaps it
    # never nearer, and half a cell farther at the end: "gets away" by the circles alone
    assert circles.min() >= circles[0] and circles[-1] >= circles[0] + costmap.resolution / 2
    centre = costmap.cell_to_world(rows, cols)[0]
    outline = np.vstack([np.linspace(a, b, 20) for a, b in
                         zip(FOOTPRINT.polygon, np.roll(FOOTPRINT.polygon, -1, axis=0))])
    nearest = min(np.hypot(*(transform_points(tuple(p), outline) - centre).T).min()
                  for p in check.poses[0])
    assert nearest < costmap.resolution / math.sqrt(2)  # but the corner enters its cell
    assert not check.valid[0]


def test_the_circles_clearance_is_a_bound_wherever_in_its_cell_a_circle_sits():
    """Against the exact distance from each circle's centre to the obstacle cell's
    centre: the clearance used is never more, and never less by more than a diagonal."""
    costmap = Costmap.rolling_window((0.0, 0.0, 0.0), 4.0, 0.05, default=FREE_SPACE)
    obstacle = np.array([1.2, 0.4])
    rows, cols = costmap.world_to_cell(obstacle[None])
    costmap.cost[rows, cols] = LETHAL
    centre = costmap.cell_to_world(rows, cols)[0]
    planner = DwaPlanner(FOOTPRINT)
    rng = np.random.default_rng(3)
    samples = np.column_stack([rng.uniform(0.0, 0.7, 40), rng.uniform(-0.3, 0.3, 40)])
    check = planner.check(costmap, (0.013, -0.021, 0.05), samples)
    centres, _ = covering_circles(FOOTPRINT)
    poses = check.poses[..., None, :]
    c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
    x = poses[..., 0] + c * centres[:, 0] - s * centres[:, 1]
    y = poses[..., 1] + s * centres[:, 0] + c * centres[:, 1]
    exact = np.hypot(x - centre[0], y - centre[1]).transpose(2, 0, 1)  # to the cell's centre
    single = 1e-5  # m: the check works in single precision, in cells
    assert (check.clearance <= exact + single).all()
    assert (check.clearance >= exact - costmap.resolution * math.sqrt(2) - single).all()



def test_evading_it_steers_for_the_widest_gap_to_people_walking_on_or_standing():
    """A walker 1.6 m ahead and 0.6 m to the right, coming at 0.9 m/s, the chair at
    0.3 m/s with the navigator's limits: no way keeps clear of them walking on, so the
    chair evades, braking to the slowest speed of the window, and of that speed's turn
    rates it takes the one whose nearest gap, to the walker walked on, to the walker
    standing where they are, or to a wall, is widest (each recomputed here with
    people_gap and the footprint check)."""
    planner = DwaPlanner(FOOTPRINT, local=NAVIGATOR_LIMITS)
    walker = np.array([[1.6, -0.6, -0.9, 0.0, 0.25]])
    standing = walker.copy()
    standing[:, 2:4] = 0.0
    costmap = corridor()
    result = planner.plan(costmap, (0.0, 0.0, 0.0), (0.3, 0.0), PATH, people=walker)
    assert result.evading
    row = np.flatnonzero(result.valid & (result.samples[:, 0] == result.samples[:, 0].min()))
    assert result.samples[result.best, 0] == pytest.approx(0.3 - 0.8 / planner.frequency)
    check = planner.check(costmap, (0.0, 0.0, 0.0), result.samples[row])
    nearest = np.minimum.reduce([
        planner.people_gap((0.0, 0.0, 0.0), result.samples[row], walker, 3.0),
        planner.people_gap((0.0, 0.0, 0.0), result.samples[row], standing, 3.0),
        check.clearance.min(axis=(0, 2)) - check.needed])
    assert result.best == row[int(np.argmax(nearest))]


def test_evading_a_walker_it_could_stop_short_of_it_brakes_as_hard_as_the_window_allows():
    """A person walking head-on down the corridor 3 m ahead at 0.9 m/s, the chair at
    0.8 m/s: no arc keeps clear of where they walk, but the chair can still stop short of
    where they stand, so it asks for the slowest speed one cycle can reach
    (v0 - acc_lim_x / controller_frequency) and says it is evading."""
    planner = DwaPlanner(FOOTPRINT)
    walker = np.array([[3.0, 0.0, -0.9, 0.0, 0.25]])
    result = planner.plan(corridor(), (0.0, 0.0, 0.0), (0.8, 0.0), PATH, people=walker)
    assert result.evading
    slowest = 0.8 - planner.local.acc_lim_x / planner.frequency
    assert result.command.v == pytest.approx(max(slowest, planner.local.min_vel_x))


def test_a_goal_just_ahead_is_driven_to_not_stood_short_of():
    """The path ends 0.3 m straight ahead of a chair creeping at 0.1 m/s in open floor,
    with the navigator's limits (no reversing, 0.8 m/s^2). The forward point (0.325 m
    ahead of each trajectory's end) would pass the goal and score driving on as no better
    than stopping; near the goal only the end counts, and the chair drives on to it."""
    costmap = Costmap.rolling_window((0.0, 0.0, 0.0), 5.0, 0.05, default=FREE_SPACE)
    path = np.column_stack([np.linspace(-0.5, 0.3, 17), np.zeros(17)])
    result = DwaPlanner(FOOTPRINT, local=NAVIGATOR_LIMITS).plan(costmap, (0.0, 0.0, 0.0),
                                                                (0.1, 0.0), path)
    assert result.command.v > 0.1
    end = result.poses[result.best, -1, :2]
    assert math.hypot(*(end - path[-1])) < 0.15


def test_a_way_counts_only_if_the_chair_can_still_stop_on_it():
    """A wall across the corridor ahead of a chair at 0.8 m/s (navigator limits, 0.5 s of
    braking delay): the nearest wall that the second at constant speed clears and the
    nearest that the stop clears lie apart by what stopping adds, the closed form
    v (period + delay) + v^2 / (2 a) - v * sim_time = 0.56 + 0.40 - 0.80 = 0.16 m."""
    planner = DwaPlanner(FOOTPRINT, local=NAVIGATOR_LIMITS, braking_delay=0.5)
    ahead = np.array([[0.8, 0.0]])
    walls = np.arange(1.3, 2.0, 0.01)

    def nearest_clear(stopping):
        return next(x for x in walls
                    if planner.check(corridor(wall_x=x), (0.0, 0.0, 0.0), ahead,
                                     stopping=stopping).valid[0])

    period = 1.0 / planner.frequency
    extra = 0.8 * (period + 0.5) + 0.8**2 / (2 * 0.8) - 0.8 * NAVIGATOR_LIMITS.sim_time
    assert nearest_clear(True) - nearest_clear(False) == pytest.approx(extra, abs=0.05)
