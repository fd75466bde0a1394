"""Talking to the real chair: the wire protocol (:mod:`abcwc.hw.protocol`), the serial
link (:mod:`abcwc.hw.link`), the real chair's body (:class:`SerialBase`) and the
firmware in the loop (:mod:`abcwc.hw.fil_base`, imported on its own: it brings the
simulator)."""

from abcwc.hw.link import (
    ChairLinkError,
    NoSuchPortError,
    NotOurFirmwareError,
    PortUnusableError,
    ProtocolVersionError,
    SerialLink,
)
from abcwc.hw.serial_base import SerialBase

__all__ = ["ChairLinkError", "NoSuchPortError", "NotOurFirmwareError", "PortUnusableError",
           "ProtocolVersionError", "SerialBase", "SerialLink"]
