"""How well the chair hears its commands: espeak-ng voices saying the commands and
sentences that share their words, at several noise levels, through the recogniser.

Two sets, each of voices and distractor sentences: the recogniser's thresholds were
chosen on ``synthesis.TUNING_VOICES`` with ``TUNING_DISTRACTORS``, and are reported on
``synthesis.TEST_VOICES`` with ``TEST_DISTRACTORS``, voices and sentences it never
saw. A distractor is conversation a person in the chair might have; each shares at least
one word with a command, and none is a command.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from abcwc.perception.speech.audio import SAMPLE_RATE, mix_at_snr, to_int16, with_noise_floor
from abcwc.perception.speech.commands import THESIS_SINGLE_WORDS, CommandSet
from abcwc.perception.speech.recognizer import CommandRecognizer, Recognition, Verification
from abcwc.perception.speech.synthesis import Voice, padded, speak

TUNING_DISTRACTORS = (
    "I left my keys on the table", "turn the radio down please", "stop worrying about it",
    "we should drive to the coast", "follow the signs to the station",
    "the office is on the right", "I will reverse the decision",
    "look forward to seeing you", "go to bed early", "where is the exit",
    "right now I am busy", "turn around and wave", "the cafeteria is closed today",
    "drive safely tonight", "is the lift working", "left or right", "meet me at the library",
    "the store opens at nine", "can you help me", "it is getting late",
)
TEST_DISTRACTORS = (
    "she turned right at the lights", "please stop talking", "go forward with the plan",
    "the library is quiet", "I am going to the meeting", "follow the doctor",
    "reverse the car into the space", "we left early", "drive me home later",
    "turn it off", "the lab is upstairs", "which way to the reading room",
    "that is right", "the bus will stop here", "tell me about your day",
    "the corridor is long", "what time is lunch", "put it on my left",
    "the lift is out of order", "go to sleep",
)
ENROLLMENT_SENTENCES = (
    "the quick brown fox jumps over the lazy dog", "she sells sea shells by the sea shore",
    "a large red book lay open on the kitchen table",
    "we watched the boats sail past the harbor wall",
    "my brother plays the guitar every thursday evening",
    "the children laughed at the funny clown", "please put the cups and plates in the cupboard",
    "the weather will be warm and sunny tomorrow",
    "he drove his old van along the narrow country road",
    "an orange cat slept quietly under the chair",
    "they built a small wooden bridge across the stream",
    "our teacher showed us pictures of the moon",
    "the farmer sold fresh eggs and milk at the market",
    "a cold wind blew through the empty streets", "she wrote a long letter to her grandmother",
    "the train was late because of the snow",
    "good food and good friends make a happy evening",
    "the doctor asked him to breathe slowly", "two young birds were singing in the garden",
    "the museum opens early on saturday morning",
    "he could hear the waves crashing on the rocks",
    "the shop sells shoes hats and warm jackets",
    "my neighbour grows tomatoes beans and peppers",
    "the pilot checked the engine before the flight",
)
"""What a speaker reads to enroll (``adaptation.enroll``): ordinary sentences covering
the phones of English, none a command or a distractor."""
FLOOR_PLACES = ("office_a", "lab", "store", "cafeteria", "lift", "meeting", "library",
                "reading", "corridor_east")


@dataclass(frozen=True)
class Trial:
    """One utterance through the recogniser: what was said, whether it is a command,
    the voice and noise, and what was heard."""

    text: str
    is_command: bool
    voice: Voice
    snr_db: float | None
    heard: Recognition
    audio_seconds: float

    @property
    def correct(self) -> bool:
        """A command recognised as itself, or a distractor refused."""
        if self.is_command:
            return self.heard.accepted and self.heard.command.phrase == self.text
        return not self.heard.accepted


def utterance(text: str, voice: Voice, snr_db: float | None = None, seed: int = 0
              ) -> np.ndarray:
    """``text`` in ``voice`` as int16 audio at 16 kHz, padded with 0.3 s each side, with
    white noise at ``snr_db`` (None: a quiet room's noise floor)."""
    x = padded(speak(text, voice))
    x = with_noise_floor(x, seed=seed) if snr_db is None else mix_at_snr(x, snr_db, seed)
    return to_int16(x)


def run_trials(recognizer: CommandRecognizer, commands: list[str], distractors: list[str],
               voices: tuple[Voice, ...], snr_db: float | None = None, seed: int = 0,
               progress: bool = False) -> list[Trial]:
    """Every command and distractor in every voice, at one noise level."""
    from tqdm.auto import tqdm

    jobs = [(t, True) for t in commands] + [(t, False) for t in distractors]
    jobs = [(t, c, v) for v in voices for t, c in jobs]
    trials = []
    for k, (text, is_command, voice) in enumerate(tqdm(jobs, disable=not progress,
                                                       desc=f"SNR {snr_db or 'quiet'}")):
        audio = utterance(text, voice, snr_db, seed + k)
        trials.append(Trial(text, is_command, voice, snr_db, recognizer.recognise(audio),
                            audio.size / SAMPLE_RATE))
    return trials


def judged_again(trials: list[Trial], recognizer: CommandRecognizer,
                 verification: Verification) -> list[Trial]:
    """``trials`` judged with other thresholds, without decoding again (record them
    with ``Verification.none()`` to judge them any way)."""
    return [replace(t, heard=recognizer.judged(t.heard, verification)) for t in trials]


@dataclass(frozen=True)
class Rates:
    """Commands recognised (fraction of commands), false activations (fraction of
    distractors taken for a command), decoding speed (audio seconds per second)."""

    recognised: float
    false_activations: float
    times_real_time: float
    commands: int
    distractors: int


def rates(trials: list[Trial]) -> Rates:
    """The figures of a list of trials."""
    commands = [t for t in trials if t.is_command]
    distractors = [t for t in trials if not t.is_command]
    decode = sum(t.heard.seconds for t in trials)
    audio = sum(t.audio_seconds for t in trials)
    return Rates(float(np.mean([t.correct for t in commands])) if commands else float("nan"),
                 float(np.mean([not t.correct for t in distractors])) if distractors
                 else float("nan"),
                 audio / decode if decode > 0 else float("nan"), len(commands),
                 len(distractors))


def enrollment_readings(voice: Voice, seed: int = 900) -> list[tuple[np.ndarray, str]]:
    """``ENROLLMENT_SENTENCES`` read by ``voice`` in a quiet room: (audio, text) pairs."""
    return [(utterance(text, voice, None, seed + k), text)
            for k, text in enumerate(ENROLLMENT_SENTENCES)]


def floor_commands() -> CommandSet:
    """The house command set with the floor world's places."""
    return CommandSet(FLOOR_PLACES)


def single_word_commands() -> CommandSet:
    """The thesis's first command set: forward, reverse, left, right, stop."""
    return CommandSet.from_phrases(THESIS_SINGLE_WORDS)
