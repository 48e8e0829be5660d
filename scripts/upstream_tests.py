#!/usr/bin/env python
"""Run Stone Soup's own tests for the components ctxmodels replaces, with ctxmodels'
drop-ins substituted.

The Stone Soup wheel ships no tests; the sdist does (``stonesoup/<sub>/tests/``). This
script

1. downloads ``stonesoup-<version>.tar.gz`` with pip (``--require-hashes`` against the
   sha256 PyPI publishes for the file) into ctxmodels' download cache
   (:mod:`ctxmodels.downloads`: ``$CTXMODELS_CACHE``, else ``~/.cache/ctxmodels``), reusing
   it when its hash matches;
2. extracts only the upstream test modules listed in :data:`UPSTREAM_TESTS`, the
   ``conftest.py`` files above them and their packages' ``__init__.py`` into a temporary
   directory (nothing is copied into this repository);
3. runs pytest on them with our substitution plugin (``tests/upstream/upstream_substitute.py``,
   which holds the stock -> ctxmodels map and its profiles), and prints which substituted
   component each passing test constructed. The plugin adds ctxmodels' checks of the Stone
   Soup internals it relies on (``tests/upstream/test_internals.py``, see
   ``ctxmodels._upstream``) to the session, reported apart.

Exit status 0 only if every selected upstream test passed (none deselected but those in
:data:`DESELECT`, each with its reason), every substituted component was constructed by
at least one passing test, and every internals check ran and passed.

    python scripts/upstream_tests.py                      # default profile
    python scripts/upstream_tests.py --profile array
    python scripts/upstream_tests.py --report out.json -- -x -k pointprocess
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path, PurePosixPath

from ctxmodels.downloads import STONESOUP, DownloadError, fetch

REPO = Path(__file__).resolve().parent.parent
PLUGIN_DIR = REPO / "tests" / "upstream"

# The sdist, pinned by the sha256 PyPI publishes for it (ctxmodels.downloads.STONESOUP).
STONESOUP_VERSION = STONESOUP.requirement.split("==")[1]
SDIST, SDIST_SHA256 = STONESOUP.filename, STONESOUP.sha256

# Upstream test modules (paths inside the sdist's stonesoup/) -> the substituted components
# they build. Every test in these modules runs; the report shows which test built which
# component (tests of other, stock classes in the same modules run too, unsubstituted).
UPSTREAM_TESTS = {
    # The tests of the substituted components' own modules.
    "tracker/tests/test_pointprocess.py":
        "PointProcessMultiTargetTracker with PHDUpdater, GaussianMixtureHypothesiser, "
        "GaussianMixtureReducer",
    "tracker/tests/test_simple.py": "MultiTargetMixtureTracker",
    "updater/tests/test_pointprocess.py": "PHDUpdater, LCCUpdater",
    "updater/tests/test_particle.py": "BernoulliParticleUpdater, SMCPHDUpdater",
    "hypothesiser/tests/test_probability.py": "PDAHypothesiser",
    "deleter/tests/test_time.py": "UpdateTimeStepsDeleter",
    "initiator/tests/test_simple.py":
        "MultiMeasurementInitiator with UpdateTimeStepsDeleter, PDAHypothesiser",
    "dataassociator/tests/test_neighbour.py": "GNNWith2DAssignment, PDAHypothesiser (conftest)",
    # Stock components built on the substituted ones (a drop-in must work inside them).
    "dataassociator/tests/test_probability.py":
        "PDAHypothesiser under PDA, JPDA, JPDAwithEHM/EHM2 (these need pyehm)",
    "dataassociator/tests/test_tree.py":
        "GNNWith2DAssignment subclassed with the k-d/TPR-tree mix-ins, PDAHypothesiser",
    "hypothesiser/tests/test_composite.py": "PDAHypothesiser in CompositeHypothesiser",
    "hypothesiser/tests/test_mfa.py": "PDAHypothesiser under the MFA hypothesiser",
    "gater/tests/test_distance.py": "PDAHypothesiser behind DistanceGater",
    "updater/tests/test_probability.py": "PDAHypothesiser feeding PDAUpdater",
}

# Upstream tests not run, each only because it checks something outside the substituted
# component's contract (never because it fails): "<path below stonesoup/>::<test id>" -> why.
# None so far: every selected upstream test passes with the substitutes.
DESELECT: dict[str, str] = {
}


def extract(sdist: Path, destination: Path) -> list[Path]:
    """Extract the selected test modules, the conftest.py files above them and their
    packages' __init__.py under ``destination/stonesoup``; return the test module paths."""
    prefix = PurePosixPath(f"stonesoup-{STONESOUP_VERSION}", "stonesoup")
    wanted = {prefix / name for name in UPSTREAM_TESTS}
    for name in UPSTREAM_TESTS:
        directory = (prefix / name).parent
        wanted.add(directory / "__init__.py")
        for ancestor in [directory, *directory.parents]:
            if ancestor == prefix.parent:
                break
            wanted.add(ancestor / "conftest.py")
    found = []
    with tarfile.open(sdist) as archive:
        for member in archive.getmembers():
            path = PurePosixPath(member.name)
            if path not in wanted:
                continue
            if not member.isfile():
                sys.exit(f"{SDIST}: {member.name} is not a regular file")
            target = destination / path.relative_to(prefix.parent)
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(archive.extractfile(member).read())
            found.append(path)
    missing = sorted(str(prefix / name) for name in UPSTREAM_TESTS if prefix / name not in found)
    if missing:
        sys.exit(f"{SDIST} lacks {missing}")
    # The directories above the test packages must be packages for pytest to import the
    # tests as stonesoup.<sub>.tests.<module> (their relative imports need it); these empty
    # markers are never imported: the plugin serves those names from the installed stonesoup.
    for name in UPSTREAM_TESTS:
        tests_dir = destination / "stonesoup" / PurePosixPath(name).parent
        if (tests_dir / "__init__.py").exists():
            for marker_dir in list(tests_dir.relative_to(destination).parents)[:-1]:
                (destination / marker_dir / "__init__.py").touch()
    return [destination / "stonesoup" / name for name in UPSTREAM_TESTS]


