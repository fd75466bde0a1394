"""Tags a camera can find and measure: QR codes and ArUco markers, and their pose.

**Making them.** :func:`qr_code_image` and :func:`aruco_marker_image` draw a code with
its white quiet zone (a QR code needs four modules of it, ISO/IEC 18004; an ArUco
marker one), ``module_px`` pixels per module, ready to print or to put on a simulated
target. :class:`FollowCard` puts an ArUco marker and a QR code side by side on one
card: the marker for the pose (it is found much farther away), the code for the name.

**Finding them.** ``cv2.QRCodeDetector`` locates and decodes QR codes (it needs about
five pixels per module); ``cv2.aruco.ArucoDetector`` finds markers of a dictionary.
Both return the code's four corners as top-left, top-right, bottom-right, bottom-left
(as printed), which is the order solvePnP's square solver wants.

**Measuring them.** :func:`square_pose` solves the perspective-n-point problem for a
square of known side: IPPE (Collins and Bartoli, "Infinitesimal Plane-based Pose
Estimation", IJCV 109, 2014), which returns the two poses a square can have; a square
facing the camera squarely can come back flipped with ``ok`` true, so the solution's
reprojection error is checked and, if it is more than ``max_reprojection_px``, the
iterative Levenberg-Marquardt solver refines from the other start. The pose gives the
tag's range (m, on the floor plane) and bearing (rad, left positive) from the camera.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from abcwc.perception.camera import PinholeCamera, to_gray

ARUCO_DICTIONARY = cv2.aruco.DICT_4X4_50
"""The marker family: 4 x 4 bits (6 x 6 cells with the black border), 50 ids. The
fewer the bits, the bigger each cell at a given size, and the farther a marker reads."""
ARUCO_CELLS = 6
"""Cells across a DICT_4X4 marker, its black border included."""
MIN_POSE_SIDE_PX = 20.0
"""px: a marker at least this wide gives its range to within 2 % (the tag sweep: 1.7 %
at worst over 450 views, 6 % at 15 px); narrower ones give a bearing only."""
QR_QUIET_MODULES = 4
ARUCO_QUIET_CELLS = 1


@dataclass(frozen=True)
class TagDetection:
    """One tag in an image: its ``kind`` ("qr" or "aruco"), what it says (``text`` for a
    QR code, ``marker_id`` for a marker) and its ``corners`` (4, 2) px, top-left first,
    clockwise."""

    kind: str
    corners: np.ndarray
    text: str = ""
    marker_id: int = -1

    @property
    def centre(self) -> np.ndarray:
        """(2,) px: where the diagonals cross (the square's centre under perspective)."""
        p0, p1, p2, p3 = self.corners
        d1, d2 = p2 - p0, p3 - p1
        denominator = d1[0] * d2[1] - d1[1] * d2[0]
        if abs(denominator) < 1e-12:
            return self.corners.mean(axis=0)
        s = ((p1 - p0)[0] * d2[1] - (p1 - p0)[1] * d2[0]) / denominator
        return p0 + s * d1

    @property
    def side_px(self) -> float:
        """The mean length of the four sides (px)."""
        return float(np.mean(np.hypot(*(self.corners - np.roll(self.corners, 1, 0)).T)))


@dataclass(frozen=True)
class TagPose:
    """Where a tag is: ``position`` (3,) m of its centre in the camera's optical frame
    (x right, y down, z ahead) and ``rotation`` (3 x 3, the tag's frame, x right, y up
    and z out of its face, to the optical frame), its ``range`` (m, along the floor)
    and ``bearing`` (rad, left of the optical axis positive), and the solution's
    ``reprojection_px`` (rms, px)."""

    position: np.ndarray
    rotation: np.ndarray
    reprojection_px: float

    @property
    def range(self) -> float:
        return float(math.hypot(self.position[0], self.position[2]))

    @property
    def bearing(self) -> float:
        return float(math.atan2(-self.position[0], self.position[2]))


def qr_code_image(text: str, module_px: int = 8) -> np.ndarray:
    """A QR code of ``text`` (grey, uint8) with its four-module quiet zone,
    ``module_px`` px per module."""
    if not text:
        raise ValueError("text must be a non-empty string")
    code = cv2.QRCodeEncoder.create().encode(text)
    if code is None or code.size == 0:
        raise ValueError(f"cannot encode {text!r} as a QR code")
    # the encoder adds a margin of its own; cut to the code itself and add ours
    dark = np.argwhere(code < 128)
    (r0, c0), (r1, c1) = dark.min(axis=0), dark.max(axis=0) + 1
    modules = code[r0:r1, c0:c1]
    padded = np.pad(modules, QR_QUIET_MODULES, constant_values=255)
    return cv2.resize(padded, None, fx=module_px, fy=module_px,
                      interpolation=cv2.INTER_NEAREST)


@lru_cache(maxsize=64)
def qr_modules(text: str) -> int:
    """Modules across the QR code of ``text`` (21 for version 1, + 4 per version)."""
    return (qr_code_image(text, 1).shape[0] - 2 * QR_QUIET_MODULES)


def printed_marker_width(side: float) -> float:
    """m across a printed ArUco marker whose black square is ``side`` m, with its quiet
    zone (:func:`aruco_marker_image`'s layout)."""
    return side * (ARUCO_CELLS + 2 * ARUCO_QUIET_CELLS) / ARUCO_CELLS


def aruco_marker_image(marker_id: int, cell_px: int = 32) -> np.ndarray:
    """ArUco marker ``marker_id`` of :data:`ARUCO_DICTIONARY` (grey, uint8) with a
    one-cell white quiet zone, ``cell_px`` px per cell."""
    dictionary = cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARY)
    if not (isinstance(marker_id, (int, np.integer)) and 0 <= marker_id
            < len(dictionary.bytesList)):
        raise ValueError(f"marker_id must be an integer 0..{len(dictionary.bytesList) - 1}, "
                         f"got {marker_id!r}")
    marker = cv2.aruco.generateImageMarker(dictionary, int(marker_id),
                                           ARUCO_CELLS * cell_px)
    return np.pad(marker, ARUCO_QUIET_CELLS * cell_px, constant_values=255)


