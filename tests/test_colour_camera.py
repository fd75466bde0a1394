"""The simulator's colour camera against closed-form projection: where a wall meets the
floor, where a target's corners land, what hides it."""

import math

import cv2
import numpy as np
import pytest

from abcwc.perception.camera import PinholeCamera
from abcwc.perception.tags import aruco_marker_image, detect_aruco_markers
from abcwc.sim import SimBase
from abcwc.sim.colour_camera import (
    CEILING_RGB,
    LUMINANCE,
    Imaging,
    PlanarTarget,
    motion_blur,
    nearest_cover,
    render_colour,
    world_to_optical,
)
from abcwc.types import CAMERA_FRAME, CameraImage, Pose2D

CAMERA = PinholeCamera.from_fov(640, 480, 57.0, 43.0)
MOUNT = (0.3, 0.0, 0.0)
HEIGHT = 0.76
POSE = Pose2D(0.0, 0.0, 0.0)
ORIGIN = np.array([0.3, 0.0])


def wall_ahead(distance: float) -> tuple[np.ndarray, np.ndarray]:
    """One long wall across the camera's view, ``distance`` m ahead of the lens."""
    x = ORIGIN[0] + distance
    return np.array([[x, -20.0, x, 20.0]]), np.array([[0.0, 2.5]])


NO_PEOPLE = np.zeros((0, 3))


def render(segments, bands, circles=NO_PEOPLE, targets=(), rng=None, gray=False):
    return render_colour(CAMERA, POSE, MOUNT, HEIGHT, segments, bands, circles, targets,
                         rng, gray=gray)


