# Each target sets up what it needs; a fresh Debian 12 machine with Python 3.11 is enough.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install test report bench findings causes mutants clean

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

# The report is what a first look needs: every comparison, the stress page, the sweeps. The
# benchmarks are targets of their own, each writing out/NAME.json; the report's benchmark page
# shows this machine's `make bench` where it has run, else the run shipped in docs/bench.json
# (the page names its machine), and its findings page is there once `make findings` has run.
report: install
	$(VENV)/bin/raycheck report --out out \
		--bench $(firstword $(wildcard out/bench.json) docs/bench.json) \
		$(if $(wildcard out/findings.json),--findings out/findings.json)

# render times of the course scenes in both renderers and the BVH's throughput, on this machine
bench: install
	mkdir -p out
	$(VENV)/bin/raycheck bench --throughput --json out/bench.json

# which bug the top finding names, for renderers with known bugs (tests/wrappers/); made again
# only when the findings, the wrapper bugs or the tracer change
findings: out/findings.json
out/findings.json: $(STAMP) tools/bench_findings.py $(wildcard harness/*.py harness/*/*.py tests/wrappers/*.py tracer/*.py tracer/*/*.py)
	mkdir -p out
	$(PY) tools/bench_findings.py --json $@

# the cause search against every mistake of the catalogue, alone and in pairs
causes: install
	mkdir -p out
	$(PY) tools/bench_causes.py --json out/causes.json

# the mutation benchmark's held-out sample: mutants of tests/solution_cpp (about 50 minutes)
mutants: install
	mkdir -p out
	$(PY) tools/bench_mutants.py --sample held-out --json out/mutants.json

clean:
	rm -rf $(VENV) out .pytest_cache
