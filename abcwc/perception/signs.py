"""Door signs of one house style: the images the simulator hangs on walls and the known
objects chapter 05 detects.

Every sign of the building's house style has the same layout: a dark green panel with a
white inset border, the university's crest on the left, the sign's word in large white
letters and a small line naming the building and level beneath it. Only the word
differs. That is what makes them a trap for local features: most of a sign's keypoints
(the crest, the border, the small line) are the same on every sign, so a ``STAIRS`` sign
matches the ``EXIT`` sign's reference with a good homography, and only the word region
(:data:`WORD_BOX`) tells them apart.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

SIGN_SIZE = (480, 240)
"""(width, height) px of a sign's reference image (2:1, like the panel)."""
WORD_BOX = (170, 45, 460, 150)
"""(x0, y0, x1, y1) px: where the word is written on every sign; the only region that
differs between signs of the house style."""
PANEL_RGB = (20, 100, 60)
INK_RGB = (245, 245, 240)
HOUSE_LINE = "BUILDING 2 - LEVEL 1"


@lru_cache(maxsize=32)
def house_sign(word: str, line: str = HOUSE_LINE) -> np.ndarray:
    """The (240, 480, 3) RGB uint8 image of the house-style sign saying ``word`` (1-8
    letters, digits, spaces or dashes), with ``line`` beneath it. Read-only (cached)."""
    if not (isinstance(word, str) and 1 <= len(word) <= 8
            and all(c.isalnum() or c in " -." for c in word)):
        raise ValueError(f"a sign's word must be 1-8 letters, digits, spaces or dashes, "
                         f"got {word!r}")
    width, height = SIGN_SIZE
    image = np.empty((height, width, 3), np.uint8)
    image[:] = PANEL_RGB
    cv2.rectangle(image, (8, 8), (width - 9, height - 9), INK_RGB, 4)
    _draw_crest(image, centre=(88, 110), size=62)
    x0, y0, x1, y1 = WORD_BOX
    font, thickness = cv2.FONT_HERSHEY_DUPLEX, 5
    (text_w, text_h), _ = cv2.getTextSize(word, font, 1.0, thickness)
    scale = min((x1 - x0) / text_w, (y1 - y0) / text_h) * 0.92
    (text_w, text_h), _ = cv2.getTextSize(word, font, scale, thickness)
    origin = (x0 + ((x1 - x0) - text_w) // 2, y0 + ((y1 - y0) + text_h) // 2)
    cv2.putText(image, word, origin, font, scale, INK_RGB, thickness, cv2.LINE_AA)
    (line_w, _), _ = cv2.getTextSize(line, cv2.FONT_HERSHEY_SIMPLEX, 0.62, 2)
    cv2.putText(image, line, (315 - line_w // 2, 200), cv2.FONT_HERSHEY_SIMPLEX, 0.62,
                INK_RGB, 2, cv2.LINE_AA)
    image.setflags(write=False)
    return image


def _draw_crest(image: np.ndarray, centre: tuple[int, int], size: int) -> None:
    """The university's crest: a quartered shield with a star, a ring and a book, the
    part every sign shares and local features latch on to."""
    cx, cy = centre
    shield = np.array([[cx - size, cy - size], [cx + size, cy - size], [cx + size, cy + 20],
                       [cx, cy + size + 25], [cx - size, cy + 20]], np.int32)
    cv2.fillPoly(image, [shield], INK_RGB, cv2.LINE_AA)
    dark = (10, 60, 35)
    cv2.rectangle(image, (cx - size + 8, cy - size + 8), (cx - 4, cy - 4), dark, -1)
    cv2.rectangle(image, (cx + 4, cy + 4), (cx + size - 8, cy + 18), dark, -1)
    star = [(cx + 32 + 26 * np.sin(k * 4 * np.pi / 5), cy - 32 - 26 * np.cos(k * 4 * np.pi / 5))
            for k in range(5)]
    cv2.polylines(image, [np.int32(star)], True, dark, 4, cv2.LINE_AA)
    cv2.circle(image, (cx - 31, cy - 31), 14, INK_RGB, 4, cv2.LINE_AA)
    book = np.array([[cx - 40, cy + 12], [cx - 4, cy + 22], [cx - 4, cy + 52], [cx - 40, cy + 42]],
                    np.int32)
    cv2.polylines(image, [book], True, dark, 4, cv2.LINE_AA)
    cv2.line(image, (cx - 22, cy + 17), (cx - 22, cy + 47), dark, 3, cv2.LINE_AA)
    cv2.circle(image, (cx + 32, cy + 44), 7, dark, -1, cv2.LINE_AA)
