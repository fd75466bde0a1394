"""How far and how well the chair's camera finds a known sign, and how often a look-alike
fools it: a seeded sweep in the simulator (:mod:`abcwc.experiments.views`).

The sign shown is the house-style sign saying ``shown``; the detector looks for the one
saying ``sought``. With both ``"EXIT"`` the sweep measures detection: how far, at what
turn, and how well the bearing agrees with the truth. With ``"STAIRS"`` shown it
measures false detections: what the pipeline reports before and after verification.

:func:`rates` is the whole assessment, in the lab's geometry (views 1.5-4 m from the
sign, up to 40 degrees off its face): the share of views of the real sign found, clean
and under each of the camera's troubles (:data:`CONDITIONS`), and the share of views
where a look-alike hangs that report the real sign. The look-alikes are words made at
measurement time from a seeded generator (:func:`look_alike_words`), so no threshold
can have been tuned on them: a third of them contain the known word inside a longer one
(``EXIT`` in ``EXITS`` or ``NEXIT``), the look-alike the first verification let
through; a third change its letters, every other one of them one letter for one whose
glyph in the house font is much like it (:func:`alike_letters`: ``FXIT``, ``EKIT``),
the look-alike the 4 x 2 cells let through; the rest are random. The false rates are
reported by kind (:func:`word_kind`).

Measured with the default detectors (288 views a condition, seed 28; found %, SIFT /
ORB): clean 98.3 / 97.9, blur 1.5 px 94.1 / 96.2, exposure x0.4 96.5 / 96.5, exposure
x1.8 96.2 / 95.8, noise 16 grey levels 97.6 / 97.6, all of these at once 46.2 / 85.1,
the same as before the stroke check (module notes of
:mod:`abcwc.perception.known_objects`, step 5d). Views of a look-alike reported as the
exit: none, for both, of every kind (96 views containing EXIT, 48 of one-letter
look-alikes, 48 of other changed letters, ZXIT's 12 among them, 96 random). Before the
stroke check 4.17 % of the views of the look-alikes then drawn (before one-letter
look-alikes were a kind of their own), every one of them ZXIT's, were reported as the
exit; of the 100 words that change one of EXIT's letters, 4 views each, the cells let
89 views through (SIFT; ORB 83), the stroke check none.
The first verification (the word read through the matches' homography) reported EXITS
as the exit in 48 % of SIFT's views.
"""

from __future__ import annotations

import math
import string
import time
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from abcwc.experiments.disk_cache import cached_on_disk
from abcwc.experiments.views import random_views
from abcwc.geometry import wrap_angle
from abcwc.params import ChairParams
from abcwc.perception.camera import to_gray
from abcwc.perception.known_objects import KnownObject, ObjectDetector
from abcwc.perception.signs import WORD_BOX, house_sign
from abcwc.sim.colour_camera import Imaging


@dataclass(frozen=True)
class SignSweep:
    """One row per view: the true ``distance`` (m, camera to the sign's centre),
    ``bearing`` and ``turn`` (rad), the sign's ``width_px`` in the image (its true
    corners projected), then for the detector: whether steps 1-4 reported the sought
    sign (``matched``), its ``correlation`` (nan where not matched), whether it was
    ``verified``, its ``bearing_error`` (rad, nan where not matched) and the
    detector's time (``ms``: as measured when the sweep was made, also where a later
    call reads it back from disk)."""

    features: str
    shown: str
    sought: str
    distance: np.ndarray
    bearing: np.ndarray
    turn: np.ndarray
    width_px: np.ndarray
    matched: np.ndarray
    correlation: np.ndarray
    verified: np.ndarray
    bearing_error: np.ndarray
    ms: np.ndarray

    def farthest(self, found: np.ndarray) -> float:
        """m: the farthest view where ``found`` (a bool row) is true."""
        return float(self.distance[found].max()) if found.any() else 0.0

    def rate(self, found: np.ndarray, within: tuple[float, float],
             max_turn: float = math.pi) -> float:
        """The share of views ``within`` (near, far) m, the sign turned at most
        ``max_turn`` rad from facing the camera, where ``found`` is true."""
        band = ((self.distance >= within[0]) & (self.distance < within[1])
                & (np.abs(self.turn) <= max_turn))
        return float(found[band].mean()) if band.any() else math.nan


