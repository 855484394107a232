"""check.json as typed records: what `raycheck check` (and `grade`, per submission, and the pytest
plugin's results folder) writes, one frozen dataclass per object of the file, with one generic
to_json / from_json and the JSON Schema of the file made from the same type hints
(docs/check.schema.json, checked in a test), so that the file's format exists once, as code.

    report = from_json(CheckReport, json.loads(path.read_text()))
    [e for e in report.cases if e.verdict == Verdict.FAIL]
"""
from __future__ import annotations

import functools
import json
import math
import types
import typing
from dataclasses import MISSING, dataclass, field, fields, is_dataclass
from enum import Enum, StrEnum
from typing import Any, TypeVar

SCHEMA_ID = "https://raycheck.invalid/check.schema.json"
# JSON has no inf or NaN: a float that is not finite (the PSNR of equal images) is written as
# its Python spelling
NON_FINITE = ("inf", "-inf", "nan")


class Verdict(StrEnum):
    PASS = "pass"
    FAIL = "fail"
    ERROR = "error"  # the program crashed, hung, wrote nothing or a bad image


class Role(StrEnum):
    """Who made an image of a case: the program checked, the reference it is judged against,
    and for a jittered case the mean of the reference's realisations."""

    CANDIDATE = "candidate"
    REFERENCE = "reference"
    MEAN = "mean"


def doc(text: str, json_name: str | None = None, **kwargs) -> Any:
    """A field with its description (the schema's) and, where the JSON key is no Python name,
    the key."""
    return field(metadata={"doc": text, "json": json_name}, **kwargs)


def optional(text: str) -> Any:
    """A field that only some records have: None where absent, and then left out of the JSON
    (not required by the schema)."""
    return field(default=None, metadata={"doc": text, "json": None, "optional": True})


@dataclass(frozen=True)
class FindingRecord:
    """A finding as check.json holds it (judge.findings.Finding, without its picture)."""

    code: str = doc("what is wrong, as a code (judge/findings.py, docs/findings.md)")
    message: str = doc("one line with the numbers")
    functions: tuple[str, ...] | None = optional(
        "a located finding's: the starter functions its evidence leaves, one where it names "
        "one; a cause's where its images cannot tell it from a mistake in another function: "
        "its function and those")


@dataclass(frozen=True)
class ImageMetrics:
    """The numbers of one image kind's comparison (judge/metrics.py), the candidate's values
    against the reference's as 8-bit shows them (a jittered image: against the mean of the
    reference's realisations)."""

    ssim: float = doc("structural similarity, 1 for equal images")
    psnr: float = doc("peak signal-to-noise ratio in dB, inf for equal images")
    rmse: float = doc("root mean square difference of the values")
    mean_abs: float = doc("mean absolute difference of the values")
    max_abs: float = doc("largest absolute difference of a value")
    off_by_more_than_one: float = doc("share of pixels more than one 8-bit level off")
    equal_bytes: float = doc("share of 8-bit values equal")
    brightness_change_pct: float = doc("mean brightness change, percent")
    flip: float = doc("NVIDIA's FLIP difference, 0 for equal images")
    beyond_tolerance: float | None = optional(
        "share of pixels beyond the tolerance's levels (deterministic images)")
    max_levels: int | None = optional("the largest difference in 8-bit levels (deterministic "
                                      "images)")

    def items(self) -> list[tuple[str, float]]:
        """(name, value) of each metric the comparison has, in field order."""
        return [(f.name, getattr(self, f.name)) for f in fields(self)
                if getattr(self, f.name) is not None]


@dataclass(frozen=True)
class StatisticRecord:
    """One statistic of the jitter test (judge/statistics.py) and its acceptance band."""

    name: str = doc("pixels, mean z, mean z^2, correlation or poisoned pixels")
    value: float | None = doc("its value; none where too few pixels measure it")
    low: float | None = doc("the band's lower end")
    high: float | None = doc("the band's upper end")
    passed: bool = doc("the value lies in the band (or there is none)")


@dataclass(frozen=True)
class JitterRecord:
    """The statistical test of a jittered image against the reference's realisations."""

    statistics: tuple[StatisticRecord, ...] = doc("each statistic with its band")
    realisations: int = doc("realisations of the reference the image was judged against")
    tested_pixels: int = doc("pixels the per-pixel test judged")
    failing_pixels: int = doc("of those, pixels beyond the per-pixel threshold")
    allowed_failing_pixels: float = doc("how many may fail (a share of the tested pixels)")
    noisy_pixels: int = doc("pixels whose reference values vary: the global statistics' pixels")
    mixed_pixels: int = doc("pixels an inf/NaN/missed sample decides in some realisations")
    pixel_threshold: float = doc("the per-pixel |z| threshold (Sidak-corrected)")


