"""Writes docs/check.schema.json, the JSON Schema of check.json, from its records
(harness/records.py); tests/harness/test_records.py fails while the file and the records differ.

    .venv/bin/python tools/check_schema.py
"""
from __future__ import annotations

import json
from pathlib import Path

from raycheck.harness.records import schema

TARGET = Path(__file__).resolve().parent.parent / "docs" / "check.schema.json"


def schema_text() -> str:
    return json.dumps(schema(), indent=1, ensure_ascii=False) + "\n"


if __name__ == "__main__":
    TARGET.write_text(schema_text(), encoding="utf-8")
    print(f"wrote {TARGET}")
