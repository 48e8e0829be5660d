"""Where a command writes: the --output folder, checked before any run and written only
when every run has finished."""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from pathlib import Path

from .validation import check_writable_folder


class OutputFolder:
    """The experiment's --output folder. Checked (created, probe file written) before any
    run; written only after every run has finished: the files are made in a hidden staging
    folder inside it and then renamed into place. A run replaces the outputs of the previous
    run in the folder — the files named in its manifest — and never touches other files."""

    MANIFEST = ".ctxmodels-outputs.json"

    def __init__(self, path):
        self.path = Path(path)
        self.created = check_writable_folder(self.path)
        self.committed = False

    def previous(self) -> set[str]:
        """Names of the files the previous run wrote here (that still exist)."""
        try:
            names = json.loads((self.path / self.MANIFEST).read_text())["files"]
        except FileNotFoundError:
            # Written before manifests existed: ctxmodels' fixed names, if it left results.json.
            names = output_names() if (self.path / "results.json").is_file() else []
        except (OSError, ValueError, KeyError, TypeError):
            names = []  # unreadable manifest: delete nothing
        if not isinstance(names, list):
            return set()
        # Plain names only: a manifest must not reach outside the folder.
        return {n for n in names if isinstance(n, str) and n not in ("", ".", "..")
                and Path(n).name == n and (self.path / n).is_file()}

    @contextlib.contextmanager
    def staging(self):
        stage = Path(tempfile.mkdtemp(prefix=".ctxmodels-staging-", dir=self.path))
        try:
            yield stage
        finally:
            shutil.rmtree(stage, ignore_errors=True)

    def commit(self, stage: Path) -> None:
        from ..experiment.executors import sigint_deferred, write_atomic
        new = {p.name for p in stage.iterdir()}
        old = self.previous()
        manifest = self.path / self.MANIFEST
        with sigint_deferred():  # a Ctrl-C now would mix two runs' files
            # The manifest covers both runs while files move, so a crash loses track of none.
            write_atomic(manifest, json.dumps({"files": sorted(old | new)}, indent=1))
            for name in new:
                os.replace(stage / name, self.path / name)
            for name in old - new:
                (self.path / name).unlink(missing_ok=True)
            write_atomic(manifest, json.dumps({"files": sorted(new)}, indent=1))
            self.committed = True

    def discard(self) -> None:
        """After a run that wrote nothing: remove the folder if this run created it."""
        if self.created and not self.committed:
            with contextlib.suppress(OSError):
                self.path.rmdir()  # only when empty


def output_names() -> list[str]:
    """Every file name ``ctxmodels experiment`` writes."""
    from ..experiment.scenarios import SCENARIOS
    from ..trackers import TRACKERS
    names = ["results.md", "results.csv", "results.json"]  # (no findings before manifests)
    for scenario in SCENARIOS:
        names += [f"coverage_{scenario}.png"] + [f"tracks_{scenario}_{t}.png" for t in TRACKERS]
    return names