def main(argv: list[str] | None = None) -> int:
    sys.path.insert(0, str(PLUGIN_DIR))
    from upstream_substitute import PROFILES

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", default="default", choices=sorted(PROFILES))
    parser.add_argument("--cache-dir", type=Path, default=None,
                        help="where the sdist is kept (default: ctxmodels' download cache)")
    parser.add_argument("--report", type=Path, help="write the JSON report here")
    parser.add_argument("--control", action="store_true",
                        help="negative control: substitute nothing; the plugin's checks must "
                             "then fail every test that builds a substituted component")
    parser.add_argument("--keep", action="store_true", help="keep the extracted tree, print where")
    parser.add_argument("pytest_args", nargs="*", help="extra pytest arguments (after --)")
    args = parser.parse_args(argv)

    import stonesoup
    if stonesoup.__version__ != STONESOUP_VERSION:
        sys.exit(f"installed stonesoup is {stonesoup.__version__}, the upstream tests are "
                 f"{STONESOUP_VERSION}'s")

    try:
        sdist = fetch(STONESOUP, args.cache_dir)
    except DownloadError as err:
        sys.exit(str(err))
    work = Path(tempfile.mkdtemp(prefix="ctxmodels-upstream-"))
    try:
        source = work / "src"
        modules = extract(sdist, source)
        # Stone Soup's own pytest settings (pyproject.toml: python_classes = []).
        ini = work / "pytest.ini"
        ini.write_text("[pytest]\npython_classes =\n")
        report = args.report.resolve() if args.report else work / "report.json"
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(PLUGIN_DIR), env.get("PYTHONPATH")]))
        env.pop("PYTEST_ADDOPTS", None)
        command = [sys.executable, "-m", "pytest", "-c", str(ini), "--rootdir", str(work),
                   "-p", "no:cacheprovider", "-p", "upstream_substitute",
                   "--ctx-upstream-root", str(source), "--ctx-profile", args.profile,
                   "--ctx-report", str(report), "-q", "-rfEs"]
        if args.control:
            command.append("--ctx-control")
        for nodeid in DESELECT:
            command += ["--deselect", f"src/stonesoup/{nodeid}"]
        command += [str(path.relative_to(work)) for path in modules] + args.pytest_args
        print(f"upstream tests from {SDIST} (sha256 {SDIST_SHA256}), profile {args.profile!r}",
              flush=True)
        status = subprocess.run(command, cwd=work, env=env).returncode
        if not report.exists():
            print("no report written", file=sys.stderr)
            return status or 1
        return summarise(json.loads(report.read_text()), status)
    finally:
        if args.keep:
            print(f"extracted tree kept in {work}")
        else:
            import shutil
            shutil.rmtree(work, ignore_errors=True)


def summarise(report: dict, status: int) -> int:
    tests = report["tests"]
    print(f"\nprofile {report['profile']!r}: {len(tests)} upstream tests, "
          + ", ".join(f"{sum(t['outcome'] == o for t in tests)} {o}"
                      for o in ("passed", "failed", "error", "skipped")))
    print("substituted component -> passing upstream tests that constructed it:")
    uncovered = []
    for stock, ours in report["map"].items():
        passing = sum(t["outcome"] == "passed" and stock in t["substituted"] for t in tests)
        failing = sum(t["outcome"] in ("failed", "error") and stock in t["substituted"] for t in tests)
        print(f"  {stock.rpartition('.')[2]:32} -> {ours.rpartition('.')[2]:32} "
              f"{passing:3} passed, {failing} failed")
        if not passing:
            uncovered.append(stock)
    leaky = [test for test in tests if test["leaks"]]
    for test in leaky[:10]:
        print(f"LEAK {test['nodeid']}: {'; '.join(test['leaks'])}")
    if len(leaky) > 10:
        print(f"... {len(leaky)} tests reached a stock class in all")
    for test in tests:
        if test["outcome"] == "skipped":
            print(f"SKIPPED {test['nodeid']}: {test.get('skip_reason')}")
    internals = report.get("internals", [])
    broken = [check for check in internals if check["outcome"] != "passed"]
    print(f"Stone Soup internals ctxmodels relies on (ctxmodels._upstream): {len(internals)} "
          f"checks, {len(internals) - len(broken)} passed")
    for check in broken:
        print(f"INTERNAL {check['outcome'].upper()} {check['nodeid']}")
    if uncovered:
        print("no passing upstream test constructed: " + ", ".join(uncovered))
        return status or 1
    if broken or not internals:
        print("the Stone Soup internals ctxmodels relies on are not as it relies on them"
              if internals else "no check of the Stone Soup internals ran")
        return status or 1
    return status


if __name__ == "__main__":
    sys.exit(main())
