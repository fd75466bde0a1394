"""Spoken commands: the command grammar, audio buffers, espeak-ng test speech and the
verified pocketsphinx recogniser."""

from abcwc.perception.speech.audio import SAMPLE_RATE, AudioError
from abcwc.perception.speech.commands import CommandSet, SpokenCommand
from abcwc.perception.speech.recognizer import CommandRecognizer, Recognition, Verification

__all__ = ["SAMPLE_RATE", "AudioError", "CommandRecognizer", "CommandSet", "Recognition",
           "SpokenCommand", "Verification"]
