"""The case matrix run for one candidate against one reference: every scene x every feature it
can exercise, each case's pictures and page, and the index (overview matrix + table), the JSON
of every number and a JUnit file. `check` and `report` are this with their own renderers,
tolerance and extra pages."""
from __future__ import annotations

import tempfile
import time
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import dataclass, field, replace
from itertools import islice
from pathlib import Path
from typing import Any, Callable, Iterable, TypeVar
from xml.sax.saxutils import quoteattr

from raycheck.tracer.analysis import analyze
from raycheck.tracer.mistakes import Switch, parse_switch
from raycheck.tracer.render_limits import LimitError
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.limits import Budget, scene_request_problem
from raycheck.tracer.scene.request import KINDS

from ..case_settings import CaseSettings
from ..cases import DEFAULT_CASE_SIZE, Case, case_matrix, kind_skip_reason
from ..catalog import BundledScene, unique_labels, with_depth_range
from ..check_options import FAMILIES, case_family, feature_family
from ..diagnosis.crash_scenes import crash_narrowings
from ..diagnosis.cross_case import SceneViews, Swap, narrowed_record, narrowings
from ..diagnosis.refute import Refutation, Refuting, Trial
from ..pages import html
from ..pages.case_files import overview_kind, write_case_images
from ..records import (
    CaseRecord,
    Role,
    SkipRecord,
    Summary,
    Verdict,
    json_text,
)
from ..renderers import Renderer
from ..storage.results import CaseOutput, ResultCache, content_key, request_key
from .case import CaseResult, run_case
from .executor import InlineExecutor, Workers, use_threads
from .progress import Progress
from .refutation import ROUNDS, Ran, Refuter, candidate_images, run_trial


@dataclass
class Matrix:
    scenes: list[BundledScene]
    candidate: Renderer
    reference: Renderer
    settings: CaseSettings = CaseSettings()
    size: tuple[int, int] | None = None  # every case at this size; None: as below
    default_size: tuple[int, int] = DEFAULT_CASE_SIZE  # for scenes without a # size line
    features: frozenset[str] | None = None  # families (check_options); None: every one
    seed: int = 0  # of the jittered cases
    budget: Budget = Budget()  # every case's memory and rays, checked before any runs

    def cases(self) -> tuple[list[Case], list[SkipRecord]]:
        """The cases to run and the skipped rows (whole features, or kinds of a case)."""
        cases, skips = [], []
        for scene in map(with_depth_range, unique_labels(self.scenes)):
            model = load_scene(scene.path, self.budget)
            scene_cases, skipped = case_matrix(scene, self.size or scene.size or self.default_size,
                                               analyze(model))
            skips += [SkipRecord(scene_id(scene), s.feature, "all", s.reason)
                      for s in skipped if self._wanted(s.feature)]
            for case in scene_cases:
                if not self._wanted(case.feature):
                    continue
                problem = case.request.limit_problem() or \
                    scene_request_problem(model, case.request, self.budget)
                if problem:  # refused before any case runs
                    raise LimitError(f"{scene.path}: {case.feature}: {problem}")
                cases.append(replace(case, request=replace(case.request, seed=self.seed)))
                skips += [SkipRecord(scene_id(scene), case.feature, k,
                                     kind_skip_reason(case.feature, k))
                          for k in KINDS if k not in case.request.kinds]
        return cases, skips

    def _wanted(self, feature: str) -> bool:
        if self.features is None:
            return True
        return feature_family(feature) in self.features


def scene_id(scene: BundledScene) -> str:
    """folder/name, longer where two scenes of a run share it (catalog.unique_labels)."""
    return scene.id


def slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def case_record(result: CaseResult) -> CaseRecord:
    case = result.case
    w, h = case.request.size
    lo, hi = case.request.depth_range
    return CaseRecord(
        case=case.id, scene=scene_id(case.scene), feature=case.feature,
        description=case.scene.description, flags=tuple(case.request.feature_flags),
        size=(w, h), jittered=case.jittered, passed=result.passed,
        verdict=Verdict(result.verdict), labels=result.labels, times=result.times,
        log=result.log, error=result.error,
        depth_range=(lo, hi), depth_origin=case.scene.depth_origin,
        kinds=tuple(k.record() for k in result.kinds),
        quirks=result.quirks,
        causes=tuple(s.exact for s in result.explanations[0]) if result.explanations else (),
        alternatives=tuple(tuple(s.exact for s in e) for e in result.explanations[1:]),
        cause=result.cause, geometry=result.geometry, views=result.views)


