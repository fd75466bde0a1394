"""The course's front page, and every chapter a chapter refers to: one that exists or one
the front page lists as still to come."""

from pathlib import Path

import nbformat

from abcwc.course_front_page import CHAPTERS_TO_COME, chapter_references, front_page

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = sorted((ROOT / "solutions").glob("*.ipynb"))


def test_references_are_read_in_every_form_the_chapters_use():
    text = ("as chapter 03 showed; chapters 06 to 09 gave three ways; see chapters 05, 11, 14 "
            "and 17, or chapter 02's table; Chapter 10 or 12; chapters 13-15")
    assert chapter_references(text) == {"02", "03", "05", "06", "09", "10", "11", "12", "13",
                                        "14", "15", "17"}
    assert chapter_references("section 3.2, table 7, figure 50, 2018") == set()


def test_every_chapter_named_in_a_chapter_exists_or_is_still_to_come():
    existing = {path.name[:2] for path in SOLUTIONS}
    allowed = existing | set(CHAPTERS_TO_COME)
    unknown = {}
    for path in SOLUTIONS:
        for cell in nbformat.read(path, as_version=4).cells:
            for number in chapter_references(cell.source) - allowed:
                unknown.setdefault(number, set()).add(path.name)
    assert not unknown, f"chapters referred to that neither exist nor are planned: {unknown}"


def test_the_front_page_lists_every_chapter_and_marks_those_to_come():
    page = front_page(ROOT / "solutions")
    assert page == (ROOT / "course" / "README.md").read_text(encoding="utf-8")
    for path in SOLUTIONS:
        title = nbformat.read(path, as_version=4).cells[0].source.splitlines()[0].lstrip("# ")
        assert f"[{title}]({path.name})" in page
    existing = {path.name[:2] for path in SOLUTIONS}
    for number, (title, _, thesis) in CHAPTERS_TO_COME.items():
        if number not in existing:
            assert f"{number} · {title} (still to come)" in page and thesis in page
    # every chapter shows its goals, all of them (the last one too)
    for path in SOLUTIONS:
        row = next(line for line in page.splitlines() if f"]({path.name})" in line)
        assert "1. " in row and "covers:" not in row, row
    assert "3. say why an open-loop square does not come back where it started" in page
