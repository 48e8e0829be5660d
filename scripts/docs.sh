#!/usr/bin/env bash
# The documentation (Sphinx: guide pages, the example gallery, the API reference) with
# warnings as errors. Every gallery example is executed, so a broken example fails the
# build. Needs the `docs` (or `test`) extra installed; installs nothing itself.
set -euo pipefail
cd "$(dirname "$0")/.."
export MPLBACKEND=Agg
# -E: a fresh environment, so every warning is reported, not only those of changed files
# (sphinx-gallery still re-runs only the examples that changed since the last build).
python -m sphinx -W --keep-going -E -b html docs docs/_build/html "$@"
