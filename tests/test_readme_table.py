"""The README's study table is the committed confirmatory run's (docs/results/), not typed
by hand: it must be what scripts/readme_table.py makes from docs/results/results.json."""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "readme_table.py"


def check(readme: Path, results: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), "--check", "--readme", str(readme),
                           "--results", str(results)], capture_output=True, text=True)


def test_the_readme_table_is_the_committed_results_file():
    done = check(ROOT / "README.md", ROOT / "docs" / "results" / "results.json")
    assert done.returncode == 0, done.stderr


def test_the_check_fails_when_a_number_differs(tmp_path):
    summary = json.loads((ROOT / "docs" / "results" / "results.json").read_text())
    summary["scores"][0]["combined"]["hota"]["mean"] += 0.5
    changed = tmp_path / "results.json"
    changed.write_text(json.dumps(summary))
    done = check(ROOT / "README.md", changed)
    assert done.returncode == 1 and "differs" in done.stderr
    # and rewriting makes it pass again
    readme = tmp_path / "README.md"
    readme.write_text((ROOT / "README.md").read_text())
    subprocess.run([sys.executable, str(SCRIPT), "--readme", str(readme), "--results",
                    str(changed)], check=True)
    assert check(readme, changed).returncode == 0
