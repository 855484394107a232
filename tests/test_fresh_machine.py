"""The README's quick `make test` as a new user's machine runs it: an empty HOME (no Dr.Jit
kernel cache, no raycheck cache, no Matplotlib or Chromium state), none of this session's
RAYCHECK_/DRJIT_/PYTEST_ settings and not CI's full matrix. The suite this test belongs to
may run on warm caches, which once hid a failure that only cold kernels' timing showed (a
Ctrl-C landing while Dr.Jit traced); the quick suite run again from nothing cannot hide it.
Part of the full run (CI's), where it adds the quick suite's cold time (minutes)."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from new_user import cold_env

REPO = Path(__file__).resolve().parent.parent
LIMIT_S = 40 * 60  # the quick suite cold takes ~3 min alone on 2 cores; CI's run shares them


@pytest.mark.full
def test_the_quick_suite_passes_from_an_empty_home(tmp_path):
    home = tmp_path / "home"
    env = {k: v for k, v in cold_env(home).items()
           if k != "CI" and not k.startswith("PYTEST_")}
    # the outer run's cache of last failures is not the new user's, nor to be overwritten
    env["PYTEST_ADDOPTS"] = "-p no:cacheprovider"
    try:
        run = subprocess.run(["make", "--no-print-directory", "test"], cwd=REPO, env=env,
                             stdin=subprocess.DEVNULL, capture_output=True, text=True,
                             timeout=LIMIT_S)
    except subprocess.TimeoutExpired as e:
        pytest.fail(f"the quick suite from an empty HOME ran past {LIMIT_S} s:\n"
                    f"{(e.stdout or b'')[-4000:]!r}")
    tail = (run.stdout + run.stderr)[-6000:]
    assert run.returncode == 0, f"make test from an empty HOME failed:\n{tail}"
    summary = [line for line in run.stdout.splitlines()
               if re.search(r"\d+ passed", line)]
    assert summary and not re.search(r"\d+ (failed|error)", summary[-1]), tail
    # it ran cold, in that HOME: Dr.Jit compiled its kernels into a cache there
    kernels = home / ".drjit"
    assert kernels.is_dir() and any(kernels.iterdir()), f"no kernel cache in {home}:\n{tail}"
    # and quick: the full matrix's tests were skipped, CI's setting did not leak in
    assert re.search(r"\d+ skipped", summary[-1]), summary[-1]
