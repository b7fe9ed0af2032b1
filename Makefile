# andyc: `make demo` runs a shipped example, `make test` the test suite,
# `make bench` the benchmarks. Each creates .venv and installs andyc first.
VENV ?= .venv
PY := $(VENV)/bin/python
ANDYC := $(VENV)/bin/andyc
STAMP := $(VENV)/.andyc-installed
DEMO := double_pendulum

.PHONY: demo test bench mutation clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(ANDYC) check models/$(DEMO).yaml
	$(ANDYC) build models/$(DEMO).yaml
	$(ANDYC) sim models/$(DEMO).yaml --t-end 20 --dt 1e-3 --every 10 --frames all \
		--out runs/$(DEMO).h5 --out runs/$(DEMO).csv
	$(ANDYC) plot runs/$(DEMO).h5 -o runs/$(DEMO).png

# Test files run in parallel, one worker per core (pytest-xdist), a file's tests on one worker so that
# the models it compiles are compiled once.
# Then every shipped model's expectations (expect:), on the builds the tests made (build/tests).
test: $(STAMP)
	$(VENV)/bin/pytest -q -n auto --dist loadfile
	$(ANDYC) test models/ --build-dir build/tests

bench: $(STAMP)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test,bench]'
	$(PY) bench/run.py
	$(PY) bench/latency.py
	$(PY) bench/ci_latency.py
	$(PY) bench/sweep.py
	$(PY) bench/go1.py
	$(PY) bench/view_page.py

# Mutation testing of the core (docs/mutation.md): slow, not in CI nor in `make test`. MUTANTS narrows the
# run to mutant names (globs of module.function), e.g. make mutation MUTANTS='andyc.analysis.sweeps.metrics*'.
mutation: $(STAMP)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test,mutation]'
	$(VENV)/bin/mutmut run $(MUTANTS)
	mkdir -p build
	$(VENV)/bin/mutmut results --all true > build/mutation-results.txt
	@echo "surviving and killed mutants: build/mutation-results.txt"

clean:
	rm -rf build runs .pytest_cache mutants
