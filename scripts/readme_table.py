"""The README's study table, regenerated from the committed confirmatory run
(docs/results/results.json): writes it between the README's markers, or with --check fails
(exit 1) when the README's table differs from what the results file gives.

    python scripts/readme_table.py            # rewrite README.md's table
    python scripts/readme_table.py --check    # the test suite runs this
"""
import argparse
import json
import sys
from pathlib import Path

from ctxmodels.experiment.report import README_MARKERS, readme_table

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results" / "results.json"


def current_block(text: str) -> str:
    start, end = README_MARKERS
    if text.count(start) != 1 or text.count(end) != 1:
        raise SystemExit(f"README.md: expected one of each marker {start!r} and {end!r}")
    i, j = text.index(start), text.index(end) + len(end)
    return text[i:j]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--readme", type=Path, default=ROOT / "README.md")
    parser.add_argument("--results", type=Path, default=RESULTS)
    args = parser.parse_args()
    text = args.readme.read_text(encoding="utf-8")
    block = current_block(text)
    wanted = readme_table(json.loads(args.results.read_text(encoding="utf-8")))
    if args.check:
        if block != wanted:
            print(f"{args.readme}: the study table differs from {args.results}; run "
                  "python scripts/readme_table.py", file=sys.stderr)
            return 1
        return 0
    args.readme.write_text(text.replace(block, wanted), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
