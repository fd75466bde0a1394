"""Spoken commands: the command grammar, audio buffers, synthetic test speech, the
verified pocketsphinx recogniser and its adaptation to one speaker."""

from abcwc.perception.speech.adaptation import MeanTransform, enroll
from abcwc.perception.speech.audio import SAMPLE_RATE, AudioError
from abcwc.perception.speech.commands import CommandSet, SpokenCommand
from abcwc.perception.speech.recognizer import CommandRecognizer, Recognition, Verification

__all__ = ["SAMPLE_RATE", "AudioError", "CommandRecognizer", "CommandSet", "MeanTransform",
           "Recognition", "SpokenCommand", "Verification", "enroll"]