@cached_on_disk  # seeded: a notebook, its student copy and its check render the views once
def sweep_sign_views(features: str = "sift", shown: str = "EXIT", sought: str = "EXIT",
                     count: int = 60, seed: int = 0, distances: tuple[float, float] = (1.5, 9.0),
                     max_bearing: float = 0.4, max_turn: float = 1.0,
                     width: float = 0.6, params: ChairParams | None = None,
                     detector: ObjectDetector | None = None,
                     imaging: Imaging | None = None) -> SignSweep:
    """Render ``count`` random views of the sign saying ``shown`` (``width`` m wide, its
    centre 1.1-1.3 m up) and look in each for the one saying ``sought`` with SIFT or ORB
    (``features``; or a ``detector`` of one's own), verification reported separately."""
    detector = detector or ObjectDetector(
        [KnownObject(sought.lower(), house_sign(sought), width, WORD_BOX)], features=features,
        verify=False)
    name = detector.objects[0].name
    image = house_sign(shown)
    rows = []
    for view in random_views(image, width, count, seed, distances, max_bearing, max_turn,
                             (1.1, 1.3), params, imaging):
        true_range, true_bearing = view.range_and_bearing(np.array(view.centre[:2]))
        half = width / 2 * np.array([-math.sin(view.facing), math.cos(view.facing)])
        ends = [view.range_and_bearing(np.array(view.centre[:2]) + k * half) for k in (-1, 1)]
        width_px = abs(view.camera.fx * (math.tan(ends[0][1]) - math.tan(ends[1][1])))
        start = time.perf_counter()
        found = [d for d in detector.detect(view.gray, view.camera.fx, view.camera.cx)
                 if d.name == name]
        ms = (time.perf_counter() - start) * 1000
        best = found[0] if found else None
        rows.append((true_range, true_bearing, view.turn, width_px, best is not None,
                     best.correlation if best else math.nan,
                     bool(best and best.verified),
                     wrap_angle(best.bearing - true_bearing) if best else math.nan,
                     ms))
    columns = [np.array(c) for c in zip(*rows)]
    return SignSweep(detector.features,
                     shown, sought, *columns[:4], columns[4].astype(bool), columns[5],
                     columns[6].astype(bool), columns[7], columns[8])


CONDITIONS = {
    "clean": Imaging(),
    "blur 1.5 px": Imaging(blur_sigma=1.5),
    "exposure x0.4": Imaging(gain=(0.4, 0.4)),
    "exposure x1.8": Imaging(gain=(1.8, 1.8)),
    "noise 16 grey levels": Imaging(noise_std=16.0),
    "all of these at once": Imaging(gain=(1.8, 1.8), blur_sigma=1.5, noise_std=16.0),
}
"""The camera's troubles the assessment sees the real sign under (the camera's default
imaging: gain 0.8-1.15, blur 0.7 px, noise 3 grey levels, no motion)."""
LAB_GEOMETRY = {"distances": (1.5, 4.0), "max_turn": math.radians(40.0)}
"""The lab's geometry: views 1.5-4 m from the sign, up to 40 degrees off its face."""


@lru_cache(maxsize=1)
def _glyphs() -> dict[str, np.ndarray]:
    """Each capital letter alone on the house sign: its word region, grey, float."""
    x0, y0, x1, y1 = WORD_BOX
    return {c: to_gray(house_sign(c))[y0:y1, x0:x1].astype(np.float64)
            for c in string.ascii_uppercase}


def alike_letters(letter: str, count: int = 4) -> tuple[str, ...]:
    """The ``count`` capital letters whose glyphs on the house sign are most like
    ``letter``'s, most alike first: each letter drawn alone on the sign, its word region
    correlated with ``letter``'s (normalised cross-correlation). F and Z are among E's:
    they keep E's bars."""
    glyphs = _glyphs()
    if letter not in glyphs:
        raise ValueError(f"letter must be one capital letter A-Z, got {letter!r}")
    if not 1 <= count <= 25:
        raise ValueError(f"count must be 1-25, got {count!r}")

    def likeness(other: str) -> float:
        a, b = glyphs[letter] - glyphs[letter].mean(), glyphs[other] - glyphs[other].mean()
        return float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum()))

    others = sorted((c for c in glyphs if c != letter), key=lambda c: (-likeness(c), c))
    return tuple(others[:count])


