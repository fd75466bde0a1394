"""Speaker adaptation (MLLR of the acoustic model's means): the estimator against a
transform it must recover, the features against a closed form, pocketsphinx reading the
transform, and enrollment on an espeak-ng voice."""

import numpy as np
import pytest

from abcwc.perception.speech.adaptation import (
    NOT_SPEECH,
    MeanTransform,
    estimate_mean_transform,
    model_gaussians,
    sphinx_features,
)
from tests.test_speech import _need_speech_tools, say


def test_features_are_the_decoders_normalised_cepstra_and_their_deltas():
    """A ramp c[t] = t v: less its mean; deltas c[t+2] - c[t-2] = 4 v inside; double
    deltas (c[t+3] - c[t-1]) - (c[t+1] - c[t-3]) = 0 inside; the ends repeat."""
    v = np.arange(1.0, 14.0)
    cepstra = np.arange(10.0)[:, None] * v
    features = sphinx_features(cepstra)
    assert features.shape == (10, 3, 13)
    np.testing.assert_allclose(features[:, 0], cepstra - 4.5 * v)
    np.testing.assert_allclose(features[2:8, 1], np.tile(4 * v, (6, 1)))
    np.testing.assert_allclose(features[3:7, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(features[0, 1], 2 * v)        # c[2] - c[0] at the start


def test_mllr_recovers_a_known_transform_of_the_models_gaussians():
    """Frames drawn from the model's own codebooks (equal weights, their variances)
    after a known affine map of the means: a few passes of the estimator move every
    mean to within a tenth of a standard deviation (95th percentile) of where the map
    puts it, where the map moved them by up to two. (The map itself is not unique where
    a codebook's means barely vary, so its means, not A and b, are compared.)"""
    _need_speech_tools()
    means, variances, phones = model_gaussians()
    rng = np.random.default_rng(3)
    books = [i for i, p in enumerate(phones) if p not in NOT_SPEECH]
    spread = np.sqrt(variances.mean(axis=(0, 2)))                  # (3, 13)
    truth = MeanTransform(np.eye(13) + 0.05 * rng.normal(size=(3, 13, 13)),
                          spread * rng.normal(size=(3, 13)), 0)
    segments = []
    for book in books:
        chosen = rng.integers(0, 128, 400)
        mu = means[book][:, chosen]                                # (3, n, 13)
        moved = np.einsum("fij,fnj->nfi", truth.A, mu) + truth.b[None]
        noise = np.sqrt(variances[book][:, chosen]).transpose(1, 0, 2)
        segments.append((book, moved + noise * rng.normal(size=moved.shape)))
    estimate = None
    for _ in range(6):
        estimate = estimate_mean_transform(segments, means, variances, estimate, top=128)

    def moved_means(t):
        return np.einsum("fij,bfmj->bfmi", t.A, means[books]) + t.b[None, :, None, :]

    sd = np.sqrt(variances[books])
    shift = np.abs(moved_means(truth) - means[books]) / sd
    error = np.abs(moved_means(estimate) - moved_means(truth)) / sd
    assert np.percentile(shift, 95) > 1.5
    assert np.percentile(error, 95) < 0.1
    assert estimate.frames == 400 * len(books)


def test_pocketsphinx_reads_the_transform():
    """The identity changes no score; a transform that moves every mean far off makes
    the same words fit much worse."""
    _need_speech_tools()
    from abcwc.experiments.speech_trials import floor_commands
    from abcwc.perception.speech.recognizer import CommandRecognizer, Verification

    commands, loose = floor_commands(), Verification.none()
    audio = say("turn left", "en-us+f4")
    plain = CommandRecognizer(commands, loose).recognise(audio)
    same = CommandRecognizer(commands, loose, adaptation=MeanTransform.identity())
    assert same.recognise(audio).word_llrs == plain.word_llrs
    off = MeanTransform.identity()
    off = MeanTransform(off.A, off.b + 3.0 * np.sqrt(model_gaussians()[1].mean(axis=(0, 2))), 0)
    moved = CommandRecognizer(commands, loose, adaptation=off).recognise(audio)
    assert moved.mean_llr < plain.mean_llr - 1.0


def test_enrolling_a_voice_makes_its_commands_fit_better():
    """24 read sentences of a voice the thresholds never saw (espeak-ng's en-us+f4, a
    stress voice): its commands' words then score higher against the best state in each
    frame."""
    _need_speech_tools()
    from abcwc.experiments.speech_trials import enrollment_readings, floor_commands, utterance
    from abcwc.perception.speech.adaptation import enroll
    from abcwc.perception.speech.recognizer import CommandRecognizer, Verification
    from abcwc.perception.speech.synthesis import ESPEAK_STRESS_VOICES

    voice = ESPEAK_STRESS_VOICES[1]
    assert voice.name == "en-us+f4"
    speaker = enroll(enrollment_readings(voice))
    assert speaker.frames > 2000
    commands = floor_commands()
    plain = CommandRecognizer(commands, Verification.none())
    adapted = CommandRecognizer(commands, Verification.none(), adaptation=speaker)
    gains = []
    for phrase in ("drive forward", "turn right", "go to the library", "go to the store"):
        audio = utterance(phrase, voice)
        before, after = plain.recognise(audio), adapted.recognise(audio)
        assert after.phrase == phrase
        gains.append(after.mean_llr - before.mean_llr)
    assert np.mean(gains) > 0.3


def test_bad_enrollment_is_refused():
    _need_speech_tools()
    from abcwc.experiments.speech_trials import floor_commands
    from abcwc.perception.speech.adaptation import enroll
    from abcwc.perception.speech.recognizer import CommandRecognizer

    with pytest.raises(ValueError, match="needs sentences"):
        enroll([])
    with pytest.raises(ValueError, match="not in the pronunciation dictionary: zxqvw"):
        enroll([(say("hello there"), "hello zxqvw")])
    with pytest.raises(ValueError, match="must be a MeanTransform"):
        CommandRecognizer(floor_commands(), adaptation=np.eye(13))
