"""Reading a downloaded zip: unsafe paths, links and sizes refused before anything is written."""

from __future__ import annotations

import stat
import warnings
import zipfile

import pytest

from grader.lms.archive import ArchiveError, ZipLimits, extract_download
from grader.pipeline import UsageError
from tests.grader.lms.conftest import grade
from tests.grader.lms.exports import write_zip


def _zip(path, entries):
    """``entries``: name → bytes, or a ZipInfo → bytes (for links and odd names)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about the duplicate on purpose
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            for name, data in entries:
                z.writestr(name, data)
    return path


def _link(name: str, target: str) -> tuple[zipfile.ZipInfo, bytes]:
    info = zipfile.ZipInfo(name)
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info, target.encode()


@pytest.mark.parametrize(("entries", "fragment"), [
    ([("ok.ipynb", b"{}"), ("../evil.py", b"x")], "'../evil.py': '..' in the path"),
    ([("a/../../evil.py", b"x")], "'..' in the path"),
    ([("/etc/cron.d/evil", b"x")], "an absolute path"),
    ([("C:\\Users\\evil.py", b"x")], "an absolute path"),
    ([("..\\evil.py", b"x")], "'..' in the path"),
    ([_link("alice.ipynb", "/etc/passwd")], "'alice.ipynb': a symbolic link"),
    ([("a.ipynb", b"1"), ("a.ipynb", b"2")], "occurs twice"),
])
def test_unsafe_entries_refuse_the_whole_archive(tmp_path, entries, fragment):
    archive = _zip(tmp_path / "in.zip", entries)
    with pytest.raises(ArchiveError, match="unsafe entries, nothing extracted") as info:
        extract_download(archive, tmp_path / "out" / "download")
    assert fragment in str(info.value)
    assert not (tmp_path / "evil.py").exists() and not (tmp_path / "out").exists()


@pytest.mark.parametrize(("limits", "size", "fragment"), [
    (ZipLimits(member=1000), 2000, "2000 bytes (at most 1000 per file)"),
    (ZipLimits(total=3000), 2000, "expands to 4000 bytes (at most 3000"),
    (ZipLimits(members=1), 10, "2 entries (at most 1 are read)"),
    (ZipLimits(), 4 * 1024**2, "a zip bomb?"),  # 4 MiB of zeros deflate about 1000-fold
])
def test_size_limits_are_checked_before_extracting(tmp_path, limits, size, fragment):
    (tmp_path / "out").mkdir()
    archive = _zip(tmp_path / "in.zip", [("a.ipynb", b"\0" * size), ("b.ipynb", b"\0" * size)])
    with pytest.raises(ArchiveError) as info:
        extract_download(archive, tmp_path / "out" / "download", limits)
    assert fragment in str(info.value)
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
    dest = extract_download(archive, tmp_path / "out" / "download")
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
    with pytest.raises(UsageError, match=r"subs\.zip: unsafe entries.*'\.\./\.\./evil\.py'"):
        grade(hw, archive)
    assert not (tmp_path / "evil.py").exists()
    assert not (hw / "graded" / "download").exists()
