"""Lists the sites in the Rust crate (rust/) outside test code that can panic or allocate
infallibly: unwrap(), expect(, panic!, unreachable!, assert!, vec![x; n], with_capacity(,
.collect, .to_vec(), so the audit of "Hardening III" can be repeated.

Test code is left out: `#[cfg(test)] mod name { ... }` blocks and files declared with
`#[cfg(test)] mod name;` (and their sub-modules). A site counts as *explained* when its line,
or one of the three lines above it, holds a `//` comment; the rest are listed as
unexplained, and the exit status is 1 when any is.

    python scripts/audit_rust_panics.py            # every site, grouped by file
    python scripts/audit_rust_panics.py --unexplained
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "rust"

PATTERNS = {
    "unwrap": re.compile(r"\.unwrap\(\)"),
    "expect": re.compile(r"\.expect\("),
    "panic": re.compile(r"\b(panic|unreachable|todo|unimplemented)!"),
    "assert": re.compile(r"(?<!debug_)\bassert(_eq|_ne)?!"),
    "vec!": re.compile(r"\bvec!\[[^\]]*;"),
    "with_capacity": re.compile(r"with_capacity\("),
    "collect": re.compile(r"\.collect\b"),
    "to_vec": re.compile(r"\.to_vec\(\)"),
}


def _blank_literals(line: str) -> str:
    """The line with string and char literals blanked (so a brace or a pattern inside one
    does not count) and a trailing // comment removed."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "' '", line)
    return line.split("//", 1)[0]


def test_blocks(lines: list[str]) -> set[int]:
    """Indices of the lines inside `#[cfg(test)] mod name { ... }` blocks."""
    inside: set[int] = set()
    i = 0
    while i < len(lines):
        if lines[i].strip().startswith("#[cfg(test)]"):
            j = i + 1 if lines[i].strip() == "#[cfg(test)]" else i
            if j < len(lines) and re.search(r"\bmod\s+\w+\s*\{", lines[j]):
                depth, k = 0, j
                while k < len(lines):
                    code = _blank_literals(lines[k])
                    depth += code.count("{") - code.count("}")
                    inside.add(k)
                    if depth == 0 and "{" in "".join(_blank_literals(x) for x in lines[j:k + 1]):
                        break
                    k += 1
                inside.add(i)
                i = k
        i += 1
    return inside


def test_files(root: Path) -> set[Path]:
    """Files declared with `#[cfg(test)] mod name;`, and every file below such a module."""
    found: set[Path] = set()
    for path in root.rglob("*.rs"):
        text = path.read_text()
        for name in re.findall(r"#\[cfg\(test\)\]\s*mod\s+(\w+)\s*;", text):
            base = path.parent if path.name in ("mod.rs", "lib.rs") else path.with_suffix("")
            for candidate in (base / f"{name}.rs", base / name / "mod.rs"):
                if candidate.exists():
                    found.add(candidate)
                    found.update((candidate.parent / name).rglob("*.rs") if candidate.name != "mod.rs"
                                 else candidate.parent.rglob("*.rs"))
    return found


def sites(root: Path = ROOT):
    skip = test_files(root)
    for path in sorted(root.rglob("*.rs")):
        if path in skip:
            continue
        lines = path.read_text().splitlines()
        tests = test_blocks(lines)
        for i, line in enumerate(lines):
            if i in tests or line.lstrip().startswith(("//", "///", "//!")):
                continue
            code = _blank_literals(line)
            for kind, pattern in PATTERNS.items():
                if pattern.search(code):
                    explained = any("//" in lines[k] and not lines[k].lstrip().startswith(("///", "//!"))
                                    for k in range(max(0, i - 3), i + 1))
                    yield path.relative_to(root.parent), i + 1, kind, line.strip(), explained


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--unexplained", action="store_true", help="only the sites without a comment")
    args = parser.parse_args()
    found = list(sites())
    counts: dict[str, int] = {}
    unexplained = 0
    current = None
    for path, line, kind, code, explained in found:
        counts[kind] = counts.get(kind, 0) + 1
        unexplained += not explained
        if args.unexplained and explained:
            continue
        if path != current:
            print(f"{path}")
            current = path
        mark = " " if explained else "!"
        print(f"  {mark} {line:5d} {kind:13s} {code[:110]}")
    summary = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    print(f"\n{len(found)} sites ({summary}); {unexplained} without a comment")
    return 1 if unexplained else 0


if __name__ == "__main__":
    sys.exit(main())
