"""CARMEN logs and benchmark relations: small logs of our own, and the real benchmark logs.

The real logs (Kümmerle et al. 2009) are the project's own copies in data/slam; raw
odometry must score the relation errors that data/slam/README.md gives for them.
"""

from __future__ import annotations

import gzip
import math

import numpy as np
import pytest

from abcwc.geometry import compose, relative
from abcwc.mapping.carmen import NO_RETURN_RANGE, read_carmen_log
from abcwc.mapping.relations import (
    RelationErrors,
    format_relation_errors,
    read_relations,
    relation_errors,
)
from abcwc.mapping.slam_data import LOG_FACTS, slam_file

# --- a small log of our own -------------------------------------------------------------

FLASER_LOG = """\
# a comment line
PARAM robot_frontlaser_offset 0.25 host 0.0
ODOM 0.0 0.0 0.0 0.0 0.0 0.0 10.000000 host 10.000000
FLASER 5 1.00 2.00 81.91 50.00 0.00 0.1 0.2 0.3 0.1 0.2 0.3 10.100000 host 10.100000
SONAR 1 2 3 something the reader does not know
ODOM 1.0 0.0 4.0 0.0 0.0 0.0 10.200000 host 10.200000
FLASER 5 1.00 1.00 1.00 1.00 1.00 1.0 0.0 0.5 1.0 0.0 0.5 10.300000 host 10.300000
"""


def robotlaser_line(ranges: list[float], remissions: list[float], laser: tuple, robot: tuple,
                    stamp: float, start: float = -1.0, resolution: float = 0.5,
                    max_range: float = 8.0) -> str:
    fields = (["ROBOTLASER1", "0", start, 2.0, resolution, max_range, 0.01, 0, len(ranges)]
              + ranges + [len(remissions)] + remissions + list(laser) + list(robot)
              + [0.1, 0.0, 0.3, 0.2, 0.0, f"{stamp:.6f}", "host", f"{stamp:.6f}"])
    return " ".join(str(f) for f in fields)


def test_flaser_log_reads_scans_odometry_and_masks(tmp_path):
    path = tmp_path / "small.clf"
    path.write_text(FLASER_LOG)
    log = read_carmen_log(path, max_range=40.0)
    assert log.laser_message == "FLASER" and len(log) == 2
    np.testing.assert_array_equal(log.stamps, [10.1, 10.3])
    np.testing.assert_allclose(log.odometry, [[0.1, 0.2, 0.3], [1.0, 0.0, 0.5]])
    np.testing.assert_allclose(log.laser_offset, [0.25, 0.0, 0.0])  # from the PARAM line
    np.testing.assert_allclose(log.angle_min, -math.pi / 2)
    np.testing.assert_allclose(log.angle_increment, math.pi / 4)
    # no return (81.91), at the given max range (40 < 50) and zero are masked
    np.testing.assert_array_equal(log.ranges.mask[0], [False, False, True, True, True])
    assert not log.ranges.mask[1].any()
    np.testing.assert_allclose(log.odom_stamps, [10.0, 10.2])
    np.testing.assert_allclose(log.odom_poses[1], [1.0, 0.0, 4.0 - 2 * math.pi])
    # beam 0 points to the right (-90 deg), beam 1 at -45 deg
    np.testing.assert_allclose(log.points(0), [[0.0, -1.0], [math.sqrt(2), -math.sqrt(2)]],
                               atol=1e-12)
    np.testing.assert_allclose(log.points(0, "base"), log.points(0) + [0.25, 0.0])
    laser_pose = compose(log.odometry[0], log.laser_offset)
    np.testing.assert_allclose(log.laser_poses[0], laser_pose)
    with pytest.raises(ValueError, match="frame 'map'"):
        log.points(0, "map")


