"""A colour camera in the simulator: the Kinect's RGB image of walls, objects, people,
the floor and flat textured targets (door signs, posters, a tag on a person's back).

The geometry is :mod:`abcwc.sim.depth_camera`'s: a pinhole camera looking straight
ahead at ``height`` m, column ``u`` a ray at bearing ``-atan((u - cx) / fx)``, row ``v``
sloping down by ``(v - cy) / fy`` per metre ahead. Each pixel shows the nearest surface
its ray meets: a wall or object standing between two heights, a person (a cylinder up to
``PERSON_HEIGHT``), the floor below the horizon, or the ceiling's shade above it. Walls
are shaded by the angle between their face and the room's light (Lambert's cosine law),
the floor darkens with distance, so the image has a horizon and corners a detector can
see without pretending to be a photograph.

**Targets** are planar rectangles carrying an image (:class:`PlanarTarget`). Each one in
view is drawn with one homography: its four corners projected through the camera
(``u = cx + fx x / z``, ``v = cy + fy y / z`` in the optical frame) fix the 3 x 3 map
from the texture to the image (Hartley and Zisserman, *Multiple View Geometry*, 2nd ed.,
section 2.3: a plane's image is a projective transformation of it), and
``cv2.warpPerspective`` draws it. The texture is first shrunk with area averaging to
about twice the size it will have on screen, as a camera's pixels average the light
that falls on them (a straight warp of a large texture would alias a QR code's modules
into noise). A target pixel is drawn only where the target is nearer than the scene
behind it: its depth along the ray, ``z = (n . p0) / (n . d)`` for the plane through
``p0`` with normal ``n`` and the pixel's ray ``d``, against the pixel's depth, so walls
and people hide it as they should. A target seen from behind is not drawn.

**Imaging**: each frame gets a lighting gain drawn from :attr:`Imaging.gain` (rooms and
exposure differ), a Gaussian blur of :attr:`Imaging.blur_sigma` px (focus), motion blur
and Gaussian noise of :attr:`Imaging.noise_std` grey levels, fresh for every frame, all
from the seeded generator the caller passes. **Motion blur** is the image's motion
during the exposure (:attr:`Imaging.exposure` s) while the chair moves at ``motion``
(v m/s ahead, w rad/s left): turning sweeps every pixel sideways by ``fx w T`` px
whatever its depth (a pure rotation moves the image by the angle turned), so the frame
is smeared along a horizontal line that long; driving ahead moves each pixel away from
the principal point by ``(p - c) v T / z`` px for a surface ``z`` m ahead (the image of
a point at depth z scales as 1/z), so the frame is averaged over samples along each
pixel's own path. At 0.4 rad/s and 30 ms that is 7 px; at 0.5 m/s a sign 2 m ahead and
200 px off centre moves 1.5 px.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from abcwc.geometry import compose
from abcwc.perception.camera import PinholeCamera
from abcwc.sim.depth_camera import column_hits, floor_depth
from abcwc.sim.world import WALL_HEIGHT
from abcwc.types import Pose2D

FLOOR_RGB = np.array([150.0, 140.0, 125.0])
"""The floor's colour near the chair (linoleum)."""
CEILING_RGB = np.array([225.0, 225.0, 220.0])
WALL_RGB = np.array([205.0, 200.0, 190.0])
OBJECT_RGB = np.array([130.0, 95.0, 65.0])
"""Furniture (anything not standing from the floor to the ceiling): wood."""
PEOPLE_RGB = np.array([[60.0, 80.0, 140.0], [140.0, 60.0, 60.0], [70.0, 120.0, 70.0],
                       [110.0, 100.0, 60.0]])
"""Clothes: the k-th person wears colour k modulo 4."""
LIGHT_DIRECTION = np.array([0.6, 0.8])
"""Unit vector (map frame) along which the room's main light falls on the walls."""
LUMINANCE = np.array([0.299, 0.587, 0.114], dtype=np.float32)
"""RGB weights of grey (ITU-R BT.601)."""
NEAREST_SURFACES = 6
"""Surfaces kept per column (nearest first): enough for a table's top and legs before
the wall behind it."""


