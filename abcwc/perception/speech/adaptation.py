"""Adapting the acoustic model to one speaker: maximum-likelihood linear regression of
its Gaussian means (MLLR; Leggetter and Woodland, "Maximum likelihood linear regression
for speaker adaptation of continuous density hidden Markov models", Computer Speech and
Language 9, 1995) from a few sentences the speaker reads.

The en-us model is phonetically tied: each of its 42 base phones has one codebook of
128 Gaussians per feature stream (cepstra, their deltas and double deltas, 13 numbers
each), shared by all the states of that phone. One affine map per stream moves every
mean, ``mu' = A mu + b``. Given frames ``o_t`` aligned to phones, and each frame's
posterior ``gamma_m(t)`` over its phone's Gaussians, row ``i`` of ``W = [A b]``
maximises the likelihood in closed form (Leggetter and Woodland, eqns 10-12, diagonal
covariances):

    G_i = sum_t sum_m gamma_m(t) / sigma_mi^2 * xi_m xi_m^T,   xi_m = [mu_m; 1]
    k_i = sum_t sum_m gamma_m(t) * o_ti / sigma_mi^2 * xi_m
    w_i = G_i^-1 k_i

pocketsphinx applies the result when the decoder is given it as an ``-mllr`` file
(``MeanTransform.write``). The frames come from pocketsphinx itself: its aligner
places the read sentence's phones, and its feature log gives the cepstra, to which the
model's batch mean normalisation and deltas (``1s_c_d_dd``) are applied here as the
decoder applies them. Two passes: the second aligns with the first pass's transform.
"""

from __future__ import annotations

import glob
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from abcwc.perception.speech.audio import SAMPLE_RATE, for_decoding, to_int16
from abcwc.perception.speech.model import decoded, model_paths

STREAMS, DIMENSIONS, GAUSSIANS = 3, 13, 128
VARIANCE_FLOOR = 1.0e-4       # pocketsphinx's -varfloor
NOT_SPEECH = ("SIL", "+NSN+", "+SPN+")


@dataclass(frozen=True)
class MeanTransform:
    """One affine map of the Gaussian means per feature stream: ``A`` (3, 13, 13) and
    ``b`` (3, 13), estimated from ``frames`` aligned speech frames (10 ms each)."""

    A: np.ndarray
    b: np.ndarray
    frames: int

    @classmethod
    def identity(cls) -> MeanTransform:
        """The transform that changes nothing."""
        return cls(np.tile(np.eye(DIMENSIONS), (STREAMS, 1, 1)),
                   np.zeros((STREAMS, DIMENSIONS)), 0)

    def write(self, path: str) -> None:
        """``path`` as pocketsphinx's ``-mllr`` file: one class, three streams, each its
        A rows, b and (unchanged) variance scales."""
        lines = ["1", str(STREAMS)]
        for f in range(STREAMS):
            lines.append(str(DIMENSIONS))
            lines += [" ".join(f"{v:.7g}" for v in row) for row in self.A[f]]
            lines.append(" ".join(f"{v:.7g}" for v in self.b[f]))
            lines.append(" ".join(["1.0"] * DIMENSIONS))
        with open(path, "w") as out:
            out.write("\n".join(lines) + "\n")


def _read_gaussian_file(path: str) -> np.ndarray:
    """A SphinxTrain s3 parameter file (means or variances) as (codebooks, streams,
    Gaussians, 13)."""
    with open(path, "rb") as file:
        data = file.read()
    start = data.index(b"endhdr\n") + len(b"endhdr\n")
    if int(np.frombuffer(data[start:start + 4], "<u4")[0]) != 0x11223344:
        raise ValueError(f"{path}: not a little-endian s3 parameter file")
    books, streams, gaussians = (int(v) for v in np.frombuffer(data[start + 4:start + 16],
                                                               "<i4"))
    lengths = np.frombuffer(data[start + 16:start + 16 + 4 * streams], "<i4")
    at = start + 16 + 4 * streams
    count = int(np.frombuffer(data[at:at + 4], "<i4")[0])
    values = np.frombuffer(data[at + 4:at + 4 + 4 * count], "<f4")
    return values.reshape(books, streams, gaussians, int(lengths[0])).astype(float)


@lru_cache(maxsize=1)
def model_gaussians() -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """The en-us model's means and (floored) variances, (42, 3, 128, 13) each, and its
    base phones in codebook order."""
    model, _ = model_paths()
    means = _read_gaussian_file(f"{model}/means")
    variances = np.maximum(_read_gaussian_file(f"{model}/variances"), VARIANCE_FLOOR)
    return means, variances, _base_phones(f"{model}/mdef")


def _base_phones(mdef: str) -> tuple[str, ...]:
    """The base phone names of a binary model definition, in their order."""
    with open(mdef, "rb") as file:
        data = file.read()
    at = data.index(b"END FILE FORMAT DESCRIPTION\n") + len(b"END FILE FORMAT DESCRIPTION\n")
    at = (at + 3) // 4 * 4
    count = int(np.frombuffer(data[at:at + 4], "<i4")[0])
    at += 40  # the header's ten numbers
    names = []
    for _ in range(count):
        end = data.index(b"\0", at)
        names.append(data[at:end].decode())
        at = end + 1
    return tuple(names)


def sphinx_features(cepstra: np.ndarray) -> np.ndarray:
    """(T, 13) cepstra as the decoder sees them, (T, 3, 13): less their mean over the
    utterance (batch normalisation), then deltas ``c[t+2] - c[t-2]`` and double deltas
    ``(c[t+3] - c[t-1]) - (c[t+1] - c[t-3])``, the ends repeated (``1s_c_d_dd``)."""
    c = np.asarray(cepstra, dtype=float)
    c = c - c.mean(axis=0)
    p = np.pad(c, ((3, 3), (0, 0)), mode="edge")
    n = len(c)
    delta = p[5:5 + n] - p[1:1 + n]
    double = (p[6:6 + n] - p[2:2 + n]) - (p[4:4 + n] - p[0:n])
    return np.stack([c, delta, double], axis=1)


