"""The pymunk simulation of the chair, its sensors and its world."""

from abcwc.sim.base import SimBase
from abcwc.sim.motor import ChairErrors
from abcwc.sim.world import World, WorldError, available_worlds, load_world

__all__ = ["ChairErrors", "SimBase", "World", "WorldError", "available_worlds", "load_world"]