def test_scan_is_a_laser_scan_with_inf_for_no_return(tmp_path):
    path = tmp_path / "small.clf"
    path.write_text(FLASER_LOG)
    scan = read_carmen_log(path).scan(0)
    assert scan.stamp == 10.1 and scan.range_max == NO_RETURN_RANGE
    np.testing.assert_array_equal(scan.ranges, [1.0, 2.0, np.inf, 50.0, np.inf])
    np.testing.assert_allclose(scan.angles, np.linspace(-math.pi / 2, math.pi / 2, 5))


def flaser_line(ranges: list[float], stamp: float = 1.0) -> str:
    pose = "0.0 0.0 0.0 0.0 0.0 0.0"
    return (f"FLASER {len(ranges)} {' '.join(f'{r:.2f}' for r in ranges)} {pose} "
            f"{stamp:.6f} host {stamp:.6f}")


@pytest.mark.parametrize(("beams", "degrees"), [
    (181, 1.0), (180, 1.0), (361, 0.5), (360, 0.5), (401, 0.25), (400, 0.25), (5, 45.0),
])
def test_flaser_beams_are_as_far_apart_as_carmen_s_own_reader_has_them(tmp_path, beams,
                                                                       degrees):
    """CARMEN's readlog.c (carmen_laser_guess_angle_increment): a SICK's 180 or 181
    readings are 1 degree apart from -90 degrees (180: the last beam, at +90, is not
    logged), 360 or 361 half a degree, 400 or 401 a quarter; other counts span 180
    degrees. A wall 2 m to the left shows in the beam that points there."""
    path = tmp_path / "sick.clf"
    left = round(90.0 / degrees) if beams % 2 else round(89.0 / degrees)  # a beam <= +90
    ranges = [30.0] * beams
    ranges[left] = 2.0
    path.write_text(flaser_line(ranges) + "\n")
    log = read_carmen_log(path)
    np.testing.assert_allclose(log.angle_increment, math.radians(degrees))
    np.testing.assert_allclose(log.angle_min, -math.pi / 2)
    angle = math.radians(-90.0 + left * degrees)
    assert min(np.hypot(*(log.points(0) - [2 * math.cos(angle), 2 * math.sin(angle)]).T)
               ) < 1e-9


def test_flaser_range_and_spacing_from_the_log_s_own_params(tmp_path):
    """A log that states its front laser's maximum range and resolution (CARMEN's
    ``robot_front_laser_max`` and ``laser_front_laser_resolution`` PARAMs) is read by
    them; a smaller ``max_range`` given to the reader still wins; a PARAM that is not a
    number > 0 is refused, naming its line."""
    path = tmp_path / "params.clf"
    params = ("PARAM robot_front_laser_max 8.0 host 0\n"
              "PARAM laser_front_laser_resolution 2.0 host 0\n")
    path.write_text(params + flaser_line([1.0, 7.9, 8.0, 9.5, 3.0]) + "\n")
    log = read_carmen_log(path)
    np.testing.assert_allclose(log.angle_increment, math.radians(2.0))
    np.testing.assert_allclose(log.range_max, 8.0)
    np.testing.assert_array_equal(log.ranges.mask[0], [False, False, True, True, False])
    np.testing.assert_allclose(read_carmen_log(path, max_range=5.0).range_max, 5.0)
    path.write_text("PARAM robot_front_laser_max -1 host 0\n" + flaser_line([1.0]) + "\n")
    with pytest.raises(ValueError, match=r"line 1: robot_front_laser_max must be a number > 0"):
        read_carmen_log(path)


def test_gzipped_log_reads_like_the_plain_one(tmp_path):
    plain, packed = tmp_path / "a.clf", tmp_path / "a.clf.gz"
    plain.write_text(FLASER_LOG)
    packed.write_bytes(gzip.compress(FLASER_LOG.encode()))
    a, b = read_carmen_log(plain), read_carmen_log(packed)
    np.testing.assert_array_equal(a.ranges.filled(-1), b.ranges.filled(-1))
    np.testing.assert_array_equal(a.odometry, b.odometry)