@dataclass(frozen=True)
class FollowCard:
    """A card for a person to wear on their back, upright: a QR code of ``name`` (its
    modules ``side`` m across: whom to follow) above ArUco ``marker_id`` (its black
    square ``side`` m across: the pose), each with its quiet zone and centred across
    the card.

    The marker is on the card's middle line and at its foot: worn with the card's
    centre at 0.9 m, the marker is at the chair's camera height. A marker beside the
    code, 0.14 m off the card's middle, was cut by the image's edge whenever the person
    was off to that side at about a metre (after each of her turns, as the chair
    swung round): the lab's follow trial read the tag in 75 % of its decisions with it
    there and in 82-86 % with it here."""

    name: str
    marker_id: int
    side: float = 0.2

    def __post_init__(self) -> None:
        if not (math.isfinite(self.side) and self.side > 0):
            raise ValueError(f"side must be a finite number > 0 m, got {self.side!r}")
        qr_modules(self.name)  # refuses what cannot be a QR code
        aruco_marker_image(self.marker_id, 1)  # refuses ids the dictionary lacks

    @property
    def marker_width(self) -> float:
        """m: the marker with its quiet zone."""
        return printed_marker_width(self.side)

    @property
    def qr_width(self) -> float:
        """m: the QR code with its quiet zone."""
        modules = qr_modules(self.name)
        return self.side * (modules + 2 * QR_QUIET_MODULES) / modules

    @property
    def width(self) -> float:
        """m: the wider of the two."""
        return max(self.marker_width, self.qr_width)

    @property
    def height(self) -> float:
        """m: the code and the marker, one above the other."""
        return self.marker_width + self.qr_width

    @property
    def marker_drop(self) -> float:
        """m from the card's centre down to the marker's (the marker is on the card's
        middle line: no offset across)."""
        return self.height / 2 - self.marker_width / 2

    def image(self, px_per_m: float = 1000.0) -> np.ndarray:
        """The card (grey, uint8) at ``px_per_m``: the code on top, the marker below."""
        cell_px = max(1, round(px_per_m * self.side / ARUCO_CELLS))
        marker = aruco_marker_image(self.marker_id, cell_px)
        scale = marker.shape[1] / self.marker_width  # px per m as drawn
        qr = qr_code_image(self.name, 8)
        qr = cv2.resize(qr, (round(self.qr_width * scale),) * 2, interpolation=cv2.INTER_AREA)
        width = max(marker.shape[1], qr.shape[1])
        card = np.full((qr.shape[0] + marker.shape[0], width), 255, np.uint8)
        left = (width - qr.shape[1]) // 2
        card[:qr.shape[0], left:left + qr.shape[1]] = qr
        left = (width - marker.shape[1]) // 2
        card[qr.shape[0]:, left:left + marker.shape[1]] = marker
        return card


