"""Pot control: joystick and angle maps, velocity controllers, the board's safety."""

from abcwc.control.interface_board import (
    BoardOutput,
    InterfaceBoard,
    cap_pot_byte,
    check_speed_cap,
    joystick_state,
)
from abcwc.control.pots import (
    TABLE_6_AS_PRINTED,
    AvoidAction,
    SonarDecision,
    angle_to_lr_byte,
    clamp_pot_byte,
    direction_pot_command,
    joystick_adc_to_pot_byte,
    joystick_to_pot_byte,
    pot_byte_to_deflection,
    sonar_turn_angle,
    turn_value,
)
from abcwc.control.velocity import (
    thesis_twist_to_pots,
    twist_to_pot_bytes_int,
    twist_to_pot_command,
    twist_to_wire_units,
)

__all__ = [
    "TABLE_6_AS_PRINTED",
    "AvoidAction",
    "BoardOutput",
    "InterfaceBoard",
    "SonarDecision",
    "angle_to_lr_byte",
    "cap_pot_byte",
    "check_speed_cap",
    "clamp_pot_byte",
    "direction_pot_command",
    "joystick_adc_to_pot_byte",
    "joystick_state",
    "joystick_to_pot_byte",
    "pot_byte_to_deflection",
    "sonar_turn_angle",
    "thesis_twist_to_pots",
    "turn_value",
    "twist_to_pot_bytes_int",
    "twist_to_pot_command",
    "twist_to_wire_units",
]
