"""The acoustic model and pronunciation dictionary that ship in pocketsphinx's wheel, and
decoding one whole utterance: what the recogniser and speaker adaptation share."""

from __future__ import annotations


def model_paths() -> tuple[str, str]:
    """(acoustic model folder, pronunciation dictionary) of pocketsphinx's en-us model."""
    from pocketsphinx import get_model_path

    model = get_model_path()
    return f"{model}/en-us/en-us", f"{model}/en-us/cmudict-en-us.dict"


def decoded(decoder: object, pcm: bytes) -> object:
    """``decoder`` after decoding ``pcm`` (16-bit samples at its rate) as one whole
    utterance, its hypothesis, segments or alignment ready to read. pocketsphinx raises
    ``RuntimeError`` when its search cannot reach the end (an alignment whose text does
    not fit the sound)."""
    decoder.start_utt()
    decoder.process_raw(pcm, full_utt=True)
    decoder.end_utt()
    return decoder
