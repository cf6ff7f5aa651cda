"""Reading a downloaded ``.zip`` of submissions safely (standard library :mod:`zipfile`).

Everything is checked from the archive's directory *before* anything is written, and the whole
archive is refused — with the entries named — when any of it is unsafe:

* a path that would leave the extraction folder: absolute (``/x``, ``C:\\x``), with a ``..``
  part, or holding a NUL; a symbolic link; an encrypted entry; a path that occurs twice;
* more than :attr:`ZipLimits.members` entries, an entry larger than :attr:`ZipLimits.member`
  bytes, more than :attr:`ZipLimits.total` bytes in all, or an entry that expands more than
  :attr:`ZipLimits.ratio` times (a "zip bomb"; entries under 1 MiB are exempt from the ratio).

While extracting, the bytes actually written are counted against the sizes the directory
declared, so an archive that lies about them is stopped too. Names stored without the zip's
UTF-8 flag (as some LMSs write them) are read as UTF-8 where they are valid UTF-8, and every
name is normalised to NFC, so that ``Müller`` matches however it was encoded.

Extraction goes into a fresh folder that the grader owns (``OUT/download``): it is written
under a temporary name beside it and renamed into place, replacing the previous run's.
"""

from __future__ import annotations

import re
import shutil
import stat
import tempfile
import unicodedata
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

UTF8_FLAG = 0x800
ENCRYPTED_FLAG = 0x1
RATIO_EXEMPT_BYTES = 1024**2
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


def _is_symlink(info: zipfile.ZipInfo) -> bool:
    return stat.S_ISLNK(info.external_attr >> 16)


def plan(archive: zipfile.ZipFile,
         limits: ZipLimits) -> list[tuple[zipfile.ZipInfo, PurePosixPath]]:
    """The files to extract and where, after every check of the module docstring."""
    infos = archive.infolist()
    if len(infos) > limits.members:
        raise ArchiveError(f"{len(infos)} entries (at most {limits.members} are read)")
    bad, files, seen, total = [], [], set(), 0
    for info in infos:
        name = entry_name(info)
        where = safe_path(name)
        why = where if isinstance(where, str) else None
        why = why or ("a symbolic link" if _is_symlink(info) else None)
        why = why or ("encrypted" if info.flag_bits & ENCRYPTED_FLAG else None)
        if why is None and not info.is_dir():
            why = _size_problem(info, limits)
            total += info.file_size
            if str(where).casefold() in seen:
                why = "occurs twice"
            seen.add(str(where).casefold())
        if why:
            bad.append(f"{name!r}: {why}")
        elif not info.is_dir():
            files.append((info, where))
    if bad:
        shown = "; ".join(bad[:5]) + (f"; and {len(bad) - 5} more" if len(bad) > 5 else "")
        raise ArchiveError(f"unsafe entries, nothing extracted: {shown}")
    if total > limits.total:
        raise ArchiveError(f"expands to {total} bytes (at most {limits.total} are extracted)")
    return files


def _size_problem(info: zipfile.ZipInfo, limits: ZipLimits) -> str | None:
    if info.file_size > limits.member:
        return f"{info.file_size} bytes (at most {limits.member} per file)"
    if info.file_size > RATIO_EXEMPT_BYTES and \
            info.file_size > limits.ratio * max(info.compress_size, 1):
        return (f"expands {info.file_size / max(info.compress_size, 1):.0f} times "
                f"(at most {limits.ratio:g}): a zip bomb?")
    return None


def _copy(archive: zipfile.ZipFile, info: zipfile.ZipInfo, target: Path) -> None:
    written = 0
    with archive.open(info) as src, open(target, "xb") as dst:
        while chunk := src.read(_CHUNK):
            written += len(chunk)
            if written > info.file_size:
                raise ArchiveError(f"{entry_name(info)!r} holds more bytes than the archive "
                                   "declares; nothing extracted")
            dst.write(chunk)


def extract_download(zip_path: Path, dest: Path, limits: ZipLimits | None = None) -> Path:
    """Extract ``zip_path`` into the folder ``dest`` (replaced), after every check; ``dest``.

    Raises
    ------
    ArchiveError
        Not a zip, unreadable, or unsafe (module docstring); ``dest`` is then left as it was.
    """
    limits = limits or ZipLimits()
    dest = Path(dest)
    try:
        with zipfile.ZipFile(zip_path) as archive:
            files = plan(archive, limits)
            _extract(archive, files, dest)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError) as e:
        raise ArchiveError(f"not a readable zip archive: {e}") from None
    except OSError as e:
        raise ArchiveError(f"cannot extract: {e.strerror or e}") from None
    return dest


def _extract(archive: zipfile.ZipFile, files: list, dest: Path) -> None:
    """Write the planned ``files`` into a temporary folder beside ``dest``, then swap it in."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
    try:
        for info, where in files:
            target = tmp.joinpath(*where.parts)
            target.parent.mkdir(parents=True, exist_ok=True)
            _copy(archive, info, target)
        if dest.exists():
            shutil.rmtree(dest)
        tmp.rename(dest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
