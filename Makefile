# situate — run `make help` for the targets.
SHELL := /bin/bash
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo

.DEFAULT_GOAL := help
.PHONY: help demo test test-rust test-python test-gui python gui lint fmt build build-tests build-more wheel prepare bench system-deps

help: ## Show the targets.
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | awk 'BEGIN {FS = ":.*## "} {printf "  make %-12s %s\n", $$1, $$2}'

demo: python gui ## The delivery demo: simulator, manager, Python sequencer; GUI on http://127.0.0.1:8080.
	$(CARGO) run --release -p situate_cli -- demo --python .venv/bin/python $(DEMO_ARGS)

test: ## Run every test in every language (what CI runs); one line per stage with its time, and the total.
	scripts/test.sh

system-deps: ## Install the system tools the tests use (iproute2), when missing.
	scripts/system-deps.sh

# The example crate outside the workspace (your own `situate` with Rust skills), linted in the
# workspace's target folder with the workspace's features, so it reuses what clippy compiled there.
EXTENSION := --manifest-path examples/rust/extension/Cargo.toml

lint: fmt ## Formatting and lints: rustfmt, clippy -D warnings.
	$(CARGO) clippy --workspace --all-targets --locked -- -D warnings
	$(CARGO) clippy $(EXTENSION) --all-targets --locked --features workspace-features \
		--target-dir "$${CARGO_TARGET_DIR:-target}" -- -D warnings

fmt: ## Formatting: rustfmt --check (the workspace and the extension example).
	$(CARGO) fmt --all -- --check
	$(CARGO) fmt $(EXTENSION) -- --check

# `make test`'s compile: every target of the workspace (tests, benches, examples) and the extension
# example, each compiled once. Under scripts/test.sh, which sets clippy-driver as the workspace's
# compiler, this is also the lint (`make lint`'s clippy) without a second, check-only compile.
build: build-tests build-more ## Compile every test target (under `make test`: with clippy's lints as errors).

build-tests: ## Compile the workspace's tests, programs and examples (what every test stage needs).
	@if [ -n "$${RUSTC_WORKSPACE_WRAPPER:-}" ]; then scripts/lint-canary.sh; fi
	$(CARGO) test --workspace --locked --no-run

build-more: ## Compile the benches and the extension example (only `test-rust` needs them).
	$(CARGO) test --workspace --benches --locked --no-run
	CARGO_INCREMENTAL=0 $(CARGO) build $(EXTENSION) --locked --features workspace-features \
		--target-dir "$${CARGO_TARGET_DIR:-target}"

wheel: ## Build the Python package as the tests use it (debug, reusing build-tests) into .venv.
	SITUATE_PY_PROFILE=debug scripts/python.sh

prepare: ## Install the tools the tests download: the Python tools in .venv, Chromium.
	scripts/python.sh tools
	scripts/gui.sh chromium

test-rust: ## The Rust tests (unit, integration, property, doc; tests/extension.rs builds examples/rust/extension).
	$(CARGO) test --workspace --locked

gui: ## Build the GUI's web app (web/dist, embedded into the `situate` program).
	scripts/gui.sh build

test-gui: ## The GUI in a real browser (headless Chromium, installed when missing).
	scripts/gui.sh test

python: ## Build the Python package (wheel) and install it into .venv.
	scripts/python.sh

test-python: ## Python: ruff, ruff format --check, mypy --strict, pytest (builds the wheel first).
	scripts/python.sh test

bench: python gui ## Run the benchmarks (ratios in one run; see bench/README.md).
	$(CARGO) bench -p situate_bench --locked --bench core
	$(CARGO) bench -p situate_bench --locked --bench languages
	$(CARGO) bench -p situate_bench --locked --bench ros2
	.venv/bin/python bench/python/overhead.py
	bench/link/run.sh
	bench/gui/run.sh
