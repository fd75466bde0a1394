"""Plots, animations and the teleop panel: geometry, artist counts, frames, key mapping."""

from __future__ import annotations

import dataclasses
import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.animation import writers  # noqa: E402
from matplotlib.collections import LineCollection, PathCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.patches import Polygon, Wedge  # noqa: E402
from PIL import Image  # noqa: E402

from abcwc import viz  # noqa: E402
from abcwc.control import direction_pot_command  # noqa: E402
from abcwc.log import RunLog  # noqa: E402
from abcwc.params import default_params  # noqa: E402
from abcwc.sim import SimBase, load_world  # noqa: E402
from abcwc.types import LaserScan, Pose2D, PotCommand, SimTruth, Twist, make_frame  # noqa: E402
from abcwc.ui.teleop import TeleopPanel, key_to_pot_command  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def lab_run() -> tuple[SimBase, RunLog]:
    chair = SimBase(world="lab", lidar=True, depth_scan=True)
    return chair, chair.drive(Twist(0.5, 0.2), 3.0)


def synthetic_log(n: int) -> RunLog:
    """An ``n``-row log on a 2 m circle round (5, 4), with every other array zero."""
    t = np.arange(n) * 0.02
    phase = t * 0.25
    pose = np.column_stack([5 + 2 * np.cos(phase), 4 + 2 * np.sin(phase), phase + np.pi / 2])
    zeros2 = np.zeros((n, 2), dtype=np.int64)
    return RunLog(t=t, ticks=zeros2, gyro_z=np.zeros(n), sonar=np.full(n, 5.0),
                  ir=np.full((n, 6), np.inf), joystick=zeros2 + 254, pots=zeros2 + 128,
                  cmd_pots=zeros2 - 1, cmd_twist=np.full((n, 2), np.nan),
                  flags=np.zeros(n, dtype=np.int64), bad_frames=np.zeros(n, dtype=np.int64),
                  pose=pose, collisions=np.zeros(n, dtype=np.int64),
                  meta={"world": "lab", "period": 0.02})


# ---------------------------------------------------------------- scan_to_points
def test_scan_of_a_wall_maps_onto_the_wall_line():
    # Chair at (1, 0.5) facing +x, scanner 0.1 m ahead: a wall at x = 3 is 1.9 m away.
    angles = np.radians(np.arange(-60, 61, 10))
    ranges = 1.9 / np.cos(angles)
    ranges[[0, 1]] = [np.inf, -np.inf]  # no return / too close: dropped
    scan = LaserScan(angles[0], math.radians(10), 0.1, 12.0, ranges)
    points = viz.scan_to_points(scan, Pose2D(1.0, 0.5, 0.0), (0.1, 0.0, 0.0))
    assert points.shape == (len(angles) - 2, 2)
    np.testing.assert_allclose(points[:, 0], 3.0)
    np.testing.assert_allclose(points[:, 1], 0.5 + 1.9 * np.tan(angles[2:]))


def test_scan_to_points_uses_the_mount_offset_and_yaw():
    # Chair facing +y (theta = 90 deg); mount 0.2 m ahead, 0.1 m to the left, yawed
    # 90 deg more, so the scanner sits at (2 - 0.1, 3 + 0.2) and looks along -x.
    scan = LaserScan(0.0, 0.1, 0.1, 12.0, np.array([1.0]))
    points = viz.scan_to_points(scan, (2.0, 3.0, math.pi / 2), (0.2, 0.1, math.pi / 2))
    np.testing.assert_allclose(points, [[2.0 - 0.1 - 1.0, 3.2]], atol=1e-12)


