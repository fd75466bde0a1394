"""Finding a known flat object (a door sign, a poster) in a camera image: local features,
matching, a homography, and a check that the match is the object and not its sibling.

The pipeline (the thesis's A.7, with its errors put right):

1. **Features.** Keypoints and descriptors in the reference image (once) and in every
   view: SIFT (Lowe, "Distinctive image features from scale-invariant keypoints", IJCV
   60(2), 2004), or ORB (Rublee et al., ICCV 2011) as the fast alternative. The
   reference is stored at three sizes (:data:`REFERENCE_WIDTHS`: 480, 240 and 120 px
   for SIFT; 300, 200 and 130 px for ORB, whose pyramid spans only about 1:4), each
   blurred by 1 px as a camera would see it: a far or blurred sign's features are
   those of a small, soft reference, not of the sharp large one.
2. **Matching.** Each view descriptor's two nearest reference descriptors, found with
   FLANN (Muja and Lowe, VISAPP 2009): randomised k-d trees for SIFT's float
   descriptors (``FLANN_INDEX_KDTREE`` is 1; A.7's 0 is the linear, brute-force
   index), multi-probe LSH for ORB's binary ones. The trees and hash tables are drawn
   from OpenCV's random generator, which the detector seeds (``seed``) before building
   each: unseeded, two detectors built the same way disagreed near the threshold (0.70
   against 0.67 on one view), depending on what had been built before.
3. **Lowe's ratio test** (section 7.1 of the SIFT paper): keep a match only if its
   nearest neighbour is clearly nearer than the second, ``d1 < ratio * d2`` (0.75); a
   feature that matches two reference places about equally well says nothing. Each
   size of the reference has its own test (a feature at two sizes would be its own
   second neighbour), and a view keypoint keeps its nearest match over the sizes.
4. **RANSAC homography** (Fischler and Bolles 1981; ``cv2.findHomography``): the plane's
   3 x 3 map from the reference to the view that most matches agree with, to within
   ``ransac_px`` (4 px; A.7 uses 3); it needs ``min_inliers`` agreeing matches (12; A.7
   asks for 30 matches, which loses the far views). The reference's corners through it
   are the object's outline in the view, which must be a convex quadrilateral of a
   sensible size, or the homography is nonsense.
5. **Verification**, which must not trust the fit it checks. Signs of one house style
   share most of their features (the crest, the border, the layout), so a ``STAIRS``
   sign passes steps 1-4 as the ``EXIT`` sign, and the object's distinctive region
   (the word) has to be read. The first version read it through the homography of
   step 4, and that failed on a word that contains the known one: on an ``EXITS`` or
   ``NEXIT`` sign the matches are the letters the two words share, the homography maps
   the reference's EXIT onto them, the outline comes out some 18 px off (1 px for the
   real sign), and through that wrong fit the word reads as EXIT (correlation up to
   0.86): 46 % of SIFT's views of such a sign were reported as the exit. Now:

   a. **The plate is fitted again from its own pixels**: the enhanced correlation
      coefficient (ECC, :func:`fit_plate`) aligns the reference *outside* the
      distinctive region (crest, border, small line: what every sign of the style
      shares) with the view, started from step 4's homography. On a real sign it
      moves the outline by a median 0.6 % of its width; on an EXITS sign by 10-33 %:
      it puts the plate where it is, so the word is read at its true place. The fit
      must correlate at least ``min_plate`` (0.6).
   b. **The blank margins** beside the word (:func:`blank_margins`: columns of the
      distinctive region blank on the reference) must be blank in the view: their ink
      (:func:`margin_ink`) at most ``max_margin_ink`` (0.35) of the word's. A longer
      word fills them (0.4-1.1; the real sign 0.03-0.33). Margins narrower than two of
      the view's pixels cannot be read and are not judged.
   c. **The word**, warped back through the plate's fit, is correlated with the
      reference's (normalised cross-correlation, the reference first blurred to the
      resolution the view had) in ``strips`` x ``rows`` cells (4 x 2), the smallest
      kept, at least ``min_correlation`` (0.6). One correlation over the whole word is
      not enough: ``LIFT`` against ``EXIT`` (the same font, two letters alike, the same
      length) scores over 0.5 as one region; in three strips one-letter changes
      (``EDIT``, ``ETIT``) reached 0.58-0.68, in 4 x 2 cells at most 0.49, while real
      views within 4 m stay above 0.69. A region cut by the image's edge is not
      verified.
   d. **Every stroke** (:func:`stroke_residual`): the cells' correlation is a mean over
      a cell, and a word that changes one letter for one sharing most of its strokes
      (``ZXIT``, ``FXIT``, ``DXIT`` against ``EXIT``: Z, F and D keep E's bars)
      correlates 0.7-0.8 in every cell at the 100-250 px a sign has in view, above
      real views of the sign at 4 m: no threshold on the cells told them apart. What
      differs is one stroke, missing or added, at full contrast. So the word, warped
      back through the plate's fit, is shifted onto the reference by the translation
      that aligns them best (at most two of the view's px), brought to the
      reference's contrast (the gain and offset that fit it best on the pixels the
      camera did not clip, the prediction clipped as the camera clips, so exposure
      and blown-out whites cancel), subtracted from the reference made as sharp as
      the view, and the difference smoothed over one of the view's px; its largest
      magnitude, in shares of the ink contrast, must be at most ``max_residual``
      (0.6). A missing or added stroke is a blob of one sign; a fit a fraction of a
      pixel off leaves a stroke's two edges with opposite signs, which the smoothing
      cancels, and noise averages out. Measured (60 views under each of the sweep's
      conditions bar all at once, 4 views of each of the 100 words that change one
      of EXIT's letters, counting those the cells let through; SIFT / ORB): real
      views at most 0.51 / 0.50 (99 % under 0.49 / 0.47), the look-alikes at least
      0.63 / 0.63 (98 % over 0.70 / 0.71). Without the shift the real views reached
      0.69 / 0.67 (99 % under 0.62 / 0.59): the two overlapped. Fitting the gain on
      every pixel, clipped or not, left 0.5-0.8 on views with the whites blown out
      and blurred, which refused nearly all of them. Chosen over judging the cells by
      their weakest (they already are: a cell holds half a letter, and the bar the
      two letters share dominates it), over finer cells (8 x 3: real views fell to
      0.38, FXIT reached 0.42) and over a second look on the next frame (ZXIT passed
      the cells in 12 of 12 views, each with fresh noise: the noise was never what let
      it through).

**What each part bought** (SIFT, 48 views 1.5-4 m, up to 40 degrees off the face; found
% on the real sign clean / at 1.5 px blur / at exposure x1.8 / all troubles at once,
and on EXITS): the old verification 98 / 69 / 71 / 15, EXITS 48; the plate fitted again
98 / 69 / 71 / 15, EXITS 0; the reference at three sizes 98 / 85 / 83 / 29; each size
blurred 1 px 98 / 92 / 88 / 33; margins judged only where two view pixels wide
98 / 98 / 98 / 54. Tried and not kept: contrast normalisation before matching (CLAHE:
blur 60, x1.8 62, worse; a min-max stretch: no change), a lower SIFT contrast
threshold (0.02, 0.01: no change), Lowe's 0.8 ratio (a few % more, at more time). For
ORB, one 200 px reference gave 96 / 90 / 94 / 75, three sizes 98 / 98 / 98 / 83. The
full assessment (288 views a condition, look-alike words made at run time) is
:func:`abcwc.experiments.sign_sweep.rates`, reported by ``abcwc bench vision``.

**What the stroke check bought** (4 views of each of the 100 one-letter changes of
EXIT, 1.5-4 m, up to 40 degrees off): the plate, margins and cells let 89 views through
for SIFT and 83 for ORB (ZXIT, FXIT, DXIT, BXIT, KXIT, EZIT among the words), the stroke
residual none. It cost the real sign no view of the full assessment (288 views a
condition, every condition's found rate the same as without it: :mod:`sign_sweep
<abcwc.experiments.sign_sweep>`'s figures).

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
REFERENCE_WIDTHS = {"sift": (480, 240, 120), "orb": (300, 200, 130)}
"""px: the sizes each reference is stored at, by kind of feature (module notes)."""
UNCLIPPED = (5, 250)
"""Grey levels strictly between which a view's pixel is taken as not clipped by the
camera (:func:`stroke_residual`)."""


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
    clockwise from top left, through ``homography``, the plate's own fit where it was
    made), the matches kept by the ratio test and the RANSAC ``inliers`` among them, the
    ``plate`` fit's correlation (the reference outside its distinctive region against
    the view, -1..1; nan where it could not be fitted), the share of ink in the blank
    ``margins`` beside the distinctive region (0 blank; nan without margins), the
    distinctive region's ``correlation`` (nan without one), whether it was ``verified``,
    and the ``bearing`` (rad, left positive) of the outline's centre, where its
    diagonals cross. ``residual`` is the distinctive region's largest local
    disagreement with the reference (:func:`stroke_residual`; nan without one)."""

    name: str
    outline: np.ndarray
    homography: np.ndarray
    matches: int
    inliers: int
    correlation: float
    verified: bool
    bearing: float
    plate: float = math.nan
    margins: float = math.nan
    residual: float = math.nan


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
                       box: tuple[int, int, int, int], strips: int = 1,
                       rows: int = 1) -> float:
    """Normalised cross-correlation (-1..1) of the reference's region ``box`` with the
    same region of ``view`` warped back into the reference's frame through
    ``homography`` (reference to view): the smallest over ``strips`` equal vertical
    strips of the box (a word is compared letter by letter, not as one blur). The
    reference is first shrunk to the size the region has in the view and enlarged
    again, so that both are equally sharp."""
    x0, y0, x1, y1 = box
    warped, patch, _ = _region_seen(view, homography, reference, box)
    across = np.linspace(0, x1 - x0, int(strips) + 1).round().astype(int)
    down = np.linspace(0, y1 - y0, int(rows) + 1).round().astype(int)
    cells = [(slice(c, d), slice(a, b)) for a, b in zip(across[:-1], across[1:])
             for c, d in zip(down[:-1], down[1:])]
    # a cell blank on the reference says nothing here (the margins' check reads blanks)
    written = [cell for cell in cells if patch[cell].std() > 0.1 * patch.std()] or cells
    return min(_ncc(warped[cell], patch[cell]) for cell in written)


