"""The `eulertop` console script itself: --version, arguments a command does not take, and a
reader that leaves the pipe early."""

from __future__ import annotations

import subprocess
import sys
from importlib import metadata

import pytest

from eulertop.cli import main


def test_version_prints_the_installed_version(capsys):
    try:
        main(["--version"])
    except SystemExit as done:  # argparse's version action exits
        assert done.code == 0
    assert capsys.readouterr().out.strip() == f"eulertop {metadata.version('eulertop')}"


@pytest.mark.parametrize("argv, command, option", [
    # a value where an option was meant: `override` takes its points as --points
    (["override", "HW", "s1", "q1_moments", "5"], "eulertop override", "--points"),
    (["key", "set", "HW", "s1:q1_moments", "1e-2"], "eulertop key set", "--rtol"),
    (["late", "set", "HW", "tomorrow"], "eulertop late set", "--due"),
    (["generate", "--out", "HW", "stray"], "eulertop generate", "--roster"),
])
def test_arguments_a_command_does_not_take_are_named_with_its_usage(argv, command, option,
                                                                     capsys):
    """Said by the command given them, with its own usage (which names the option meant),
    not with eulertop's, which lists none; nothing is run (usage error, status 2)."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"usage: {command} ")
    assert option in err
    assert f"{command}: error: unrecognized arguments: {argv[-1]}" in err


def test_an_unknown_option_before_any_command_is_eulertops_to_name(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--nosuch"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: eulertop [-h]")
    assert "eulertop: error: unrecognized arguments: --nosuch" in err


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


CLASS_COMMANDS = [
    ["rescore", "{hw}"],
    ["key", "set", "{hw}", "q1_T", "--rtol", "0.01"],
    ["rekey", "{hw}"],
    ["override", "{hw}", "ada", "--points", "1", "--reason", "r"],
    ["late", "set", "{hw}", "--due", "2026-01-01T00:00:00+00:00"],
    ["export", "{hw}", "--to", "moodle"],
    ["review", "{hw}", "--no-browser"],
    ["report", "{hw}"],
    ["grade", "{hw}", "{subs}"],
]


@pytest.mark.parametrize("folder, fragment", [
    ("HW-typo", "HW-typo: no such assignment folder"),
    ("empty", "assignment.json: no assignment manifest (assignment.json) here"),
])
@pytest.mark.parametrize("argv", CLASS_COMMANDS,
                         ids=lambda argv: " ".join(a for a in argv[:2] if "{" not in a))
def test_every_command_on_a_class_names_a_wrong_assignment_folder_first(
        tmp_path, capsys, argv, folder, fragment):
    """A mistyped or wrong HW folder is said to be one, not taken for a class that has not
    been graded yet ("run 'eulertop grade' first"); one line, status 2, nothing written."""
    (tmp_path / "empty").mkdir()
    (tmp_path / "subs").mkdir()
    hw = tmp_path / folder
    before = sorted(tmp_path.rglob("*"))
    code = main([a.format(hw=hw, subs=tmp_path / "subs") for a in argv])
    err = capsys.readouterr().err
    assert code == 2
    assert fragment in err and "eulertop grade' first" not in err and "Traceback" not in err
    assert err.count("\n") == 1
    assert sorted(tmp_path.rglob("*")) == before
