"""The `eulertop` console script itself: --version, and a reader that leaves the pipe early."""

from __future__ import annotations

import subprocess
import sys
from importlib import metadata

from eulertop.cli import main


def test_version_prints_the_installed_version(capsys):
    try:
        main(["--version"])
    except SystemExit as done:  # argparse's version action exits
        assert done.code == 0
    assert capsys.readouterr().out.strip() == f"eulertop {metadata.version('eulertop')}"


def test_a_closed_pipe_prints_no_traceback():
    """`eulertop problems | head -1`: the reader is gone before the listing is written."""
    proc = subprocess.Popen([sys.executable, "-m", "eulertop", "problems"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # before the interpreter has even started: every write hits EPIPE
    stderr = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141  # 128 + SIGPIPE, as a shell reports a cut pipe
    assert stderr == ""


def test_head_one_through_a_shell_shows_the_first_line_only():
    done = subprocess.run(f"'{sys.executable}' -m eulertop problems | head -1", shell=True,
                          capture_output=True, text=True, timeout=60)
    assert done.stderr == ""
    assert done.stdout.split()[0] == "inertia_tensor" and done.stdout.count("\n") == 1
