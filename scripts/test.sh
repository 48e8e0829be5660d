#!/usr/bin/env bash
# The whole test suite, from a clean checkout: installs the package (building the Rust
# extension) with its test dependencies, then runs the linters (ruff, cargo fmt, clippy),
# the Rust unit tests, the stub check and pytest. Extra arguments go to pytest (e.g.
# `-m slow` for the opt-in soaks).
set -euo pipefail
cd "$(dirname "$0")/.."

python -m pip install --quiet --upgrade pip
python -m pip install --quiet -e ".[test]"

python -m ruff check python tests benches scripts docs/examples
cargo fmt --check
cargo clippy --quiet --all-targets --all-features -- -D warnings
cargo test --quiet
python -m mypy.stubtest ctxmodels._core
python -m pytest -q "$@"
