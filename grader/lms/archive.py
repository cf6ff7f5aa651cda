"""Reading a downloaded ``.zip`` of submissions safely (standard library :mod:`zipfile`).

Everything is checked from the archive's directory *before* anything is written. What one
student's upload can cause is refused **for that entry only** (:attr:`Extraction.refused`: its
owner's submission is then invalid, and everyone else is graded):

* an entry larger than :attr:`ZipLimits.member` bytes, or one over :data:`RATIO_EXEMPT_BYTES`
  that expands more than :attr:`ZipLimits.ratio` times (a notebook of repeated output);
* two or more entries whose names differ only in case or Unicode form (``HW.ipynb`` and
  ``hw.ipynb``, ``Müller`` composed and decomposed), or the same name twice: none of them is
  extracted, since which one a folder keeps would depend on the file system;
* the archive as a whole expanding past :attr:`ZipLimits.ratio` times its own size (many small
  entries, each under the exemption: a "zip bomb"): then every entry that expands more than
  that is refused whatever its size, and the most expanding ones after it until the rest fits;
* the archive as a whole expanding past :attr:`ZipLimits.total` bytes: the largest entries are
  refused until the rest fits.

What no LMS writes, and so no upload can cause, refuses the **whole archive**
(:class:`ArchiveError`, nothing extracted): a path that would leave the extraction folder
(absolute, ``C:\\``, ``..``, NUL), a symbolic link, an encrypted entry, a compression other
than stored or deflated, a file and a folder of the same name, more than
:attr:`ZipLimits.members` entries, and data that does not match the directory. The bytes are
counted while they are decompressed, against the size the directory declared, so an archive
that lies about its sizes writes no more than it declared.

Names stored without the zip's UTF-8 flag (as some LMSs write them) are read as UTF-8 where they
are valid UTF-8, and every name is normalised to NFC, so that ``Müller`` matches however it was
encoded.

Extraction goes into a fresh folder that the grader owns (``OUT/download``): it is written
under a temporary name beside it and renamed into place, replacing the previous run's. A
refused entry leaves an empty placeholder file where it would have been, so that the LMS
modules see its name and find its owner; :attr:`Extraction.refused` says which files those are.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import tempfile
import unicodedata
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import BinaryIO

from grader.submission_file import size_text

UTF8_FLAG = 0x800
ENCRYPTED_FLAG = 0x1
RATIO_EXEMPT_BYTES = 1024**2
"""An entry up to this size is not refused for its own ratio (while the whole archive's ratio
is within :attr:`ZipLimits.ratio`)."""
COMPRESSIONS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
"""What LMSs write; deflate's output is bounded per read, unlike bzip2's or LZMA's."""
_CHUNK = 1 << 20


class ArchiveError(ValueError):
    """The archive is unreadable or unsafe; nothing was extracted. The message says why."""


@dataclass(frozen=True)
class ZipLimits:
    """Size limits of one downloaded archive (bytes, after decompression)."""

    total: int = 4 * 1024**3
    member: int = 512 * 1024**2
    ratio: float = 200.0
    members: int = 50_000


@dataclass(frozen=True)
class Extraction:
    """What :func:`extract_download` wrote.

    Attributes
    ----------
    folder : Path
        The extraction folder.
    refused : dict
        Path of each refused entry's (empty) placeholder file → why it was refused, a phrase
        naming the entry (``"'a/HW.ipynb' expands 1024 times …; not extracted"``).
    """

    folder: Path
    refused: dict[Path, str] = field(default_factory=dict)


def entry_name(info: zipfile.ZipInfo) -> str:
    """The entry's name as its writer meant it (module docstring), NFC-normalised."""
    name = info.filename
    if not info.flag_bits & UTF8_FLAG:
        try:
            name = name.encode("cp437").decode("utf-8")
        except (UnicodeEncodeError, UnicodeDecodeError):
            pass
    return unicodedata.normalize("NFC", name)


