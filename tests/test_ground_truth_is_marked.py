"""The simulator's ground truth is marked apart (``SensorFrame.truth``) and nothing that
drives the chair or estimates its pose reads it: only the judges (``checks/``,
``experiments/`` and their plots in ``viz/``), the bodies that make it (``sim/``, the
firmware in the loop), the log that records it, and the one "estimator" that steers by
it on purpose, :class:`abcwc.behaviours.GroundTruth`."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from abcwc.sim import SimBase
from abcwc.types import Pose2D, SimTruth

PACKAGE = Path(__file__).resolve().parent.parent / "abcwc"
MAY_READ_TRUTH = ("checks/", "experiments/", "viz/", "sim/", "hw/fil_base.py", "log.py",
                  "types.py")
ALLOWED_CLASSES = {"behaviours/waypoints.py": {"GroundTruth"}}


def truth_reads(path: Path) -> list[tuple[int, str | None]]:
    """(line, enclosing class) of every ``<something>.truth`` in ``path``."""
    tree = ast.parse(path.read_text())
    found = []

    def visit(node: ast.AST, cls: str | None) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Attribute) and child.attr == "truth":
                found.append((child.lineno, cls))
            visit(child, child.name if isinstance(child, ast.ClassDef) else cls)

    visit(tree, None)
    return found


def test_no_behaviour_estimator_or_planner_reads_the_ground_truth():
    offending = []
    for path in sorted(PACKAGE.rglob("*.py")):
        name = path.relative_to(PACKAGE).as_posix()
        if name.startswith(MAY_READ_TRUTH):
            continue
        allowed = ALLOWED_CLASSES.get(name, set())
        offending += [f"{name}:{line}" for line, cls in truth_reads(path)
                      if cls not in allowed]
    assert not offending, f"these read frame.truth: {offending}"


def test_the_check_finds_a_read(tmp_path):
    sneaky = tmp_path / "sneaky.py"
    sneaky.write_text("class Planner:\n    def decide(self, frame):\n"
                      "        return frame.truth.pose\n")
    assert truth_reads(sneaky) == [(3, "Planner")]


def test_the_simulator_marks_its_truth_and_a_real_chair_frame_has_none():
    chair = SimBase(seed=1, people=False)
    frame = chair.step()
    assert isinstance(frame.truth, SimTruth)
    assert frame.truth.pose == chair.pose and frame.truth.collisions == 0
    assert not hasattr(frame, "pose") and not hasattr(frame, "collisions")
    with pytest.raises(ValueError, match="SimTruth or None"):
        type(frame)(0.0, 0, 0, 0.0, joystick_fb=254, joystick_lr=254, pot_fb=128,
                    pot_lr=128, truth=Pose2D())