def detect_qr_codes(gray: np.ndarray, upscale: int = 1) -> list[TagDetection]:
    """The QR codes in ``gray`` (uint8), decoded, corners in ``gray``'s pixels. With
    ``upscale`` 2 the image is enlarged first, which reads codes about 1.6 times
    farther away at four times the cost."""
    image = to_gray(gray)
    if upscale > 1:
        image = cv2.resize(image, None, fx=upscale, fy=upscale,
                           interpolation=cv2.INTER_CUBIC)
    detector = cv2.QRCodeDetector()
    ok, texts, points, _ = detector.detectAndDecodeMulti(image)
    if not ok or points is None:
        return []
    return [TagDetection("qr", np.asarray(p, float).reshape(4, 2) / upscale, text=t)
            for t, p in zip(texts, points) if t]


def detect_aruco_markers(gray: np.ndarray) -> list[TagDetection]:
    """The :data:`ARUCO_DICTIONARY` markers in ``gray`` (uint8), each corner where two
    of the marker's refitted edges cross (:func:`refine_square_edges`)."""
    image = to_gray(gray)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_NONE
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARY),
                                       parameters)
    corners, ids, _ = detector.detectMarkers(image)
    if ids is None:
        return []
    return [TagDetection("aruco", refine_square_edges(image, np.asarray(c, float).reshape(4, 2)),
                         marker_id=int(i))
            for c, i in zip(corners, ids.ravel())]


def refine_square_edges(gray: np.ndarray, corners: np.ndarray, reach: float = 2.5,
                        samples: int = 12) -> np.ndarray:
    """Corners (4, 2) of a dark square on a light ground, refined from the rough
    ``corners`` by refitting its four edges (AprilTag 3's edge refinement: Krogius,
    Haggenmiller and Olson, "Flexible layouts for fiducial tags", IROS 2019): along each
    edge, at ``samples`` points, the image is read across the edge ``reach`` px either
    way, and the edge put where the intensity crosses halfway between its dark and light
    ends (a blur spreads an edge evenly both ways, so the halfway point stays put); a
    straight line is fitted through those points (total least squares) and neighbouring
    lines crossed. A contour-based corner sits on the dark side of a blurred edge, which
    makes a small marker look smaller and farther (3-6 % at 15-25 px across). Corners
    that cannot be refitted are kept."""
    from scipy import ndimage

    # only the pixels round the square are read: a crop reaching past every probe (and to
    # the image's edge where a probe does, for mode="nearest") gives the same values
    low = np.maximum(np.floor(corners.min(axis=0) - reach) - 1, 0).astype(int)
    high = np.minimum(np.floor(corners.max(axis=0) + reach) + 3, gray.shape[1::-1]).astype(int)
    image = gray[low[1]:high[1], low[0]:high[0]].astype(np.float64)
    lines = []
    offsets = np.linspace(-reach, reach, int(4 * reach) + 1)
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        along = b - a
        length = float(np.hypot(*along))
        if length < 4:
            return corners
        unit = along / length
        normal = np.array([unit[1], -unit[0]])  # outwards for corners in clockwise order
        centre = corners.mean(axis=0)
        if (a + b) / 2 @ normal < centre @ normal:
            normal = -normal
        t = np.linspace(0.15, 0.85, samples)[:, None]
        points = a + t * along  # (S, 2) on the rough edge
        probe = points[:, None, :] + offsets[None, :, None] * normal  # (S, O, 2) x, y
        values = ndimage.map_coordinates(image, [probe[..., 1] - low[1], probe[..., 0] - low[0]],
                                         order=1, mode="nearest")  # (S, O): dark in, light out
        dark, light = values[:, :2].mean(axis=1), values[:, -2:].mean(axis=1)
        half = (dark + light) / 2
        edges = []
        for row, level, point, contrast in zip(values, half, points, light - dark):
            if contrast < 20:
                continue
            above = np.flatnonzero(row >= level)
            if not len(above) or above[0] == 0:
                continue
            j = above[0]
            fraction = (level - row[j - 1]) / max(row[j] - row[j - 1], 1e-9)
            edges.append(point + (offsets[j - 1] + fraction * (offsets[j] - offsets[j - 1]))
                         * normal)
        if len(edges) < 3:
            return corners
        edges = np.array(edges)
        middle = edges.mean(axis=0)
        _, _, vt = np.linalg.svd(edges - middle)
        lines.append((middle, vt[0]))
    refined = []
    for k in range(4):
        (p0, d0), (p1, d1) = lines[k - 1], lines[k]  # the edges ending and starting here
        matrix = np.column_stack([d0, -d1])
        if abs(np.linalg.det(matrix)) < 1e-6:
            return corners
        s_, _ = np.linalg.solve(matrix, p1 - p0)
        refined.append(p0 + s_ * d0)
    refined = np.array(refined)
    if np.hypot(*(refined - corners).T).max() > reach:
        return corners  # a fit that moved a corner farther than it looked: keep the rough one
    return refined