def case_output(result: CaseResult) -> CaseOutput:
    """The case's record and picture files (rendered in a scratch folder, read back)."""
    with tempfile.TemporaryDirectory(prefix="raycheck-pictures-") as tmp:
        files = write_case_images(result, Path(tmp))
        blobs = {p.name: p.read_bytes() for p in Path(tmp).iterdir()}
    command = result.case.request.to_argv(result.case.scene.path.name)
    return CaseOutput(replace(case_record(result), files=files), blobs, command)


def place_case(output: CaseOutput, folder: Path, prov: dict[str, str],
               index_href: str | None = None) -> CaseRecord:
    """The case's pictures and page under folder; returns its record."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in output.files.items():
        (folder / name).write_bytes(data)
    (folder / "index.html").write_text(
        html.case_page(output.row, output.command, prov, index_href), encoding="utf-8")
    return output.row


def write_case(result: CaseResult, folder: Path, prov: dict[str, str],
               index_href: str | None = None) -> CaseRecord:
    """The case's images and page under folder; returns its record with the file names."""
    return place_case(case_output(result), folder, prov, index_href)


def place_case_under(out: Path, output: CaseOutput, prov: dict[str, str]) -> CaseRecord:
    """The case's folder out/cases/SCENE/FEATURE, linked to out/index.html; returns its record
    with the page relative to out."""
    rel = Path("cases") / slug(output.row.scene) / slug(output.row.feature)
    row = place_case(output, out / rel, prov, "../../../index.html")
    return replace(row, page=f"{rel.as_posix()}/index.html")


def write_case_under(out: Path, result: CaseResult, prov: dict[str, str]) -> CaseRecord:
    """place_case_under for a result of this process (the pytest plugin runs cases itself)."""
    return place_case_under(out, case_output(result), prov)


@dataclass(frozen=True)
class Job:
    """One case to run: everything a worker needs, picklable."""

    case: Case
    candidate: Renderer
    reference: Renderer
    settings: CaseSettings
    label: str = ""  # what progress lines prefix the case's id with (grade: the submission)
    # the causes found in the program's other cases, tried first: a jittered case's, its
    # scene's unjittered ones (program_priors); an unjittered case's, those of the program's
    # cases in the waves before its own (first_waves)
    priors: tuple[tuple[Switch, ...], ...] = ()
    # the causes the program's passing cases rule out, and those cases (refutation.py)
    refuting: Refuting = Refuting()

    def key(self) -> str:
        """The result cache's key: what the result depends on."""
        return content_key(
            request_key(self.candidate, self.case.scene.path, self.case.request),
            self.reference.identity(), self.case.feature, self.case.scene.depth_origin,
            *self.settings.key(), [[s.exact for s in prior] for prior in self.priors],
            self.refuting.key())

    def ran(self, output: CaseOutput) -> Ran:
        """The job's output as the refutation of causes reads it."""
        return Ran(self.program, self.case, output.row, candidate_images(output),
                   self.settings.tolerance)

    def ran_result(self, result: CaseResult) -> Ran:
        """The job's result (run in this process) as the refutation of causes reads it."""
        return Ran(self.program, self.case, case_record(result),
                   result.images.get(Role.CANDIDATE) if result.passed else None,
                   self.settings.tolerance)

    @property
    def program(self) -> tuple[str, str]:
        """Whose case it is: the label (a graded submission's) and the candidate's name."""
        return self.label, self.candidate.name


def run_job(job: Job, threads: int | None) -> CaseOutput:
    """The pure function a worker runs: case in, row and picture files out."""
    use_threads(threads)
    return case_output(run_case(job.case, job.candidate, job.reference, job.settings,
                                job.priors, job.refuting))


def scene_priors(found: Iterable[tuple[Switch, ...]]) -> tuple[tuple[Switch, ...], ...]:
    """A jittered case's priors: the explanations its scene's unjittered cases of the same
    program found (`found`, in the matrix's order, each case's cause before the explanations
    its images cannot tell from it; () where one found none), each once."""
    return tuple(dict.fromkeys(f for f in found if f))


def program_priors(done: list[Job], rows: list[CaseRecord], jobs: list[Job]) -> list[Job]:
    """`jobs` (jittered) with their priors (scene_priors) from the records of the jobs `done`
    (unjittered, in the same order): a function of those cases' results, whatever order they
    ran in (the pytest plugin, which runs one case at a time, gives the same)."""
    found: dict[tuple[tuple[str, str], str], list[tuple[Switch, ...]]] = {}
    for job, row in zip(done, rows):
        found.setdefault((job.program, row.scene), []).extend(_explanations(row))
    return [replace(job, priors=scene_priors(
        found.get((job.program, scene_id(job.case.scene)), ()))) for job in jobs]


