"""abcwc: turn a powered wheelchair into an autonomous robot.

``chair = abcwc.connect()`` gives the simulated chair; ``abcwc.connect("/dev/ttyACM0")``
(or with ``ABCWC_PORT`` set) the real one, through the same interface.
"""

from abcwc.base import connect
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import LaserScan, Pose2D, PotCommand, SensorFrame, StatusFlags, Twist

__version__ = "0.1.0"

__all__ = [
    "ChairParams",
    "LaserScan",
    "Pose2D",
    "PotCommand",
    "RunLog",
    "SensorFrame",
    "StatusFlags",
    "Twist",
    "connect",
    "default_params",
]
