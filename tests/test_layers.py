"""README's layers hold: every module of abcwc sits in exactly one row of the Layout table,
and imports only from its own row and the rows above it.

The table is read from README.md itself (the ``| layer | modules | what it holds |`` table
under "## Layout"; each row's modules in backticks: ``name`` is the module
``abcwc/name.py``, ``name/`` the package ``abcwc/name/`` at any depth, ``name/sub`` one
module inside a package, and a module belongs to the most specific entry that names it;
``__init__`` is the package's own ``abcwc/__init__.py``). Moving a module means moving
it in README, and a module the table does not name fails. Imports are read from the source
(``ast``), those inside functions too, since a late import is still a dependency; an
import under ``if TYPE_CHECKING:`` is allowed to go anywhere: it only feeds type hints and
never runs.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "abcwc"
README = ROOT / "README.md"
TABLE_HEADER = "| layer | modules | what it holds |"


@dataclass(frozen=True)
class Layer:
    """One row of README's table: its place from the top (0), name and entries."""

    rank: int
    name: str
    entries: tuple[str, ...]


def read_layers(readme: str) -> list[Layer]:
    """The rows of the Layout section's table, top (the lowest layer) first."""
    section = readme.partition("\n## Layout")[2].partition("\n## ")[0]
    lines = section.splitlines()
    try:
        start = next(k for k, line in enumerate(lines)
                     if " ".join(line.split()) == TABLE_HEADER)
    except StopIteration:
        raise AssertionError(f"README's Layout section has no table {TABLE_HEADER!r}") from None
    layers = []
    for line in lines[start + 2:]:  # after the header and its --- row
        if not line.startswith("|"):
            break
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        entries = tuple(re.findall(r"`([^`]+)`", cells[1]))
        assert entries, f"README's layer {cells[0]!r} names no modules in backticks"
        layers.append(Layer(len(layers), cells[0], entries))
    return layers


def candidate_entries(parts: list[str]) -> list[str]:
    """The table entries that could hold the module ``abcwc/<parts>`` (``parts`` without
    ``.py``), most specific first: ``a/b/c``, ``a/b/``, ``a/``."""
    folders = ["/".join(parts[:k]) + "/" for k in range(len(parts) - 1, 0, -1)]
    return ["/".join(parts), *folders]


