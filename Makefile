# situate — run `make help` for the targets.
SHELL := /bin/bash
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo

.DEFAULT_GOAL := help
.PHONY: help demo test test-rust test-python python lint bench system-deps

help: ## Show the targets.
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | awk 'BEGIN {FS = ":.*## "} {printf "  make %-10s %s\n", $$1, $$2}'

demo: ## Run the demo: the toy robot of examples/toybot.yaml for 10 s, then its summary.
	$(CARGO) run --release -q -p situate_cli -- run examples/toybot.yaml --cycles 200

test: system-deps lint test-rust test-python ## Run every test in every language (what CI runs).

system-deps: ## Install the system tools the tests use (iproute2), when missing.
	scripts/system-deps.sh

lint: ## Formatting and lints: rustfmt, clippy -D warnings.
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets --locked -- -D warnings

test-rust: ## The Rust tests (unit, integration, property, doc).
	$(CARGO) test --workspace --locked

python: ## Build the Python package (wheel) and install it into .venv.
	scripts/python.sh

test-python: ## Python: ruff, ruff format --check, mypy --strict, pytest (builds the wheel first).
	scripts/python.sh test

bench: python ## Run the benchmarks (ratios in one run; see bench/README.md): the core, then the link.
	$(CARGO) bench -p situate_bench --locked --bench core
	bench/link/run.sh