def test_robotlaser1_fields_give_geometry_offset_and_odometry(tmp_path):
    robot = (1.0, 2.0, math.pi / 2)
    laser = tuple(compose(robot, (0.2, 0.05, 0.1)))
    lines = [robotlaser_line([1.0, 9.0, 3.0], [7.0, 7.0, 7.0], laser, robot, 5.0),
             robotlaser_line([2.0, 2.5], [], laser, robot, 5.5, start=-0.5, resolution=1.0),
             "FLASER 2 1.0 1.0 0 0 0 0 0 0 5.0 host 5.0"]  # ignored: ROBOTLASER1 wins
    path = tmp_path / "robot.clf"
    path.write_text("\n".join(lines) + "\n")
    log = read_carmen_log(path)
    assert log.laser_message == "ROBOTLASER1" and len(log) == 2
    np.testing.assert_allclose(log.laser_offset, [0.2, 0.05, 0.1])
    np.testing.assert_allclose(log.odometry, [robot, robot])
    np.testing.assert_allclose(log.angle_min, [-1.0, -0.5])
    np.testing.assert_allclose(log.angle_increment, [0.5, 1.0])
    np.testing.assert_allclose(log.range_max, [8.0, 8.0])
    # 9.0 is beyond the 8 m max range; the shorter scan is padded and masked
    np.testing.assert_array_equal(log.ranges.mask, [[False, True, False], [False, False, True]])
    np.testing.assert_array_equal(log.scan(1).ranges, [2.0, 2.5])
    flaser = read_carmen_log(path, laser_message="FLASER", laser_offset=(0.1, 0.0, 0.0))
    assert len(flaser) == 1 and flaser.laser_offset[0] == 0.1


@pytest.mark.parametrize(("text", "message"), [
    ("FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.0 host\n",
     r"line 1: FLASER with 5 readings needs 16 fields, got 15"),
    ("# ok\nFLASER 3 1 2 3 4 0 0 0 0 0 0 1.0 host 1.0\n",
     r"line 2: FLASER with 3 readings needs 14 fields, got 15"),
    ("FLASER x 1 2\n", r"line 1: FLASER's number of readings 'x' is not a whole number"),
    ("FLASER\n", r"line 1: FLASER has 1 fields, too few to hold its number of readings"),
    ("FLASER 2 1.0 oops 0 0 0 0 0 0 1.0 host 1.0\n", r"line 1: 'oops' is not a number"),
    ("ODOM 1 2 3\n", r"line 1: ODOM needs at least 8 fields"),
    ("ROBOTLASER1 0 -1 2 0.5 8 0.01 0 2 1.0 1.0 5 1 1\n",
     r"line 1: ROBOTLASER1 with 2 readings and 5 remissions needs 31 fields, got 14"),
    ("ODOM 0 0 0 0 0 0 1.0 host 1.0\n", r"no FLASER lines"),
])
def test_bad_lines_are_refused_with_file_and_line(tmp_path, text, message):
    path = tmp_path / "bad.clf"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as error:
        read_carmen_log(path)
    assert str(path) in str(error.value)


