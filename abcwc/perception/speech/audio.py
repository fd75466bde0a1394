"""Audio buffers for the recogniser: checked, brought to 16 kHz mono 16-bit, and given
the low noise floor a real room has.

The acoustic model that ships with pocketsphinx was trained on 16 kHz speech, so every
buffer is resampled to ``SAMPLE_RATE`` with a polyphase filter
(``scipy.signal.resample_poly``: 22 050 Hz espeak-ng output becomes 16 000 Hz by
320/441). Synthetic speech comes wrapped in pure digital silence, which real rooms never
have: the decoder's feature normalisation (cepstral mean over the utterance) is thrown
off by it, so ``with_noise_floor`` adds white noise about 60 dB below full scale.

What the decoder hears is :func:`for_decoding`'s: the buffer checked and resampled, its
DC offset taken out (a microphone's, or a sound card's: a constant the energy of every
frame rides on, so that the quiet around a command no longer looks quiet; 0.1 of full
scale let 7.5 % of the held-out sentences through as commands, against 0.8 % without),
and the noise floor added at most ``FLOOR_BELOW_SPEECH_DB`` below the speech's loud
frames (:func:`speech_level`), so that a quiet talker, or a microphone far away, is not
buried in a hiss meant for digital silence (speech at -45 dBFS under a fixed -60 dBFS
floor is 15 dB SNR: half its commands were lost).

Audio taken below 16 kHz is accepted with a warning: it lacks the band above half its
rate that the model was trained with (at 8 kHz, a telephone's, the held-out speakers'
commands were recognised 74 % of the time, against 92 % at 16 kHz or more).

A buffer that cannot hold speech is refused with a message that says what is allowed:
empty, shorter than ``MIN_SECONDS``, longer than ``MAX_SECONDS``, not finite, silent,
or clipped on more than ``MAX_CLIPPED_FRACTION`` of its samples.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.signal import resample_poly

SAMPLE_RATE = 16_000          # Hz, what the acoustic model was trained on
MIN_RATE, MAX_RATE = 8_000, 96_000
MIN_SECONDS = 0.2             # shorter than the shortest command ("stop" is ~0.4 s)
MAX_SECONDS = 30.0            # one utterance, not a recording session
SILENT_RMS = 1.0e-4           # of full scale (-80 dBFS): nothing was heard
MAX_CLIPPED_FRACTION = 0.01   # of samples at full scale
NOISE_FLOOR = 1.0e-3          # RMS of full scale (-60 dBFS), a quiet room's hiss
FLOOR_BELOW_SPEECH_DB = 35.0  # dB the added floor stays below the speech (-60 dBFS is
                              # that below speech at -25 dBFS, a talker near the microphone)
FRAME_RATE = 100              # pocketsphinx's feature frames per second (10 ms each)


class AudioError(ValueError):
    """An audio buffer the recogniser cannot use; the message says what is allowed."""


INTEGER_FULL_SCALE = {np.dtype(np.int16): (0.0, 32768.0), np.dtype(np.int32): (0.0, 2.0 ** 31),
                      np.dtype(np.uint8): (128.0, 128.0)}
"""(zero, full scale) of the integer sample types WAV files hold: 16-bit, 24- or 32-bit
(read as int32, left-justified), and 8-bit (unsigned, silence at 128)."""
FLOAT_OVERSHOOT = 1.01
"""Float samples up to this peak are clipped to [-1, 1] (a resampler's ringing at full
scale); beyond it the buffer is not full-scale floats at all."""


def to_float_audio(samples: np.ndarray, rate: int) -> np.ndarray:
    """Check ``samples`` (mono: int16, int32 or uint8 as in WAV files, in either byte
    order; or float in [-1, 1]) taken at ``rate`` Hz, and return them as float64 in
    [-1, 1] at ``SAMPLE_RATE``.

    Raises ``AudioError`` for a buffer that is empty, multi-channel, of another dtype,
    at a rate outside 8-96 kHz, too short or too long, not finite, silent or clipped."""
    if samples is None or isinstance(samples, (bytes, bytearray, str)):
        raise AudioError(f"audio must be an array of samples (int16, int32, uint8, or float "
                         f"in [-1, 1]), got {type(samples).__name__}: decode a file's bytes "
                         f"first (for example with scipy.io.wavfile.read)")
    x = np.asarray(samples)
    if not x.dtype.isnative:
        x = x.astype(x.dtype.newbyteorder("="))
    if isinstance(rate, bool) or not isinstance(rate, (int, np.integer)):
        raise AudioError(f"rate must be an integer number of samples per second, got {rate!r}")
    if not MIN_RATE <= rate <= MAX_RATE:
        raise AudioError(f"rate {rate} Hz is outside {MIN_RATE}-{MAX_RATE} Hz; "
                         f"speech is usually recorded at 16000, 22050, 44100 or 48000 Hz")
    if x.ndim == 2 and 1 in x.shape:
        x = x.reshape(-1)
    if x.ndim != 1:
        raise AudioError(f"audio must be mono, one sample per entry; got shape {x.shape} "
                         f"(average the channels first)")
    if x.size == 0:
        raise AudioError("the audio buffer is empty")
    if x.dtype in INTEGER_FULL_SCALE:
        zero, full = INTEGER_FULL_SCALE[x.dtype]
        x = (x.astype(np.float64) - zero) / full
    elif np.issubdtype(x.dtype, np.floating):
        x = x.astype(np.float64)
        if not np.all(np.isfinite(x)):
            raise AudioError("audio holds NaN or infinite samples")
        peak = float(np.max(np.abs(x)))
        if peak > FLOAT_OVERSHOOT:
            raise AudioError(f"float audio must lie in [-1, 1] (full scale); its peak is "
                             f"{peak:.4g}: pass int16 samples, or divide by 32768")
        x = np.clip(x, -1.0, 1.0)
    else:
        raise AudioError(f"audio must be int16, int32 or uint8 (a WAV file's samples) or "
                         f"float in [-1, 1]; got {x.dtype}")
    seconds = x.size / rate
    if not MIN_SECONDS <= seconds <= MAX_SECONDS:
        raise AudioError(f"audio lasts {seconds:.3g} s; one command needs "
                         f"{MIN_SECONDS}-{MAX_SECONDS} s")
    rms = math.sqrt(float(np.mean(x * x)))
    if rms < SILENT_RMS:
        raise AudioError(f"the audio is silent (RMS {20 * math.log10(max(rms, 1e-12)):.0f} "
                         f"dBFS; anything above {20 * math.log10(SILENT_RMS):.0f} dBFS is "
                         f"heard): is the microphone muted?")
    clipped = float(np.mean(np.abs(x) >= 32767 / 32768))
    if clipped > MAX_CLIPPED_FRACTION:
        raise AudioError(f"{100 * clipped:.1f} % of the samples are at full scale (clipped; "
                         f"at most {100 * MAX_CLIPPED_FRACTION:.0f} % allowed): turn the "
                         f"microphone's gain down")
    if rate < SAMPLE_RATE:
        warnings.warn(f"audio at {rate} Hz has no sound above {rate // 2} Hz, which the "
                      f"{SAMPLE_RATE} Hz acoustic model was trained with: expect fewer "
                      f"commands recognised (74 % instead of 92 % at 8000 Hz)",
                      stacklevel=2)
    if rate != SAMPLE_RATE:
        g = math.gcd(SAMPLE_RATE, int(rate))
        x = resample_poly(x, SAMPLE_RATE // g, int(rate) // g)
    return x


def frame_powers(x: np.ndarray) -> np.ndarray:
    """The mean square (of full scale) of each whole 10 ms frame of ``x`` (float audio at
    16 kHz), the decoder's frames."""
    hop = SAMPLE_RATE // FRAME_RATE
    n = x.size // hop
    return np.mean(x[: n * hop].reshape(n, hop) ** 2, axis=1)


