"""Pinned downloads from the package index (ctxmodels.downloads), without the network: a
cached archive is used when its hash matches, a wrong one is fetched again, an unreachable
index raises DownloadError saying where to put the file, and members are extracted once."""
import hashlib
import io
import tarfile
import zipfile

import pytest

from ctxmodels import downloads
from ctxmodels.downloads import Archive, DownloadError


def archive_of(path, requirement="example==1.0"):
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return Archive(requirement, path.name, digest, 1)


def make_sdist(directory):
    path = directory / "example-1.0.tar.gz"
    with tarfile.open(path, "w:gz") as tar:
        data = b"a,b\n1,2\n"
        info = tarfile.TarInfo("example-1.0/docs/data.csv")
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))
    return path


def test_cache_directory_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("CTXMODELS_CACHE", str(tmp_path / "a"))
    assert downloads.cache_dir() == tmp_path / "a"
    monkeypatch.delenv("CTXMODELS_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "b"))
    assert downloads.cache_dir() == tmp_path / "b" / "ctxmodels"


def test_a_cached_archive_is_used_and_its_members_extracted_once(tmp_path):
    sdist = make_sdist(tmp_path)
    archive = archive_of(sdist)
    assert downloads.fetch(archive, tmp_path) == sdist
    extracted = downloads.member(archive, "docs/data.csv", tmp_path)
    assert extracted == tmp_path / "example-1.0" / "docs" / "data.csv"
    assert extracted.read_bytes() == b"a,b\n1,2\n"
    sdist.unlink()  # extracted already: the archive is not needed again
    assert downloads.member(archive, "docs/data.csv", tmp_path).read_bytes() == b"a,b\n1,2\n"


def test_a_wheel_member(tmp_path):
    wheel = tmp_path / "example-1.0-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("pkg/data.bin", b"\x01\x02")
    archive = archive_of(wheel)
    assert downloads.member(archive, "pkg/data.bin", tmp_path).read_bytes() == b"\x01\x02"


def test_without_an_index_the_error_says_where_to_put_the_file(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("PIP_NO_INDEX", "1")
    (tmp_path / "elsewhere").mkdir()
    sdist = make_sdist(tmp_path / "elsewhere")
    archive = archive_of(sdist)
    cache = tmp_path / "cache"
    with pytest.raises(DownloadError, match=r"could not download example-1.0.tar.gz .*put the file "
                                            r"\(sha256 [0-9a-f]{64}\) at .*cache/example-1.0.tar.gz"):
        downloads.fetch(archive, cache)
    assert "downloading example-1.0.tar.gz" in capsys.readouterr().err
    # a cached file with the wrong hash is removed and fetched again (which fails here)
    (cache / archive.filename).write_bytes(b"not it")
    with pytest.raises(DownloadError):
        downloads.fetch(archive, cache)
    assert "does not match its sha256" in capsys.readouterr().err
    assert not (cache / archive.filename).exists()
    assert list(cache.iterdir()) == []  # no scratch left behind


def test_processes_extracting_at_once_get_whole_files(tmp_path):
    """A study's workers may extract the same member at once on first use."""
    import subprocess
    import sys
    wheel = tmp_path / "example-1.0-py3-none-any.whl"
    payload = bytes(range(256)) * 40_000  # 10 MB: long enough for the writes to overlap
    with zipfile.ZipFile(wheel, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("pkg/big.bin", payload)
    archive = archive_of(wheel)
    code = ("import sys; from pathlib import Path; from ctxmodels import downloads; "
            f"a = downloads.Archive({archive.requirement!r}, {archive.filename!r}, "
            f"{archive.sha256!r}, 1); "
            "print(downloads.member(a, 'pkg/big.bin', Path(sys.argv[1])))")
    runs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stdout=subprocess.PIPE)
            for _ in range(4)]
    paths = {run.communicate()[0].decode().strip() for run in runs}
    assert all(run.returncode == 0 for run in runs)
    (path,) = paths
    assert open(path, "rb").read() == payload
    assert not list((tmp_path / "example-1.0-py3-none-any").rglob("*.partial"))