def camera_matrix(camera: PinholeCamera) -> np.ndarray:
    """K (3 x 3), as ROS CameraInfo and OpenCV write it."""
    return np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy],
                     [0.0, 0.0, 1.0]])


def square_pose(corners: np.ndarray, side: float, camera: PinholeCamera,
                max_reprojection_px: float = 1.0) -> TagPose:
    """The pose of a square of ``side`` m whose corners (top-left first, clockwise) are
    seen at ``corners`` (4, 2) px by ``camera`` (module notes)."""
    corners = np.asarray(corners, dtype=np.float64).reshape(4, 2)
    if not (math.isfinite(side) and side > 0):
        raise ValueError(f"side must be a finite number > 0 m, got {side!r}")
    if not np.isfinite(corners).all():
        raise ValueError("corners must be finite pixel coordinates")
    h = side / 2  # IPPE_SQUARE's model: x right and y up on the face, z out of it
    model = np.array([[-h, h, 0], [h, h, 0], [h, -h, 0], [-h, -h, 0]], dtype=np.float64)
    k = camera_matrix(camera)
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    count, rvecs, tvecs, errors = cv2.solvePnPGeneric(
        model, corners, k, None, flags=cv2.SOLVEPNP_IPPE_SQUARE)
    for rvec, tvec, error in zip(rvecs, tvecs, np.ravel(errors)):
        if tvec[2, 0] > 0 and (best is None or error < best[0]):
            best = (float(error), rvec, tvec)
    if best is None or best[0] > max_reprojection_px:
        start = best[1:] if best is not None else (np.zeros((3, 1)),
                                                   np.array([[0.0], [0.0], [1.0]]))
        ok, rvec, tvec = cv2.solvePnP(model, corners, k, None, rvec=start[0].copy(),
                                      tvec=start[1].copy(), useExtrinsicGuess=True,
                                      flags=cv2.SOLVEPNP_ITERATIVE)
        projected, _ = cv2.projectPoints(model, rvec, tvec, k, None)
        error = float(np.sqrt(np.mean(np.sum((projected.reshape(4, 2) - corners) ** 2, 1))))
        if ok and tvec[2, 0] > 0 and (best is None or error < best[0]):
            best = (error, rvec, tvec)
    if best is None:
        raise ValueError("no pose puts the square in front of the camera")
    rotation, _ = cv2.Rodrigues(best[1])
    return TagPose(best[2].ravel().copy(), rotation, best[0])


def find_marker(gray: np.ndarray, marker_id: int, side: float, camera: PinholeCamera
                ) -> tuple[TagDetection, TagPose] | None:
    """Marker ``marker_id`` of :data:`ARUCO_DICTIONARY` in ``gray`` (the first, if
    several) and its pose as a square of ``side`` m seen by ``camera``; None if it is
    not in the image."""
    for marker in detect_aruco_markers(gray):
        if marker.marker_id == marker_id:
            return marker, square_pose(marker.corners, side, camera)
    return None


__all__ = ["ARUCO_DICTIONARY", "MIN_POSE_SIDE_PX", "FollowCard", "TagDetection", "TagPose",
           "aruco_marker_image", "camera_matrix", "detect_aruco_markers", "detect_qr_codes",
           "find_marker", "printed_marker_width",
           "qr_code_image", "qr_modules", "refine_square_edges", "square_pose"]