Done = TypeVar("Done")  # what a job gives: its CaseOutput, or its CaseResult


def _explanations(row: CaseRecord) -> list[tuple[Switch, ...]]:
    return [tuple(parse_switch(s) for s in spelled) for spelled in (row.causes,
                                                                   *row.alternatives)]


def first_waves(first: list[Job], run: Callable[[list[Job]], list[Done]],
                record: Callable[[Done], CaseRecord]) -> list[Done]:
    """What the unjittered jobs `first` give, run in three waves: each program's first case;
    its first case of each other scene; its other cases. Each job gets the causes its program's
    cases of the waves before found as priors (the job with them replaces the job in
    `first`), so that a mistake found once is tried first everywhere else (causes.py). A
    function of the earlier waves' results, whatever order their cases ran in. Where `run`
    gives fewer results than jobs (a benchmark's run stopped at a timeout), those it gave.
    The waves and the priors' order follow the cases' ids (a scene's plain case first), not
    the order the scenes were given in, so that what a case names does not depend on it."""
    def canonical(i: int) -> tuple[tuple[str, str], str, bool, str]:
        case = first[i].case
        return first[i].program, scene_id(case.scene), case.feature != "plain", case.feature

    order = sorted(range(len(first)), key=canonical)
    programs: dict[tuple[str, str], int] = {}
    scenes: dict[tuple[tuple[str, str], str], int] = {}
    for i in order:
        programs.setdefault(first[i].program, i)
        scenes.setdefault((first[i].program, scene_id(first[i].case.scene)), i)
    opening, leading = set(programs.values()), set(scenes.values())
    waves = ([i for i in order if i in opening], [i for i in order if i in leading - opening],
             [i for i in order if i not in leading])
    found: dict[tuple[str, str], list[tuple[Switch, ...]]] = {}
    out: dict[int, Done] = {}
    for wave in waves:
        for i in wave:
            first[i] = replace(first[i], priors=scene_priors(found.get(first[i].program, ())))
        done = run([first[i] for i in wave])
        if len(done) < len(wave):
            return [*out.values(), *done]
        for i, result in zip(wave, done):
            out[i] = result
            found.setdefault(first[i].program, []).extend(_explanations(record(result)))
    return [out[i] for i in range(len(first))]


def refuting_rounds(first: list[Job], done: list[Done],
                    again: Callable[[list[Job]], list[Done]],
                    trials: Callable[[list[Trial]], list[tuple[Refutation, ...]]],
                    read: Callable[[Job, Done], Ran]) -> Refuter:
    """The causes of the unjittered jobs `first` (what they gave, `done`: their outputs, or
    their results; `read` reads one as a Ran) tried on the cases each program passes
    (refutation.py); the failing jobs whose cause is refuted run `again` without it, in
    place in both lists, for up to ROUNDS rounds. Returns the refutations, which the
    jittered jobs leave out too."""
    refuter = Refuter()
    for _ in range(ROUNDS):
        ran = [read(job, output) for job, output in zip(first, done)]
        tried = refuter.trials(ran)
        refuter.take(ran, tried, trials([t for _, t in tried]))
        rerun = {i: replace(first[i], refuting=r) for i, r in refuter.again(ran).items()
                 if r.refuted != first[i].refuting.refuted}
        if not rerun:
            break
        for i, output in zip(rerun, again(list(rerun.values()))):
            first[i], done[i] = rerun[i], output
    return refuter


def narrowed_round(ran: list[Job], done: list[Done], read: Callable[[Done], CaseRecord],
                   swap: Callable[[Done, Swap], Done],
                   by_scene: SceneViews | None = None) -> list[Done]:
    """`done` (what the jobs `ran` gave; `read` reads one's record) with the located findings
    each program's cases narrow to one function (cross_case.py), and its crashes the scenes
    they happen in locate (crash_scenes.py), swapped in (`swap`).
    by_scene: the views of passing cases' scenes rendered so far, kept by a caller that
    narrows again."""
    out = list(done)
    programs: dict[tuple[str, str], list[int]] = {}
    for i, job in enumerate(ran):
        programs.setdefault(job.program, []).append(i)
    by_scene = {} if by_scene is None else by_scene
    for indices in programs.values():
        cases, rows = [ran[i].case for i in indices], [read(out[i]) for i in indices]
        swaps = narrowings(cases, rows, by_scene)
        for j, crash in crash_narrowings(cases, rows).items():
            swaps.setdefault(j, {}).update(crash)
        for j, found in swaps.items():
            out[indices[j]] = swap(out[indices[j]], found)
    return out


