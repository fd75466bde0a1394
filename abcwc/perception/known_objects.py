"""Finding a known flat object (a door sign, a poster) in a camera image: local features,
matching, a homography, and a check that the match is the object and not its sibling.

The pipeline (the thesis's A.7, with its errors put right):

1. **Features.** Keypoints and descriptors in the reference image (once) and in every
   view: SIFT (Lowe, "Distinctive image features from scale-invariant keypoints", IJCV
   60(2), 2004), or ORB (Rublee et al., ICCV 2011) as the fast alternative. SIFT is
   found at every scale; ORB's pyramid spans about 1:4, so its reference is stored at
   the size the object usually has in view.
2. **Matching.** Each view descriptor's two nearest reference descriptors, found with
   FLANN (Muja and Lowe, VISAPP 2009): randomised k-d trees for SIFT's float
   descriptors (``FLANN_INDEX_KDTREE`` is 1; A.7's 0 is the linear, brute-force
   index), multi-probe LSH for ORB's binary ones.
3. **Lowe's ratio test** (section 7.1 of the SIFT paper): keep a match only if its
   nearest neighbour is clearly nearer than the second, ``d1 < ratio * d2`` (0.75); a
   feature that matches two reference places about equally well says nothing.
4. **RANSAC homography** (Fischler and Bolles 1981; ``cv2.findHomography``): the plane's
   3 x 3 map from the reference to the view that most matches agree with, to within
   ``ransac_px``; it needs ``min_inliers`` agreeing matches. The reference's corners
   through it are the object's outline in the view, which must be a convex
   quadrilateral of a sensible size, or the homography is nonsense.
5. **Verification.** Signs of one house style share most of their features (the crest,
   the border, the layout), so a ``STAIRS`` sign passes steps 1-4 as the ``EXIT`` sign.
   The view is warped back into the reference's frame through the homography, and the
   object's distinctive region (the word) is correlated with the reference's
   (normalised cross-correlation, after blurring the reference to the resolution the
   view had), strip by strip: the object is found only where every strip agrees. One
   correlation over the whole word is not enough: ``LIFT`` against ``EXIT`` (the same
   font, two letters alike, the same length) scores 0.6-0.73 as one region, as much as
   a true but distant or oblique view of ``EXIT``; in three strips it scores at most
   0.5 while true views stay above 0.85. A region cut by the image's edge is not
   verified.

The object's **bearing** is the ray through its outline's centre,
``-atan((u - cx) / fx)`` (left positive, as the chair's heading turns).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from abcwc.perception.camera import to_gray
from abcwc.types import CameraImage

FLANN_INDEX_KDTREE = 1
FLANN_INDEX_LSH = 6
FEATURES = ("sift", "orb")


@dataclass(frozen=True)
class KnownObject:
    """An object to look for: its reference ``image`` (grey or RGB uint8), how wide it
    is (``width``, m) and its ``distinctive`` region ((x0, y0, x1, y1) px of the
    reference: what sets it apart from look-alikes; None to skip verification)."""

    name: str
    image: np.ndarray
    width: float
    distinctive: tuple[int, int, int, int] | None = None

    def __post_init__(self) -> None:
        image = np.asarray(self.image)
        if image.dtype != np.uint8 or image.ndim not in (2, 3) or min(image.shape[:2]) < 16:
            raise ValueError(f"{self.name}: the reference must be a uint8 grey or RGB image of "
                             f"at least 16 x 16 px, got {image.dtype} {image.shape}")
        if not (math.isfinite(self.width) and self.width > 0):
            raise ValueError(f"{self.name}: width must be a finite number > 0 m, "
                             f"got {self.width!r}")
        if self.distinctive is not None:
            x0, y0, x1, y1 = self.distinctive
            height, width = image.shape[:2]
            if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
                raise ValueError(f"{self.name}: distinctive {self.distinctive} must lie "
                                 f"inside the {width} x {height} px reference")

    @property
    def gray(self) -> np.ndarray:
        """The reference in grey."""
        return to_gray(self.image)


@dataclass(frozen=True)
class Detection:
    """One object found in a view: its ``outline`` (4, 2 px: the reference's corners,
    clockwise from top left, through ``homography``), the matches kept by the ratio test
    and the RANSAC ``inliers`` among them, the distinctive region's ``correlation``
    (nan without one), whether it was ``verified``, and the ``bearing`` (rad, left
    positive) of the outline's centre, where its diagonals cross."""

    name: str
    outline: np.ndarray
    homography: np.ndarray
    matches: int
    inliers: int
    correlation: float
    verified: bool
    bearing: float


