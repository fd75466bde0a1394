"""The chair's URDF and the frame tree: transforms against hand-worked cases and
against composing planar poses (abcwc.geometry), and clear errors on bad files."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.description import (
    DescriptionError,
    chair_description,
    homogeneous,
    load_urdf,
    parse_urdf,
)
from abcwc.frames import FrameError, FrameTree, planar_transform
from abcwc.geometry import compose, transform_points
from abcwc.params import default_params
from abcwc.types import Pose2D

ARM = """<robot name="arm">
  <link name="base"/>
  <link name="upper"/>
  <link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 1" rpy="0 0 1.5707963267948966"/>
  </joint>
  <joint name="elbow" type="fixed">
    <parent link="upper"/><child link="tool"/>
    <origin xyz="2 0 0" rpy="0 1.5707963267948966 0"/>
  </joint>
</robot>"""


def test_rpy_is_fixed_axis_roll_then_pitch_then_yaw():
    """URDF: R = Rz(yaw) Ry(pitch) Rx(roll); a quarter roll then a quarter yaw takes
    y onto z and x onto y."""
    rotation = homogeneous(rpy=(math.pi / 2, 0.0, math.pi / 2))[:3, :3]
    np.testing.assert_allclose(rotation @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rotation @ [0, 1, 0], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(rotation @ [0, 0, 1], [1, 0, 0], atol=1e-12)


def test_a_chain_of_joints_composes_by_hand():
    """The shoulder lifts 1 m and turns 90 degrees about z; the elbow reaches 2 m along
    the upper arm's x, now the base's y: the tool sits at (0, 2, 1)."""
    arm = parse_urdf(ARM)
    assert arm.root == "base" and arm.parent_of("tool") == "upper"
    assert [j.name for j in arm.chain("tool")] == ["shoulder", "elbow"]
    np.testing.assert_allclose(arm.transform("tool")[:3, 3], [0, 2, 1], atol=1e-12)
    # a quarter pitch about y takes z onto x (Ry z = (sin, 0, cos)): the tool's z axis is
    # the upper arm's x, which the shoulder turned onto the base's y
    np.testing.assert_allclose(arm.transform("tool")[:3, 2], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(arm.transform("tool", "upper")[:3, 3], [2, 0, 0], atol=1e-12)


@pytest.mark.parametrize("text, message", [
    ("<robot><link name='a'/><link name='a'/></robot>", "defined twice"),
    ("<robot><link name='a'/><joint name='j' type='fixed'><parent link='a'/>"
     "<child link='b'/></joint></robot>", "link 'b', which is not defined"),
    ("<robot><link name='a'/><link name='b'/></robot>", "exactly one root"),
    ("<robot><link name='a'/><link name='b'/><joint name='j' type='hinge'>"
     "<parent link='a'/><child link='b'/></joint></robot>", "type 'hinge'"),
    ("<robot><link name='a'/><link name='b'/><joint name='j' type='fixed'>"
     "<parent link='a'/><child link='b'/><origin xyz='1 2'/></joint></robot>",
     "3 finite numbers"),
    ("<robot><link name='a'><visual><geometry><box size='1 -1 1'/></geometry></visual>"
     "</link></robot>", "must be positive"),
    ("<robot><link name='a'><visual><geometry><mesh filename='x.stl'/></geometry>"
     "</visual></link></robot>", "meshes are not read"),
    ("<robot><link name='a'>", "not well-formed"),
    ("<sdf/>", "must be <robot>"),
])
def test_a_bad_urdf_is_refused_with_the_reason(text, message):
    with pytest.raises(DescriptionError, match=message):
        parse_urdf(text, "bad.urdf")


def test_a_missing_urdf_names_the_file(tmp_path):
    with pytest.raises(DescriptionError, match="nowhere.urdf: cannot read"):
        load_urdf(tmp_path / "nowhere.urdf")


def test_the_chair_description_is_one_tree_with_every_sensor_frame():
    chair = chair_description()
    assert chair.root == "base_link"
    for frame in default_params().sensors:
        chair.chain(frame)  # reaches base_link
    assert chair.parent_of("depth_scan_link") == "camera_link"
    # the tray sensors sit above the lidar, the IR ring below it
    assert chair.height("depth_scan_link") > chair.height("sonar_link") > \
        chair.height("lidar_link") > chair.height("ir_0_link") > 0


def test_rep105_chain_agrees_with_composing_planar_poses():
    """map -> odom -> base_link -> lidar_link by the tree equals compose() of the same
    planar poses, for points and for poses."""
    tree = FrameTree.from_description(chair_description())
    map_to_odom, odom_to_base = Pose2D(1.0, -2.0, 0.3), Pose2D(4.0, 1.5, -2.0)
    tree.set_pose("map", "odom", map_to_odom)
    tree.set_pose("odom", "base_link", odom_to_base)
    mount = Pose2D(*default_params().lidar.mount)
    expected = compose(compose(map_to_odom, odom_to_base), mount)
    rng = np.random.default_rng(5)
    points = rng.uniform(-5, 5, (20, 2))
    np.testing.assert_allclose(tree.transform_points(points, "lidar_link", "map"),
                               transform_points(expected, points), atol=1e-12)
    got = tree.pose_of("lidar_link", "map")
    np.testing.assert_allclose((got.x, got.y, got.theta), (expected.x, expected.y, expected.theta),
                               atol=1e-12)
    # and back: the map's points seen from the lidar
    back = tree.transform_points(transform_points(expected, points), "map", "lidar_link")
    np.testing.assert_allclose(back, points, atol=1e-12)
    # 3-D: a point at the lidar keeps the lidar's height in the map
    at_lidar = tree.transform_points(np.zeros((1, 3)), "lidar_link", "map")
    assert at_lidar[0, 2] == pytest.approx(default_params().lidar.height)


def test_lookups_between_sibling_sensors_and_across_branches():
    tree = FrameTree.from_description(chair_description())
    # ir_0 faces forward at (0.34, 0); ir_3 faces back at (-0.06, 0): 0.4 m apart
    pose = tree.pose_of("ir_3_link", "ir_0_link")
    assert (pose.x, pose.y) == pytest.approx((-0.4, 0.0), abs=1e-12)
    assert abs(abs(pose.theta) - math.pi) < 1e-12
    lookup = tree.lookup("ir_0_link", "ir_3_link")
    np.testing.assert_allclose(np.linalg.inv(lookup), tree.lookup("ir_3_link", "ir_0_link"),
                               atol=1e-12)


def test_frame_tree_errors_say_what_is_wrong():
    tree = FrameTree()
    tree.set_pose("map", "odom", (0, 0, 0))
    tree.set_pose("odom", "base_link", (1, 0, 0))
    tree.set_pose("elsewhere", "thing", (0, 0, 0))
    with pytest.raises(FrameError, match="no frame 'lidar'"):
        tree.lookup("map", "lidar")
    with pytest.raises(FrameError, match="separate trees"):
        tree.lookup("map", "thing")
    with pytest.raises(FrameError, match="loop"):
        tree.set_pose("base_link", "map", (0, 0, 0))
    with pytest.raises(FrameError, match="one parent"):
        tree.set_pose("map", "base_link", (0, 0, 0))
    with pytest.raises(ValueError, match="finite"):
        tree.set_pose("odom", "base_link", (math.nan, 0, 0))
    with pytest.raises(ValueError, match=r"\(N, 2\) or \(N, 3\)"):
        tree.transform_points(np.zeros(3), "odom", "map")
    # moving a frame under the same parent is how a pose is updated
    tree.set_pose("odom", "base_link", (2, 0, 0))
    np.testing.assert_allclose(tree.lookup("map", "base_link"), planar_transform((2, 0, 0)))
