# asmplan: set-up, demo, tests. Everything installs into .venv with pip.
# torch is pinned to the CPU build 2.13.0 first; the project's range (>=2.3,<2.15) then keeps it.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: venv install demo test lint format bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e '.[test,cluster,step]'
	$(BIN)/python -m asmplan.warmup  # compile the numba kernels once (about a minute)
	touch $(STAMP)

venv: $(STAMP)
install: $(STAMP)

demo: $(STAMP)
	$(BIN)/asmplan plan examples/vacuum_pump --output results/vacuum_pump

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m pytest

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff format .
	$(BIN)/ruff check --fix .

bench: $(STAMP)
	$(BIN)/python benchmarks/solve_scale.py
	$(BIN)/python benchmarks/fractional_costs.py
	$(BIN)/python benchmarks/relations_scale.py
	$(BIN)/python benchmarks/state_graph_scale.py

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
