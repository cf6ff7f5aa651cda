"""Reading a downloaded zip: what no LMS writes refuses the archive; what one upload can cause
refuses that entry only; the expansion of the whole archive is bounded before anything is
written and counted while it is."""

from __future__ import annotations

import io
import json
import re
import stat
import unicodedata
import warnings
import zipfile
from pathlib import Path

import pytest

from grader.assignment import UsageError
from grader.lms.archive import ArchiveError, ZipLimits, copy_entry, extract_download
from tests.grader.lms.conftest import grade
from tests.grader.lms.exports import write_zip

MiB = 1024**2


def _zip(path, entries, compression=zipfile.ZIP_DEFLATED):
    """``entries``: (name or ZipInfo, bytes) pairs, written in order (duplicates allowed)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about a duplicate name on purpose
        with zipfile.ZipFile(path, "w", compression) as z:
            for name, data in entries:
                z.writestr(name, data)
    return path


def _link(name: str, target: str) -> tuple[zipfile.ZipInfo, bytes]:
    info = zipfile.ZipInfo(name)
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info, target.encode()


def _bzip2(name: str) -> tuple[zipfile.ZipInfo, bytes]:
    info = zipfile.ZipInfo(name)
    info.compress_type = zipfile.ZIP_BZIP2
    return info, b"{}"


def _written(folder: Path) -> int:
    """Bytes of every file below ``folder`` (what extraction wrote to disk)."""
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


@pytest.mark.parametrize(("entries", "fragment"), [
    ([("ok.ipynb", b"{}"), ("../evil.py", b"x")], "'../evil.py': '..' in the path"),
    ([("a/../../evil.py", b"x")], "'..' in the path"),
    ([("/etc/cron.d/evil", b"x")], "an absolute path"),
    ([("C:\\Users\\evil.py", b"x")], "an absolute path"),
    ([("..\\evil.py", b"x")], "'..' in the path"),
    ([_link("alice.ipynb", "/etc/passwd")], "'alice.ipynb': a symbolic link"),
    ([_bzip2("alice.ipynb")], "'alice.ipynb': compression method 12 (only stored or deflated"),
    ([("a", b"1"), ("a/b.ipynb", b"2")], "'a': a file and a folder of the same name"),
])
def test_what_no_lms_writes_refuses_the_whole_archive(tmp_path, entries, fragment):
    (tmp_path / "out").mkdir()
    archive = _zip(tmp_path / "in.zip", entries)
    with pytest.raises(ArchiveError, match="not an archive as an LMS writes it") as info:
        extract_download(archive, tmp_path / "out" / "download")
    assert fragment in str(info.value) and str(info.value).endswith("; nothing extracted")
    assert not (tmp_path / "evil.py").exists() and list((tmp_path / "out").iterdir()) == []


def test_too_many_entries_refuse_the_whole_archive(tmp_path):
    (tmp_path / "out").mkdir()
    archive = _zip(tmp_path / "in.zip", [("a.ipynb", b"{}"), ("b.ipynb", b"{}")])
    with pytest.raises(ArchiveError, match=r"^2 entries \(at most 1 are read\)$"):
        extract_download(archive, tmp_path / "out" / "download", ZipLimits(members=1))
    assert list((tmp_path / "out").iterdir()) == []


HONEST = b'{"cells": [], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}'
NFC, NFD = (unicodedata.normalize(f, "Müller.ipynb") for f in ("NFC", "NFD"))


@pytest.mark.parametrize(("unsafe", "limits", "refused", "pattern"), [
    ([("eve/big.ipynb", b"\0" * 2000)], ZipLimits(member=1000), ["eve/big.ipynb"],
     r"^'eve/big\.ipynb' is 1\.95 KiB unpacked \(at most 1000 bytes per file\); not extracted$"),
    ([("eve/big.ipynb", b"x" * 9 * MiB)], ZipLimits(), ["eve/big.ipynb"],
     r"^'eve/big\.ipynb' expands \d{3,} times, to 9 MiB \(at most 200 times\): a zip bomb\?; "
     r"not extracted$"),
    ([("eve/HW.ipynb", HONEST), ("eve/hw.ipynb", HONEST)], ZipLimits(),
     ["eve/HW.ipynb", "eve/hw.ipynb"],
     r"^'eve/HW\.ipynb' and 'eve/hw\.ipynb': 2 entries with names that differ only in case or "
     r"Unicode form \(or not at all\); none of them extracted$"),
    ([(f"eve/{NFC}", HONEST), (f"eve/{NFD}", HONEST)], ZipLimits(), [f"eve/{NFC}"],
     r"^'eve/Müller\.ipynb': 2 entries with names that differ only in case or Unicode form"),
    ([("eve/a.ipynb", HONEST), ("eve/a.ipynb", HONEST)], ZipLimits(), ["eve/a.ipynb"],
     r"^'eve/a\.ipynb': 2 entries .*\(or not at all\); none of them extracted$"),
    ([("eve/big.ipynb", bytes(range(256)) * 20)], ZipLimits(total=3000), ["eve/big.ipynb"],
     r"^'eve/big\.ipynb' is 5 KiB unpacked and the archive would expand to 5\.\d+ KiB \(at "
     r"most 2\.93 KiB\): the largest entries are not extracted$"),
])
def test_an_unsafe_entry_is_refused_alone(tmp_path, unsafe, limits, refused, pattern):
    """One student's unsafe upload: only that entry is refused (an empty placeholder marks it,
    with why); a classmate's entries are extracted byte for byte."""
    (tmp_path / "out").mkdir()
    archive = _zip(tmp_path / "in.zip", [("ann/hw.ipynb", HONEST), *unsafe,
                                         ("bob/hw.ipynb", HONEST)])
    got = extract_download(archive, tmp_path / "out" / "download", limits)
    for sid in ("ann", "bob"):
        assert (got.folder / sid / "hw.ipynb").read_bytes() == HONEST
    assert sorted(str(p.relative_to(got.folder)) for p in got.refused) == sorted(refused)
    assert all(re.search(pattern, why) for why in got.refused.values()), got.refused
    assert all(p.is_file() and p.stat().st_size == 0 for p in got.refused)
    assert _written(got.folder) == 2 * len(HONEST)