def narrowed_output(output: CaseOutput, swaps: Swap) -> CaseOutput:
    return replace(output, row=narrowed_record(output.row, swaps))


def narrowed_result(result: CaseResult, swaps: Swap) -> CaseResult:
    for kind in result.kinds:
        kind.findings[:] = [g for f in kind.findings for g in swaps.get(f, (f,))]
    return result


@dataclass
class Runner:
    """How a run's cases are executed: on which workers, with which result cache, and
    whether finished results are reused (--resume)."""

    workers: Workers = field(default_factory=lambda: Workers(InlineExecutor(), 1, None))
    cache: ResultCache | None = None
    resume: bool = False
    quiet: bool = False

    def run(self, jobs: list[Job]) -> list[CaseOutput]:
        """Every job's output in the order of `jobs`, whatever order they finish in; cached
        ones (with resume) without running them. Each result is cached as soon as it
        arrives, so an interrupted run loses only the cases still running. The unjittered
        jobs run first, and the failing ones whose cause a passing case refutes run again
        without it (refuting_rounds): the jittered ones get their causes as priors
        (program_priors) and leave the refuted ones out; last, each program's cases narrow
        its located findings (narrowed_round)."""
        if self.cache is not None and not self.resume:
            self.cache.clear()
        first = [j for j in jobs if not j.case.jittered]
        progress = Progress(len(jobs), quiet=self.quiet)
        done = first_waves(first, lambda wave: self._run(wave, progress),
                           lambda output: output.row)

        def again(jobs: list[Job]) -> list[CaseOutput]:
            progress.total += len(jobs)
            return self._run(jobs, progress)

        def trials(chosen: list[Trial]) -> list[tuple[Refutation, ...]]:
            return [f.result() for f in [self.workers.executor.submit(
                run_trial, t, self.workers.threads) for t in chosen]]

        refuter = refuting_rounds(first, done, again, trials, Job.ran)
        then = program_priors(first, [o.row for o in done],
                              [replace(j, refuting=refuter.of(j.program))
                               for j in jobs if j.case.jittered])
        later = iter(self._run(then, progress))
        early = iter(done)
        return narrowed_round(jobs, [next(later) if j.case.jittered else next(early)
                                     for j in jobs], lambda output: output.row, narrowed_output)

    def _run(self, jobs: list[Job], progress: Progress) -> list[CaseOutput]:
        keys = [job.key() if self.cache is not None else "" for job in jobs]
        outputs: list[CaseOutput | None] = [
            self.cache.load(k) if self.cache is not None and self.resume else None for k in keys]
        progress.total -= sum(o is not None for o in outputs)
        todo = iter([i for i, o in enumerate(outputs) if o is None])
        running: dict[Future, int] = {}
        # a window of queued cases, not all of them at once: results (and the cache) fill up
        # as cases finish, and in this process (-j 1) each case runs as it is submitted
        window = 1 if isinstance(self.workers.executor, InlineExecutor) \
            else 2 * self.workers.slots
        while True:
            for i in islice(todo, window - len(running)):
                running[self.workers.executor.submit(run_job, jobs[i], self.workers.threads)] = i
            if not running:
                break
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                i = running.pop(future)
                output = outputs[i] = future.result()
                if self.cache is not None:
                    self.cache.store(keys[i], output)
                row = output.row
                worst = next((f for k in row.kinds for f in k.failures), "")
                progress.step(f"{jobs[i].label}{jobs[i].case.id} {row.verdict}"
                              f"{': ' + worst if worst else ''}", failed=not row.passed)
        return outputs  # type: ignore[return-value]  # every slot is filled above


def matrix_jobs(matrix: Matrix) -> tuple[list[Job], list[SkipRecord]]:
    cases, skips = matrix.cases()
    return [Job(c, matrix.candidate, matrix.reference, matrix.settings) for c in cases], skips


def run_matrix(matrix: Matrix, out: Path, prov: dict[str, str], quiet: bool = False,
               runner: Runner | None = None) -> tuple[list[CaseRecord], list[SkipRecord], float]:
    """Runs every case (in this process unless `runner` says otherwise), writing each one's
    folder under out/cases/ and showing progress; returns (case records, skipped rows,
    seconds)."""
    out.mkdir(parents=True, exist_ok=True)
    runner = runner or Runner(quiet=quiet)
    start = time.perf_counter()
    jobs, skips = matrix_jobs(matrix)
    rows = [place_case_under(out, o, prov) for o in runner.run(jobs)]
    return rows, skips, time.perf_counter() - start