def look_alike_words(known: str, count: int, seed: int) -> tuple[str, ...]:
    """``count`` different words of the house sign's alphabet (capital letters, at most 8),
    none of them ``known``, drawn from a seeded generator: the first third ``known``
    with letters before, after or both (a longer word containing it), the second
    ``known`` with letters changed (the same length and mostly the same letters), every
    other one of them one letter for one of the four whose glyph is most like it
    (:func:`alike_letters`: ZXIT, FXIT for EXIT), the rest one or two letters at random
    (as LIFT is to EXIT); the last third 3-8 random letters."""
    if not (isinstance(known, str) and known.isalpha() and 1 <= len(known) <= 6):
        raise ValueError(f"known must be a word of 1-6 letters (room for a longer one "
                         f"containing it), got {known!r}")
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count!r}")
    rng = np.random.default_rng(seed)
    letters = np.array(list(string.ascii_uppercase))
    words: list[str] = []
    while len(words) < count:
        if len(words) < (count + 2) // 3:
            extra = int(rng.integers(1, 8 - len(known) + 1))
            before = int(rng.integers(0, extra + 1))
            pad = "".join(rng.choice(letters, extra))
            word = pad[:before] + known.upper() + pad[before:]
        elif len(words) < 2 * count // 3 + (count % 3 == 2):
            chars = list(known.upper())
            if (len(words) - (count + 2) // 3) % 2 == 0:  # one letter, for a look-alike
                at = int(rng.integers(len(chars)))
                chars[at] = str(rng.choice(alike_letters(chars[at])))
            else:
                for at in rng.choice(len(chars), min(len(chars), int(rng.integers(1, 3))),
                                     replace=False):
                    chars[at] = str(rng.choice(letters))
            word = "".join(chars)
        else:
            word = "".join(rng.choice(letters, int(rng.integers(3, 9))))
        if word != known.upper() and word not in words:
            words.append(word)
    return tuple(words)


WORD_KINDS = ("containing", "one letter alike", "letters changed", "other")
"""The kinds of look-alike word (:func:`word_kind`)."""


def word_kind(word: str, known: str) -> str:
    """Which of :data:`WORD_KINDS` ``word`` is to ``known``: it contains it; it is
    ``known`` with one letter changed for one of the four most alike
    (:func:`alike_letters`); the same length with other letters changed; or other."""
    word, known = word.upper(), known.upper()
    if known in word:
        return "containing"
    if len(word) != len(known):
        return "other"
    changed = [(k, w) for k, w in zip(known, word) if k != w]
    if len(changed) == 1 and changed[0][0].isalpha() and \
            changed[0][1] in alike_letters(changed[0][0]):
        return "one letter alike"
    return "letters changed"


@dataclass(frozen=True)
class Rates:
    """One detector's assessment (:func:`rates`): ``found`` (condition -> share of views
    of the real sign found), ``false`` (the share of views with a look-alike that report
    the real sign), ``false_by_kind`` (the same over each of :data:`WORD_KINDS`), the
    ``words`` used, ``views`` per condition, and the median ``ms`` a detection took on
    the clean views."""

    features: str
    found: dict[str, float]
    false: float
    false_by_kind: dict[str, float]
    words: tuple[str, ...]
    views: int
    ms: float


@lru_cache(maxsize=4)
def rates(features: str = "sift", count: int = 288, seed: int = 28, words: int = 24) -> Rates:
    """The default detector for the EXIT sign with ``features``, on ``count`` views of the
    real sign under each of :data:`CONDITIONS` and ``count`` views of look-alikes
    (``words`` of them, made with :func:`look_alike_words`, each hanging in an equal
    share of the views), all in :data:`LAB_GEOMETRY` (module notes). Takes a few
    minutes for SIFT."""
    detector = ObjectDetector([KnownObject("exit", house_sign("EXIT"), 0.6, WORD_BOX)],
                              features=features)
    found, ms = {}, math.nan
    for k, (name, imaging) in enumerate(CONDITIONS.items()):
        sweep = sweep_sign_views(detector=detector, count=count, seed=seed + k,
                                 imaging=imaging, **LAB_GEOMETRY)
        found[name] = float(sweep.verified.mean())
        if name == "clean":
            ms = float(np.median(sweep.ms))
    fakes = look_alike_words("EXIT", words, seed)
    share = [count // words + (i < count % words) for i in range(words)]
    fooled = [sweep_sign_views(detector=detector, shown=word, count=n, seed=seed + 100 + i,
                               **LAB_GEOMETRY).verified for i, (word, n) in
              enumerate(zip(fakes, share))]
    by_kind = {}
    for kind in WORD_KINDS:
        seen = [f for word, f in zip(fakes, fooled) if word_kind(word, "EXIT") == kind]
        by_kind[kind] = float(np.concatenate(seen).mean()) if seen else math.nan
    return Rates(features, found, float(np.concatenate(fooled).mean()), by_kind, fakes,
                 count, ms)


__all__ = ["CONDITIONS", "LAB_GEOMETRY", "WORD_KINDS", "Rates", "SignSweep", "alike_letters",
           "look_alike_words", "rates", "sweep_sign_views", "word_kind"]