def speech_level(x: np.ndarray) -> float:
    """RMS (of full scale) of the loudest tenth of ``x``'s 10 ms frames (float audio at
    16 kHz; one frame of it all if shorter): the level of the speech in it, whatever
    silence or noise surrounds it (the idea of ITU-T P.56's active speech level, the loud
    frames standing for the active ones)."""
    powers = frame_powers(x) if x.size >= SAMPLE_RATE // FRAME_RATE else np.mean(x ** 2)
    return math.sqrt(float(np.percentile(powers, 90)))


def for_decoding(samples: np.ndarray, rate: int, seed: int = 0) -> np.ndarray:
    """What the decoder hears of ``samples`` at ``rate`` Hz (module notes): checked and
    at 16 kHz (:func:`to_float_audio`), without its DC offset (the mean taken out), and
    with the noise floor ``NOISE_FLOOR`` added, or ``FLOOR_BELOW_SPEECH_DB`` below the
    speech's level where that is quieter (seeded by ``seed``)."""
    x = to_float_audio(samples, rate)
    x = x - float(np.mean(x))
    floor = min(NOISE_FLOOR, speech_level(x) * 10 ** (-FLOOR_BELOW_SPEECH_DB / 20))
    return with_noise_floor(x, floor, seed)


def with_noise_floor(x: np.ndarray, rms: float = NOISE_FLOOR, seed: int = 0) -> np.ndarray:
    """``x`` (float, full scale 1) with seeded white noise of ``rms`` added: the hiss of a
    quiet room, which pure digital silence around synthetic speech lacks."""
    rng = np.random.default_rng(seed)
    return x + rng.normal(0.0, rms, x.size)


def room_noise(n: int, seed: int = 0) -> np.ndarray:
    """``n`` samples of seeded noise whose power falls 3 dB per octave (pink, 1/f, from
    20 Hz up), unit RMS: closer to a room's ventilation and motors than white noise."""
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.normal(0.0, 1.0, n))
    hz = np.fft.rfftfreq(n, 1.0 / SAMPLE_RATE)
    noise = np.fft.irfft(spectrum / np.sqrt(np.maximum(hz, 20.0)), n)
    return noise / math.sqrt(float(np.mean(noise ** 2)))


def mix_at_snr(speech: np.ndarray, snr_db: float, seed: int = 0,
               speech_mask: np.ndarray | None = None, noise: str = "white") -> np.ndarray:
    """``speech`` with seeded ``noise`` ("white", or "room": ``room_noise``) at ``snr_db``
    dB signal-to-noise ratio, the signal power measured where ``speech_mask`` is true
    (default: samples above 1 % of the peak, so that padding silence does not dilute
    it)."""
    if not math.isfinite(snr_db):
        raise ValueError(f"snr_db must be finite, got {snr_db}")
    if noise not in ("white", "room"):
        raise ValueError(f'noise must be "white" or "room", got {noise!r}')
    if speech_mask is None:
        speech_mask = np.abs(speech) > 0.01 * float(np.max(np.abs(speech)))
    power = float(np.mean(speech[speech_mask] ** 2))
    if noise == "room":
        unit = room_noise(speech.size, seed)
    else:
        unit = np.random.default_rng(seed).normal(0.0, 1.0, speech.size)
    return speech + math.sqrt(power / 10 ** (snr_db / 10)) * unit


def to_int16(x: np.ndarray) -> np.ndarray:
    """Float audio in [-1, 1] as int16 samples, clipped at full scale."""
    return np.clip(np.round(x * 32768.0), -32768, 32767).astype(np.int16)
