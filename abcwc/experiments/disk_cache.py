"""Keep a slow, seeded computation's result on disk, keyed by the code that made it.

A seeded drive of the simulator gives the same result every time the same code runs it
with the same arguments, so a notebook run again (or its student copy, run beside it)
need not drive again. :func:`cached_on_disk` wraps such a function: a call looks for a
file named by a hash of

* the function's own source and the values of the plain constants it reads from its
  module (numbers, strings, booleans and tuples of them: a notebook's ``STILL = 2.0``);
* the call's arguments (their ``repr``), each bound to its parameter's name with the
  defaults filled in, so ``f(0, 60.0)`` and ``f(seed=0, seconds=60.0)`` share a result;
* every ``.py`` file of the ``abcwc`` package and every file of its ``data`` folder
  (a change anywhere below makes new keys);
* the BLAS kernels OpenBLAS is told to use (``OPENBLAS_CORETYPE``, which the test
  suite's kernels set: :data:`abcwc.nbval_plugin.BLAS_KERNELS`): kernels sum in their
  own orders, and a drive whose decisions follow the last bits (SLAM's loop closures)
  comes out otherwise under others;

and returns what the file holds, or calls the function and writes its result there
(pickled, written to a temporary file and renamed, so a reader never sees half a file).
Two processes asking for the same key at once take turns on a lock file (one beside
each result): the second reads what the first wrote. The folder is
``$ABCWC_CACHE_DIR``, else ``$XDG_CACHE_HOME/abcwc``, else ``~/.cache/abcwc``; where it
cannot be written, or where an argument has no ``repr`` of its own (``<... object at
0x...>``, a detector handed in, say: no later call could name it), the function simply
runs; delete the folder to free its space
(chapter 10's drives take about 11 MB and chapter 14's survey 17 MB for each version of
the code). Only deterministic functions belong here: every random source seeded by the
arguments or the constants.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import inspect
import os
import pickle
import re
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import abcwc
from abcwc.paths import NotACheckoutError, cache_folder, data_dir, write_whole

Result = TypeVar("Result")

_PLAIN = (bool, int, float, str, type(None))
_AT_AN_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+>")
"""Python's default ``repr`` of an object, ``<module.Class object at 0x7f...>``."""


@functools.lru_cache(maxsize=1)
def package_fingerprint() -> str:
    """A hash of the ``abcwc`` package's ``.py`` files and its data folder's files."""
    digest = hashlib.sha256()
    folders = [Path(abcwc.__file__).parent]
    try:
        folders.append(data_dir())
    except NotACheckoutError:  # an installed package without a checkout: its code alone
        pass
    for folder in folders:
        pattern = "*.py" if folder == folders[0] else "*"
        for path in sorted(p for p in folder.rglob(pattern) if p.is_file()):
            digest.update(str(path.relative_to(folder)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _plain(value: object) -> bool:
    if isinstance(value, tuple):
        return all(_plain(item) for item in value)
    return isinstance(value, _PLAIN)


def call_key(function: Callable, args: tuple, kwargs: dict) -> str | None:
    """The hash a call of ``function`` is kept under (module notes); None where an
    argument's ``repr`` names a memory address (an object with no repr of its own, such
    as a detector handed in): such a call would never be met again, so it is not kept."""
    code = function.__code__
    constants = {name: function.__globals__[name] for name in sorted(code.co_names)
                 if name in function.__globals__ and _plain(function.__globals__[name])}
    try:
        source = inspect.getsource(function)
    except (OSError, TypeError):  # no source file to read: the compiled code instead
        source = repr((code.co_code, code.co_consts))
    try:
        bound = inspect.signature(function).bind(*args, **kwargs)
    except TypeError as wrong:  # the call itself is wrong: say so, as the function would
        raise TypeError(f"{function.__qualname__}(): {wrong}") from None
    bound.apply_defaults()
    arguments = repr(list(bound.arguments.items()))
    if _AT_AN_ADDRESS.search(arguments):
        return None
    parts = [function.__qualname__, source, repr(constants),
             arguments, package_fingerprint(),
             f"OPENBLAS_CORETYPE={os.environ.get('OPENBLAS_CORETYPE')}"]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:32]


def cached_on_disk(function: Callable[..., Result]) -> Callable[..., Result]:
    """``function`` with its results kept on disk (module notes)."""

    @functools.wraps(function)
    def cached(*args: object, **kwargs: object) -> Result:
        key = call_key(function, args, kwargs)
        if key is None:  # an argument with no repr of its own: nothing to key it by
            return function(*args, **kwargs)
        folder = cache_folder()
        path = folder / f"{function.__name__}-{key}.pickle"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            lock = open(path.with_suffix(".lock"), "a")  # noqa: SIM115
        except OSError:  # nowhere to keep it: just run
            return function(*args, **kwargs)
        with lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # one process computes, the others wait
            if path.exists():
                with open(path, "rb") as kept:
                    return pickle.load(kept)
            result = function(*args, **kwargs)
            write_whole(path, pickle.dumps(result))
            return result

    return cached


__all__ = ["cache_folder", "cached_on_disk", "call_key", "package_fingerprint"]
