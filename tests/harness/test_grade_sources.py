"""`raycheck grade` on a class of C++ sources, built with CMake in the sandbox.

The submissions are made here, for the test: each is a copy of the starter-shaped C++ solution
(tests/solution_cpp/), some with a mistake written into its C++, so that what each row must
say is known: real programs, as a teacher's class. They differ in how they come and how they
build: a folder with its CMakeLists.txt (clean), a .zip (shadow rays never cast), a .tar.gz of
the starter's layout without a CMakeLists.txt, a git bundle whose CMakeLists asks for C++11
where the code needs C++17, one that does not compile, and a hostile one that tries to write
outside its folder, read another submission's sources, reach the network and leave a process
behind before it renders."""
from __future__ import annotations

import csv
import io
import json
import os
import shutil
import subprocess
import tarfile
import time
import zipfile
from pathlib import Path

import pytest
from gradescope_format import gradescope_problems
from listener import listening
from solution import Edit, copy_solution
from test_check import processes_naming

from raycheck.harness.cli.grade import main as grade_main

REPO = Path(__file__).resolve().parents[2]
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
NEEDS = [t for t in ("bwrap", "cmake", "g++", "git") if shutil.which(t) is None]
pytestmark = pytest.mark.skipif(bool(NEEDS), reason=f"not installed: {', '.join(NEEDS)}")

HOSTILE = r'''
    {   // what a sandbox must stop; the rendering after it is the course's
        FILE *f = fopen("OUTSIDE", "w");
        if (f) { fputs("escaped\n", f); fclose(f); }
        FILE *in = fopen("SECRET", "r");
        if (in) fprintf(stderr, "reached: the secret\n");
        int s = socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{}; a.sin_family = AF_INET; a.sin_port = htons(PORT);
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        if (s >= 0 && connect(s, (sockaddr *)&a, sizeof a) == 0) {
            fprintf(stderr, "reached: the network\n");
            if (write(s, "hi\n", 3) < 0) return 1;
        }
        if (fork() == 0) {
            setsid();
            if (fork() == 0) execl("/bin/sh", "MARKER", "-c", "sleep 60", (char *)0);
            _exit(0);
        }
    }
'''
HOSTILE_INCLUDES = """#include <arpa/inet.h>
#include <unistd.h>
#include <cstdio>
#include <netinet/in.h>
#include <sys/socket.h>
"""


# the slip of the shadowless submission: Renderer::traceRay never casts its shadow rays
NO_SHADOW_RAYS = Edit("src/Renderer.cpp", "        if (_args.shadows) {", "        if (false) {")