def _region_seen(view: np.ndarray, homography: np.ndarray, reference: np.ndarray,
                 box: tuple[int, int, int, int]) -> tuple[np.ndarray, np.ndarray, float]:
    """The region ``box`` of ``view`` warped back into the reference's frame through
    ``homography`` (reference to view), the reference's same region shrunk to the size
    it has in the view and enlarged again (as sharp as the view's), both float, and
    that size (view px per reference px, at most 1)."""
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
    return back[y0:y1, x0:x1].astype(np.float64), patch.astype(np.float64), float(scale)


def stroke_residual(view: np.ndarray, homography: np.ndarray, reference: np.ndarray,
                    box: tuple[int, int, int, int], smooth_px: float = 1.0,
                    max_shift_px: float = 2.0) -> float:
    """The largest local disagreement between the reference's region ``box`` and the
    same region of ``view`` warped back through ``homography`` (reference to view), in
    shares of the region's ink contrast. The reference is made as sharp as the view
    (:func:`_region_seen`); the view's region is shifted onto it by the translation
    that aligns them best (ECC, as :func:`fit_plate`; kept only up to ``max_shift_px``
    of the view's px) and brought to its contrast (the gain and offset that fit it
    best, least squares, on the pixels the camera did not clip (:data:`UNCLIPPED`), the
    prediction clipped to 0-255 as the camera clips: exposure, lighting and whites
    blown out cancel); their difference is smoothed
    over ``smooth_px`` of the view's px (a Gaussian's sigma) and its largest magnitude
    taken. A stroke missing or added (Z's diagonal for E's upright and middle bar)
    leaves a blob of one sign about a stroke wide: near 0.8 of the contrast or more; a
    fit a fraction of a pixel off leaves a stroke's two edges of opposite signs, which
    the smoothing cancels, and noise averages out; real views stay near 0.5 (module
    notes). Returns inf where the view's region does not brighten with the reference's
    ink (gain <= 0)."""
    warped, patch, scale = _region_seen(view, homography, reference, box)
    try:
        _, shift = cv2.findTransformECC(
            patch.astype(np.float32), warped.astype(np.float32), np.eye(2, 3, dtype=np.float32),
            cv2.MOTION_TRANSLATION, (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 1e-4),
            None, 1)
        if np.hypot(*shift[:, 2]) * scale <= max_shift_px:
            warped = cv2.warpAffine(warped, shift, warped.shape[::-1],
                                    flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                    borderMode=cv2.BORDER_REPLICATE)
    except cv2.error:  # no direction to go: compared where the plate's fit put it
        pass
    contrast = float(np.percentile(patch, 99) - np.percentile(patch, 1))
    design = np.column_stack([patch.ravel(), np.ones(patch.size)])
    # a clipped pixel says only that it is at least as bright (or dark) as it shows:
    # the gain and offset are fitted on the others, and the prediction clipped as the
    # camera clips
    unclipped = ((warped > UNCLIPPED[0]) & (warped < UNCLIPPED[1])).ravel()
    if unclipped.mean() < 0.25:
        unclipped[:] = True
    (gain, offset), *_ = np.linalg.lstsq(design[unclipped], warped.ravel()[unclipped],
                                         rcond=None)
    if not gain * contrast > 0:
        return math.inf
    predicted = np.clip(gain * patch + offset, 0, 255)
    difference = (warped - predicted) / (gain * contrast)
    return float(np.abs(cv2.GaussianBlur(difference, (0, 0), smooth_px / scale,
                                         borderType=cv2.BORDER_CONSTANT)).max())