@dataclass(frozen=True)
class SkipRecord:
    scene: str = doc("the scene's id: course/arch, or a file's path")
    feature: str = doc("the case's feature, or the feature family not run")
    kind: str = doc("the image kind skipped, or all")
    reason: str = doc("why the scene cannot exercise it")


@dataclass(frozen=True)
class KindRecord:
    """An image kind's verdict (judge.verdict.KindVerdict, as a case's record holds it)."""

    kind: str = doc("color, normals or depth")
    verdict: Verdict = doc("pass, fail or error")
    metrics: ImageMetrics | None = doc("numbers of the comparison; none where the image is "
                                       "missing")
    failures: tuple[str, ...] = doc("each failed threshold, with the number and the limit")
    findings: tuple[FindingRecord, ...] = doc("what is wrong, most specific first")
    jitter: JitterRecord | None = doc("the statistical test of a jittered image; none for "
                                      "the others")


@dataclass(frozen=True)
class CauseRecord:
    """The cause the search found for a case's images, in words: what a case page opens
    with (its findings hold the same per mistake, with the numbers)."""

    mistakes: tuple[str, ...] = doc("each mistake: its function and what the program does")
    how: str = doc("how the reference with them matches the images, with the numbers")
    reproduces: bool = doc("it reproduces every image of the case")
    command: str = doc("the command that renders the case's reference with them")


@dataclass(frozen=True)
class ObjectView:
    """The objects of one kind in a case's image, transformed or not: what the case shows of
    the work of the functions that draw them, for the contrast across a program's cases
    (diagnosis/cross_case.py)."""

    kind: str = doc("sphere, plane, triangle or mesh")
    transformed: bool = doc("they sit in a Transform")
    pixels: int = doc("the pixels of the reference's image that show them (of a -jitter or "
                      "-filter case, rendered at three times its size without them: a ninth "
                      "of the sub-pixels)")
    changed: float = doc("the share of those pixels and those within 2 pixels of them (6 "
                         "sub-pixels) where a failing normals or depth image differs")
    scale: int = doc("the size of the image they were read from over the case's: 3 for a "
                     "-jitter or -filter case, else 1", default=1)


@dataclass(frozen=True)
class CaseRecord:
    """One case's result as the pages, the result cache, report.json and check.json read it."""

    case: str = doc("scene/feature")
    scene: str = doc("the scene's id")
    feature: str = doc("the case's feature")
    description: str = doc("the scene's description")
    flags: tuple[str, ...] = doc("the course flags of the case's features")
    size: tuple[int, int] = doc("image width and height")
    jittered: bool = doc("the candidate's images are a random draw (-jitter)")
    passed: bool = doc("every image kind passed")
    verdict: Verdict = doc("error if a kind erred, else fail if one failed, else pass")
    labels: dict[Role, str] = doc("role -> renderer name")
    times: dict[Role, dict[str, float | None]] = doc("role -> cold_s, warm_s")
    log: str = doc("the candidate's last output lines")
    error: FindingRecord | None = doc("the whole render failed: its code and message")
    depth_range: tuple[float, float] = doc("the depth image's range")
    depth_origin: str = doc("where the depth range came from")
    kinds: tuple[KindRecord, ...] = doc("each image kind's verdict")
    files: dict[str, dict[str, str]] = doc("kind -> role -> picture file", default_factory=dict)
    page: str = doc("the case's page, relative to the run's folder", default="")
    quirks: tuple[str, ...] = doc("the course program's quirks that change this case's "
                                  "reference (quirk-sensitive)", default=())
    causes: tuple[str, ...] = doc("the mistakes the cause search found to explain the case's "
                                  "images (where no one set explains every kind, those of "
                                  "the kinds it explains), as --mistake switches (code or "
                                  "code=value)", default=())
    alternatives: tuple[tuple[str, ...], ...] = doc(
        "other sets of mistakes that explain the images as well, which they cannot tell "
        "from the causes", default=())
    cause: CauseRecord | None = doc("the cause of its images, where the search found one",
                                    default=None)
    geometry: tuple[str, ...] = doc("the normals or depth images that differ, where its "
                                    "geometry was read (rendered for the purpose where the "
                                    "case asks for color alone)", default=())
    views: tuple[ObjectView, ...] = doc("what its image shows of each intersect function's "
                                        "work, where its geometry was read", default=())

    def top_finding(self) -> FindingRecord | None:
        """The first finding of the case's first failing kind, else the quirk note of a kind
        that passed only by the handouts' reading (diagnosis/quirks.py), if any."""
        return next((k.findings[0] for k in self.kinds
                     if k.verdict == Verdict.FAIL and k.findings), None) or next(
            (k.findings[0] for k in self.kinds if k.verdict == Verdict.PASS and k.findings
             and k.findings[0].code.startswith("quirk:")), None)