def write_program(folder: Path, edits: tuple[Edit, ...] = (), *, cmake: bool = True,
                  extra: str = "", includes: str = "") -> Path:
    """A submission's source tree in `folder`: the solution with `edits`, `includes` before its
    main.cpp's own and `extra` first in main()."""
    main = "src/main.cpp"
    code = (Edit(main, '#include "ArgParser.h"\n', includes + '#include "ArgParser.h"\n'),
            Edit(main, "{\n    ArgParser args", "{\n" + extra + "\n    ArgParser args"))
    copy_solution(folder, edits + code)
    if not cmake:
        (folder / "CMakeLists.txt").unlink()
    return folder


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """The class, graded once: (its folder, grades.csv's rows by name, what the hostile
    submission's attempts reached)."""
    tmp = tmp_path_factory.mktemp("class")
    subs = tmp / "submissions"
    write_program(subs / "clean")
    shadowless = write_program(tmp / "src" / "shadowless-1.0", (NO_SHADOW_RAYS,))
    with zipfile.ZipFile(subs / "shadowless.zip", "w") as z:
        for path in shadowless.rglob("*"):
            z.write(path, path.relative_to(shadowless.parent))
    starter = write_program(tmp / "src" / "starter", cmake=False)
    with tarfile.open(subs / "starter.tar.gz", "w:gz") as t:
        t.add(starter, arcname="starter")
    # the solution's CMakeLists.txt asks for C++11
    modern = write_program(tmp / "src" / "modern", includes="#include <optional>\n",
                           extra="std::optional<int> unused = 1; (void)unused;")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", "-C", str(modern)]
    subprocess.run(["git", "init", "-q", str(modern)], check=True)
    subprocess.run([*git, "add", "."], check=True)
    subprocess.run([*git, "commit", "-qm", "a2"], check=True)
    subprocess.run([*git, "bundle", "create", "-q", str(subs / "modern.bundle"), "HEAD"],
                   check=True)
    broken = write_program(subs / "broken")
    (broken / "src" / "main.cpp").write_text("int main() { return 0 }\n")

    secret = subs / "clean" / "src" / "main.cpp"
    outside = tmp / "escaped.txt"
    marker = f"raycheck-daemon-{os.getpid()}-{time.time_ns()}"
    with listening() as (port, heard):
        attack = HOSTILE.replace("OUTSIDE", str(outside)).replace("SECRET", str(secret)) \
            .replace("PORT", str(port)).replace("MARKER", marker)
        write_program(subs / "hostile", includes=HOSTILE_INCLUDES, extra=attack)
        out = tmp / "class"
        start = time.perf_counter()
        code = grade_main([str(subs / n) for n in ("clean", "shadowless.zip", "starter.tar.gz",
                                                   "modern.bundle", "broken", "hostile")]
                          + ["--scenes", str(SHADOWS), "--size", "12", "12", "--features",
                             "plain,shadows", "--out", str(out), "-j", "2", "--quiet",
                             "--sandbox", "required"])
        seconds = time.perf_counter() - start
    left = processes_naming(marker)
    for pid in left:
        os.kill(pid, 9)
    assert code == 0
    rows = {r["name"]: r for r in csv.DictReader(io.StringIO((out / "grades.csv").read_text()))}
    logs = [c["stderr_tail"] for c in
            json.loads((out / "hostile" / "check.json").read_text())["cases"]]
    reached = {"outside": outside.exists(), "heard": heard, "daemons": left,
               "said": sorted({ln for log in logs for ln in log.splitlines()
                               if ln.startswith("reached:")})}
    return out, rows, reached, seconds


def test_every_submission_has_its_row(graded):
    out, rows, _, seconds = graded
    table = {name: (float(r["score"]), r["plain passed"], r["shadows passed"], r["build"])
             for name, r in rows.items()}
    assert table == {
        "clean": (35.0, "1", "1", "built"),
        "shadowless": (20.0, "1", "0", "built"),
        "starter": (35.0, "1", "1", "built (no CMakeLists.txt: the starter's)"),
        "modern": (35.0, "1", "1", "built (needed C++17)"),
        "broken": (0.0, "0", "0", "build failed"),
        "hostile": (35.0, "1", "1", "built"),
    }, seconds


def test_a_submission_that_does_not_build_says_why(graded):
    out, rows, _, _ = graded
    # gcc's own words, the file named as in the submission
    assert rows["broken"]["build_error"].startswith("src/main.cpp:1:22: error: expected ")
    assert "int main() { return 0 }" in (out / "broken" / "build.log").read_text()
    results = json.loads((out / "broken" / "results.json").read_text())
    assert results["score"] == 0 and results["tests"][0]["status"] == "failed"
    assert results["tests"][0]["output"] == rows["broken"]["build_error"]


def test_the_cause_of_a_planted_mistake_is_named(graded):
    out, _, _, _ = graded
    grades = json.loads((out / "grades.json").read_text())
    shadowless = next(s for s in grades["submissions"] if s["name"] == "shadowless")
    assert shadowless["causes"] == {"shadows": "cause:shadow_missing"}
    page = (out / "index.html").read_text()
    assert "cause:shadow_missing" in page and 'id="histogram"' in page


def test_the_hostile_submissions_attempts_were_stopped(graded):
    _, _, reached, _ = graded
    assert reached == {"outside": False, "heard": [], "daemons": [], "said": []}


def test_the_same_sources_are_built_once(graded):
    out, rows, _, _ = graded
    builds = out.parent / ".class.cache" / "builds"
    kept = {json.loads(p.read_text())["sha256"] for p in builds.glob("*/build.json")}
    assert len(kept) == 6 and rows["clean"]["report"] == "clean/index.html"


def test_each_submission_has_gradescopes_results(graded):
    out, rows, _, _ = graded
    for name, row in rows.items():
        data = json.loads((out / name / "results.json").read_text())
        assert gradescope_problems(data) == [], name
        assert data["score"] == float(row["score"]), name