def _ncc(a: np.ndarray, b: np.ndarray) -> float:
    """Normalised cross-correlation of two equal arrays (0 where either is flat)."""
    a, b = a - a.mean(), b - b.mean()
    norm = math.sqrt(float((a * a).sum() * (b * b).sum()))
    return float((a * b).sum() / norm) if norm > 0 else 0.0


def fit_plate(view: np.ndarray, homography: np.ndarray, reference: np.ndarray,
              mask: np.ndarray | None = None, iterations: int = 40
              ) -> tuple[float, np.ndarray] | None:
    """The plate fitted again, pixel by pixel: the homography (reference to view) that
    best aligns the ``reference``'s pixels under ``mask`` (uint8, nonzero where used;
    None: all) with ``view``, by Evangelidis and Psarakis's enhanced correlation
    coefficient (ECC, IEEE PAMI 30(10), 2008; ``cv2.findTransformECCWithMask``),
    started from ``homography``, and the correlation (-1..1) it reaches; None where it
    does not converge. The reference is shrunk to the size it has in the view and the
    view cut to the plate's surroundings first, so that it costs a few ms."""
    height, width = reference.shape[:2]
    corners = cv2.perspectiveTransform(
        np.float32([[[0, 0], [width, 0], [width, height], [0, height]]]), homography)[0]
    across = max(np.hypot(*(corners[1] - corners[0])), np.hypot(*(corners[2] - corners[3])))
    scale = float(np.clip(across / width, 16 / min(width, height), 1.0))
    small = cv2.resize(reference, (round(width * scale), round(height * scale)),
                       interpolation=cv2.INTER_AREA) if scale < 1 else reference
    used = np.full(small.shape[:2], 255, np.uint8) if mask is None else cv2.resize(
        mask, (small.shape[1], small.shape[0]), interpolation=cv2.INTER_NEAREST)
    pad = 0.25 * across + 8
    left, top = np.floor(np.maximum(corners.min(axis=0) - pad, 0)).astype(int)
    right, bottom = np.ceil(np.minimum(corners.max(axis=0) + pad,
                                       [view.shape[1], view.shape[0]])).astype(int)
    if right - left < 16 or bottom - top < 16:
        return None
    crop = np.ascontiguousarray(view[top:bottom, left:right], dtype=np.float32)
    to_crop = np.array([[1, 0, -left], [0, 1, -top], [0, 0, 1]], float)
    start = to_crop @ homography @ np.diag([1 / scale, 1 / scale, 1.0])
    try:
        score, warp = cv2.findTransformECCWithMask(
            small.astype(np.float32), crop, used, np.full(crop.shape, 255, np.uint8),
            (start / start[2, 2]).astype(np.float32), cv2.MOTION_HOMOGRAPHY,
            (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, iterations, 1e-4), 3)
    except cv2.error:  # ECC stops where the pixels give no direction to go
        return None
    fitted = np.linalg.inv(to_crop) @ warp.astype(np.float64) @ np.diag([scale, scale, 1.0])
    return float(score), fitted / fitted[2, 2]