@dataclass(frozen=True)
class CheckEntry:
    """One case and image kind."""

    scene: str = doc("the scene's id: course/arch, or a file's path")
    feature: str = doc("the case: plain, shadows, bounces4, shadows+bounces4, jitter, ...")
    flags: tuple[str, ...] = doc("the course flags of the case's features")
    size: tuple[int, int] = doc("image width and height")
    kind: str = doc("color, normals or depth")
    verdict: Verdict = doc("pass, fail or error")
    metrics: ImageMetrics | None = doc("numbers of the comparison; none where the image is "
                                       "missing")
    failures: tuple[str, ...] = doc("each failed threshold, with the number and the limit")
    findings: tuple[FindingRecord, ...] = doc("what is wrong, most specific first")
    jitter: JitterRecord | None = doc("the statistical test of a jittered image (statistics, "
                                      "realisations, failing pixels); none for the others")
    stderr_tail: str | None = doc("the last lines the program wrote")
    seconds: float | None = doc("the program's run time for the case")
    page: str = doc("the case's page, relative to the folder")
    quirks: tuple[str, ...] = doc("the course program's quirks that change this case's "
                                  "reference (quirk-sensitive)", default=())


@dataclass(frozen=True)
class MistakeFound:
    """A mistake the cause search found in the program: the cases it explains, and where to
    see it."""

    mistake: str = doc("as a --mistake switch: its code, and =value where it has a "
                       "parameter (the value most of its cases have)")
    function: str = doc("the starter-code function it is in")
    description: str = doc("what the program does, in words")
    quirk: bool = doc("a quirk of the course program's that the program differs on (counted "
                      "only with --strict), not a mistake")
    cases: tuple[str, ...] = doc("the failing cases it explains, alone or with the others "
                                 "(scene/feature)")
    together: tuple[str, ...] = doc("the other mistakes it explains some of them with")
    example: str = doc("the case that shows it most clearly: it alone reproduces every "
                       "image there, where one does")
    page: str = doc("that case's page, relative to the folder")
    command: str = doc("the command that renders that case's reference with its mistakes")


@dataclass(frozen=True)
class OpenCase:
    """A failing case that no mistake of the catalogue explains."""

    case: str = doc("scene/feature")
    page: str = doc("the case's page, relative to the folder")
    kind: str = doc("its first failing image kind")
    finding: FindingRecord | None = doc("that kind's top finding: where to look (located), "
                                        "an output-level change, a symptom or the error")


@dataclass(frozen=True)
class ProgramDiagnosis:
    """What is wrong with the program, over every case: the mistakes found, then the failing
    cases none explains."""

    failing_cases: int = doc("cases that failed or erred")
    mistakes: tuple[MistakeFound, ...] = doc("the mistakes found, the one that explains most "
                                             "cases first")
    unexplained: tuple[OpenCase, ...] = doc("the failing cases no mistake explains")


@dataclass(frozen=True)
class Summary:
    passed: int = doc("image kinds that passed", json_name="pass")
    failed: int = doc("image kinds that failed", json_name="fail")
    errors: int = doc("image kinds the program did not deliver", json_name="error")


@dataclass(frozen=True)
class CheckReport:
    """check.json."""

    renderer: dict[str, Any] = doc("the candidate: its command, and the sha256 of its file")
    reference: str = doc("what it was judged against: tracer or mitsuba")
    reference_identity: dict[str, Any] = doc("the reference's name and version")
    tolerance: str = doc("the pixel rule of deterministic images, in words")
    cases: tuple[CheckEntry, ...] = doc("one entry per case and image kind")
    skipped: tuple[SkipRecord, ...] = doc("features and kinds the scenes cannot exercise")
    summary: Summary = doc("counts of the entries' verdicts")
    seconds: float = doc("the check's wall time")
    provenance: dict[str, str] = doc("versions, machine and time of the run")
    diagnosis: ProgramDiagnosis = doc("what is wrong with the program: the mistakes found "
                                      "and the failing cases none explains")

    @property
    def passed(self) -> bool:
        return self.summary.failed == 0 and self.summary.errors == 0


