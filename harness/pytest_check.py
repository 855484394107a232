"""The pytest plugin's check (pytest_plugin.py): the matrix of the settings, one test item per
case and image kind, rendered once per case, and the results folder written as `raycheck check`
writes it."""
from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Generator, Iterator

import pytest

from raycheck.tracer.scene import SceneError

from .cases import Case
from .check_options import ConfigError
from .commands.check import write_check
from .commands.check_config import CheckConfig
from .diagnosis.cross_case import SceneViews
from .diagnosis.refute import refutations
from .judge.verdict import KindVerdict
from .pipeline.case import CaseResult, run_case
from .pipeline.matrix import (
    Job,
    Matrix,
    case_record,
    first_waves,
    narrowed_result,
    narrowed_round,
    refuting_rounds,
    scene_id,
    scene_priors,
    write_case_under,
)
from .pipeline.refutation import Refuter
from .provenance import provenance
from .records import CaseRecord, SkipRecord, Verdict

if TYPE_CHECKING:
    from _pytest._code.code import TerminalRepr


def register(config: pytest.Config, settings: dict[str, Any]) -> None:
    """The session's check, from the settings (option name -> the command line's value, else
    the ini file's, else None); a bad one is a usage error naming the plugin's own option."""
    from raycheck.tracer.cache import size_limit

    try:
        size_limit()  # as every raycheck command does before it starts
        matrix = _config(settings).matrix()
    except ConfigError as e:
        raise pytest.UsageError(f"raycheck: --raycheck-{e.option}: {e.problem}") from None
    except (SceneError, ValueError) as e:
        raise pytest.UsageError(f"raycheck: {e}") from None
    config.pluginmanager.register(CheckRun(matrix, _results(config)), "raycheck-run")


def _config(settings: dict[str, Any]) -> CheckConfig:
    size, timeout = settings["size"], settings["timeout"]
    return CheckConfig(
        renderer=settings["renderer"], reference=settings["reference"] or "tracer",
        scenes=tuple(settings["scenes"] or ()),
        size=_size(size),
        features=settings["features"],
        timeout=CheckConfig.timeout if timeout is None else float(timeout))


def _size(size: list[str] | list[int] | None) -> tuple[int, int] | None:
    """--raycheck-size W H (ints from the command line, words from an ini file); whether they
    are at least 1 is CheckConfig's to say."""
    if not size:
        return None
    try:
        width, height = (int(side) for side in size)
    except ValueError:  # not numbers, or not two of them
        raise ConfigError("size", f"expected W H, found {' '.join(map(str, size))}") from None
    return width, height


def _results(config: pytest.Config) -> Path | None:
    """The results folder: the command line's, else the ini file's relative to that file."""
    results = config.getoption("raycheck_results")
    if results is None and config.getini("raycheck_results"):
        base = config.inipath.parent if config.inipath else config.rootpath
        results = base / config.getini("raycheck_results")
    return results


