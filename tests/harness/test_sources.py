"""A submission's sources, unpacked (harness/submission/sources.py): what is refused, what is left
out, where the root is, and the digest that names a build."""
from __future__ import annotations

import io
import tarfile
import zipfile
from pathlib import Path

import pytest

from raycheck.harness.submission import sources
from raycheck.harness.submission.sources import SourcesError, digest, is_sources, unpack


def zip_of(path: Path, files: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w") as z:
        for name, data in files.items():
            z.writestr(name, data)
    return path


def test_an_archive_with_one_folder_unpacks_to_that_folder(tmp_path):
    archive = zip_of(tmp_path / "alice.zip", {"alice-a2/src/main.cpp": b"int main(){}",
                                              "alice-a2/CMakeLists.txt": b"project(a2)"})
    root = unpack(archive, tmp_path / "out")
    assert root == tmp_path / "out" / "alice-a2"
    assert (root / "src" / "main.cpp").read_bytes() == b"int main(){}"


@pytest.mark.parametrize("name", ["../escape.cpp", "/tmp/escape.cpp", "a/../../escape.cpp"])
def test_a_zip_member_outside_the_folder_is_refused(tmp_path, name):
    archive = zip_of(tmp_path / "evil.zip", {"main.cpp": b"", name: b"escaped"})
    with pytest.raises(SourcesError, match="would land outside"):
        unpack(archive, tmp_path / "out")
    assert not (tmp_path / "escape.cpp").exists()


def test_links_in_a_tar_are_left_out(tmp_path):
    archive = tmp_path / "links.tar.gz"
    with tarfile.open(archive, "w:gz") as t:
        data = b"int main(){}"
        info = tarfile.TarInfo("main.cpp")
        info.size = len(data)
        t.addfile(info, io.BytesIO(data))
        link = tarfile.TarInfo("secret.cpp")
        link.type = tarfile.SYMTYPE
        link.linkname = "/etc/passwd"
        t.addfile(link)
    root = unpack(archive, tmp_path / "out")
    assert sorted(p.name for p in root.iterdir()) == ["main.cpp"]


def test_a_damaged_archive_is_one_line(tmp_path):
    archive = tmp_path / "cut.zip"
    archive.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(SourcesError, match=r"cut\.zip: not a readable zip"):
        unpack(archive, tmp_path / "out")
    tarball = tmp_path / "cut.tar.gz"
    tarball.write_bytes(b"\x1f\x8b garbage")
    with pytest.raises(SourcesError, match=r"cut\.tar\.gz: not a readable tar archive"):
        unpack(tarball, tmp_path / "out2")


def test_the_size_limits_are_checked_as_it_unpacks(tmp_path, monkeypatch):
    monkeypatch.setattr(sources, "MAX_FILES", 3)
    archive = zip_of(tmp_path / "many.zip", {f"f{k}.cpp": b"" for k in range(5)})
    with pytest.raises(SourcesError, match="more than 3 files"):
        unpack(archive, tmp_path / "out")
    monkeypatch.setattr(sources, "MAX_FILES", 100)
    monkeypatch.setattr(sources, "MAX_BYTES", 1 << 20)
    archive = zip_of(tmp_path / "big.zip", {"big.cpp": b"x" * (2 << 20)})
    with pytest.raises(SourcesError, match="more than 1 MiB"):
        unpack(archive, tmp_path / "out2")


def test_the_digest_names_the_sources_not_their_builds(tmp_path):
    a = tmp_path / "a"
    (a / "src").mkdir(parents=True)
    (a / "src" / "main.cpp").write_text("int main(){}")
    before = digest(a)
    (a / "build" / "CMakeFiles").mkdir(parents=True)
    (a / "build" / "a2").write_bytes(b"\x7fELF")
    (a / ".git").mkdir()
    (a / ".git" / "HEAD").write_text("ref")
    assert digest(a) == before
    (a / "src" / "main.cpp").write_text("int main(){ return 1; }")
    assert digest(a) != before


def test_what_counts_as_sources(tmp_path):
    (tmp_path / "cpp" / "src").mkdir(parents=True)
    (tmp_path / "cpp" / "src" / "main.cpp").write_text("")
    (tmp_path / "program").mkdir()
    (tmp_path / "program" / "a2").write_text("#!/bin/sh\n")
    (tmp_path / "x.tar.gz").write_bytes(b"")
    assert [is_sources(tmp_path / n) for n in ("cpp", "program", "x.tar.gz", "none")] == \
        [True, False, True, False]
