"""Maps as ROS map_server files: a YAML header and a binary PGM image (thesis 4.3.8).

What ROS 1 map_server/map_saver and Nav2's nav2_map_server read and write
(http://wiki.ros.org/map_server): ``name.yaml`` holds

    image: name.pgm            # relative to the YAML's folder, or absolute
    mode: trinary
    resolution: 0.05           # m per pixel
    origin: [x, y, yaw]        # map pose of the lower-left pixel's corner (m, m, rad)
    negate: 0
    occupied_thresh: 0.65
    free_thresh: 0.196

and ``name.pgm`` is a P5 (binary, maxval 255) greyscale image whose top row is the map's
largest y. A pixel value ``v`` reads as ``p = (255 - v) / 255`` (``v / 255`` when
``negate``): occupied when ``p > occupied_thresh``, free when ``p < free_thresh``, unknown
otherwise. map_saver writes occupied cells 0, free 254 and unknown 205 (p = 0.196078...,
just above ``free_thresh`` 0.196, hence that odd default), and so does :func:`save_map`.

Many ROS consumers (costmap_2d, AMCL) ignore the origin's yaw: keep it 0 for maps meant
for them. Only ``mode: trinary`` (map_server's default when ``mode`` is absent) and PGM images are
read; anything else is refused with a message naming the file.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import yaml

from abcwc.mapping.grid import (
    FREE,
    FREE_THRESH,
    OCCUPIED,
    OCCUPIED_THRESH,
    UNKNOWN,
    InverseSensorModel,
    OccupancyGrid,
)
from abcwc.paths import read_document

PIXEL_OCCUPIED = 0
PIXEL_FREE = 254
PIXEL_UNKNOWN = 205
REQUIRED_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")


class MapFileError(ValueError):
    """A map YAML or image that cannot be read, with the file and what is allowed."""


def _yaml_float(value: float) -> str:
    """A float YAML 1.1 readers (PyYAML, yaml-cpp) both take as a float and that reads
    back exactly: Python's shortest repr, with a ``.0`` where an exponent has no point."""
    text = repr(float(value))
    if "e" in text and "." not in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def save_map(grid: OccupancyGrid, yaml_path: str | Path,
             occupied_thresh: float = OCCUPIED_THRESH,
             free_thresh: float = FREE_THRESH) -> Path:
    """Write ``grid`` as ``yaml_path`` plus a PGM of the same name beside it, as map_saver
    does: cells with p(occupied) > ``occupied_thresh`` as 0, below ``free_thresh`` as 254,
    the rest 205. Returns the YAML's path."""
    yaml_path = Path(yaml_path)
    if yaml_path.suffix not in (".yaml", ".yml"):
        raise MapFileError(f"{yaml_path}: a map header's name ends in .yaml or .yml")
    image_path = yaml_path.with_suffix(".pgm")
    cells = grid.trinary(occupied_thresh, free_thresh)
    pixels = np.full(cells.shape, PIXEL_UNKNOWN, dtype=np.uint8)
    pixels[cells == OCCUPIED] = PIXEL_OCCUPIED
    pixels[cells == FREE] = PIXEL_FREE
    header = (f"P5\n# CREATOR: abcwc {grid.resolution:.3f} m/pix\n"
              f"{grid.width} {grid.height}\n255\n").encode("ascii")
    image_path.write_bytes(header + pixels[::-1].tobytes())  # top row = largest y
    origin = ", ".join(_yaml_float(v) for v in (grid.origin.x, grid.origin.y,
                                                 grid.origin.theta))
    yaml_path.write_text(
        f"image: {image_path.name}\n"
        f"mode: trinary\n"
        f"resolution: {_yaml_float(grid.resolution)}\n"
        f"origin: [{origin}]\n"
        f"negate: 0\n"
        f"occupied_thresh: {_yaml_float(occupied_thresh)}\n"
        f"free_thresh: {_yaml_float(free_thresh)}\n")
    return yaml_path