def overview_cells(rows: list[CaseRecord]) -> dict[tuple[str, str], html.OverviewCell]:
    """(scene, feature family) -> its case's cell."""
    cells = {}
    for row in rows:
        folder = row.page.rsplit("/", 1)[0]
        kind = overview_kind(list(row.files))
        files = row.files.get(kind, {}) if kind is not None else {}
        thumbs = tuple((f"{folder}/{files.get('thumb_' + r, files[r])}", r)
                       for r in (Role.CANDIDATE, "diff") if r in files)
        title = next((f for k in row.kinds for f in k.failures), str(row.verdict))
        finding = row.top_finding()
        verdict = str(row.verdict)
        if finding:
            title += f"; finding {finding.code}: {finding.message}"
            if finding.code.startswith("quirk:") and row.verdict == Verdict.PASS:
                title = f"pass (quirk): {finding.message}"
        family = case_family(row.feature)
        bounces = "".join(c for c in row.feature if c.isdigit())
        note = (f"{bounces} bounce{'s' if bounces != '1' else ''}" if bounces else "")
        cells[(row.scene, family)] = html.OverviewCell(verdict, row.page, title, thumbs, note)
    return cells


def families_in_order(rows: list[CaseRecord]) -> list[str]:
    present = {case_family(r.feature) for r in rows}
    return [f for f in FAMILIES if f in present]


def skipped_cells(skips: list[SkipRecord]) -> dict[tuple[str, str], str]:
    """(scene, feature family) -> why the scene has no case of it."""
    out: dict[tuple[str, str], str] = {}
    for s in skips:
        family = feature_family(s.feature)
        if s.kind == "all" and family is not None:
            out.setdefault((s.scene, family), s.reason)
    return out


def write_index(out: Path, rows: list[CaseRecord], skips: list[SkipRecord],
                labels: dict[Role, str], intro: str, prov: dict[str, str], title: str,
                extra: str = "", head: str = "") -> None:
    """The index: `head` (a check's diagnosis of the program), the matrix, every row."""
    scenes = list(dict.fromkeys(r.scene for r in rows))
    matrix = html.overview(overview_cells(rows), scenes, families_in_order(rows),
                           skipped_cells(skips)) if rows else ""
    (out / "index.html").write_text(
        html.index_page(rows, skips, labels, intro, prov, title, matrix, extra, head),
        encoding="utf-8")


def summary(rows: list[CaseRecord]) -> Summary:
    """Counts of kind verdicts."""
    verdicts = [k.verdict for row in rows for k in row.kinds]
    return Summary(verdicts.count(Verdict.PASS), verdicts.count(Verdict.FAIL),
                   verdicts.count(Verdict.ERROR))


def write_junit(path: Path, rows: list[CaseRecord], suite: str) -> None:
    """One testcase per case and kind (classname scene, name feature/kind), failures and errors
    with their messages, skipped kinds left out."""
    counts = summary(rows)
    cases = []
    for row in rows:
        for k in row.kinds:
            seconds = (row.times.get(Role.CANDIDATE) or {}).get("cold_s") or 0.0
            attrs = (f'classname={quoteattr(row.scene)} '
                     f'name={quoteattr(row.feature + "/" + k.kind)} time="{seconds:.3f}"')
            message = "; ".join(k.failures)
            if k.verdict == Verdict.PASS:
                cases.append(f"  <testcase {attrs}/>")
            else:
                tag = "failure" if k.verdict == Verdict.FAIL else "error"
                code = k.findings[0].code if k.findings else str(k.verdict)
                cases.append(f"  <testcase {attrs}>\n    <{tag} message={quoteattr(message)} "
                             f"type={quoteattr(code)}/>\n  </testcase>")
    total = counts.passed + counts.failed + counts.errors
    path.write_text(
        '<?xml version="1.0" encoding="utf-8"?>\n'
        f'<testsuite name={quoteattr(suite)} tests="{total}" failures="{counts.failed}" '
        f'errors="{counts.errors}" skipped="0">\n' + "\n".join(cases) + "\n</testsuite>\n",
        encoding="utf-8")


def write_json(path: Path, data: Any) -> None:
    path.write_text(json_text(data), encoding="utf-8")