def estimate_mean_transform(segments: Sequence[tuple[int, np.ndarray]],
                            means: np.ndarray, variances: np.ndarray,
                            prior: MeanTransform | None = None, top: int = 8
                            ) -> MeanTransform:
    """The MLLR mean transform (module notes) from ``segments``: (codebook, features
    (n, 3, 13)) for each aligned phone. Each frame's posterior is taken over its
    codebook's ``top`` likeliest Gaussians (equal weights), with the means moved by
    ``prior`` when given (a second pass)."""
    G = np.zeros((STREAMS, DIMENSIONS, DIMENSIONS + 1, DIMENSIONS + 1))
    K = np.zeros((STREAMS, DIMENSIONS, DIMENSIONS + 1))
    frames = 0
    for book, features in segments:
        frames += len(features)
        for f in range(STREAMS):
            mu, var = means[book, f], variances[book, f]          # (128, 13)
            near = mu if prior is None else mu @ prior.A[f].T + prior.b[f]
            o = features[:, f]                                     # (n, 13)
            loglik = -0.5 * ((((o[:, None] - near[None]) ** 2) / var[None]).sum(-1)
                             + np.log(var).sum(-1)[None])          # (n, 128)
            best = np.argsort(loglik, axis=1)[:, -top:]
            rows = np.arange(len(o))[:, None]
            chosen = loglik[rows, best]
            weights = np.exp(chosen - chosen.max(axis=1, keepdims=True))
            gamma = np.zeros_like(loglik)
            gamma[rows, best] = weights / weights.sum(axis=1, keepdims=True)
            xi = np.hstack([mu, np.ones((len(mu), 1))])            # (128, 14)
            occupancy = gamma.sum(axis=0)                          # (128,)
            weighted = occupancy[:, None] / var                    # (128, 13)
            G[f] += np.einsum("mi,mj,mk->ijk", weighted, xi, xi)
            K[f] += np.einsum("mi,mi,mk->ik", gamma.T @ o, 1.0 / var, xi)
    if frames == 0:
        raise ValueError("no speech frames to adapt from: the sentences could not be "
                         "aligned to their texts")
    W = np.linalg.solve(G + 1e-6 * np.eye(DIMENSIONS + 1), K[..., None])[..., 0]
    return MeanTransform(W[..., :DIMENSIONS], W[..., DIMENSIONS], frames)


def enroll(readings: Sequence[tuple[np.ndarray, str]], rate: int = SAMPLE_RATE,
           passes: int = 2) -> MeanTransform:
    """The speaker's mean transform from ``readings``: (audio, the text read) pairs
    (int16 or float audio at ``rate``; some 20 sentences of ordinary speech). A
    sentence the aligner cannot fit to its text is left out; raises ``ValueError``
    when none fit or a text holds a word the dictionary lacks."""
    from pocketsphinx import Decoder

    if not readings:
        raise ValueError("enroll needs sentences the speaker read: (audio, text) pairs")
    means, variances, phones = model_gaussians()
    model, dictionary = model_paths()
    checker = Decoder(hmm=model, dict=dictionary, lm=None, loglevel="FATAL")
    unknown = sorted({w for _, text in readings for w in text.lower().split()
                      if checker.lookup_word(w) is None})
    if unknown:
        raise ValueError(f"not in the pronunciation dictionary: {', '.join(unknown)}")
    pcms = [to_int16(for_decoding(audio, rate)).tobytes()
            for audio, _ in readings]
    transform = None
    with tempfile.TemporaryDirectory() as work:
        for k in range(passes):
            mllr = None
            if transform is not None:
                mllr = os.path.join(work, f"pass{k}.mllr")
                transform.write(mllr)
            segments = []
            for j, (pcm, (_, text)) in enumerate(zip(pcms, readings)):
                segments += _aligned_segments(pcm, text.lower(), os.path.join(work, f"{k}-{j}"),
                                              mllr, phones)
            transform = estimate_mean_transform(segments, means, variances, transform)
    return transform


def _aligned_segments(pcm: bytes, text: str, folder: str, mllr: str | None,
                      phones: tuple[str, ...]
                      ) -> list[tuple[int, np.ndarray]]:
    """(codebook, features) of each speech phone of ``text`` aligned to ``pcm``; none
    when the aligner cannot fit the text."""
    from pocketsphinx import Decoder

    os.makedirs(folder)
    extra = {"mllr": mllr} if mllr else {}
    model, dictionary = model_paths()
    aligner = Decoder(hmm=model, dict=dictionary, lm=None, samprate=SAMPLE_RATE,
                      mfclogdir=folder, loglevel="FATAL", **extra)
    aligner.set_align_text(text)
    try:
        decoded(aligner, pcm)        # the words' places
        aligner.set_alignment()
        decoded(aligner, pcm)        # then their phones' and states' within them
    except RuntimeError:             # the text cannot be fitted to the sound
        return []
    cepstra = np.fromfile(sorted(glob.glob(f"{folder}/*.mfc"))[-1], dtype=">f4", offset=4)
    features = sphinx_features(cepstra.reshape(-1, DIMENSIONS))
    return [(phones.index(p.name), features[p.start:p.start + p.duration])
            for word in aligner.get_alignment() for p in word
            if p.name in phones and p.name not in NOT_SPEECH]
