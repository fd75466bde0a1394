"""The Base interface and connect(): what every body offers, and who imports what."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

import abcwc
from abcwc.base import Base
from abcwc.params import ChairParams
from abcwc.sim.base import SimBase

ROOT = Path(__file__).resolve().parents[1]


def _modules_loaded_by(statement: str) -> list[str]:
    """The abcwc modules a fresh interpreter holds after ``statement``."""
    code = (f"{statement}\nimport sys\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('abcwc'))))")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, cwd=ROOT)
    return out.stdout.split()


def test_base_imports_no_body():
    loaded = _modules_loaded_by("import abcwc.base")
    assert "abcwc.base" in loaded
    bodies = [m for m in loaded if m.startswith(("abcwc.sim", "abcwc.hw"))]
    assert bodies == [], f"importing abcwc.base loaded {bodies}"


def test_base_names_no_body_even_inside_functions():
    """Not even a deferred import: abcwc.base sits below every body."""
    tree = ast.parse((ROOT / "abcwc" / "base.py").read_text())
    imported = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    imported += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    above = [m for m in imported if m and m.startswith(("abcwc.sim", "abcwc.hw", "abcwc.connect"))]
    assert above == [], above


def test_connect_loads_only_the_body_it_picks():
    loaded = _modules_loaded_by("import abcwc\nabcwc.connect(world='lab', people=False)")
    assert "abcwc.sim.base" in loaded
    assert not [m for m in loaded if m.startswith("abcwc.hw.")], loaded


def test_connect_names_at_package_level():
    from abcwc.connect import HARDWARE_CELL_CAP, PORT_ENV, SIMAVR_PORT, connect, hardware_chair

    assert abcwc.connect is connect and abcwc.hardware_chair is hardware_chair
    assert (abcwc.PORT_ENV, abcwc.SIMAVR_PORT) == (PORT_ENV, SIMAVR_PORT) == ("ABCWC_PORT",
                                                                              "simavr")
    assert abcwc.HARDWARE_CELL_CAP == HARDWARE_CELL_CAP == 20
    assert callable(abcwc.connect)


def test_the_simulator_is_a_base_with_params():
    params = abcwc.default_params()
    chair = SimBase(world="lab", people=False, params=params)
    assert isinstance(chair, Base)
    assert chair.params is params and isinstance(chair.params, ChairParams)
    assert chair.period == params.control_period


def test_a_body_without_params_is_not_a_base():
    """The protocol checks ``params``: a chair-like object without them is no Base."""

    class NoParams:
        period = 0.02

        def __getattr__(self, name):  # every method the protocol asks for, but no params
            if name == "params":
                raise AttributeError(name)
            return lambda *a, **k: None

    assert not isinstance(NoParams(), Base)


def test_run_until_ends_the_run_in_the_period_it_says_so():
    """``until`` is asked after every period; the run ends at the first True, and the
    log holds exactly the periods driven (the truth's clock agrees)."""
    from abcwc.sim import SimBase

    chair = SimBase("lab", seed=0)
    calls = []

    def until():
        calls.append(chair.t)
        return chair.t >= 1.0 - 1e-9

    log = chair.run(lambda frame: abcwc.Twist(0.3, 0.0), 10.0, until=until)
    assert len(log) == 50 == len(calls)
    assert abs(chair.t - 1.0) < 1e-9
    assert abs(log.t[-1] - chair.t) < 1e-9
    with pytest.raises(ValueError, match="until must be a function"):
        chair.run(lambda frame: None, 1.0, until=True)