def test_a_wall_meets_the_floor_and_the_ceiling_where_the_pinhole_puts_them():
    distance = 6.0  # far enough for the wall's top to be in view
    image = render(*wall_ahead(distance)).astype(float)
    column = image[:, CAMERA.width // 2]
    foot = CAMERA.cy + CAMERA.fy * HEIGHT / distance  # the wall's foot: v = cy + fy h / z
    top = CAMERA.cy - CAMERA.fy * (2.5 - HEIGHT) / distance
    wall = column[int(CAMERA.cy)]
    assert np.allclose(column[math.ceil(foot) + 1], column[math.ceil(foot) + 2], atol=3)
    assert not np.allclose(column[math.ceil(foot) + 1], wall, atol=3)  # floor below
    assert np.allclose(column[math.floor(foot) - 1], wall)  # wall above its foot
    assert np.allclose(column[math.floor(top) - 1], CEILING_RGB)  # ceiling over its top
    assert np.allclose(column[math.ceil(top) + 1], wall)


def test_with_nothing_standing_within_reach_the_cameras_see_floor_and_ceiling():
    """A hall whose walls are all beyond the camera's 30 m, with no one in it: the
    picture is the floor below the horizon and the ceiling above (the same as a wall at
    100 m gives), and the depth camera reads only the floor; a chair in such a hall
    drives with its camera on."""
    from abcwc.sim.depth_camera import render_depth
    from abcwc.sim.world import box_world
    from abcwc.types import Twist

    nothing = render(np.zeros((0, 4)), np.zeros((0, 2)))
    assert np.array_equal(nothing, render(*wall_ahead(100.0)))
    assert np.allclose(nothing[0], CEILING_RGB) and not np.allclose(nothing[-1], CEILING_RGB)
    depth = render_depth(CAMERA, POSE, MOUNT, HEIGHT, np.zeros((0, 4)), np.zeros((0, 2)),
                         NO_PEOPLE, 0.5, 30.0)
    rows = np.arange(CAMERA.height) - CAMERA.cy
    below = rows > CAMERA.fy * HEIGHT / 30.0  # rows whose floor is within 30 m
    assert np.allclose(depth[below, 0], CAMERA.fy * HEIGHT / rows[below])
    assert np.isnan(depth[~below]).all()
    chair = SimBase(box_world(80.0, 80.0), people=False, camera="gray")
    chair.drive(Twist(0.3, 0.0), 0.5)
    assert chair.frame.readings[CAMERA_FRAME].pixels.shape == (480, 640)


def test_a_marker_is_drawn_where_its_corners_project_and_is_found_there():
    marker = aruco_marker_image(3, cell_px=40)
    side = 0.3 * 6 / 8  # the black square of a 0.3 m card with a one-cell quiet zone
    centre = (ORIGIN[0] + 2.0, 0.25, 0.9)
    target = PlanarTarget("marker", marker, 0.3, centre, math.pi - 0.4)
    image = render(*wall_ahead(5.0), targets=(target,), gray=True)
    found = detect_aruco_markers(image)
    assert [m.marker_id for m in found] == [3]
    # the black square's corners: the card's corners shrunk by the quiet zone
    card = target.corners()
    square = card.mean(axis=0) + (card - card.mean(axis=0)) * (side / 0.3)
    optical = world_to_optical(square, ORIGIN, 0.0, HEIGHT)
    expected = np.column_stack([CAMERA.cx + CAMERA.fx * optical[:, 0] / optical[:, 2],
                                CAMERA.cy + CAMERA.fy * optical[:, 1] / optical[:, 2]])
    assert np.abs(found[0].corners - expected).max() < 0.35  # px


def test_walls_and_people_hide_a_target_and_its_back_is_not_drawn():
    card = np.zeros((40, 40), np.uint8)  # black: easy to find
    centre = (ORIGIN[0] + 3.0, 0.0, 0.9)
    facing_camera = PlanarTarget("card", card, 0.4, centre, math.pi)
    walls, bands = wall_ahead(6.0)

    def dark_pixels(image):
        return int((image < 20).sum())

    assert dark_pixels(render(walls, bands, targets=(facing_camera,), gray=True)) > 1000
    between = np.vstack([walls, [[ORIGIN[0] + 1.5, -1.0, ORIGIN[0] + 1.5, 1.0]]])
    hidden = render(between, np.vstack([bands, [[0.0, 2.5]]]), targets=(facing_camera,),
                    gray=True)
    assert dark_pixels(hidden) == 0
    person = np.array([[ORIGIN[0] + 2.0, 0.0, 0.25]])
    behind_a_person = render(walls, bands, person, targets=(facing_camera,), gray=True)
    assert dark_pixels(behind_a_person) == 0
    turned_away = PlanarTarget("card", card, 0.4, centre, 0.0)
    assert dark_pixels(render(walls, bands, targets=(turned_away,), gray=True)) == 0


def test_grey_is_the_colour_image_s_luminance_and_noise_is_seeded():
    walls, bands = wall_ahead(3.0)
    people = np.array([[ORIGIN[0] + 2.0, 0.5, 0.25]])
    colour = render(walls, bands, people)
    gray = render(walls, bands, people, gray=True)
    assert np.abs(colour.astype(float) @ LUMINANCE - gray).max() <= 1.0
    assert np.abs(cv2.cvtColor(colour, cv2.COLOR_RGB2GRAY).astype(int) - gray).max() <= 1
    one = render(walls, bands, rng=np.random.default_rng(4))
    again = render(walls, bands, rng=np.random.default_rng(4))
    other = render(walls, bands, rng=np.random.default_rng(5))
    assert np.array_equal(one, again) and not np.array_equal(one, other)


def test_each_pixel_shows_the_nearest_layer_covering_it_as_painting_far_to_near_would():
    rng = np.random.default_rng(11)
    rows, width, layers = 40, 300, 6
    top = rng.uniform(-10.0, 50.0, (width, layers)).astype(np.float32)
    bottom = (top + rng.uniform(-5.0, 30.0, (width, layers))).astype(np.float32)
    top[rng.random((width, layers)) < 0.1] = np.inf  # a layer the column's ray missed
    bottom[rng.random((width, layers)) < 0.05] = np.inf
    top[rng.random((width, layers)) < 0.05] = -np.inf
    bottom[rng.random((width, layers)) < 0.03] = np.nan
    top[:5] = np.round(top[:5])  # runs that start and end on a row exactly
    bottom[:5] = np.round(bottom[:5])
    painted = np.full((rows, width), -1)
    v = np.arange(rows, dtype=np.float32)[:, None]
    for j in range(layers):  # far to near, each layer over the ones behind it
        painted[(v >= top[:, j]) & (v <= bottom[:, j])] = j
    assert np.array_equal(nearest_cover(top, bottom, rows), painted)
    with pytest.raises(ValueError, match="at most 8"):
        nearest_cover(np.zeros((3, 9), np.float32), np.ones((3, 9), np.float32), 4)


def test_the_simulated_chair_sends_its_camera_image_in_the_frame():
    chair = SimBase("lab", camera="gray")
    image = chair.step().readings[CAMERA_FRAME]
    assert isinstance(image, CameraImage) and image.pixels.shape == (480, 640)
    assert (image.fx, image.cx) == (chair.camera.fx, chair.camera.cx)
    stamps = sorted({chair.step().readings[CAMERA_FRAME].stamp for _ in range(25)})
    assert np.allclose(np.diff(stamps[1:]), 0.1)  # 10 Hz: a new image every fifth period
    assert CAMERA_FRAME not in SimBase("lab").step().readings


def test_bad_camera_input_is_refused_with_what_is_allowed():
    with pytest.raises(ValueError, match="rgb, gray"):
        SimBase("lab", camera="infrared")
    with pytest.raises(ValueError, match="uint8"):
        PlanarTarget("sign", np.zeros((4, 4)), 0.2, (0, 0, 1), 0.0)
    with pytest.raises(ValueError, match="width"):
        PlanarTarget("sign", np.zeros((4, 4), np.uint8), 0.0, (0, 0, 1), 0.0)
    with pytest.raises(ValueError, match="finite"):
        PlanarTarget("sign", np.zeros((4, 4), np.uint8), 0.2, (0, math.nan, 1), 0.0)


def test_each_frame_has_its_own_noise_not_a_shifted_copy():
    """Two frames of the same still scene from one generator: their noise residuals
    (frame minus the ideal image) are unrelated at every shift, and have the std asked
    for."""
    walls, bands = wall_ahead(3.0)
    ideal = render(walls, bands, gray=True).astype(np.float32)
    imaging = Imaging(gain=(1.0, 1.0), blur_sigma=0.0, noise_std=8.0, exposure=0.0)
    rng = np.random.default_rng(3)
    first, second = (render_colour(CAMERA, POSE, MOUNT, HEIGHT, walls, bands, NO_PEOPLE, (),
                                   rng, imaging, gray=True).astype(np.float32) - ideal
                     for _ in range(2))
    centre = second[100:380, 100:540]
    # every shift of up to 100 px: a shifted copy would correlate 1 at one of them
    best = cv2.matchTemplate(first, centre, cv2.TM_CCOEFF_NORMED).max()
    assert best < 0.1
    assert np.std(first[50:-50, 50:-50]) == pytest.approx(8.0, rel=0.05)  # before clipping


def edge_width(row: np.ndarray) -> int:
    """px between 10 % and 90 % of the way from a row's dark to its light level."""
    low, high = row.min(), row.max()
    inside = (row > low + 0.1 * (high - low)) & (row < low + 0.9 * (high - low))
    return int(inside.sum())


@pytest.mark.parametrize("turn", [0.0, 0.2, 0.4])
def test_turning_smears_the_image_sideways_by_the_angle_turned_in_the_exposure(turn):
    """A black card's vertical edges: sharp without motion, a ramp of fx w T px when
    the chair turns at w rad/s for T s (a rotation moves the image by fx times the angle
    turned, whatever the depth)."""
    card = PlanarTarget("card", np.zeros((40, 40), np.uint8), 0.6, (ORIGIN[0] + 2.0, 0.0, 0.76),
                        math.pi)
    walls, bands = wall_ahead(4.0)
    imaging = Imaging(gain=(1.0, 1.0), blur_sigma=0.0, noise_std=0.0, exposure=0.03)
    image = render_colour(CAMERA, POSE, MOUNT, HEIGHT, walls, bands, NO_PEOPLE, (card,),
                          np.random.default_rng(0), imaging, gray=True, motion=(0.0, turn))
    row = image[int(CAMERA.cy)].astype(float)
    left_edge = row[: int(CAMERA.cx)]
    assert edge_width(left_edge) == pytest.approx(0.8 * CAMERA.fx * turn * 0.03, abs=1.5)


def test_driving_smears_each_pixel_along_its_path_from_the_principal_point():
    """Driving at v m/s for T s, a point at depth z and u - cx px off centre moves
    (u - cx) v T / z px: the edge between a card's black and white halves, well left of
    centre, smears by that much; the principal point does not move."""
    halves = np.zeros((400, 400), np.uint8)  # finer than the screen: a sharp edge
    halves[:, 200:] = 255
    depth, left = 1.5, 0.4
    card = PlanarTarget("card", halves, 0.6, (ORIGIN[0] + depth, left, 0.76), math.pi)
    walls, bands = wall_ahead(4.0)
    imaging = Imaging(gain=(1.0, 1.0), blur_sigma=0.0, noise_std=0.0, exposure=0.05)
    still, moving = (render_colour(CAMERA, POSE, MOUNT, HEIGHT, walls, bands, NO_PEOPLE,
                                   (card,), np.random.default_rng(0), imaging, gray=True,
                                   motion=(v, 0.0))[int(CAMERA.cy)].astype(float)
                     for v in (0.0, 1.0))
    edge = round(CAMERA.cx - CAMERA.fx * left / depth)  # where the halves meet
    window = slice(edge - 15, edge + 16)
    expected = (CAMERA.cx - edge) * 1.0 * 0.05 / depth
    assert edge_width(still[window]) <= 1
    assert edge_width(moving[window]) == pytest.approx(0.8 * expected, abs=1.5)
    assert moving[int(CAMERA.cx)] == pytest.approx(still[int(CAMERA.cx)])
    with pytest.raises(ValueError, match="exposure"):
        Imaging(exposure=-0.01)


def plain_driving_blur(image: np.ndarray, depth: np.ndarray, along: float,
                       samples: int) -> np.ndarray:
    """The driving blur written out plainly (module notes of abcwc.sim.colour_camera):
    the mean of ``samples`` copies of ``image``, each pixel fetched from ``t`` of its
    path ``(u - cx, v - cy) along / z`` px, ``t`` evenly from -1/2 to 1/2."""
    rows, cols = image.shape
    u, v = np.meshgrid(np.arange(cols, dtype=np.float32), np.arange(rows, dtype=np.float32))
    grow = (along / depth).astype(np.float32)
    du, dv = (u - np.float32(CAMERA.cx)) * grow, (v - np.float32(CAMERA.cy)) * grow
    total = np.zeros_like(image)
    for t in np.linspace(-0.5, 0.5, samples, dtype=np.float32):
        total += cv2.remap(image, u + t * du, v + t * dv, cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_REPLICATE)
    return total / np.float32(samples)


@pytest.mark.parametrize("speed", [0.3, 1.0, 3.0])
def test_the_driving_blur_is_the_plain_mean_of_samples_along_each_path(speed):
    """The blur as the simulator computes it (its pixel grids kept between frames, its
    sample maps built in place, the longest path found from its square) is, bit for
    bit, the plain mean of copies along each pixel's path, with one sample per pixel of
    the longest path plus one (3 to 9)."""
    rng = np.random.default_rng(7)
    image = rng.uniform(0, 255, (CAMERA.height, CAMERA.width)).astype(np.float32)
    depth = rng.uniform(2.0, 20.0, image.shape).astype(np.float32)  # 3, 7 and 9 samples
    exposure = 0.03
    along = speed * exposure
    reach = (np.hypot(*np.meshgrid(np.arange(CAMERA.width) - CAMERA.cx,
                                   np.arange(CAMERA.height) - CAMERA.cy)) * along / depth)
    samples = int(np.clip(math.ceil(reach.max()) + 1, 3, 9))
    blurred = motion_blur(image, CAMERA, depth, speed, 0.0, exposure)
    assert np.array_equal(blurred, plain_driving_blur(image, depth, along, samples))
    assert np.array_equal(motion_blur(image, CAMERA, depth, speed, 0.0, exposure), blurred)