def _number(header: dict, key: str, where: Path) -> float:
    value = header[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapFileError(f"{where}: {key} must be a finite number, got {value!r}")
    return float(value)


def read_header(yaml_path: str | Path) -> dict:
    """The checked header of a map YAML: ``image`` (a Path, resolved against the YAML's
    folder), ``resolution`` (m), ``origin`` (x, y, yaw), ``negate`` (bool), the two
    thresholds and ``mode``."""
    yaml_path = Path(yaml_path)
    header = read_document(yaml_path, yaml.safe_load, parse_errors=(yaml.YAMLError,),
                           error=MapFileError, kind="map file", language="YAML")
    if not isinstance(header, dict):
        raise MapFileError(f"{yaml_path}: a map header is a mapping of "
                           f"{', '.join(REQUIRED_KEYS)}")
    missing = [key for key in REQUIRED_KEYS if key not in header]
    if missing:
        raise MapFileError(f"{yaml_path}: missing {', '.join(missing)} "
                           f"(a map header needs {', '.join(REQUIRED_KEYS)})")
    if not isinstance(header["image"], str) or not header["image"]:
        raise MapFileError(f"{yaml_path}: image must be a file name, got {header['image']!r}")
    resolution = _number(header, "resolution", yaml_path)
    if resolution <= 0:
        raise MapFileError(f"{yaml_path}: resolution {resolution} must be > 0 m/pixel")
    origin = header["origin"]
    if (not isinstance(origin, list) or len(origin) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       and math.isfinite(v) for v in origin)):
        raise MapFileError(f"{yaml_path}: origin must be [x, y, yaw] of finite numbers, "
                           f"got {origin!r}")
    negate = header["negate"]
    if negate not in (0, 1):  # 0/1 as map_saver writes, or false/true
        raise MapFileError(f"{yaml_path}: negate must be 0 or 1, got {negate!r}")
    occupied = _number(header, "occupied_thresh", yaml_path)
    free = _number(header, "free_thresh", yaml_path)
    if not 0.0 <= free <= occupied <= 1.0:
        raise MapFileError(f"{yaml_path}: thresholds out of order: need 0 <= free_thresh "
                           f"({free}) <= occupied_thresh ({occupied}) <= 1")
    mode = header.get("mode", "trinary")
    if mode != "trinary":
        raise MapFileError(f"{yaml_path}: mode {mode!r} is not read here; only trinary is")
    image = Path(header["image"])
    return {"image": image if image.is_absolute() else yaml_path.parent / image,
            "resolution": resolution, "origin": tuple(float(v) for v in origin),
            "negate": bool(negate), "occupied_thresh": occupied, "free_thresh": free,
            "mode": mode}


def _pgm_token(data: bytes, at: int, where: Path) -> tuple[bytes, int]:
    """The next whitespace-separated header token of a PGM (skipping ``#`` comments)."""
    while at < len(data):
        if data[at:at + 1].isspace():
            at += 1
        elif data[at:at + 1] == b"#":
            end = data.find(b"\n", at)
            at = len(data) if end < 0 else end + 1
        else:
            break
    end = at
    while end < len(data) and not data[end:end + 1].isspace() and data[end:end + 1] != b"#":
        end += 1
    if end == at:
        raise MapFileError(f"{where}: PGM header ends early")
    return data[at:end], end


def read_pgm(path: str | Path) -> np.ndarray:
    """The pixels of a binary (P5) 8-bit PGM as a (rows, columns) uint8 array, top row
    first, as stored."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise MapFileError(f"{path}: map image not found") from None
    if data[:2] != b"P5" or not data[2:3].isspace():
        raise MapFileError(f"{path}: not a binary PGM: magic {data[:2]!r}, expected b'P5'")
    at = 2
    fields = []
    for _ in range(3):
        token, at = _pgm_token(data, at, path)
        if not token.isdigit():
            raise MapFileError(f"{path}: PGM header field {token!r} is not a whole number")
        fields.append(int(token))
    width, height, maxval = fields
    if maxval != 255:
        raise MapFileError(f"{path}: PGM maxval {maxval}, expected 255 (8-bit pixels)")
    if width < 1 or height < 1:
        raise MapFileError(f"{path}: PGM size {width} x {height} has no pixels")
    pixels = data[at + 1:]  # one whitespace byte ends the header
    if len(pixels) != width * height:
        raise MapFileError(f"{path}: PGM of {width} x {height} needs {width * height} pixel "
                           f"bytes, has {len(pixels)}")
    return np.frombuffer(pixels, dtype=np.uint8).reshape(height, width)


def load_map(yaml_path: str | Path,
             model: InverseSensorModel | None = None) -> OccupancyGrid:
    """Read a map_server map: an :class:`OccupancyGrid` with the file's resolution and
    origin whose trinary view is the file's (occupied at ``l_max``, free at ``l_min``,
    unknown at 0; row 0 the lowest y), by map_server's rules (module notes)."""
    header = read_header(yaml_path)
    pixels = read_pgm(header["image"])[::-1]  # row 0 = lowest y
    p = pixels / 255.0 if header["negate"] else (255 - pixels.astype(float)) / 255.0
    cells = np.full(pixels.shape, UNKNOWN, dtype=np.int8)
    cells[p < header["free_thresh"]] = FREE
    cells[p > header["occupied_thresh"]] = OCCUPIED
    return OccupancyGrid.from_trinary(cells, header["resolution"], header["origin"], model)
