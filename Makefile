# `make demo` and `make test` do all set-up themselves (a virtualenv in .venv, torch pinned first).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint docs bench clean

# PYTHONWARNINGS=ignore: no setuptools editable-install banner under --quiet
$(STAMP): pyproject.toml setup.py sb3_smc_gym_hook.pth
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip "setuptools>=77"
	$(PY) -m pip install --quiet torch==2.13.0
	PYTHONWARNINGS=ignore $(PY) -m pip install --quiet -e ".[test,docs]"
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m sb3_smc.demo

# the default suite on TEST_WORKERS processes (pytest-xdist), a test module's tests on one of them
TEST_WORKERS ?= 2
test: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile
	$(VENV)/bin/mypy
	$(MAKE) --no-print-directory docs

# the documentation site (docs/ + the API reference from the docstrings) in strict mode: a warning fails it
docs: $(STAMP)
	$(PY) -m mkdocs build --strict --quiet --site-dir site

# ruff, then the type check of both packages (mypy; its settings: [tool.mypy] in pyproject.toml)
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

bench: $(STAMP)
	$(PY) -m pip install --quiet minigrid
	$(PY) benchmarks/bench_env_steps.py
	$(PY) benchmarks/bench_generation.py
	$(PY) benchmarks/bench_training.py
	$(PY) benchmarks/bench_policies.py
	$(PY) benchmarks/bench_curriculum.py
	$(PY) benchmarks/bench_concepts.py
	$(PY) benchmarks/bench_pushing.py
	$(PY) benchmarks/bench_level2.py --timesteps 100000

clean:
	rm -rf $(VENV)