@dataclass(frozen=True)
class FamilyCount:
    passed: int = doc("cases of the family that passed (every image kind of the case)")
    total: int = doc("cases of the family")


@dataclass(frozen=True)
class GradeRow:
    """A submission's line of `raycheck grade`'s class table (grades.json's submissions)."""

    name: str = doc("the submission's name")
    score: float = doc("points: per family its points times the share of its cases passed")
    max_score: float = doc("the points of the families its scenes exercise")
    families: dict[str, FamilyCount] = doc("feature family -> cases passed and in all")
    cases: int = doc("cases checked")
    passed: int = doc("cases passed")
    crashes: int = doc("cases whose program crashed")
    timeouts: int = doc("cases whose program ran out of time")
    errors: int = doc("cases that erred in any way")
    report: str = doc("the submission's report, relative to the class folder")
    quirks: tuple[str, ...] = doc("the course program's quirks it differs on (not counted "
                                  "unless --strict)")
    sha256: str | None = doc("the submission's program file's sha256 (sources: theirs)")
    build: str = doc("prebuilt, built (with the fix it needed), or build failed")
    build_error: str = doc("the compiler's first error where the build failed")
    build_log: str | None = doc("the build's log, relative to the class folder")
    causes: dict[str, str] = doc("feature family -> the top finding most of its failing "
                                 "cases have")
    mistakes: tuple[str, ...] = doc("the mistakes found in it (check.json's diagnosis), as "
                                    "--mistake switches", default=())


@dataclass(frozen=True)
class ClassMistake:
    """A mistake found in a class's submissions (grades.json's mistakes): who makes it."""

    mistake: str = doc("its code (--mistake CODE; the parameter may differ by submission)")
    function: str = doc("the starter-code function it is in")
    description: str = doc("what a program with it does, at the value most submissions have")
    submissions: tuple[str, ...] = doc("the submissions it is found in")


@dataclass(frozen=True)
class StressRow:
    """A variant of the tracer on an extreme scene against the float64 robust reference
    (`raycheck stress`, stress.json)."""

    scene: str = doc("the extreme scene's name")
    variant: str = doc("course, robust, course-float64, mitsuba")
    size: tuple[int, int] = doc("image width and height")
    nonfinite: int | None = doc("pixels with a NaN or infinite channel (none: no image)")
    differing: float = doc("share of pixels more than one level off the reference")
    ssim: float = doc("SSIM against the reference")
    cold_s: float | None = doc("first render's seconds")
    warm_s: float | None = doc("a warm render's seconds")
    passed: bool = doc("no NaN/inf pixel and SSIM at least the goal")
    description: str = doc("the scene's description")
    error: str | None = optional("why the variant could not render the scene")
    image: str | None = optional("the variant's image, relative to the folder")
    floats: str | None = optional("its float values (.npy)")
    reference: str | None = optional("the reference's image")
    reference_nonfinite: int | None = optional("the reference's NaN/inf pixels")
    diff: str | None = optional("the difference heatmap of a failing row")
    diff_scale: float | None = optional("the value the heatmap's brightest color stands for")


R = TypeVar("R")


def _key(f) -> str:
    return f.metadata.get("json") or f.name


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def to_json(value: Any) -> Any:
    """A record (or a value inside one) as JSON data: dataclasses as objects with their fields
    in order, tuples as arrays, enums as their values, non-finite floats as strings."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if is_dataclass(value) and not isinstance(value, type):
        return {_key(f): to_json(getattr(value, f.name)) for f in fields(value)
                if not (f.metadata.get("optional") and getattr(value, f.name) is None)}
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, (tuple, list)):
        return [to_json(v) for v in value]
    if isinstance(value, dict):
        return {k: to_json(v) for k, v in value.items()}
    return value



def json_text(data: Any) -> str:
    """Strict JSON of data (to_json: non-finite floats, such as the PSNR of equal images, as
    strings), as every JSON file of raycheck's is written."""
    return json.dumps(to_json(data), indent=1, allow_nan=False)


def from_json(cls: type[R], data: Any) -> R:
    """The record of type `cls` that `data` holds (ValueError naming the key where it does
    not)."""
    return _read(cls, data, cls.__name__)