def blank_margins(reference: np.ndarray, box: tuple[int, int, int, int],
                  ink: float = 0.1) -> tuple[tuple[int, int], tuple[int, int]]:
    """((x0, x1), (x0, x1)) px: the columns at the left and right ends of ``box`` that
    are blank in ``reference`` (no column of them departs from the box's background,
    its median, by more than ``ink`` of the box's range); a side with none is (x, x)."""
    x0, y0, x1, y1 = box
    patch = reference[y0:y1, x0:x1].astype(np.float64)
    spread = np.abs(patch - np.median(patch)).max(axis=0)
    inked = np.flatnonzero(spread > ink * max(np.ptp(patch), 1e-9))
    if not len(inked):
        return (x0, x0), (x1, x1)
    return (x0, x0 + int(inked[0])), (x0 + int(inked[-1]) + 1, x1)


def margin_ink(view: np.ndarray, homography: np.ndarray, reference: np.ndarray,
               box: tuple[int, int, int, int], inset: int = 3) -> float:
    """How much ink the view has where the reference's ``box`` has blank margins
    (:func:`blank_margins`): the grey levels' standard deviation in those margins,
    warped back through ``homography``, over that of the whole box (0: blank as on the
    reference; about 1: as busy as the word); nan where the box has no margins. The
    margins are taken ``inset`` px in from their edges (the detector takes two of the
    view's px, so neither a fit a pixel off nor the view's blur reads the word's edge as
    ink); margins narrower than that cannot be read, and give nan too."""
    height, width = reference.shape[:2]
    x0, y0, x1, y1 = box
    strips = [(a + inset, b - inset) for a, b in blank_margins(reference, box)
              if b - a > 2 * inset + 2]
    if not strips:
        return math.nan
    back = cv2.warpPerspective(view, homography, (width, height),
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                               borderMode=cv2.BORDER_REPLICATE).astype(np.float64)
    rows = slice(y0 + inset, y1 - inset)
    margins = np.hstack([back[rows, a:b] for a, b in strips])
    whole = back[y0:y1, x0:x1].std()
    return float(margins.std() / whole) if whole > 0 else math.nan