def safe_path(name: str) -> PurePosixPath | str:
    """The relative path an entry name stands for, or why it is not safe.

    Examples
    --------
    >>> safe_path("a/./b.ipynb")
    PurePosixPath('a/b.ipynb')
    >>> safe_path("../evil.py")
    "'..' in the path"
    """
    if "\x00" in name:
        return "a NUL character in the name"
    if name.startswith(("/", "\\")) or re.match(r"^[A-Za-z]:", name):
        return "an absolute path"
    parts = [p for p in re.split(r"[\\/]", name) if p not in ("", ".")]
    if ".." in parts:
        return "'..' in the path"
    if not parts:
        return "an empty path"
    return PurePosixPath(*parts)


def ratio(info: zipfile.ZipInfo) -> float:
    """How many times the entry expands (declared size over compressed size)."""
    return info.file_size / max(info.compress_size, 1)


def _structural(info: zipfile.ZipInfo, where: PurePosixPath | str) -> str | None:
    """What about this entry no LMS writes (module docstring), or None."""
    if isinstance(where, str):
        return where
    if stat.S_ISLNK(info.external_attr >> 16):
        return "a symbolic link"
    if info.flag_bits & ENCRYPTED_FLAG:
        return "encrypted"
    if info.compress_type not in COMPRESSIONS:
        return f"compression method {info.compress_type} (only stored or deflated is read)"
    return None


def _refuse_whole(problems: list[str], why: str) -> None:
    if problems:
        shown = "; ".join(problems[:5]) + (f"; and {len(problems) - 5} more"
                                           if len(problems) > 5 else "")
        raise ArchiveError(f"{why}: {shown}; nothing extracted")


Planned = list[tuple[zipfile.ZipInfo, PurePosixPath]]


def plan(archive: zipfile.ZipFile, limits: ZipLimits,
         archive_bytes: int) -> tuple[Planned, dict[PurePosixPath, str]]:
    """The files to extract and where, and the entries refused with why (module docstring).

    ``archive_bytes`` is the size of the archive file, which bounds the expansion of the whole.

    Raises
    ------
    ArchiveError
        What refuses the whole archive (module docstring).
    """
    infos = archive.infolist()
    if len(infos) > limits.members:
        raise ArchiveError(f"{len(infos)} entries (at most {limits.members} are read)")
    files, bad = [], []
    for info in infos:
        where = safe_path(entry_name(info))
        why = _structural(info, where)
        if why:
            bad.append(f"{entry_name(info)!r}: {why}")
        elif not info.is_dir():
            files.append((info, where))
    bad += _files_that_are_folders(files)
    _refuse_whole(bad, "not an archive as an LMS writes it")
    refused = {**_collisions(files), **_too_big(files, limits)}
    kept = [(i, w) for i, w in files if w not in refused]
    refused |= _over_budget(kept, limits, archive_bytes)
    kept = [(i, w) for i, w in kept if w not in refused]
    refused |= _over_total(kept, limits)
    return [(i, w) for i, w in kept if w not in refused], refused


def _files_that_are_folders(files: Planned) -> list[str]:
    folders = {str(p).casefold() for _, w in files for p in w.parents}
    return [f"{str(w)!r}: a file and a folder of the same name" for _, w in files
            if str(w).casefold() in folders]


def _collisions(files: Planned) -> dict[PurePosixPath, str]:
    """Entries whose names differ only in case or Unicode form (already NFC), or are equal."""
    groups: dict[str, list[PurePosixPath]] = {}
    for _, where in files:
        groups.setdefault(str(where).casefold(), []).append(where)
    refused = {}
    for same in groups.values():
        if len(same) > 1:
            names = " and ".join(sorted({repr(str(w)) for w in same}))
            why = (f"{names}: {len(same)} entries with names that differ only in case or "
                   "Unicode form (or not at all); none of them extracted")
            refused |= dict.fromkeys(same, why)
    return refused


def _too_big(files: Planned, limits: ZipLimits) -> dict[PurePosixPath, str]:
    refused = {}
    for info, where in files:
        if info.file_size > limits.member:
            refused[where] = (f"{str(where)!r} is {size_text(info.file_size)} unpacked (at "
                              f"most {size_text(limits.member)} per file); not extracted")
        elif info.file_size > RATIO_EXEMPT_BYTES and ratio(info) > limits.ratio:
            refused[where] = _ratio_reason(info, where, limits)
    return refused