def _read(tp: Any, data: Any, where: str) -> Any:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if tp is Any:
        return _floats_restored(data)
    if origin in (typing.Union, types.UnionType):
        if data is None and type(None) in args:
            return None
        (inner,) = [a for a in args if a is not type(None)]
        return _read(inner, data, where)
    if isinstance(tp, type) and is_dataclass(tp):
        if not isinstance(data, dict):
            raise ValueError(f"{where}: expected an object")
        hints = _hints(tp)
        unknown = set(data) - {_key(f) for f in fields(tp)}
        if unknown:
            raise ValueError(f"{where}: unexpected {', '.join(sorted(unknown))}")
        values = {}
        for f in fields(tp):
            if not f.init:  # derived from the others (written, not read)
                continue
            if _key(f) not in data:
                if f.default is MISSING and f.default_factory is MISSING:
                    raise ValueError(f"{where}: no {_key(f)!r}")
                continue
            values[f.name] = _read(hints[f.name], data[_key(f)], f"{where}.{_key(f)}")
        return tp(**values)
    if isinstance(tp, type) and issubclass(tp, Enum):
        return tp(data)
    if origin is tuple:
        if not isinstance(data, list):
            raise ValueError(f"{where}: expected an array")
        items = args[:1] * len(data) if args[-1:] == (...,) else args
        if len(items) != len(data):
            raise ValueError(f"{where}: expected {len(items)} items")
        return tuple(_read(t, v, f"{where}[{i}]") for i, (t, v) in enumerate(zip(items, data)))
    if origin is dict:
        if not isinstance(data, dict):
            raise ValueError(f"{where}: expected an object")
        return {_read(args[0], k, f"{where}: key"): _read(args[1], v, f"{where}.{k}")
                for k, v in data.items()}
    if tp is float and data in NON_FINITE:
        return float(data)
    if tp is float and isinstance(data, int) and not isinstance(data, bool):
        return data  # an int is a float's value (a count among the metrics): kept as written
    if not isinstance(data, tp) or (tp is int and isinstance(data, bool)):
        raise ValueError(f"{where}: expected {tp.__name__}, found {type(data).__name__}")
    return data


def _floats_restored(data: Any) -> Any:
    """Untyped JSON data (a jittered image's statistics) with the strings to_json writes for
    non-finite floats read back as floats, so that a record read back equals the one written."""
    if isinstance(data, str) and data in NON_FINITE:
        return float(data)
    if isinstance(data, dict):
        return {k: _floats_restored(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_floats_restored(v) for v in data]
    return data


def schema(cls: type = CheckReport) -> dict:
    """The JSON Schema (2020-12) of a record type's JSON, from its type hints and field docs."""
    definitions: dict[str, dict] = {}
    root = _schema(cls, definitions)
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": SCHEMA_ID,
            "title": cls.__name__, **root, "$defs": dict(sorted(definitions.items()))}


_PRIMITIVES = {str: "string", int: "integer", float: "number", bool: "boolean",
               type(None): "null"}


def _schema(tp: Any, definitions: dict[str, dict], top: bool = True) -> dict:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if tp is Any:
        return {}
    if tp is float:
        return {"anyOf": [{"type": "number"}, {"enum": list(NON_FINITE)}]}
    if tp in _PRIMITIVES:
        return {"type": _PRIMITIVES[tp]}
    if origin in (typing.Union, types.UnionType):
        return {"anyOf": [_schema(a, definitions, False) for a in args]}
    if isinstance(tp, type) and issubclass(tp, Enum):
        return {"enum": [m.value for m in tp]}
    if origin is tuple:
        if args[-1:] == (...,):
            return {"type": "array", "items": _schema(args[0], definitions, False)}
        return {"type": "array", "prefixItems": [_schema(a, definitions, False) for a in args],
                "minItems": len(args), "maxItems": len(args)}
    if origin is dict:
        keys = ({"propertyNames": {"enum": [m.value for m in args[0]]}}
                if isinstance(args[0], type) and issubclass(args[0], Enum) else {})
        return {"type": "object", **keys,
                "additionalProperties": _schema(args[1], definitions, False)}
    if isinstance(tp, type) and is_dataclass(tp):
        hints = _hints(tp)
        body = {"type": "object",
                "properties": {_key(f): {**_schema(hints[f.name], definitions, False),
                                         "description": f.metadata["doc"]}
                               for f in fields(tp)},
                "required": [_key(f) for f in fields(tp) if not f.metadata.get("optional")],
                "additionalProperties": False}
        if tp.__doc__ and not tp.__doc__.startswith(tp.__name__ + "("):
            body = {"description": tp.__doc__.strip(), **body}
        if top:
            return body
        definitions[tp.__name__] = body
        return {"$ref": f"#/$defs/{tp.__name__}"}
    raise TypeError(f"no JSON Schema for {tp!r}")
