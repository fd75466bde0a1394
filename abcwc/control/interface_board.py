"""The interface board's safety logic, as the firmware runs it every loop.

Between the joystick and the motor controller sits the Arduino. Whatever the host
asks, it keeps three rules (DESIGN.md section 6):

1. the joystick always wins: a deflection outside the dead band (248..260 on the pot
   scale) drives the pots through eqn 1 within one loop;
2. pot outputs never leave the safe range 8..253 (and the host's speed cap);
3. no valid command for 250 ms puts both pots at neutral.

After the joystick has taken over, a joystick fault or a watchdog trip, the pots stay
neutral until the host sends a new command: an old command never resumes by itself.

:class:`InterfaceBoard` is the Python twin of ``firmware/core``; the simulator runs it
so a simulated chair obeys the same rules as the real one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from abcwc.control.pots import clamp_pot_byte, joystick_adc_to_pot_byte
from abcwc.control.velocity import twist_to_pot_command
from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, StatusFlags, Twist

# Joystick ADC readings outside this band cannot come from a working joystick
# (disconnected: near 0; shorted: near 1023).
JOYSTICK_PLAUSIBLE_MIN = 60
JOYSTICK_PLAUSIBLE_MAX = 450


def joystick_state(fb_adc: int, lr_adc: int, params: ChairParams) -> str:
    """``"fault"`` if a reading is outside 60..450 (no working joystick reads that),
    else ``"deflected"`` if a channel is outside the dead band 248..260, else
    ``"neutral"``. Unlike A.18's checkjoystick, either axis alone counts."""
    readings = (fb_adc, lr_adc)
    if any(not JOYSTICK_PLAUSIBLE_MIN <= r <= JOYSTICK_PLAUSIBLE_MAX for r in readings):
        return "fault"
    low, high = params.joystick_dead_band_low, params.joystick_dead_band_high
    if any(not low <= r <= high for r in readings):
        return "deflected"
    return "neutral"


def check_speed_cap(offset: object, params: ChairParams | None = None) -> int:
    """A host speed cap (largest |pot byte - 128|, 0..125) as an int, or ValueError."""
    full = (params or default_params()).pot_full_scale_offset
    if isinstance(offset, bool) or not isinstance(offset, (int, np.integer)) \
            or not 0 <= int(offset) <= full:
        raise ValueError(f"speed cap {offset!r} outside 0..{full} (pot bytes from 128)")
    return int(offset)


def cap_pot_byte(byte: int, cap: int, params: ChairParams | None = None) -> int:
    """A host pot byte limited to ``128 +- cap`` (a cap above 125 means 125) and to
    the safe range 8..253, as the board (and the firmware's CONFIGURE caps) do."""
    p = params or default_params()
    c = min(int(cap), p.pot_full_scale_offset)
    return clamp_pot_byte(min(max(int(byte), p.pot_neutral - c), p.pot_neutral + c), p)


@dataclass(frozen=True)
class BoardOutput:
    """What the board writes to the pots this loop, and why."""

    pots: PotCommand
    flags: StatusFlags


class InterfaceBoard:
    """Joystick override, clamps, speed cap and watchdog (times in seconds)."""

    def __init__(self, params: ChairParams | None = None, speed_cap: int | None = None):
        self.params = params or default_params()
        p = self.params
        self.speed_cap = p.pot_full_scale_offset if speed_cap is None else speed_cap
        self.set_speed_cap(self.speed_cap)
        self._command: PotCommand | None = None
        self._command_time = float("-inf")
        self._command_fresh = False  # False once overridden: wait for a new command

    def set_speed_cap(self, offset: int) -> None:
        """Limit host commands to ``128 +- offset`` on each channel (0..125)."""
        self.speed_cap = check_speed_cap(offset, self.params)

    def command(self, command: PotCommand | Twist, now: float) -> None:
        """Accept a host command at time ``now`` (s); it feeds the watchdog."""
        if isinstance(command, Twist):
            command = twist_to_pot_command(command, self.params)
        elif not isinstance(command, PotCommand):
            raise TypeError(f"command must be a PotCommand or Twist, got {type(command).__name__}")
        self._command = command
        self._command_time = now
        self._command_fresh = True

    @property
    def last_command(self) -> PotCommand | None:
        """The last host command as pot bytes (before clamps and the cap)."""
        return self._command

    def stop(self, now: float) -> None:
        """Host asks for an immediate stop (a valid command: neutral pots)."""
        self.command(PotCommand(self.params.pot_neutral, self.params.pot_neutral), now)

    def update(self, now: float, joystick_fb: int, joystick_lr: int) -> BoardOutput:
        """One firmware loop: decide the pot bytes from the joystick and last command."""
        p = self.params
        neutral = PotCommand(p.pot_neutral, p.pot_neutral)
        state = joystick_state(joystick_fb, joystick_lr, p)
        if state == "fault":
            self._command_fresh = False
            return BoardOutput(neutral, StatusFlags.JOYSTICK_FAULT)
        if state == "deflected":
            self._command_fresh = False
            return BoardOutput(
                PotCommand(joystick_adc_to_pot_byte(joystick_fb, p),
                           joystick_adc_to_pot_byte(joystick_lr, p)),
                StatusFlags.JOYSTICK_OVERRIDE)
        stale = now - self._command_time > p.watchdog_timeout + 1e-9
        if self._command is None or stale or not self._command_fresh:
            self._command_fresh = False
            return BoardOutput(neutral, StatusFlags.WATCHDOG_TRIPPED)
        flags = StatusFlags.HOST_ACTIVE
        bytes_out = []
        for value in (self._command.fb, self._command.lr):
            capped = cap_pot_byte(value, self.speed_cap, p)
            if capped != value:
                flags |= StatusFlags.SPEED_CAPPED
            bytes_out.append(capped)
        return BoardOutput(PotCommand(*bytes_out), flags)
