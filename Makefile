# Each target sets up what it needs; a fresh Debian 12 machine with Python 3.11 is enough.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install test report clean

install: $(STAMP)

$(STAMP): pyproject.toml tools/ensure_llvm.sh
	bash tools/ensure_llvm.sh
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,mutants]'
	$(PY) -c "import raycheck.tracer.kernel.backend as b; b.import_drjit(); print('Dr.Jit uses', b.llvm_description())"
	touch $(STAMP)

# One worker per core (pytest-xdist), each test file in one worker: a file's module fixtures
# (a report, a check per defect) are made once. Bytecode is written even where the environment
# sets PYTHONDONTWRITEBYTECODE: without it every worker and every renderer process the tests
# start compiles its modules again, and pytest rewrites every test module and Hypothesis's
# (~8 s of CPU in the quick suite on 2 cores; __pycache__ is git-ignored).
TEST_WORKERS ?= auto

test: install
	bash tools/ensure_chromium.sh
	bash tools/ensure_grading_tools.sh
	$(VENV)/bin/ruff check --quiet .
	mkdir -p $(VENV)/mypy/raycheck
	for p in tracer mitsuba_ref harness; do ln -sfn ../../../$$p $(VENV)/mypy/raycheck/$$p; done
	$(VENV)/bin/mypy
	$(VENV)/bin/mypy tools
	env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest -q --numprocesses $(TEST_WORKERS) \
		--maxprocesses 8 --dist loadfile

# the findings benchmark, again only when the findings, the wrapper bugs or the tracer change
out/findings.json: $(STAMP) tools/bench_findings.py $(wildcard harness/*.py harness/*/*.py tests/wrappers/*.py tracer/*.py tracer/*/*.py)
	mkdir -p out
	$(PY) tools/bench_findings.py --json $@

report: install out/findings.json
	$(VENV)/bin/raycheck report --out out --findings out/findings.json

clean:
	rm -rf $(VENV) out .pytest_cache
