"""Reading a submission without trusting it (issue 11): regular files under the size limit
only, never following a link, never blocking on a FIFO or a device."""

from __future__ import annotations

import os
import threading

import pytest

from grader.submission_file import InvalidSubmission, read_submission, size_text


def test_a_regular_file_is_read_whole(tmp_path):
    path = tmp_path / "a.ipynb"
    path.write_bytes(b'{"cells": []}')
    assert read_submission(path, 100) == b'{"cells": []}'


def test_a_file_over_the_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = tmp_path / "big.ipynb"
    path.write_bytes(b"x" * 2000)
    opened = []
    monkeypatch.setattr(os, "open", lambda *a, **k: opened.append(a) or 1 / 0)
    with pytest.raises(InvalidSubmission, match=r"big.ipynb is 1.95 KiB, over the 1000 bytes"):
        read_submission(path, 1000)
    assert opened == []  # refused from lstat alone


@pytest.mark.parametrize(("make", "kind"), [
    (lambda p, t: os.symlink(t, p), "a symbolic link"),
    (lambda p, t: os.mkfifo(p), "a named pipe (FIFO)"),
    (lambda p, t: os.mkdir(p), "a folder"),
    (lambda p, t: os.symlink("/dev/zero", p), "a symbolic link"),
])
def test_links_fifos_devices_and_folders_are_refused_without_blocking(tmp_path, make, kind):
    target = tmp_path / "solutions.ipynb"
    target.write_text("{}")
    path = tmp_path / "eve.ipynb"
    make(path, target)
    outcome = []
    reader = threading.Thread(target=lambda: outcome.append(_attempt(path)), daemon=True)
    reader.start()
    reader.join(5)
    assert outcome == [f"eve.ipynb is {kind}, not a file"]


def _attempt(path):
    try:
        read_submission(path, 1000)
    except InvalidSubmission as e:
        return str(e)
    return "read"


def test_a_file_swapped_for_a_fifo_after_the_check_neither_blocks_nor_is_read(tmp_path,
                                                                             monkeypatch):
    path = tmp_path / "eve.ipynb"
    path.write_text("{}")
    real_lstat = os.lstat

    def lstat_then_swap(p):
        info = real_lstat(p)
        os.remove(p)
        os.mkfifo(p)  # between the check and the open
        return info

    monkeypatch.setattr(os, "lstat", lstat_then_swap)
    with pytest.raises(InvalidSubmission, match="changed while it was being read"):
        read_submission(path, 1000)


@pytest.mark.parametrize(("n", "text"), [(12, "12 bytes"), (2048, "2 KiB"),
                                         (20 * 1024**2, "20 MiB"), (75 * 10**6, "71.5 MiB")])
def test_sizes_read_as_people_write_them(n, text):
    assert size_text(n) == text
