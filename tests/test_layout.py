"""docs/layout.md names every module of the package and of the Rust core (a package's
``__init__``, a Rust folder's ``mod.rs``, ``lib.rs`` and the test files aside): a newcomer
finds each by its name there."""
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parent.parent
LAYOUT = (ROOT / "docs" / "layout.md").read_text(encoding="utf-8")


def _modules() -> list[pathlib.Path]:
    found = sorted((ROOT / "python" / "ctxmodels").rglob("*.py")) + sorted((ROOT / "rust").rglob("*.rs"))
    return [path for path in found if path.stem not in ("__init__", "__main__", "lib", "mod")
            and not path.stem.endswith("tests") and "__pycache__" not in path.parts]


def _named(stem: str) -> bool:
    return re.search(rf"(?<![\w]){re.escape(stem)}(?![\w])", LAYOUT) is not None


def test_every_module_is_named():
    missing = [str(path.relative_to(ROOT)) for path in _modules() if not _named(path.stem)]
    assert missing == [], f"docs/layout.md does not name {missing}"


def test_the_check_can_fail():
    assert _named("array_initiator") and not _named("no_such_module_here")
    assert len(_modules()) > 100
