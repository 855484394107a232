"""check.json's format as code (harness/records.py): the committed JSON Schema is the one the
records make, real check.json files (passing, failing, erring and jittered cases) validate
against it and read back into records that write the same JSON, and the schema refuses what
the format does not allow. The validator here is written apart from the schema's generator,
for the subset of JSON Schema 2020-12 the schema uses."""
from __future__ import annotations

import copy
import json
import shlex
import sys
from pathlib import Path

import pytest

from raycheck.harness.cli import main as raycheck_main
from raycheck.harness.records import CheckReport, Verdict, from_json, to_json

REPO = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((REPO / "docs" / "check.schema.json").read_text(encoding="utf-8"))
FALLOFF = REPO / "scenes" / "features" / "falloff.txt"
TYPES = {"string": str, "integer": int, "number": (int, float), "boolean": bool,
         "object": dict, "array": list, "null": type(None)}


def problems(value, schema: dict, where: str = "$") -> list[str]:
    """Where `value` breaks `schema` (resolving $ref against SCHEMA)."""
    if "$ref" in schema:
        return problems(value, SCHEMA["$defs"][schema["$ref"].rsplit("/", 1)[1]], where)
    if "anyOf" in schema:
        if all(problems(value, s, where) for s in schema["anyOf"]):
            return [f"{where}: matches none of anyOf"]
        return []
    if "enum" in schema and value not in schema["enum"]:
        return [f"{where}: {value!r} not in {schema['enum']}"]
    if "type" in schema:
        kind = TYPES[schema["type"]]
        if not isinstance(value, kind) or (isinstance(value, bool) and schema["type"] != "boolean"):
            return [f"{where}: expected {schema['type']}"]
    found = []
    if isinstance(value, dict):
        found += [f"{where}: no {k!r}" for k in schema.get("required", []) if k not in value]
        props, extra = schema.get("properties", {}), schema.get("additionalProperties", {})
        for k, v in value.items():
            if k in props:
                found += problems(v, props[k], f"{where}.{k}")
            elif extra is False:
                found.append(f"{where}: unexpected {k!r}")
            else:
                found += problems(v, extra, f"{where}.{k}")
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0) or len(value) > schema.get("maxItems", 1e9):
            found.append(f"{where}: {len(value)} items")
        for i, v in enumerate(value):
            prefix = schema.get("prefixItems", [])
            item = prefix[i] if i < len(prefix) else schema.get("items", {})
            found += problems(v, item, f"{where}[{i}]")
    return found


@pytest.fixture(scope="module")
def check_files(tmp_path_factory) -> dict[str, dict]:
    """check.json of a passing check with a jittered case, and of a program that fails (the
    tracer with its colors offset) and of one that crashes."""
    base = tmp_path_factory.mktemp("records")
    dim = shlex.join([sys.executable, str(REPO / "tests" / "wrappers" / "corrupt.py"),
                      "offset"])
    crash = shlex.join([sys.executable, "-c", "import sys; sys.exit(3)"])
    files = {}
    for name, renderer, features in (("tracer", "tracer", "plain,jitter"),
                                     ("dim", dim, "plain"), ("crash", crash, "plain")):
        out = base / name
        status = raycheck_main(["check", "--renderer", renderer, str(FALLOFF), "--size", "8",
                                "8", "--features", features, "--realisations", "8", "--quiet",
                                "--out", str(out)])
        assert status == (0 if name == "tracer" else 1)
        files[name] = json.loads((out / "check.json").read_text(encoding="utf-8"))
    return files


def test_the_committed_schema_is_the_records_one():
    sys.path.insert(0, str(REPO / "tools"))
    try:
        from check_schema import schema_text
    finally:
        sys.path.pop(0)
    assert json.loads(schema_text()) == SCHEMA, "run: .venv/bin/python tools/check_schema.py"


def test_real_check_files_validate_and_read_back(check_files):
    verdicts = set()
    for name, data in check_files.items():
        assert problems(data, SCHEMA) == [], name
        report = from_json(CheckReport, data)
        assert to_json(report) == data, name
        verdicts |= {e.verdict for e in report.cases}
    assert verdicts == {Verdict.PASS, Verdict.FAIL, Verdict.ERROR}
    assert any(e.jitter for e in from_json(CheckReport, check_files["tracer"]).cases)
    crashed = from_json(CheckReport, check_files["crash"])
    assert {f.code for e in crashed.cases for f in e.findings} == {"exit_status"}


@pytest.mark.parametrize("change, expected", [
    (lambda d: d["cases"][0].pop("verdict"), "$.cases[0]: no 'verdict'"),
    (lambda d: d["cases"][0].update(verdict="flaky"), "$.cases[0].verdict: 'flaky' not in"),
    (lambda d: d["cases"][0].update(size=[8]), "$.cases[0].size: 1 items"),
    (lambda d: d["summary"].update(passes=1), "$.summary: unexpected 'passes'"),
    (lambda d: d.update(seconds="soon"), "$.seconds: matches none of anyOf"),
])
def test_the_schema_refuses_what_the_format_does_not_allow(check_files, change, expected):
    data = copy.deepcopy(check_files["tracer"])
    change(data)
    assert any(p.startswith(expected) for p in problems(data, SCHEMA)), problems(data, SCHEMA)
    with pytest.raises(ValueError):
        from_json(CheckReport, data)