def entry_of(path: Path, entries: dict[str, int] | None = None,
             package: Path = PACKAGE) -> str | None:
    """The table entry a source file belongs to (the most specific), None if none does."""
    parts = list(path.relative_to(package).with_suffix("").parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts = parts[:-1] + ["__init__"]  # a package's __init__ is inside the package
    table = RANK if entries is None else entries
    return next((entry for entry in candidate_entries(parts) if entry in table), None)


def module_name(path: Path, package: Path = PACKAGE) -> str:
    """``abcwc.x.y`` for ``abcwc/x/y.py`` (a package's ``__init__`` is the package)."""
    parts = [package.name, *path.relative_to(package).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking_only(node: ast.AST) -> bool:
    test = node.test if isinstance(node, ast.If) else None
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement in ``tree``, at any depth, except under TYPE_CHECKING."""
    found = []
    for node in ast.iter_child_nodes(tree):
        if _type_checking_only(node):
            found += [n for child in node.orelse for n in _imports_in(child)]
            continue
        found += _imports_in(node)
    return found


def _imports_in(node: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    own = [node] if isinstance(node, ast.Import | ast.ImportFrom) else []
    return own + _imports(node)


def imported_modules(path: Path, package: Path = PACKAGE) -> list[str]:
    """The abcwc modules ``path`` imports: ``import abcwc.x``, ``from abcwc.x import y``
    (``abcwc.x.y`` when ``y`` is a module of its own), relative imports resolved."""
    here = module_name(path, package).split(".")
    if path.name != "__init__.py":
        here = here[:-1]  # the package the module is in
    names = []
    for node in _imports(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
            continue
        base = here[:len(here) - node.level + 1] if node.level else []
        module = ".".join(base + ([node.module] if node.module else []))
        for alias in node.names:
            child = f"{module}.{alias.name}"
            is_module = (package.parent / child.replace(".", "/")).with_suffix(".py").is_file() \
                or (package.parent / child.replace(".", "/") / "__init__.py").is_file()
            names.append(child if is_module else module)
    return [name for name in names if name.split(".")[0] == package.name]


def entry_of_module(name: str) -> str | None:
    """The table entry of an imported module: ``abcwc`` itself is its ``__init__``."""
    parts = name.split(".")[1:]
    path = PACKAGE.joinpath(*parts)
    file = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    return entry_of(file)


def sources(package: Path = PACKAGE) -> list[Path]:
    return sorted(p for p in package.rglob("*.py") if "__pycache__" not in p.parts)


LAYERS = read_layers(README.read_text())
RANK = {entry: layer.rank for layer in LAYERS for entry in layer.entries}


def test_the_table_has_the_layers_and_names_each_entry_once():
    assert len(LAYERS) >= 5, [layer.name for layer in LAYERS]
    named = [entry for layer in LAYERS for entry in layer.entries]
    twice = sorted({entry for entry in named if named.count(entry) > 1})
    assert not twice, f"README's table names these in more than one row: {twice}"


def test_every_entry_of_the_table_is_in_the_package():
    present = {entry_of(path) for path in sources()}
    missing = sorted(set(RANK) - present)
    assert not missing, f"README's table names modules that are not in abcwc/: {missing}"


def test_every_module_of_the_package_is_in_the_table():
    unplaced = [str(path.relative_to(ROOT)) for path in sources() if entry_of(path) is None]
    assert not unplaced, f"add these to a row of README's Layout table: {unplaced}"


@pytest.mark.parametrize("layer", LAYERS, ids=[layer.name for layer in LAYERS])
def test_a_layer_imports_only_its_own_and_the_layers_above_it(layer):
    files = [path for path in sources() if RANK.get(entry_of(path)) == layer.rank]
    assert files
    upward = []
    for path in files:
        for name in imported_modules(path):
            rank = RANK.get(entry_of_module(name), -1)
            if rank > layer.rank:
                upward.append(f"{path.relative_to(ROOT)} imports {name} ({LAYERS[rank].name})")
    assert not upward, "\n".join(upward)


# --- the reader itself, on made-up sources -------------------------------------------------


def test_imports_are_found_at_any_depth_and_relative_ones_resolved(tmp_path):
    package = tmp_path / "abcwc"
    (package / "sim").mkdir(parents=True)
    for name in ("__init__.py", "types.py", "sim/__init__.py", "sim/base.py", "sim/world.py"):
        (package / name).write_text("")
    bad = package / "sim" / "motor.py"
    bad.write_text("import math\nfrom abcwc.sim.base import SimBase\n"
                   "def late():\n    from abcwc import types\n    import abcwc.sim.world\n"
                   "from . import world\nfrom .base import Body\nfrom .. import types as t\n"
                   "from abcwc import connect\n")
    assert imported_modules(bad, package) == [
        "abcwc.sim.base", "abcwc.types", "abcwc.sim.world", "abcwc.sim.world",
        "abcwc.sim.base", "abcwc.types", "abcwc"]


def test_type_checking_imports_are_allowed(tmp_path):
    package = tmp_path / "abcwc"
    package.mkdir()
    (package / "__init__.py").write_text("")
    typed = package / "types.py"
    typed.write_text("from typing import TYPE_CHECKING\nimport typing\n"
                     "if TYPE_CHECKING:\n    from abcwc.viz import plot\n"
                     "else:\n    from abcwc.geometry import x\n"
                     "if typing.TYPE_CHECKING:\n    import abcwc.cli\n")
    assert imported_modules(typed, package) == ["abcwc.geometry"]


def test_a_module_belongs_to_the_most_specific_entry(tmp_path):
    table = {"navigation/": 4, "navigation/panel": 5, "types": 0, "__init__": 3}
    for name, entry in (("navigation/panel.py", "navigation/panel"),
                        ("navigation/dwa.py", "navigation/"),
                        ("navigation/__init__.py", "navigation/"), ("types.py", "types"),
                        ("__init__.py", "__init__"), ("teleop.py", None)):
        assert entry_of(PACKAGE / name, table) == entry, name


def test_the_table_is_read_from_its_rows():
    readme = ("# x\n\n## Layout\n\nSome words.\n\n" + TABLE_HEADER + "\n| --- | --- | --- |\n"
              "| low | `types`, `geometry` | maths, `not_a_module` here |\n"
              "| high | `sim/`, `cli` | bodies |\n\nMore words.\n\n## Next\n")
    assert read_layers(readme) == [Layer(0, "low", ("types", "geometry")),
                                   Layer(1, "high", ("sim/", "cli"))]
