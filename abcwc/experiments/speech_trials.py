"""How well the chair hears its commands: synthetic speakers saying the commands and
sentences that share their words, at several noise levels, through the recogniser.

Two sets, split by speaker (``synthesis.TUNING_SPEAKERS`` and ``HELD_OUT_SPEAKERS``) and
by sentence: the recogniser's thresholds were chosen on ``synthesis.TUNING_VOICES``
(with the espeak-ng ``ESPEAK_TUNING_VOICES``) and ``TUNING_DISTRACTORS``, and are
reported on ``synthesis.HELD_OUT_VOICES`` (and the espeak-ng ``ESPEAK_STRESS_VOICES``)
with ``HELD_OUT_DISTRACTORS``, speakers and sentences no threshold saw. A distractor is
conversation a person in the chair might have; each shares at least one word with a
command, many hold a whole command inside a longer sentence, and none is a command.

Each utterance is cut with a pause of 0.15-0.6 s before and after it (seeded), as a
push-to-talk button or a voice-activity detector would cut it, and heard in a quiet
room (``with_noise_floor``) or in room noise (``audio.room_noise``) at an SNR.
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
    "we will go to the lab after lunch", "can you stop here for a moment",
    "I need to turn right at the end", "she said follow me to the office",
    "you should go to the store first", "then turn left by the window",
    "my sister had to drive forward into the snow", "nobody wants to go to the office today",
)
HELD_OUT_DISTRACTORS = (
    "she turned right at the lights", "please stop talking", "go forward with the plan",
    "the library is quiet", "I am going to the meeting later", "follow the doctor",
    "reverse the car into the space", "we left early", "drive me home later",
    "turn it off", "the lab is upstairs", "which way to the reading room",
    "that is right", "the bus will stop here", "tell me about your day",
    "the corridor is long", "what time is lunch", "put it on my left",
    "the lift is out of order", "go to sleep",
    "could you turn left at the corner", "we could go to the cafeteria tomorrow",
    "he told me to stop at the desk", "I think we turn right after the lift",
    "they want to go to the library on friday", "the children follow me everywhere",
    "let us go to the lab together", "do not drive forward yet",
    "I forgot to go to the store", "why did you turn left there",
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


def utterance(text: str, voice: Voice, snr_db: float | None = None, seed: int = 0,
              pause: float | None = None) -> np.ndarray:
    """``text`` in ``voice`` as int16 audio at 16 kHz, with ``pause`` seconds of silence
    each side (None: 0.3 s), in a quiet room (``snr_db`` None) or in room noise at
    ``snr_db``."""
    x = padded(speak(text, voice), 0.3 if pause is None else pause)
    if snr_db is None:
        return to_int16(with_noise_floor(x, seed=seed))
    return to_int16(mix_at_snr(x, snr_db, seed, noise="room"))


def seeded_pause(seed: int) -> float:
    """A pause of 0.15-0.6 s around an utterance, drawn from ``seed``."""
    return float(np.random.default_rng(seed).uniform(0.15, 0.6))


def run_trials(recognizer: CommandRecognizer, commands: list[str], distractors: list[str],
               voices: tuple[Voice, ...], snr_db: float | None = None, seed: int = 0,
               progress: bool = False) -> list[Trial]:
    """Every command and distractor in every voice, at one noise level, each with its
    own seeded pause (``seeded_pause``) and noise."""
    from tqdm.auto import tqdm

    jobs = [(t, True) for t in commands] + [(t, False) for t in distractors]
    jobs = [(t, c, v) for v in voices for t, c in jobs]
    trials = []
    for k, (text, is_command, voice) in enumerate(tqdm(jobs, disable=not progress,
                                                       desc=f"SNR {snr_db or 'quiet'}")):
        audio = utterance(text, voice, snr_db, seed + k, seeded_pause(seed + k))
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


MEAN_GRID = tuple(np.arange(-8.0, -3.99, 0.25))
WEAKEST_GRID = tuple(np.arange(-14.0, -4.99, 0.5))
SINGLE_GRID = tuple(np.arange(-8.0, -3.99, 0.25))
OUTSIDE_GRID = (0.1, 0.15, 0.2, 0.3)


def tuned_verification(trials: list[Trial], recognizer: CommandRecognizer,
                       max_false_activations: float = 0.0) -> tuple[Verification, Rates]:
    """The thresholds that recognise the most commands of ``trials`` (decoded by
    ``recognizer`` with ``Verification.none()``) while taking at most
    ``max_false_activations`` of its distractors for commands (none by default: the
    held-out speakers are allowed 2 %, and voices never heard need the margin); where
    several tie, the strictest (the highest sum of the three ratio thresholds, then the
    smallest ``max_outside_speech``). Every combination of ``MEAN_GRID``,
    ``WEAKEST_GRID``, ``SINGLE_GRID`` and ``OUTSIDE_GRID`` is tried. Returns the
    thresholds and their rates on ``trials``."""
    heard = [t.heard for t in trials]
    if not any(t.is_command for t in trials) or all(t.is_command for t in trials):
        raise ValueError("tuning needs both commands and distractors among the trials")
    right = np.array([bool(h.word_llrs) and (not t.is_command or h.phrase == t.text)
                      for t, h in zip(trials, heard)])
    is_command = np.array([t.is_command for t in trials])
    single = np.array([len(h.word_llrs) == 1 for h in heard])
    mean = np.array([h.mean_llr for h in heard])
    weakest = np.array([h.weakest_llr for h in heard])
    outside = np.array([h.outside_speech for h in heard])
    best: tuple[float, tuple[float, ...], Verification] | None = None
    for o in OUTSIDE_GRID:
        inside = right & (outside <= o)
        for m in MEAN_GRID:
            for w in WEAKEST_GRID:
                several = ~single & (mean >= m) & (weakest >= w)
                for s in SINGLE_GRID:
                    accepted = inside & (several | (single & (weakest >= s)))
                    false = accepted[~is_command].mean()
                    if false > max_false_activations:
                        continue
                    score = (accepted[is_command].mean(), (m + w + s, -o))
                    if best is None or score > best[:2]:
                        best = (*score, Verification(float(m), float(w), float(s), o))
    if best is None:
        raise ValueError("no thresholds of the grid keep the false activations at "
                         f"{100 * max_false_activations:.1f} % or below")
    chosen = best[2]
    return chosen, rates(judged_again(trials, recognizer, chosen))



def figures_by_engine(trials: list[Trial], label: str) -> dict[str, float]:
    """``rates`` of ``trials`` for each engine and all together, as named figures:
    "<label> <engine>: recognised (%)", "... false activations (%)", "... x real time"."""
    engines = sorted({t.voice.engine for t in trials})
    groups = {engine: [t for t in trials if t.voice.engine == engine] for engine in engines}
    if len(engines) > 1:
        groups["all"] = trials
    figures = {}
    for name, group in groups.items():
        found = rates(group)
        figures[f"{label} {name}: recognised (%)"] = 100 * found.recognised
        figures[f"{label} {name}: false activations (%)"] = 100 * found.false_activations
        figures[f"{label} {name}: x real time"] = found.times_real_time
    return figures


def spotting_false_activations(phrases: list[str], distractors: list[str],
                               voices: tuple[Voice, ...]) -> float:
    """The fraction of ``distractors`` read by ``voices`` on which a keyword spotter of
    ``phrases`` fires: the command may be anywhere in the utterance, as the thesis's
    BitVoicer listened (``Verification(max_outside_speech=1.0)``)."""
    listener = CommandRecognizer(CommandSet.from_phrases(phrases),
                                 replace(Verification(), max_outside_speech=1.0))
    return rates(run_trials(listener, [], distractors, voices)).false_activations


def speech_figures(progress: bool = False) -> dict[str, float]:
    """The full measurement (``abcwc bench speech``): the library's thresholds on the
    held-out speakers, per engine and together, and on the espeak-ng stress voices,
    quiet and in room noise at 20 and 10 dB SNR; the held-out speakers with each voice
    enrolled first (24 sentences read at its own rate and pitch); and the thesis's
    comparison, single words against two-word commands, spotted in the held-out
    sentences."""
    from abcwc.perception.speech.adaptation import enroll
    from abcwc.perception.speech.synthesis import ESPEAK_STRESS_VOICES, HELD_OUT_VOICES

    commands = floor_commands()
    recogniser = CommandRecognizer(commands)
    figures: dict[str, float] = {}
    for snr in (None, 20.0, 10.0):
        label = "quiet" if snr is None else f"{snr:.0f} dB"
        for voices in (HELD_OUT_VOICES, ESPEAK_STRESS_VOICES):
            figures |= figures_by_engine(
                run_trials(recogniser, commands.phrases, list(HELD_OUT_DISTRACTORS), voices,
                           snr, seed=0, progress=progress), label)
    enrolled = []
    for own in [v for v in HELD_OUT_VOICES if v.rate == 1.0 and v.pitch == 0.0]:
        speaker = CommandRecognizer(commands, adaptation=enroll(enrollment_readings(own)))
        renditions = tuple(v for v in HELD_OUT_VOICES
                           if (v.engine, v.name) == (own.engine, own.name))
        enrolled += run_trials(speaker, commands.phrases, list(HELD_OUT_DISTRACTORS),
                               renditions, seed=0, progress=progress)
    figures |= figures_by_engine(enrolled, "enrolled, quiet")
    pairs = {"single words": list(THESIS_SINGLE_WORDS[:4]),
             "two-word commands": ["drive forward", "drive reverse", "turn left",
                                   "turn right"]}
    for name, phrases in pairs.items():
        figures[f"spotting {name}: false activations (%)"] = 100 * spotting_false_activations(
            phrases, list(HELD_OUT_DISTRACTORS), HELD_OUT_VOICES)
    return figures
