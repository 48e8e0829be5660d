#!/usr/bin/env bash
# The whole test suite, from a clean checkout: installs the package (building the Rust
# extension) with its test dependencies, then runs the Rust unit tests, the stub check and
# pytest. Extra arguments go to pytest (e.g. `-m slow` for the opt-in soaks).
set -euo pipefail
cd "$(dirname "$0")/.."

python -m pip install --quiet --upgrade pip
python -m pip install --quiet -e ".[test]"

cargo test --quiet
python -m mypy.stubtest ctxmodels._core
python -m pytest -q "$@"