def make_features(kind: str = "sift", count: int = 0):
    """OpenCV's SIFT (``count`` 0: all it finds) or ORB (``count`` 0: 1500) detector."""
    if kind == "sift":
        return cv2.SIFT_create(nfeatures=count)
    if kind == "orb":
        return cv2.ORB_create(nfeatures=count or 1500, scaleFactor=1.2, nlevels=8,
                              fastThreshold=10)
    raise ValueError(f"features must be one of {', '.join(FEATURES)}, got {kind!r}")


def make_matcher(kind: str = "sift") -> cv2.FlannBasedMatcher:
    """FLANN for ``kind``'s descriptors: five randomised k-d trees for SIFT, multi-probe
    LSH for ORB (checked 50 leaves either way)."""
    if kind == "sift":
        index = {"algorithm": FLANN_INDEX_KDTREE, "trees": 5}
    elif kind == "orb":
        index = {"algorithm": FLANN_INDEX_LSH, "table_number": 6, "key_size": 12,
                 "multi_probe_level": 1}
    else:
        raise ValueError(f"features must be one of {', '.join(FEATURES)}, got {kind!r}")
    return cv2.FlannBasedMatcher(index, {"checks": 50})


def ratio_test(pairs: list, ratio: float = 0.75) -> list:
    """Lowe's ratio test: of each query's two nearest matches ``(m, n)`` keep ``m`` when
    ``m.distance < ratio * n.distance``; a query with fewer than two neighbours (LSH can
    return one or none) is dropped."""
    if not 0 < ratio <= 1:
        raise ValueError(f"ratio must be in (0, 1], got {ratio!r}")
    return [pair[0] for pair in pairs
            if len(pair) == 2 and pair[0].distance < ratio * pair[1].distance]


def plausible_outline(outline: np.ndarray, image_shape: tuple[int, ...],
                      min_side: float = 8.0) -> bool:
    """Whether ``outline`` (4, 2 px) can be a plane's image: a convex quadrilateral, each
    side at least ``min_side`` px, no larger than four times the image, with its
    corners in the order the reference's (no fold)."""
    outline = np.asarray(outline, dtype=np.float64)
    if outline.shape != (4, 2) or not np.isfinite(outline).all():
        return False
    sides = np.hypot(*(np.roll(outline, -1, axis=0) - outline).T)
    if sides.min() < min_side:
        return False
    edges = np.roll(outline, -1, axis=0) - outline
    turns = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - \
        edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    if not (turns > 0).all():  # image y points down: clockwise corners turn positive
        return False
    area = cv2.contourArea(outline.astype(np.float32))
    return area < 4 * image_shape[0] * image_shape[1]


