"""abcwc: turn a powered wheelchair into an autonomous robot.

``chair = abcwc.connect()`` gives the simulated chair; ``abcwc.connect("/dev/ttyACM0")``
the real one, through the same interface; ``with abcwc.hardware_chair() as real:`` is a
course cell's speed-capped real chair (``ABCWC_PORT``), or ``None`` when there is none.
"""

from abcwc.base import Base
from abcwc.connect import HARDWARE_CELL_CAP, PORT_ENV, SIMAVR_PORT, connect, hardware_chair
from abcwc.log import RunLog
from abcwc.params import ChairParams, NavigationParams, default_params, load_navigation_params
from abcwc.types import (
    LaserScan,
    Pose2D,
    PotCommand,
    SensorFrame,
    SimTruth,
    StatusFlags,
    Twist,
    make_frame,
)

__version__ = "0.1.0"

__all__ = [
    "HARDWARE_CELL_CAP",
    "PORT_ENV",
    "SIMAVR_PORT",
    "Base",
    "ChairParams",
    "NavigationParams",
    "LaserScan",
    "Pose2D",
    "PotCommand",
    "RunLog",
    "SensorFrame",
    "SimTruth",
    "StatusFlags",
    "Twist",
    "connect",
    "hardware_chair",
    "default_params",
    "load_navigation_params",
    "make_frame",
]
