"""Suite-wide options: the comparison suite's full matrix runs in CI (CI=true) or with --full;
a quick subset runs otherwise. The browser tests' Chromium starts with the session."""
from __future__ import annotations

import os
import signal
from concurrent.futures import Future, ThreadPoolExecutor

import pytest

# commands run their cases in this process unless a test asks for workers (-j N): a pool's
# start-up (seconds) would dominate the few tiny cases of each test
os.environ.setdefault("RAYCHECK_JOBS", "1")


def pytest_addoption(parser):
    parser.addoption("--full", action="store_true",
                     help="run the whole comparison matrix (default in CI)")


def is_full_run(config: pytest.Config) -> bool:
    return bool(config.getoption("--full")) or os.environ.get("CI") == "true"


@pytest.fixture
def python_sigint_handler():
    """Python's own SIGINT handler, as a terminal's process has it: a test run started in the
    background by a shell (`cmd &`) inherits SIGINT ignored, which interrupts_raised leaves
    ignored, and the tests that use this send it."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.fixture(scope="session")
def full_run(request) -> bool:
    """Whether this is the full run: a test that tries a quick subset of its inputs otherwise
    tries them all (each such test says why its subset still covers the property)."""
    return is_full_run(request.config)


def pytest_configure(config):
    config.addinivalue_line("markers", "full: part of the full comparison matrix only")


@pytest.fixture(autouse=True, scope="session")
def _jitter_cache(tmp_path_factory):
    """The reference distributions of jittered cases go to a cache of the session's own, not
    the user's ~/.cache/raycheck."""
    previous = os.environ.get("RAYCHECK_CACHE")
    os.environ["RAYCHECK_CACHE"] = str(tmp_path_factory.mktemp("raycheck-cache"))
    yield
    if previous is None:
        del os.environ["RAYCHECK_CACHE"]
    else:
        os.environ["RAYCHECK_CACHE"] = previous


def pytest_collection_modifyitems(config, items):
    if is_full_run(config):
        return
    skip = pytest.mark.skip(reason="full comparison matrix: run with --full (CI does)")
    for item in items:
        if "full" in item.keywords:
            item.add_marker(skip)


def pytest_collection_finish(session):
    """Starts Chromium for the browser tests as the session begins, in a thread, where a test
    that will run uses it: its start is disk-bound (10.6 s with a cold page cache, 0.5 s warm,
    measured on the 2-core VM), so it overlaps the CPU-bound tests before them. Under
    pytest-xdist every worker collects every test but runs only some, so a worker starts it
    when its first browser test asks (make test's --dist loadfile sends them all to one)."""
    if session.config.option.collectonly or hasattr(session.config, "workerinput"):
        return
    if any("browser" in getattr(item, "fixturenames", ()) and not item.get_closest_marker("skip")
           for item in session.items):
        _start_browser(session.config)


def _start_browser(config: pytest.Config) -> Future | None:
    """This process's Chromium, started once, in a thread; None where there is none. It is
    closed when the session ends, whether or not a test used it (-x, Ctrl-C, a failed
    fixture)."""
    from cdp import Browser, find_chromium

    if _BROWSER not in config.stash:
        binary = find_chromium()
        started = None
        if binary is not None:
            pool = ThreadPoolExecutor(1, thread_name_prefix="chromium")
            started = pool.submit(Browser, binary)
            pool.shutdown(wait=False)
            config.add_cleanup(lambda: _close(started))
        config.stash[_BROWSER] = started
    return config.stash[_BROWSER]


def _close(started: Future) -> None:
    try:
        browser = started.result()
    except Exception:  # noqa: BLE001 - a start that failed left nothing to close
        return
    browser.close()


_BROWSER = pytest.StashKey["Future | None"]()


@pytest.fixture(scope="session")
def browser(request):
    """A headless Chromium (tests/cdp.py), started by pytest_collection_finish or now."""
    started = _start_browser(request.config)
    if started is None:
        pytest.skip("no Chromium on this machine (make test installs Debian's chromium as root)")
    return started.result()