@pytest.fixture(scope="module")
def bomb(tmp_path_factory):
    """The battery's archive: 320 entries of 1 MiB − 1 byte (each under the 1 MiB exemption),
    320 MiB from about 355 KiB, between two honest students."""
    root = tmp_path_factory.mktemp("bomb")
    return _zip(root / "bomb.zip", [("ann/hw.ipynb", HONEST),
                                    *((f"eve/{i}.ipynb", b"\0" * (MiB - 1)) for i in range(320)),
                                    ("bob/hw.ipynb", HONEST)])


def test_a_bomb_of_small_entries_writes_nothing_of_the_bomb(tmp_path, bomb):
    """Before: 320 MiB written (every entry under the per-entry exemption). Now the whole
    archive's expansion (over 900 times its size) refuses every entry that expands more than
    200 times, before anything is written: only the honest notebooks reach the disk."""
    assert bomb.stat().st_size < 400 * 1024
    got = extract_download(bomb, tmp_path / "download")
    assert _written(got.folder) == 2 * len(HONEST)
    assert len(got.refused) == 320
    assert all("the whole archive, " in why and "a zip bomb?" in why
               for why in got.refused.values())
    assert (got.folder / "bob" / "hw.ipynb").read_bytes() == HONEST


def test_sizes_that_lie_are_counted_while_decompressing(tmp_path):
    """A stream holding ten times what the directory declares: no more than the declared
    bytes reach the disk, and the copy stops with the entry named."""
    target = tmp_path / "x.ipynb"
    with open(target, "wb") as out, pytest.raises(ArchiveError) as info:
        copy_entry(io.BytesIO(b"x" * 10 * MiB), out, MiB, "eve/x.ipynb")
    assert target.stat().st_size <= MiB
    assert str(info.value) == ("'eve/x.ipynb' holds more bytes than the archive declares "
                               f"({MiB}); nothing extracted")