def distance_to_walls(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Each point's distance (m) to the nearest wall segment."""
    a, b = walls[:, None, :2], walls[:, None, 2:]
    d = b - a
    u = np.clip(((points[None] - a) * d).sum(-1) / (d * d).sum(-1), 0, 1)
    return np.linalg.norm(points[None] - (a + u[..., None] * d), axis=-1).min(axis=0)


def test_simulated_lidar_points_lie_on_walls():
    chair = SimBase(world="lab", lidar=True)  # the first scan is taken at the start pose
    points = viz.scan_to_points(chair.frame.lidar, chair.pose, chair.params.lidar.mount)
    assert len(points) > 300
    assert distance_to_walls(points, chair.world.walls).max() < 0.05  # 1 cm noise


def test_logged_scans_are_drawn_from_the_pose_they_were_taken_at(lab_run):
    chair, log = lab_run  # driving 0.5 m/s and turning: a stale pose would miss by cm
    scan, pose = viz.scan_row(log, "lidar", len(log) - 1)
    points = viz.scan_to_points(scan, pose, chair.params.lidar.mount)
    assert distance_to_walls(points, chair.world.walls).max() < 0.05


# ---------------------------------------------------------------- static plots
def test_plot_world_draws_every_wall_and_place():
    world = load_world("floor")
    ax = viz.plot_world(world)
    walls = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(walls) == 1 and len(walls[0].get_segments()) == len(world.walls)
    assert len(ax.texts) == len(world.places)
    assert ax.get_aspect() == 1.0 and ax.get_xlabel() == "x (m)"
    assert len(viz.plot_world("lab", places=False).texts) == 0


def test_plot_chair_is_to_scale_at_the_pose():
    p = default_params()
    ax = viz.plot_chair(Pose2D(2.0, 3.0, math.pi / 2), params=p)
    patches = [a for a in ax.patches if isinstance(a, Polygon)]
    assert len(patches) == 4  # body, two wheels, heading arrow
    body = patches[0].get_xy()[:4]
    front, half = p.length - p.axle_to_rear, p.width / 2
    # facing +y: the front-left corner (front, +half) lands at (2 - half, 3 + front)
    assert np.isclose(body, [2.0 - half, 3.0 + front]).all(axis=1).any()
    wheels = np.array([patch.get_xy()[:4].mean(axis=0) for patch in patches[1:3]])
    np.testing.assert_allclose(sorted(wheels[:, 0]), [2 - p.wheel_base / 2, 2 + p.wheel_base / 2])


def test_plot_trajectory_accepts_log_or_array_and_thins_long_paths():
    log = synthetic_log(15_000)
    ax = viz.plot_trajectory(log, label="run")
    assert len(ax.lines) == 3  # path, start marker, end marker
    path = ax.lines[0].get_xydata()
    assert len(path) <= 4000
    np.testing.assert_allclose(path[-1], log.pose[-1, :2])
    ax = viz.plot_trajectory(log.pose[:50], markers=False)
    assert len(ax.lines) == 1 and len(ax.lines[0].get_xydata()) == 50
    with pytest.raises(ValueError, match="ground-truth"):
        viz.plot_trajectory(np.full((5, 3), np.nan))


def test_plot_sensors_draws_sonar_ir_and_scans():
    p = default_params()
    ir = np.array([0.5, np.inf, 1.0, -np.inf, 1.2, np.inf])
    scan = LaserScan(-math.pi, 2 * math.pi / 8, 0.15, 12.0,
                     np.array([1.0, 2.0, np.inf, 1.5, 1.0, -np.inf, 3.0, 2.0]))
    frame = make_frame(sonar=1.25, ir=ir, truth=SimTruth(Pose2D(1.0, 1.0, 0.3)), lidar=scan)
    ax = viz.plot_sensors(frame, params=p)
    wedges = [a for a in ax.patches if isinstance(a, Wedge)]
    assert len(wedges) == 1 and wedges[0].r == pytest.approx(1.25)
    assert wedges[0].theta2 - wedges[0].theta1 == pytest.approx(2 * p.sonar.half_angle_deg)
    rays = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(rays) == 1 and len(rays[0].get_segments()) == 3  # finite IR readings only
    lengths = [np.linalg.norm(np.diff(s, axis=0)) for s in rays[0].get_segments()]
    np.testing.assert_allclose(lengths, [0.5, 1.0, 1.2])
    dots = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert sorted(len(c.get_offsets()) for c in dots) == [1, 6]  # IR too close; lidar


def test_plot_people_from_circles_and_from_a_chair():
    ax = viz.plot_people(np.array([[1.0, 2.0, 0.25], [3.0, 4.0, 0.3]]))
    assert len(ax.collections) == 1 and len(ax.collections[0].get_paths()) == 2
    chair = SimBase(world="floor")
    ax = viz.plot_people(chair)
    assert len(ax.collections[0].get_paths()) == len(chair.walkers) > 0


def test_plot_run_marks_each_collision_increment(lab_run):
    _, log = lab_run
    counts = np.zeros(len(log), dtype=np.int64)
    counts[10:] += 1
    counts[40:] += 2  # two contacts in one period: one mark
    fig = viz.plot_run(dataclasses.replace(log, collisions=counts))
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    marks = [c for c in ax.collections if c.get_label().startswith("collision")]
    assert len(marks) == 1
    np.testing.assert_allclose(marks[0].get_offsets(), log.pose[[10, 40], :2])
    labels = {h.get_label() for h in ax.get_legend().legend_handles}
    assert {"path", "chair (end)", "lidar scan", "collision (2)"} <= labels


def test_plot_signals_panels_and_thinning():
    log = synthetic_log(15_000)
    fig = viz.plot_signals(log, names=list(viz.SIGNALS))
    assert len(fig.axes) == len(viz.SIGNALS)
    assert all(len(line.get_xdata()) <= 4000 for ax in fig.axes for line in ax.lines)
    with pytest.raises(ValueError, match="choose from"):
        viz.plot_signals(log, names=("speed",))


def test_the_safety_filter_figure_shows_what_was_wanted_sent_and_why():
    start = Pose2D(5.0, 6.5, 0.0)
    bare = SimBase(seed=0, start=start, people=False).run(lambda f: Twist(0.8, 0.0), 8.0,
                                                          safety=None)
    kept = SimBase(seed=0, start=start, people=False).run(lambda f: Twist(0.8, 0.0), 8.0)
    fig = viz.plot_safety_filter(kept, bare, gap=lambda log: 10.0 - log.pose[:, 0],
                                 gap_label="to the wall (m)")
    ax_v, ax_gap, ax_why = fig.axes
    labels = [line.get_label() for line in ax_v.get_lines()]
    assert labels == ["wanted", "sent by the filter", "true, through the filter",
                      "true, bare"]
    np.testing.assert_array_equal(ax_v.get_lines()[1].get_ydata(), kept.cmd_twist[:, 0])
    assert "contact" in [line.get_label() for line in ax_gap.get_lines()]  # the bare run
    obstacle = ax_why.collections[0]  # the first band: obstacle stops
    assert obstacle.get_label() == "obstacle" and len(obstacle.get_paths()) >= 1
    assert ax_why.collections[1].get_label() == "speed limit"
    assert not any(len(c.get_paths()) for c in ax_why.collections[1:])  # only obstacles
    signals = viz.plot_signals(kept, ("v", "safety"))
    assert "wanted (before the safety filter)" in [
        line.get_label() for line in signals.axes[0].get_lines()]
    with pytest.raises(ValueError, match="empty"):
        viz.plot_safety_filter(kept.select(slice(0, 0)))


def test_encoder_velocity_is_the_wheel_speed_and_survives_the_counter_wrap():
    p, n = default_params(), 50
    right = np.arange(n, dtype=np.int64) * 20  # 20 counts a period, steady
    left = 2**31 - 1 - 200 + np.arange(n, dtype=np.int64) * 10  # 10, wrapping past int32
    left = (left + 2**31) % 2**32 - 2**31
    assert (np.diff(left) < 0).any()
    log = dataclasses.replace(synthetic_log(n), ticks=np.column_stack([left, right]))
    v, w = viz.encoder_velocity(log)
    speeds = np.array([10, 20]) * p.distance_per_count / 0.02
    assert np.allclose(v, speeds.mean()) and np.allclose(w, (speeds[1] - speeds[0]) / p.wheel_base)


# ---------------------------------------------------------------- animation
def test_frame_rows_end_on_the_last_row():
    rows = viz.frame_rows(15_000)
    assert len(rows) <= 150 and rows[-1] == 14_999 and rows[0] < 101
    np.testing.assert_array_equal(viz.frame_rows(100, stride=7), np.arange(99, -1, -7)[::-1])
    with pytest.raises(ValueError, match="stride"):
        viz.frame_rows(10, stride=0)


def test_animate_run_and_save_gif(lab_run, tmp_path):
    _, log = lab_run
    anim = viz.animate_run(log, max_frames=8, fps=5)
    assert len(anim.frame_rows) <= 8 and anim.frame_rows[-1] == len(log) - 1
    assert not plt.get_fignums()  # closed: it will not also show as a still image
    path = viz.save_animation(anim, tmp_path / "run.gif")
    assert path.stat().st_size > 1000
    with Image.open(path) as gif:
        assert gif.n_frames == len(anim.frame_rows)


@pytest.mark.parametrize("options", [{}, {"zoom": 1.0, "scans": False, "trail": False}])
def test_the_gif_drawn_by_blitting_is_matplotlib_s_own_frame_for_frame(lab_run, tmp_path,
                                                                      options):
    """save_animation draws only the moving artists over a still picture; matplotlib's
    PillowWriter redraws the whole figure for every frame. The frames must be the same,
    pixel for pixel, and the animation must still draw whole frames afterwards."""
    _, log = lab_run
    anim = viz.animate_run(log, "lab", max_frames=12, **options)
    ours = viz.save_animation(anim, tmp_path / "ours.gif")
    anim.save(tmp_path / "theirs.gif", writer=writers["pillow"](fps=10))
    with Image.open(ours) as a, Image.open(tmp_path / "theirs.gif") as b:
        assert a.n_frames == b.n_frames == len(anim.frame_rows) > 1
        assert a.info["duration"] == b.info["duration"] == 100
        for k in range(a.n_frames):
            a.seek(k)
            b.seek(k)
            assert np.array_equal(np.asarray(a.convert("RGB")), np.asarray(b.convert("RGB")))
    assert "data:image/png;base64" in viz.to_html(anim)


def test_to_html_and_save_errors(lab_run, tmp_path):
    _, log = lab_run
    anim = viz.animate_run(log, "lab", stride=len(log))
    assert len(anim.frame_rows) == 1
    html = viz.to_html(anim)
    assert "<script" in html and "data:image/png;base64" in html
    with pytest.raises(ValueError, match=r"\.gif or \.mp4"):
        viz.save_animation(anim, tmp_path / "run.avi")
    if not writers.is_available("ffmpeg"):
        with pytest.raises(RuntimeError, match="install ffmpeg.*gif"):
            viz.save_animation(anim, tmp_path / "run.mp4")


# ---------------------------------------------------------------- teleop
@pytest.mark.parametrize("key, full", [
    ("w", "forward"), ("a", "left"), ("s", "reverse"), ("d", "right"), (" ", "stop"),
    ("space", "stop"), ("W", "forward"),
])
def test_key_to_pot_command_at_full_speed_is_table_6(key, full):
    assert key_to_pot_command(key, 1.0) == direction_pot_command(full)


def test_key_to_pot_command_scales_and_follows_the_sign_convention():
    assert key_to_pot_command("w", 0.5) == PotCommand(128 + 62, 128)  # round(62.5) = 62
    assert key_to_pot_command("s", 0.5) == PotCommand(128 - 62, 128)
    assert key_to_pot_command("a", 0.2) == PotCommand(128, 128 - 25)  # LR below 128: left
    assert key_to_pot_command("d", 0.2) == PotCommand(128, 128 + 25)
    assert key_to_pot_command(" ", 0.7) == PotCommand(128, 128)
    assert key_to_pot_command("s", 1.0).fb == 8  # 128 - 125 = 3, clamped to the safe 8


@pytest.mark.parametrize("key, fraction, message", [
    ("x", 0.5, "unknown key 'x'; allowed: w .*space"),
    ("", 0.5, "unknown key"),
    (None, 0.5, "unknown key"),
    ("w", 1.5, "outside 0..1"),
    ("w", -0.1, "outside 0..1"),
    ("w", float("nan"), "finite"),
])
def test_key_to_pot_command_rejects_bad_input(key, fraction, message):
    with pytest.raises(ValueError, match=message):
        key_to_pot_command(key, fraction)


def test_teleop_panel_drives_the_simulated_chair():
    chair = SimBase(world="lab")
    panel = TeleopPanel(chair, speed=0.6, hold=0.5)
    assert panel.display() is panel.widget and panel.image.value[:4] == b"\x89PNG"
    assert panel.press("a") == key_to_pot_command("a", 0.6)
    assert chair.pose.theta > 0.05 and chair.t == pytest.approx(0.5)  # left = CCW
    x0 = chair.pose.x
    panel.keybox.value = "dw"  # the last typed key counts; the box is cleared
    assert panel.keybox.value == "" and panel.last_command == key_to_pot_command("w", 0.6)
    assert chair.pose.x > x0
    panel.keybox.value = "q"
    assert "unknown key 'q'" in panel.status.value and chair.t == pytest.approx(1.0)
    assert len(panel.trail) == 1 + 2 * 25
    with pytest.raises(ValueError, match="speed"):
        TeleopPanel(chair, speed=0.0)


def test_distance_and_bearing_figure_states_eqns_11_and_12():
    """The left panel's chair at (1, 1) facing 15 deg, goal (6.5, 5): rho = hypot(5.5, 4) =
    6.80 m, alpha = atan2(4, 5.5) - 15 deg = +21.0 deg; the right panel wraps alpha."""
    from abcwc import viz

    fig = viz.plot_distance_and_bearing()
    left, right = fig.axes
    assert "rho = 6.80 m" in left.get_title() and "alpha = +21.0°" in left.get_title()
    assert "wrap alpha" in right.get_title()
    plt.close(fig)


def test_the_state_machine_is_drawn_from_the_rule_it_is_given():
    from abcwc.behaviours import MissionState, next_state
    from abcwc.viz import plot_state_machine, probe_rule

    st = MissionState
    edges = probe_rule(next_state)
    assert "lost" in edges[(st.NAVIGATING, st.LOCALISING)]
    assert "found / clear" in edges[(st.LOCALISING, st.NAVIGATING)]
    assert "blocked" in edges[(st.WAITING, st.NAVIGATING)]
    assert (st.MANUAL_OVERRIDE, st.NAVIGATING) in edges  # a new command, only
    assert edges[(st.MANUAL_OVERRIDE, st.NAVIGATING)] == ["go to"]

    def resumes(state, situation):
        if state is st.MANUAL_OVERRIDE and not situation.joystick and not situation.command:
            return st.NAVIGATING, "released"
        return next_state(state, situation)

    assert "released" in probe_rule(resumes)[(st.MANUAL_OVERRIDE, st.NAVIGATING)]
    ax = plot_state_machine(resumes)
    labels = [text.get_text() for text in ax.texts]
    assert "released" in labels and "manual override" in labels
    assert any(label.startswith("from every state: joystick: to manual override")
               for label in labels)
    plt.close(ax.figure)
