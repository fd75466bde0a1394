"""The README's layers: estimation, mapping and perception import nothing from the layers
above them."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "abcwc"
ABOVE_ESTIMATION_AND_MAPPING = (
    "abcwc.sim", "abcwc.base", "abcwc.connect", "abcwc.behaviours", "abcwc.experiments",
    "abcwc.navigation", "abcwc.hw", "abcwc.viz", "abcwc.checks", "abcwc.teleop", "abcwc.cli",
    "abcwc.bench", "abcwc.course", "abcwc.control")


def imported_modules(path: Path) -> list[str]:
    """Every module an ``import`` or ``from ... import`` in ``path`` names."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.append(node.module or "")
    return names


@pytest.mark.parametrize("layer", ["estimation", "mapping", "perception"])
def test_a_lower_layer_imports_nothing_above_it(layer):
    """Estimators and mappers turn frames, scans and logs into estimates and maps: they
    depend on messages, geometry, logs and parameters only, never on a body, a behaviour
    or the presentation."""
    files = sorted((PACKAGE / layer).glob("*.py"))
    assert files
    offending = [f"{path.name}: {name}" for path in files for name in imported_modules(path)
                 if name.startswith(ABOVE_ESTIMATION_AND_MAPPING)]
    assert not offending, offending


def test_the_check_finds_an_upward_import(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import math\nfrom abcwc.sim.base import SimBase\n")
    assert "abcwc.sim.base" in imported_modules(bad)