def region_correlation(view: np.ndarray, homography: np.ndarray, reference: np.ndarray,
                       box: tuple[int, int, int, int], strips: int = 1) -> float:
    """Normalised cross-correlation (-1..1) of the reference's region ``box`` with the
    same region of ``view`` warped back into the reference's frame through
    ``homography`` (reference to view): the smallest over ``strips`` equal vertical
    strips of the box (a word is compared letter by letter, not as one blur). The
    reference is first shrunk to the size the region has in the view and enlarged
    again, so that both are equally sharp."""
    x0, y0, x1, y1 = box
    height, width = reference.shape[:2]
    back = cv2.warpPerspective(view, homography, (width, height),
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                               borderMode=cv2.BORDER_REPLICATE)
    corners = np.float32([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])[None]
    seen = cv2.perspectiveTransform(corners, homography)[0]
    scale = min(1.0, max(np.hypot(*(seen[1] - seen[0])) / (x1 - x0),
                         np.hypot(*(seen[3] - seen[0])) / (y1 - y0), 1e-3))
    patch = reference[y0:y1, x0:x1]
    if scale < 1.0:
        small = cv2.resize(patch, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        patch = cv2.resize(small, (x1 - x0, y1 - y0), interpolation=cv2.INTER_LINEAR)
    warped = back[y0:y1, x0:x1].astype(np.float64)
    patch = patch.astype(np.float64)
    edges = np.linspace(0, x1 - x0, int(strips) + 1).round().astype(int)
    return min(_ncc(warped[:, a:b], patch[:, a:b]) for a, b in zip(edges[:-1], edges[1:]))


def _ncc(a: np.ndarray, b: np.ndarray) -> float:
    """Normalised cross-correlation of two equal arrays (0 where either is flat)."""
    a, b = a - a.mean(), b - b.mean()
    norm = math.sqrt(float((a * a).sum() * (b * b).sum()))
    return float((a * b).sum() / norm) if norm > 0 else 0.0


@dataclass
class _Reference:
    obj: KnownObject
    scale: float  # reference px per matched px (ORB matches a shrunk reference)
    keypoints: tuple
    descriptors: np.ndarray | None
    matcher: cv2.FlannBasedMatcher = field(repr=False)


class ObjectDetector:
    """Finds ``objects`` (:class:`KnownObject`) in views with ``features`` ``"sift"`` or
    ``"orb"`` (module notes). ``ratio`` is Lowe's ratio, ``ransac_px`` RANSAC's
    reprojection threshold (px), ``min_inliers`` the agreeing matches a homography
    needs, ``min_correlation`` the distinctive region's agreement a verified detection
    needs, the smallest over ``strips`` vertical strips of it (set ``verify`` False to
    see what steps 1-4 alone report)."""

    def __init__(self, objects: list[KnownObject], features: str = "sift",
                 ratio: float = 0.75, ransac_px: float = 4.0, min_inliers: int = 12,
                 min_correlation: float = 0.7, strips: int = 3, verify: bool = True,
                 orb_reference_width: int = 200):
        if not objects:
            raise ValueError("give at least one KnownObject to look for")
        if not 0 < ratio <= 1:
            raise ValueError(f"ratio must be in (0, 1], got {ratio!r}")
        if not (math.isfinite(ransac_px) and ransac_px > 0):
            raise ValueError(f"ransac_px must be a finite number > 0, got {ransac_px!r}")
        if int(min_inliers) < 4:
            raise ValueError(f"a homography needs at least 4 matches, got {min_inliers!r}")
        self.features = features
        self.ratio, self.ransac_px, self.min_inliers = ratio, ransac_px, int(min_inliers)
        self.min_correlation, self.verify = min_correlation, verify
        if int(strips) < 1:
            raise ValueError(f"strips must be >= 1, got {strips!r}")
        self.strips = int(strips)
        self._detector = make_features(features)
        self._references = []
        for obj in objects:
            gray = obj.gray
            scale = 1.0
            if features == "orb" and gray.shape[1] > orb_reference_width:
                scale = gray.shape[1] / orb_reference_width
                gray = cv2.resize(gray, (orb_reference_width, round(gray.shape[0] / scale)),
                                  interpolation=cv2.INTER_AREA)
            # ORB drops keypoints within its 31 px patch of the border: a margin of the
            # reference's own edge colour lets the sign's outer features count
            margin = 32 if features == "orb" else 0
            padded = cv2.copyMakeBorder(gray, margin, margin, margin, margin,
                                        cv2.BORDER_REPLICATE)
            keypoints, descriptors = self._detector.detectAndCompute(padded, None)
            keypoints = tuple(cv2.KeyPoint(k.pt[0] - margin, k.pt[1] - margin, k.size,
                                           k.angle, k.response, k.octave) for k in keypoints)
            matcher = make_matcher(features)
            if descriptors is not None and len(descriptors) >= 2:
                matcher.add([descriptors])
                matcher.train()
            self._references.append(_Reference(obj, scale, tuple(keypoints), descriptors,
                                               matcher))

    @property
    def objects(self) -> list[KnownObject]:
        """The objects looked for."""
        return [ref.obj for ref in self._references]

    def detect(self, image: np.ndarray | CameraImage,
               fx: float | None = None, cx: float | None = None) -> list[Detection]:
        """Every object found in ``image`` (grey or RGB, or a :class:`CameraImage`,
        whose intrinsics give the bearing; else ``fx`` and ``cx`` px, or the bearing is
        nan), best first; with ``verify`` only verified ones."""
        if isinstance(image, CameraImage):
            fx, cx = image.fx, image.cx
        view = to_gray(image)
        keypoints, descriptors = self._detector.detectAndCompute(view, None)
        found = []
        if descriptors is None or len(keypoints) < self.min_inliers:
            return found
        for ref in self._references:
            detection = self._match(ref, view, keypoints, descriptors, fx, cx)
            if detection is not None and (detection.verified or not self.verify):
                found.append(detection)
        return sorted(found, key=lambda d: -d.inliers)

    def _match(self, ref: _Reference, view: np.ndarray, keypoints: tuple,
               descriptors: np.ndarray, fx: float | None, cx: float | None
               ) -> Detection | None:
        if ref.descriptors is None or len(ref.descriptors) < 2:
            return None
        good = ratio_test(ref.matcher.knnMatch(descriptors, k=2), self.ratio)
        if len(good) < self.min_inliers:
            return None
        source = np.float32([ref.keypoints[m.trainIdx].pt for m in good]) * ref.scale
        target = np.float32([keypoints[m.queryIdx].pt for m in good])
        homography, mask = cv2.findHomography(source, target, cv2.RANSAC, self.ransac_px,
                                              maxIters=2000, confidence=0.995)
        if homography is None or int(mask.sum()) < self.min_inliers:
            return None
        height, width = ref.obj.image.shape[:2]
        corners = np.float32([[0, 0], [width - 1, 0], [width - 1, height - 1],
                              [0, height - 1]])[None]
        outline = cv2.perspectiveTransform(corners, homography)[0].astype(np.float64)
        if not plausible_outline(outline, view.shape):
            return None
        correlation = math.nan
        verified = True
        if ref.obj.distinctive is not None:
            x0, y0, x1, y1 = ref.obj.distinctive
            region = cv2.perspectiveTransform(
                np.float32([[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]]), homography)[0]
            rows, cols = view.shape[:2]
            if ((region >= 0) & (region <= [cols - 1, rows - 1])).all():
                correlation = region_correlation(view, homography, ref.obj.gray,
                                                 ref.obj.distinctive, self.strips)
            # a region cut by the image's edge cannot be read: not verified
            verified = correlation >= self.min_correlation
        centre = _diagonal_crossing(outline)
        bearing = (-math.atan((centre[0] - cx) / fx) if fx is not None and cx is not None
                   else math.nan)
        return Detection(ref.obj.name, outline, homography, len(good), int(mask.sum()),
                         correlation, verified, bearing)


def _diagonal_crossing(outline: np.ndarray) -> np.ndarray:
    """Where the quadrilateral's diagonals cross: the image of the plane's centre (a
    homography keeps lines and their crossings; the corners' mean does not)."""
    p0, p1, p2, p3 = np.asarray(outline, dtype=np.float64)
    d1, d2 = p2 - p0, p3 - p1
    denom = d1[0] * d2[1] - d1[1] * d2[0]
    if abs(denom) < 1e-12:
        return (p0 + p1 + p2 + p3) / 4
    t = ((p1[0] - p0[0]) * d2[1] - (p1[1] - p0[1]) * d2[0]) / denom
    return p0 + t * d1