def _ratio_reason(info: zipfile.ZipInfo, where: PurePosixPath, limits: ZipLimits,
                  whole: str = "") -> str:
    return (f"{str(where)!r} expands {ratio(info):.0f} times, to {size_text(info.file_size)} "
            f"(at most {limits.ratio:g} times{whole}): a zip bomb?; not extracted")


def _over_budget(files: Planned, limits: ZipLimits,
                 archive_bytes: int) -> dict[PurePosixPath, str]:
    """Entries refused so that the whole archive expands at most ``limits.ratio`` times its own
    size: when it would expand more, every entry expanding more than that (the rest then fits,
    their compressed data being part of the archive), and should entries share their data, the
    most expanding ones after them until the rest fits."""
    budget = limits.ratio * archive_bytes
    total = sum(info.file_size for info, _ in files)
    if total <= budget:
        return {}
    whole = (f"; the whole archive, {size_text(archive_bytes)}, would expand "
             f"{total / max(archive_bytes, 1):.0f} times")
    refused = {}
    for info, where in sorted(files, key=lambda f: ratio(f[0]), reverse=True):
        if total <= budget and ratio(info) <= limits.ratio:
            break
        refused[where] = _ratio_reason(info, where, limits, whole)
        total -= info.file_size
    return refused


def _over_total(files: Planned, limits: ZipLimits) -> dict[PurePosixPath, str]:
    """The largest entries, refused until the rest is at most ``limits.total`` bytes."""
    total = sum(info.file_size for info, _ in files)
    whole = f"the archive would expand to {size_text(total)} (at most {size_text(limits.total)})"
    refused = {}
    for info, where in sorted(files, key=lambda f: f[0].file_size, reverse=True):
        if total <= limits.total:
            break
        refused[where] = (f"{str(where)!r} is {size_text(info.file_size)} unpacked and {whole}: "
                          "the largest entries are not extracted")
        total -= info.file_size
    return refused


def copy_entry(source: BinaryIO, target: BinaryIO, declared: int, name: str) -> int:
    """Copy ``source`` into ``target``, never more than ``declared`` bytes; the bytes written.

    Raises
    ------
    ArchiveError
        ``source`` holds more than ``declared`` bytes: the archive lies about its sizes.
    """
    written = 0
    while chunk := source.read(min(_CHUNK, declared - written + 1)):
        written += len(chunk)
        if written > declared:
            raise ArchiveError(f"{name!r} holds more bytes than the archive declares "
                               f"({declared}); nothing extracted")
        target.write(chunk)
    return written


def extract_download(zip_path: Path, dest: Path, limits: ZipLimits | None = None) -> Extraction:
    """Extract ``zip_path`` into the folder ``dest`` (replaced), after every check.

    Raises
    ------
    ArchiveError
        Not a zip, unreadable, or unsafe as a whole (module docstring); ``dest`` is then left
        as it was.
    """
    limits = limits or ZipLimits()
    dest = Path(dest)
    try:
        with zipfile.ZipFile(zip_path) as archive:
            files, refused = plan(archive, limits, os.stat(zip_path).st_size)
            _extract(archive, files, refused, dest)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError) as e:
        raise ArchiveError(f"not a readable zip archive: {e}") from None
    except OSError as e:
        raise ArchiveError(f"cannot extract: {e.strerror or e}") from None
    return Extraction(dest, {dest.joinpath(*where.parts): why for where, why in refused.items()})


def _extract(archive: zipfile.ZipFile, files: Planned, refused: dict[PurePosixPath, str],
             dest: Path) -> None:
    """Write the planned ``files`` and a placeholder per refused entry into a temporary
    folder beside ``dest``, then swap it in."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
    try:
        for info, where in files:
            target = _target(tmp, where)
            try:
                with archive.open(info) as src, open(target, "xb") as dst:
                    copy_entry(src, dst, info.file_size, entry_name(info))
            except (zipfile.BadZipFile, zlib.error, EOFError) as e:
                raise ArchiveError(f"{entry_name(info)!r} does not match the archive's "
                                   f"directory ({e}); nothing extracted") from None
        for where in refused:
            _target(tmp, where).touch()
        if dest.exists():
            shutil.rmtree(dest)
        tmp.rename(dest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _target(root: Path, where: PurePosixPath) -> Path:
    target = root.joinpath(*where.parts)
    target.parent.mkdir(parents=True, exist_ok=True)
    return target