class CheckRun:
    """The session's matrix and each case's result, rendered at most once, and the rows the
    results folder's index is made of."""

    def __init__(self, matrix: Matrix, results: Path | None) -> None:
        self.matrix = matrix
        self.results = results
        self.skips: list[SkipRecord] = []
        self.rows: dict[tuple[str, str], CaseRecord] = {}  # case -> its record, with results
        self.seconds = 0.0
        self._done: dict[tuple[str, str], CaseResult] = {}
        self._prov: dict[str, str] | None = None
        self.cases: list[Case] = []  # the matrix's, once collected
        self._refuter = Refuter()  # the unjittered cases' refuted causes, once run
        self._unjittered_run = False
        self._views: SceneViews = {}  # cross_case.py's, of passing cases' scenes

    @pytest.hookimpl(wrapper=True)
    def pytest_make_collect_report(
            self, collector: pytest.Collector
    ) -> Generator[None, pytest.CollectReport, pytest.CollectReport]:
        """Hangs the cases under the session itself: they need no test file."""
        report = yield
        if isinstance(collector, pytest.Session) and report.passed:
            report.result.append(CheckCollector.from_parent(collector, name="raycheck",
                                                            nodeid="raycheck", run=self))
        return report

    def result(self, case: Case) -> CaseResult:
        """The case's result, rendering it the first time one of its kinds asks: as `raycheck
        check` does (pipeline/matrix.py), every unjittered case at the first, with the
        rounds that refute causes by the cases the program passes; a jittered case with
        their causes as priors."""
        key = _key(case)
        if not self._unjittered_run:  # a jittered case's refutations are every scene's
            self._unjittered()
        if key not in self._done:
            priors = scene_priors(e for other in self.cases
                                  if not other.jittered and other.scene == case.scene
                                  for e in self.result(other).explanations)
            job = self._job(case)
            job = replace(job, priors=priors, refuting=self._refuter.of(job.program))
            unjittered = [c for c in self.cases if not c.jittered]
            # narrowed by the unjittered cases (already narrowed: no longer open) and itself
            narrowed = narrowed_round([*map(self._job, unjittered), job],
                                      [*(self._done[_key(c)] for c in unjittered),
                                       self._run([job])[0]],
                                      case_record, narrowed_result, self._views)
            self._store(narrowed[-1])
        return self._done[key]

    def _job(self, case: Case) -> Job:
        m = self.matrix
        return Job(case, m.candidate, m.reference, m.settings)

    def _run(self, jobs: list[Job]) -> list[CaseResult]:
        start = time.perf_counter()
        results = [run_case(j.case, j.candidate, j.reference, j.settings, j.priors, j.refuting)
                   for j in jobs]
        self.seconds += time.perf_counter() - start
        return results

    def _unjittered(self) -> None:
        self._unjittered_run = True
        jobs = [self._job(c) for c in self.cases if not c.jittered]
        results = first_waves(jobs, self._run, case_record)
        self._refuter = refuting_rounds(jobs, results, self._run,
                                        lambda trials: [refutations(t) for t in trials],
                                        Job.ran_result)
        results = narrowed_round(jobs, results, case_record, narrowed_result, self._views)
        for result in results:
            self._store(result)

    def _store(self, result: CaseResult) -> None:
        key = _key(result.case)
        self._done[key] = result
        if self.results is not None:
            self.rows[key] = write_case_under(self.results, result, self.prov)

    @property
    def prov(self) -> dict[str, str]:
        if self._prov is None:
            self._prov = provenance()
        return self._prov

    def pytest_sessionfinish(self) -> None:
        if self.results is not None and self.rows:
            write_check(self.matrix, self.results, list(self.rows.values()), self.skips,
                        self.seconds, self.prov, junit=False)


def _key(case: Case) -> tuple[str, str]:
    return scene_id(case.scene), case.feature


class CheckCollector(pytest.Collector):
    """The node `raycheck`: the matrix's cases, found when pytest collects, not at start-up
    (scene analysis is work that `pytest --help` should not do)."""

    def __init__(self, *, run: CheckRun, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.run = run

    def collect(self) -> Iterator[pytest.Item]:
        cases, self.run.skips = self.run.matrix.cases()
        self.run.cases = cases
        for case in cases:
            for kind in case.request.kinds:
                yield KindItem.from_parent(self, name=f"{scene_id(case.scene)}/{case.feature}/"
                                           f"{kind}", case=case, kind=kind)


class KindFailed(Exception):
    """A kind's verdict was not pass; the message is what the test report shows."""


class KindItem(pytest.Item):
    """One image kind of one case: passes where the kind's verdict does."""

    def __init__(self, *, case: Case, kind: str, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.case = case
        self.kind = kind

    def runtest(self) -> None:
        assert isinstance(self.parent, CheckCollector)  # the collector made this item
        run = self.parent.run
        verdict = next(k for k in run.result(self.case).kinds if k.kind == self.kind)
        if not verdict.passed:
            raise KindFailed(self._message(verdict, run))

    def _message(self, verdict: KindVerdict, run: CheckRun) -> str:
        """The failures (an error's finding codes and messages; a failure's findings after
        it), first line first, as pytest's short summary and JUnit show that; then the case's
        page."""
        if verdict.verdict == Verdict.ERROR:
            lines = [f"{f.code}: {f.message}" for f in verdict.findings]
        else:
            lines = [f"{line} (against {run.matrix.reference.name})" for line in verdict.failures]
            lines += [f"finding {f.code}: {f.message}" for f in verdict.findings]
        if run.results is not None:
            lines.append(f"page: {run.results / run.rows[_key(self.case)].page}")
        return "\n".join(lines)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException],
                     style=None) -> str | TerminalRepr:
        if isinstance(excinfo.value, KindFailed):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.case.scene.path, None, self.name
