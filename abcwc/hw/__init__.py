"""Talking to the real chair: the serial wire protocol (``abcwc.hw.protocol``)."""