@dataclass
class _Level:
    """The reference at one size: its keypoints (in the full reference's px) and the
    FLANN index of their descriptors."""

    keypoints: tuple
    descriptors: np.ndarray
    matcher: cv2.FlannBasedMatcher = field(repr=False)


@dataclass
class _Reference:
    obj: KnownObject
    levels: list[_Level]
    plate_mask: np.ndarray = field(repr=False)  # 255 where the plate fit looks


class ObjectDetector:
    """Finds ``objects`` (:class:`KnownObject`) in views with ``features`` ``"sift"`` or
    ``"orb"`` (module notes). ``ratio`` is Lowe's ratio, ``ransac_px`` RANSAC's
    reprojection threshold (px), ``min_inliers`` the agreeing matches a homography
    needs. A verified detection needs the plate fitted again to correlate at least
    ``min_plate``, at most ``max_margin_ink`` ink in the blank margins beside the
    distinctive region, and the distinctive region to correlate at least
    ``min_correlation``, the smallest over ``strips`` x ``rows`` cells of it, and to
    disagree with the reference nowhere by more than ``max_residual`` of its ink
    contrast (:func:`stroke_residual`: a letter's stroke missing or added; set
    ``verify`` False to see what steps 1-4 alone report; the checks are still made and
    reported). ``seed`` seeds OpenCV's random generator before each FLANN index is
    built, so that the same view gives the same answer whatever was built before."""

    def __init__(self, objects: list[KnownObject], features: str = "sift",
                 ratio: float = 0.75, ransac_px: float = 4.0, min_inliers: int = 12,
                 min_correlation: float = 0.6, strips: int = 4, rows: int = 2,
                 verify: bool = True,
                 reference_widths: tuple[int, ...] | None = None,
                 reference_blur: float = 1.0, min_plate: float = 0.6,
                 max_margin_ink: float = 0.35, max_residual: float = 0.6,
                 seed: int = 0):
        if not objects:
            raise ValueError("give at least one KnownObject to look for")
        if not 0 < ratio <= 1:
            raise ValueError(f"ratio must be in (0, 1], got {ratio!r}")
        if not (math.isfinite(ransac_px) and ransac_px > 0):
            raise ValueError(f"ransac_px must be a finite number > 0, got {ransac_px!r}")
        if int(min_inliers) < 4:
            raise ValueError(f"a homography needs at least 4 matches, got {min_inliers!r}")
        if int(strips) < 1:
            raise ValueError(f"strips must be >= 1, got {strips!r}")
        for name, value in (("min_correlation", min_correlation), ("min_plate", min_plate)):
            if not -1 <= value <= 1:
                raise ValueError(f"{name} is a correlation, in [-1, 1]; got {value!r}")
        for name, value in (("max_margin_ink", max_margin_ink),
                            ("max_residual", max_residual)):
            if not value >= 0:
                raise ValueError(f"{name} must be >= 0, got {value!r}")
        self.features = features
        self.ratio, self.ransac_px, self.min_inliers = ratio, ransac_px, int(min_inliers)
        self.min_correlation, self.verify, self.strips = min_correlation, verify, int(strips)
        self.rows = int(rows)
        self.min_plate, self.max_margin_ink = min_plate, max_margin_ink
        self.max_residual = max_residual
        self._detector = make_features(features)
        widths = reference_widths or REFERENCE_WIDTHS[features]
        self._references = [
            _Reference(obj, [level for width in widths if (level := self._level(
                obj.gray, width, reference_blur, seed)) is not None], _plate_mask(obj))
            for obj in objects]

    def _level(self, gray: np.ndarray, width: int, blur: float, seed: int) -> _Level | None:
        """The reference shrunk to ``width`` px (never enlarged) and blurred by ``blur``
        px, its features and their FLANN index; None where it has fewer than two."""
        scale = 1.0
        if gray.shape[1] > width:
            scale = gray.shape[1] / width
            gray = cv2.resize(gray, (width, round(gray.shape[0] / scale)),
                              interpolation=cv2.INTER_AREA)
        if blur > 0:
            gray = cv2.GaussianBlur(gray, (0, 0), blur)
        # ORB drops keypoints within its 31 px patch of the border: a margin of the
        # reference's own edge colour lets the sign's outer features count
        margin = 32 if self.features == "orb" else 0
        padded = cv2.copyMakeBorder(gray, margin, margin, margin, margin, cv2.BORDER_REPLICATE)
        keypoints, descriptors = self._detector.detectAndCompute(padded, None)
        if descriptors is None or len(descriptors) < 2:
            return None
        keypoints = tuple(cv2.KeyPoint((k.pt[0] - margin) * scale, (k.pt[1] - margin) * scale,
                                       k.size * scale, k.angle, k.response, k.octave)
                          for k in keypoints)
        matcher = make_matcher(self.features)
        matcher.add([descriptors])
        cv2.setRNGSeed(seed)  # FLANN draws its trees and tables from it
        matcher.train()
        return _Level(keypoints, descriptors, matcher)

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
        # each size of the reference has its own ratio test (the same feature at two
        # sizes would otherwise be its own second neighbour); a view keypoint keeps its
        # nearest match over the sizes
        best: dict[int, tuple[float, tuple[float, float]]] = {}
        for level in ref.levels:
            for m in ratio_test(level.matcher.knnMatch(descriptors, k=2), self.ratio):
                if m.queryIdx not in best or m.distance < best[m.queryIdx][0]:
                    best[m.queryIdx] = (m.distance, level.keypoints[m.trainIdx].pt)
        if len(best) < self.min_inliers:
            return None
        source = np.float32([pt for _, pt in best.values()])
        target = np.float32([keypoints[i].pt for i in best])
        good = best
        homography, mask = cv2.findHomography(source, target, cv2.RANSAC, self.ransac_px,
                                              maxIters=2000, confidence=0.995)
        if homography is None or int(mask.sum()) < self.min_inliers:
            return None
        if not plausible_outline(_outline(ref.obj, homography), view.shape):
            return None
        reference = ref.obj.gray
        # verification (module notes, step 5): the plate fitted again from its own
        # pixels, not the matches, then its blank margins and its word read through it
        plate = fit_plate(view, homography, reference, ref.plate_mask)
        plate_score = math.nan
        if plate is not None and plausible_outline(_outline(ref.obj, plate[1]), view.shape):
            plate_score, homography = plate
        verified = plate_score >= self.min_plate
        correlation = margins = residual = math.nan
        if ref.obj.distinctive is not None:
            box = ref.obj.distinctive
            x0, y0, x1, y1 = box
            region = cv2.perspectiveTransform(
                np.float32([[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]]), homography)[0]
            rows, cols = view.shape[:2]
            if ((region >= 0) & (region <= [cols - 1, rows - 1])).all():
                correlation = region_correlation(view, homography, reference, box,
                                                 self.strips, self.rows)
                # two of the view's px, in the reference's
                across = np.hypot(*(region[1] - region[0]))
                margins = margin_ink(view, homography, reference, box,
                                     max(3, math.ceil(2 * (x1 - x0) / max(across, 1e-9))))
                residual = stroke_residual(view, homography, reference, box)
            # a region cut by the image's edge cannot be read: not verified
            verified = (verified and correlation >= self.min_correlation
                        and not margins > self.max_margin_ink
                        and residual <= self.max_residual)
        outline = _outline(ref.obj, homography)
        centre = _diagonal_crossing(outline)
        bearing = (-math.atan((centre[0] - cx) / fx) if fx is not None and cx is not None
                   else math.nan)
        return Detection(ref.obj.name, outline, homography, len(good), int(mask.sum()),
                         correlation, bool(verified), bearing, plate_score, margins,
                         residual)


def _plate_mask(obj: KnownObject) -> np.ndarray:
    """uint8, 255 where the plate fit looks: the reference outside its distinctive
    region (what every sign of the style shares)."""
    mask = np.full(obj.gray.shape, 255, np.uint8)
    if obj.distinctive is not None:
        x0, y0, x1, y1 = obj.distinctive
        mask[y0:y1, x0:x1] = 0
    return mask


def _outline(obj: KnownObject, homography: np.ndarray) -> np.ndarray:
    """(4, 2) px: the reference's corners, clockwise from top left, through
    ``homography``."""
    height, width = obj.image.shape[:2]
    corners = np.float32([[0, 0], [width - 1, 0], [width - 1, height - 1],
                          [0, height - 1]])[None]
    return cv2.perspectiveTransform(corners, homography)[0].astype(np.float64)


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
