"""Every rule of docs/course-format.md says what it is: `required` (a handout asks for it, and
the tag cites it), `convention` (a choice a correct program makes one way or another, fixed by
the starter code or the handout) or `quirk` (the course program's own behaviour, found by a
probe scene or the disassembly: the tag names it). A rule is a bullet (nested ones too) or a
paragraph of the numbered sections; a table's rule is the paragraph after it. Every quirk of
tracer/quirks.py is one of the spec's quirk rules."""
from __future__ import annotations

import re
from pathlib import Path

from raycheck.tracer.quirks import QUIRKS

SPEC = Path(__file__).resolve().parent.parent / "docs" / "course-format.md"
TAG = re.compile(r"\[(required|convention|quirk)(?:: ([^\]]+))?\]")


def rules() -> list[tuple[str, str]]:
    """(section, text) of every rule: the bullets and paragraphs of the numbered sections,
    outside code blocks and tables."""
    found: list[tuple[str, str]] = []
    top, section, fenced, block = "", "", False, []

    def close() -> None:
        if block and section:
            found.append((section, " ".join(block)))
        block.clear()

    for line in SPEC.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            fenced = not fenced
            close()
            continue
        if fenced:
            continue
        if line.startswith("#"):
            close()
            if line.startswith("## "):
                top = line if re.match(r"## \d", line) else ""
                section = top
            else:  # a subsection of a numbered section is part of it
                section = f"{top} / {line}" if top else ""
            continue
        if not line.strip() or line.startswith("|"):
            close()
            continue
        if line.lstrip().startswith("* "):  # a bullet, nested ones too
            close()
        block.append(line.strip())
    close()
    return found


def test_every_rule_has_a_status():
    untagged = [f"{section}: {text[:80]}" for section, text in rules() if not TAG.search(text)]
    assert untagged == []


def test_a_required_rule_cites_its_handout_and_a_quirk_its_evidence():
    for section, text in rules():
        for status, why in TAG.findall(text):
            if status in ("required", "quirk"):
                assert why and len(why) > 10, f"{section}: {text[:80]}"


def test_every_modelled_quirk_is_a_quirk_rule_of_the_spec():
    said = {why for _, text in rules() for status, why in TAG.findall(text) if status == "quirk"}
    assert [q.code for q in QUIRKS if not any(q.code in why for why in said)] == []


def test_every_probe_scene_names_the_rules_it_exercises():
    text = SPEC.read_text(encoding="utf-8")
    table = text[text.index("## Probe scenes and the rules they exercise"):]
    named = {line.split("|")[1].strip() for line in table.splitlines()
             if line.startswith("| ") and "§" in line}
    probes = {p.stem for p in (SPEC.parent.parent / "scenes" / "features").glob("*.txt")}
    assert named == probes