def test_a_directory_that_lies_about_a_size_extracts_nothing(tmp_path):
    """The central directory says 10 bytes for an entry of 100 KiB (deflated): decompressing
    stops at 10, the data does not match, and nothing is left behind."""
    archive = _zip(tmp_path / "in.zip", [("ann/hw.ipynb", HONEST), ("eve/x.ipynb", b"x" * 102400)])
    data = bytearray(archive.read_bytes())
    eve = [m.start() for m in re.finditer(rb"PK\x01\x02", data)][1]  # eve's directory entry
    assert data[eve + 46:eve + 49] == b"eve"
    data[eve + 24:eve + 28] = (10).to_bytes(4, "little")  # its uncompressed size
    archive.write_bytes(bytes(data))
    (tmp_path / "out").mkdir()
    with pytest.raises(ArchiveError, match=r"'eve/x.ipynb' does not match the archive's "
                                           r"directory \(Bad CRC-32"):
        extract_download(archive, tmp_path / "out" / "download")
    assert list((tmp_path / "out").iterdir()) == []


class _LegacyName(zipfile.ZipInfo):
    """An entry whose UTF-8 name is stored without the UTF-8 flag, as some LMSs write it."""

    def _encodeFilenameFlags(self):  # zipfile's own (private) hook
        return self.filename.encode("utf-8"), self.flag_bits


def test_folders_inside_and_names_without_the_utf8_flag(tmp_path):
    (tmp_path / "out").mkdir()
    legacy = _LegacyName("top/Müller_1_2_hw.ipynb")
    archive = _zip(tmp_path / "in.zip", [("top/", b""), ("top/sub/x.ipynb", b"{}"),
                                         (legacy, b"{}")])
    assert not zipfile.ZipFile(archive).infolist()[2].flag_bits & 0x800
    dest = extract_download(archive, tmp_path / "out" / "download").folder
    assert sorted(str(p.relative_to(dest)) for p in dest.rglob("*.ipynb")) == [
        "top/Müller_1_2_hw.ipynb", "top/sub/x.ipynb"]


def test_a_new_extraction_replaces_the_last_one(tmp_path):
    (tmp_path / "out").mkdir()
    dest = tmp_path / "out" / "download"
    extract_download(_zip(tmp_path / "1.zip", [("old.ipynb", b"{}")]), dest)
    extract_download(_zip(tmp_path / "2.zip", [("new.ipynb", b"{}")]), dest)
    assert [p.name for p in dest.iterdir()] == ["new.ipynb"]
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["download"]


def test_not_a_zip(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "x.zip").write_bytes(b"PK\3\4 not really")
    with pytest.raises(ArchiveError, match="not a readable zip archive"):
        extract_download(tmp_path / "x.zip", tmp_path / "out" / "download")


def test_grading_an_unsafe_zip_is_a_usage_error_naming_the_entry(tmp_path, generated_assignment):
    import shutil

    hw = shutil.copytree(generated_assignment.hw, tmp_path / "HW")
    archive = write_zip(tmp_path / "subs.zip", {"alice.ipynb": "{}", "../../evil.py": "x"})
    with pytest.raises(UsageError, match=r"subs\.zip: not an archive as an LMS writes it: "
                                         r"'\.\./\.\./evil\.py'"):
        grade(hw, archive)
    assert not (tmp_path / "evil.py").exists()
    assert not (hw / "graded" / "download").exists()


def test_a_refused_entry_of_a_plain_folder_zip_is_its_own_students_invalid_submission(
        tmp_path, generated_assignment):
    """A zip of ``<id>.ipynb`` (eulertop's own layout): bob's 9 MiB notebook of repeated output
    is his invalid submission; alice, beside it, is graded in full."""
    import shutil

    a = generated_assignment
    hw = shutil.copytree(a.hw, tmp_path / "HW")
    repeated = a.notebook("solutions", "bob")
    repeated["cells"][0]["source"] = "#" + "x" * 9 * MiB
    archive = write_zip(tmp_path / "subs.zip", {
        "alice.ipynb": a.solutions("alice").read_text(encoding="utf-8"),
        "bob.ipynb": json.dumps(repeated)})
    report = grade(hw, archive)
    got = {r.student_id: r for r in report.results}
    assert got["alice"].status == "graded" and got["alice"].points == got["alice"].max_points
    assert got["bob"].status == "failed" and got["bob"].points == 0
    assert got["bob"].message.startswith("invalid submission: 'bob.ipynb' expands ")
    assert report.not_graded == (f"bob: {got['bob'].message}",)