def test_missing_and_truncated_files_are_refused(tmp_path):
    with pytest.raises(ValueError, match=r"nothere\.clf: cannot read"):
        read_carmen_log(tmp_path / "nothere.clf")
    packed = gzip.compress((FLASER_LOG * 200).encode())
    path = tmp_path / "cut.clf.gz"
    path.write_bytes(packed[: len(packed) // 2])
    with pytest.raises(ValueError, match=r"cut\.clf\.gz: gzip stream truncated after line \d+"):
        read_carmen_log(path)
    with pytest.raises(ValueError, match="laser_message 'LASER3'"):
        read_carmen_log(tmp_path / "cut.clf.gz", laser_message="LASER3")


# --- relations and the metric -----------------------------------------------------------


def write_relations(path, rows):
    path.write_text("".join(" ".join(f"{v:.6f}" for v in row) + "\n" for row in rows))


def test_relation_errors_of_the_reference_are_zero_and_of_a_shift_known(tmp_path):
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(-5, 5, (20, 2)), rng.uniform(-3, 3, 20)])
    stamps = 100.0 + 0.2 * np.arange(20)
    pairs = [(0, 1), (3, 7), (2, 19), (10, 5)]
    rows = []
    for i, j in pairs:
        x, y, yaw = relative(poses[i], poses[j])
        rows.append([stamps[i], stamps[j], x, y, 0.0, 0.0, 0.0, yaw])
    path = tmp_path / "log.relations"
    write_relations(path, rows)
    relations = read_relations(path, stamps)
    np.testing.assert_array_equal(relations.first, [i for i, _ in pairs])
    np.testing.assert_array_equal(relations.second, [j for _, j in pairs])
    exact = relation_errors(poses, relations)
    np.testing.assert_allclose(exact.translational, 0, atol=1e-5)
    np.testing.assert_allclose(exact.rotational, 0, atol=1e-5)
    # move and turn pose 19 in its own frame: relation (2, 19) errs by exactly that
    moved = poses.copy()
    moved[19] = compose(poses[19], (0.3, -0.4, 0.02))
    errors = relation_errors(moved, relations)
    np.testing.assert_allclose(errors.translational, [0, 0, 0.5, 0], atol=1e-5)
    np.testing.assert_allclose(errors.rotational, [0, 0, 0.02, 0], atol=1e-5)


def test_relations_must_name_scans_of_the_log(tmp_path):
    stamps = np.array([1.0, 1.5, 2.0])
    path = tmp_path / "r.relations"
    write_relations(path, [[1.0, 1.5, 0, 0, 0, 0, 0, 0], [1.5, 1.75, 0, 0, 0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"r\.relations, line 2: timestamp 1\.750000 is not"):
        read_relations(path, stamps)
    path.write_text("1.0 1.5 0 0 0 0 0\n")
    with pytest.raises(ValueError, match=r"line 1: a relation is 8 fields"):
        read_relations(path, stamps)
    path.write_text("1.0 1.5 0 0 0 0 zero 0\n")
    with pytest.raises(ValueError, match=r"line 1: not all of"):
        read_relations(path, stamps)
    # a time written with fewer decimals matches the scan it rounds from
    path.write_text("1.00000 1.50000 0 0 0 0 0 0\n")
    assert read_relations(path, stamps + 4e-6).second[0] == 1


def test_format_relation_errors_gives_two_lines():
    errors = RelationErrors(translational=np.array([0.0, 0.1]),
                            rotational=np.radians([0.0, 1.0]))
    assert format_relation_errors(errors) == ("translational error: 0.050 ± 0.050 m\n"
                                              "rotational error: 0.50 ± 0.50 deg")


# --- the real benchmark logs ------------------------------------------------------------

# (log, relations, reader options, data/slam/README.md's raw odometry error: m, deg)
BENCHMARK_LOGS = {
    name: (f"{name}.clf.gz", f"{name}.relations", LOG_FACTS[name], metres, degrees)
    for name, metres, degrees in (("aces", 0.55, 2.2), ("mit-csail", 1.7, 5.1),
                                  ("fr079", 6.5, 30.0))
}
SHAPES = {"aces": (7374, 180), "mit-csail": (1988, 361), "fr079": (4934, 360)}


@pytest.mark.parametrize("name", list(BENCHMARK_LOGS))
def test_raw_odometry_scores_the_published_relation_errors(name):
    log_file, relations_file, options, metres, degrees = BENCHMARK_LOGS[name]
    log = read_carmen_log(slam_file(log_file), **options)
    assert log.ranges.shape == SHAPES[name]
    assert np.all(np.diff(log.stamps) > 0)
    assert not np.any(log.ranges[~log.ranges.mask] >= NO_RETURN_RANGE)
    relations = read_relations(slam_file(relations_file), log.stamps)
    errors = relation_errors(log.odometry, relations)
    assert errors.translational_mean == pytest.approx(metres, rel=0.1)
    assert errors.rotational_mean_deg == pytest.approx(degrees, rel=0.1)