@dataclass(frozen=True)
class PlanarTarget:
    """A flat rectangle carrying ``image`` ((h, w) grey or (h, w, 3) RGB, uint8), ``width``
    m wide (its height follows the image's aspect), standing upright with its centre at
    ``centre`` (x, y, z m, map frame) and facing ``facing`` (rad: the heading of its
    front's normal, the side it is seen from)."""

    name: str
    image: np.ndarray
    width: float
    centre: tuple[float, float, float]
    facing: float

    def __post_init__(self) -> None:
        image = np.asarray(self.image)
        if image.dtype != np.uint8 or image.ndim not in (2, 3) or min(image.shape[:2]) < 2:
            raise ValueError(f"target {self.name!r}: image must be an (h, w) or (h, w, 3) "
                             f"uint8 array, got {image.dtype} {image.shape}")
        if not (math.isfinite(self.width) and self.width > 0):
            raise ValueError(f"target {self.name!r}: width must be a finite number > 0 m, "
                             f"got {self.width!r}")
        if not all(math.isfinite(v) for v in (*self.centre, self.facing)):
            raise ValueError(f"target {self.name!r}: centre and facing must be finite")

    @property
    def height(self) -> float:
        """m, from the width and the image's aspect ratio."""
        return self.width * self.image.shape[0] / self.image.shape[1]

    def corners(self) -> np.ndarray:
        """(4, 3) map points of the image's top-left, top-right, bottom-right and
        bottom-left corners as seen from the front."""
        # seen from the front, looking along -normal, the image's right is the
        # viewing direction turned 90 degrees clockwise
        right = np.array([-math.sin(self.facing), math.cos(self.facing), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        c = np.asarray(self.centre, dtype=float)
        half_w, half_h = self.width / 2, self.height / 2
        return np.array([c - half_w * right + half_h * up, c + half_w * right + half_h * up,
                         c + half_w * right - half_h * up, c - half_w * right - half_h * up])


@dataclass(frozen=True)
class Imaging:
    """How a frame departs from the ideal: a lighting gain drawn uniformly from
    ``gain``, a Gaussian blur of ``blur_sigma`` px, fresh noise of ``noise_std`` grey
    levels, and the motion blur of an ``exposure`` s long (module notes; 0: none).

    A real indoor camera's exposure is about 30 ms: the Kinect's colour camera takes 30
    frames/s, so no exposure lasts longer than a frame's 33 ms, and under a room's few
    hundred lux automatic exposure runs at or near that limit, and that is the default:
    turning at 0.4 rad/s smears the image by 7 px. ``exposure=0`` gives stills that do
    not smear, for a test that needs them."""

    gain: tuple[float, float] = (0.8, 1.15)
    blur_sigma: float = 0.7
    noise_std: float = 3.0
    exposure: float = 0.03  # s the shutter is open (motion blur; 0: none)

    def __post_init__(self) -> None:
        low, high = self.gain
        if not (0 < low <= high and math.isfinite(high)):
            raise ValueError(f"gain must be (low, high) with 0 < low <= high, got {self.gain}")
        for name in ("blur_sigma", "noise_std", "exposure"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")


def world_to_optical(points: np.ndarray, origin: np.ndarray, heading: float,
                     height: float) -> np.ndarray:
    """Map points (N, 3) in the camera's optical frame (N, 3: x right, y down, z ahead;
    REP 103) for a camera at ``origin`` (x, y) and ``height`` m looking along
    ``heading`` (rad), level."""
    dx, dy = points[:, 0] - origin[0], points[:, 1] - origin[1]
    c, s = math.cos(heading), math.sin(heading)
    ahead, left = c * dx + s * dy, -s * dx + c * dy
    return np.column_stack([-left, height - points[:, 2], ahead])


def render_colour(camera: PinholeCamera, pose: Pose2D, mount: tuple[float, float, float],
                  height: float, segments: np.ndarray, bands: np.ndarray,
                  circles: np.ndarray, targets: tuple[PlanarTarget, ...] = (),
                  rng: np.random.Generator | None = None, imaging: Imaging | None = None,
                  max_range: float = 30.0, gray: bool = False,
                  motion: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """The RGB image (height x width x 3, uint8) of a camera at ``height`` m on the chair
    at ``pose``, mounted at ``mount`` (x, y, yaw in base_link), seeing wall
    ``segments`` (N, 4) standing between ``bands`` (N, 2), people ``circles`` (M, 3),
    the floor and ``targets`` (module notes). With ``rng``, the frame gets
    ``imaging``'s lighting, blur, noise and the motion blur of the chair moving at
    ``motion`` (v m/s ahead, w rad/s left); without, it is the ideal image. With
    ``gray``, the image is (height x width) luminance (ITU-R BT.601, as OpenCV's
    RGB2GRAY), at a third of the cost."""
    sensor = compose(pose, mount)  # x, y, heading in the world
    origin, heading = sensor[:2], sensor[2]
    seen = column_hits(camera, origin, heading, segments, bands, circles, max_range)
    z_hits, low, high, slope = seen.z, seen.low, seen.high, seen.slope
    people = len(low) - len(seen.walls)
    colours = np.vstack([_wall_colours(seen.walls, seen.bands, origin),
                         PEOPLE_RGB[np.arange(people) % len(PEOPLE_RGB)]])
    if not z_hits.shape[1]:  # nothing stands within reach: one layer that is never hit
        z_hits, low, high = np.full((camera.width, 1), np.inf), np.zeros(1), np.zeros(1)
        colours = np.zeros((1, 3))
    # the nearest few surfaces of each column, far to near
    keep = min(NEAREST_SURFACES, z_hits.shape[1])
    if keep < z_hits.shape[1]:
        nearest = np.argpartition(z_hits, keep - 1, axis=1)[:, :keep]
    else:
        nearest = np.broadcast_to(np.arange(keep), z_hits.shape)
    z_near = np.take_along_axis(z_hits, nearest, axis=1)  # (W, J)
    order = np.argsort(-z_near, axis=1)  # far to near (no hit, inf, first)
    nearest = np.take_along_axis(nearest, order, axis=1)
    z_near = np.take_along_axis(z_near, order, axis=1)
    # each surface fills one run of rows in each column it crosses: row v's ray is at
    # height `height - slope z` at depth z, so a surface standing from `low` to `high`
    # z m ahead fills rows cy + fy (height - high) / z to cy + fy (height - low) / z.
    # Each pixel shows the nearest surface whose run covers it, else the floor or ceiling.
    hit = np.isfinite(z_near)
    safe_z = np.where(hit, z_near, 1.0)
    top = np.where(hit, camera.cy + camera.fy * (height - high[nearest]) / safe_z,
                   np.inf).astype(np.float32)
    bottom = (camera.cy + camera.fy * (height - low[nearest]) / safe_z).astype(np.float32)
    shown = nearest_cover(top, bottom, camera.height)  # (H, W): layer index, -1 none
    floor_z = floor_depth(slope, height)
    fade = (0.55 + 0.45 * np.exp(-floor_z / 12.0)).astype(np.float32)  # the floor darkens
    palette = np.vstack([CEILING_RGB, FLOOR_RGB, colours]).astype(np.float32)
    if gray:
        palette = (palette @ LUMINANCE[:, None])[:, 0]
    on_floor = np.isfinite(floor_z)
    background = palette[on_floor.astype(int)]  # (H[, 3]) each row's floor or ceiling
    background[on_floor] *= fade[on_floor].reshape(-1, *(1,) * (background.ndim - 1))
    # each pixel the colour of the layer it shows, else its row's floor or ceiling
    layer_colours = palette[2 + nearest.T].reshape(-1, *palette.shape[1:])  # (J W[, 3])
    image = layer_colours[np.maximum(shown, 0).astype(np.intp) * camera.width
                          + np.arange(camera.width)]
    np.copyto(image, background[:, None], where=(shown < 0).reshape(
        *shown.shape, *(1,) * (background.ndim - 1)))
    depth = SceneDepth(shown, z_near.astype(np.float32), floor_z.astype(np.float32))
    imaging = imaging or Imaging()
    driving = rng is not None and imaging.exposure > 0 and motion[0] != 0
    # each pixel's depth, targets included, for the blur of driving ahead
    z_image = depth.box(0, camera.height, 0, camera.width) if driving else None
    for target in sorted(targets, key=lambda t: -_distance(t, origin)):
        _draw_target(image, depth, camera, target, origin, heading, height, z_image)
    if rng is not None:
        image = motion_blur(image, camera, z_image, *motion, imaging.exposure)
        image = _imaging(image, rng, imaging)
    return np.clip(image, 0, 255).astype(np.uint8)


def _wall_colours(walls: np.ndarray, bands: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(N, 3) each segment's shade: walls by Lambert's law, furniture in wood."""
    if not len(walls):
        return np.zeros((0, 3))
    edge = walls[:, 2:4] - walls[:, :2]
    normal = np.column_stack([-edge[:, 1], edge[:, 0]])
    normal /= np.maximum(np.hypot(*normal.T), 1e-12)[:, None]
    lit = 0.6 + 0.4 * np.abs(normal @ LIGHT_DIRECTION)
    full_height = (bands[:, 0] <= 0.0) & (bands[:, 1] >= WALL_HEIGHT)
    base = np.where(full_height[:, None], WALL_RGB, OBJECT_RGB)
    return base * lit[:, None]


_HIGHEST_BIT = np.array([-1] + [n.bit_length() - 1 for n in range(1, 256)], np.int8)
"""The index of the highest set bit of each byte, -1 for none."""


def nearest_cover(top: np.ndarray, bottom: np.ndarray, rows: int) -> np.ndarray:
    """(rows, W) int8: for each pixel, the last of the J layers whose run of rows covers
    it (-1: none), each layer j covering rows ``top[:, j] <= v <= bottom[:, j]`` (W, J)
    of each column. Layers are ordered far to near, so the last one covering a pixel is
    the one seen there. Each layer sets its own bit over its run, through a difference
    array summed down the rows; the highest bit set is the nearest layer (J <= 8)."""
    width, layers = top.shape
    if layers > 8:
        raise ValueError(f"at most 8 layers fit the bit mask, got {layers}")
    first, last = np.ceil(top), np.floor(bottom)  # whole rows inside each run
    empty = ~(first <= last) | (last < 0) | (first > rows - 1)  # NaN too
    first = np.where(empty, rows, np.clip(first, 0, rows)).astype(np.intp)
    after = np.where(empty, rows, np.clip(last, -1, rows - 1) + 1).astype(np.intp)
    marks = np.zeros((rows + 1, width), np.uint8)
    columns = np.arange(width)
    for j in range(layers):
        bit = np.uint8(1 << j)
        marks[first[:, j], columns] += bit
        marks[after[:, j], columns] -= bit  # wraps round, and the sum below back
    return _HIGHEST_BIT[np.cumsum(marks[:rows], axis=0, dtype=np.uint8)]


@dataclass(frozen=True)
class SceneDepth:
    """The depth (m, along the optical axis) of what each pixel shows: layer ``shown``
    (H, W; -1 the floor or nothing) at ``z`` (W, J), or the floor's ``floor_z`` (H,)."""

    shown: np.ndarray
    z: np.ndarray
    floor_z: np.ndarray

    def box(self, top: int, bottom: int, left: int, right: int) -> np.ndarray:
        """(bottom - top, right - left): the depth of rows top..bottom-1, columns
        left..right-1."""
        shown = self.shown[top:bottom, left:right]
        layer_z = self.z[np.arange(left, right), shown]
        return np.where(shown >= 0, layer_z, self.floor_z[top:bottom, None])


def _distance(target: PlanarTarget, origin: np.ndarray) -> float:
    return math.hypot(target.centre[0] - origin[0], target.centre[1] - origin[1])


def _draw_target(image: np.ndarray, depth: SceneDepth, camera: PinholeCamera,
                 target: PlanarTarget, origin: np.ndarray, heading: float,
                 height: float, z_image: np.ndarray | None = None) -> None:
    """Warp ``target`` into ``image`` where it is in front of ``depth`` (module notes),
    and write its depth into ``z_image`` (each pixel's depth) where one is given."""
    to_camera = np.array([origin[0] - target.centre[0], origin[1] - target.centre[1]])
    if to_camera @ [math.cos(target.facing), math.sin(target.facing)] <= 0.0:
        return  # seen from behind
    corners = world_to_optical(target.corners(), origin, heading, height)
    if (corners[:, 2] < 0.05).any():
        return  # partly behind the camera: nothing a detector could use
    projected = np.column_stack([camera.cx + camera.fx * corners[:, 0] / corners[:, 2],
                                 camera.cy + camera.fy * corners[:, 1] / corners[:, 2]])
    left, top = np.floor(projected.min(axis=0)).astype(int)
    right, bottom = np.ceil(projected.max(axis=0)).astype(int) + 1
    left, top = max(left, 0), max(top, 0)
    right, bottom = min(right, camera.width), min(bottom, camera.height)
    if right <= left or bottom <= top:
        return
    texture = target.image
    if image.ndim == 3 and texture.ndim == 2:
        texture = np.repeat(texture[..., None], 3, axis=2)
    elif image.ndim == 2 and texture.ndim == 3:
        texture = cv2.cvtColor(texture, cv2.COLOR_RGB2GRAY)
    on_screen = float(np.max(np.hypot(*(projected - np.roll(projected, 1, axis=0)).T)))
    scale = min(1.0, 2.0 * on_screen / max(texture.shape[:2]))
    if scale < 1.0:
        texture = cv2.resize(texture, (max(2, round(texture.shape[1] * scale)),
                                       max(2, round(texture.shape[0] * scale))),
                             interpolation=cv2.INTER_AREA)
    th, tw = texture.shape[:2]
    source = np.float32([[0, 0], [tw, 0], [tw, th], [0, th]]) - 0.5
    homography = cv2.getPerspectiveTransform(source, np.float32(projected - [left, top]))
    size = (right - left, bottom - top)
    warped = cv2.warpPerspective(texture, homography, size, flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_REPLICATE)
    mask = np.zeros((size[1], size[0]), np.uint8)
    cv2.fillConvexPoly(mask, np.round((projected - [left, top]) * 16).astype(np.int32),
                       1, lineType=cv2.LINE_8, shift=4)
    # the plane's depth along each pixel's ray: z = (n . p0) / (n . d)
    normal = world_to_optical(np.array([[math.cos(target.facing) + origin[0],
                                         math.sin(target.facing) + origin[1], height]]),
                              origin, heading, height)[0]
    p0 = corners.mean(axis=0)
    u = (np.arange(left, right) - camera.cx) / camera.fx
    v = (np.arange(top, bottom) - camera.cy) / camera.fy
    facing_ray = normal[0] * u[None, :] + normal[1] * v[:, None] + normal[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        plane_z = (normal @ p0) / facing_ray
    visible = (mask > 0) & (plane_z > 0) & (plane_z <= depth.box(top, bottom, left, right) + 0.02)
    region = image[top:bottom, left:right]
    region[visible] = warped[visible]
    if z_image is not None:
        z_image[top:bottom, left:right][visible] = plane_z[visible]


def motion_blur(image: np.ndarray, camera: PinholeCamera, depth: np.ndarray | None,
                v: float, w: float, exposure: float, max_samples: int = 9) -> np.ndarray:
    """``image`` smeared by the camera's motion during ``exposure`` s, moving ``v`` m/s
    ahead and turning ``w`` rad/s (module notes): sideways along a line of ``fx w T`` px
    for the turn, and for driving along each pixel's path from the principal point
    (sampled every px or so, at most ``max_samples`` times), given each pixel's
    ``depth`` (m along the optical axis; needed only to drive)."""
    if exposure <= 0:
        return image
    image = np.asarray(image, np.float32)
    along = float(v) * exposure  # m driven during the exposure
    if abs(along) > 1e-4:
        if depth is None:
            raise ValueError("the blur of driving ahead needs each pixel's depth")
        z = depth
        with np.errstate(divide="ignore", invalid="ignore"):
            grow = np.where(np.isfinite(z) & (z > 0.05), along / z,
                            0.0).astype(np.float32, copy=False)
        u, vv, from_u, from_v = _pixel_grid(*image.shape[:2], camera.cx, camera.cy)
        du, dv = from_u * grow, from_v * grow
        # the longest path (px): hypot only where the square of it may be the greatest
        # (float32 squares are within a few parts in 10^7 of it)
        square = np.multiply(du, du)
        square += np.multiply(dv, dv, out=grow)
        near_top = square >= square.max() * np.float32(1 - 1e-5)
        longest = float(np.hypot(du[near_top], dv[near_top]).max())
        samples = int(np.clip(math.ceil(longest) + 1, 3, max_samples))
        image = _mean_of_remaps(image, u, vv, du, dv, samples)
    sweep = abs(camera.fx * float(w) * exposure)  # px the turn moves the image
    if sweep > 0.5:
        length = 2 * math.ceil(sweep / 2) + 1
        kernel = np.zeros((1, length), np.float32)
        # a box of `sweep` px, its two end taps shared so the length is exact
        kernel[0] = np.clip(sweep / 2 + 0.5 - np.abs(np.arange(length) - length // 2), 0, 1)
        image = cv2.filter2D(image, -1, kernel / kernel.sum(), borderType=cv2.BORDER_REPLICATE)
    return image


BLUR_BAND_ROWS = 48
"""Rows of the image the driving blur samples at a time: the band's maps stay in the
processor's cache between the samples (the same sums as one band of all rows)."""


def _mean_of_remaps(image: np.ndarray, u: np.ndarray, v: np.ndarray, du: np.ndarray,
                    dv: np.ndarray, samples: int) -> np.ndarray:
    """The mean over ``samples`` times ``t`` evenly from -0.5 to 0.5 of ``image`` sampled
    at ``(u + t du, v + t dv)`` (each pixel's column and row plus ``t`` of its path, px;
    float32, bilinear, edges repeated), taken a band of rows at a time."""
    times = np.linspace(-0.5, 0.5, samples, dtype=np.float32)
    total = np.empty_like(image)
    band_u = np.empty((BLUR_BAND_ROWS, image.shape[1]), np.float32)
    band_v = np.empty_like(band_u)
    for top in range(0, image.shape[0], BLUR_BAND_ROWS):
        rows = slice(top, top + BLUR_BAND_ROWS)
        map_u, map_v = band_u[:len(u[rows])], band_v[:len(u[rows])]
        for k, t in enumerate(times):
            np.add(u[rows], np.multiply(t, du[rows], out=map_u), out=map_u)
            np.add(v[rows], np.multiply(t, dv[rows], out=map_v), out=map_v)
            sampled = cv2.remap(image, map_u, map_v, cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_REPLICATE)
            if k == 0:
                total[rows] = sampled
            else:
                total[rows] += sampled
    return np.divide(total, np.float32(samples), out=total)


@functools.lru_cache(maxsize=4)
def _pixel_grid(rows: int, cols: int, cx: float, cy: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(rows x cols float32, read-only) each pixel's column ``u`` and row ``v``, and
    ``u - cx`` and ``v - cy``: the same for every frame of one camera."""
    u, v = np.meshgrid(np.arange(cols, dtype=np.float32), np.arange(rows, dtype=np.float32))
    grids = (u, v, u - np.float32(cx), v - np.float32(cy))
    for grid in grids:
        grid.flags.writeable = False
    return grids


def _imaging(image: np.ndarray, rng: np.random.Generator, imaging: Imaging) -> np.ndarray:
    """Lighting gain, blur and fresh noise (module notes)."""
    image = image * np.float32(rng.uniform(*imaging.gain))
    if imaging.blur_sigma > 0:
        image = cv2.GaussianBlur(image, (0, 0), imaging.blur_sigma, dst=image)
    if imaging.noise_std > 0:
        noise = rng.standard_normal(image.shape, dtype=np.float32)
        image += np.multiply(np.float32(imaging.noise_std), noise, out=noise)
    return image


__all__ = ["Imaging", "PlanarTarget", "motion_blur", "render_colour", "world_to_optical"]
