"""What a machine may lack: the one error every hardware path raises when its device is
not there.

The real chair's serial port, our firmware on the far end of it, the AVR toolchain and
simavr for the firmware in the loop, and the instructor's microphone are each present on
some machines and not on others. When one is missing (or there but unusable: permission
denied, another firmware answering, no input device), the code that needed it raises
:class:`DeviceUnavailableError`, whose message names what is missing and how to get it.
A course's real-chair cell (:func:`abcwc.hardware_chair`) prints that message and goes
on, so a notebook runs to its end on any machine.

The hardware modules' own errors subclass it where they mean "not here"
(:class:`abcwc.hw.link.NoSuchPortError`, :class:`abcwc.hw.fil_base.FirmwareToolchainError`,
...); a link that fails while the chair is driving is not one of them: that is a
:class:`abcwc.hw.link.ChairLinkError` and stops the cell with its traceback.
"""

from __future__ import annotations

__all__ = ["DeviceUnavailableError"]


class DeviceUnavailableError(RuntimeError):
    """A device this code needs is not on this machine, or cannot be used; the message
    says which, and how to get it."""
