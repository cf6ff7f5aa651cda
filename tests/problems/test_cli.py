"""`eulertop problems` and `eulertop generate` from the command line: exit codes and messages."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from eulertop.cli import main

from .conftest import ROSTER, make_rod_family


def test_problems_lists_one_line_per_family(families, capsys):
    assert main(["problems"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(families)
    assert lines[list(families).index("rod")].split(None, 3) == [
        "rod", "test", "R2", "moment of inertia of a thin rod (test only)"]
    assert lines[0].split(None, 3)[:3] == ["inertia_tensor", "built-in", "R2,R4"]


def test_generate_writes_an_assignment(tmp_path, families, roster_path, capsys):
    out = tmp_path / "HW"
    code = main(["generate", "--roster", str(roster_path), "--out", str(out), "--seed", "3",
                 "--problems", "rod,rod2", "--title", "Week 3"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "generated 3 student(s) × 2 question(s)" in printed
    assert (out / "release" / "carol.ipynb").is_file()
    assert (out / "solutions" / "carol.ipynb").is_file()
    # it ends by saying where each part is, and which folder to hand out
    tail = printed.splitlines()[-3:]
    assert f"{out / 'release'}/" in tail[0] and "hand out this folder" in tail[0]
    assert f"{out / 'solutions'}/" in tail[1] and "instructor only" in tail[1]
    assert str(out / "key.json") in tail[2] and "instructor only" in tail[2]


def test_seedless_run_reports_its_seed(tmp_path, families, roster_path, capsys):
    assert main(["generate", "--roster", str(roster_path), "--out", str(tmp_path / "HW")]) == 0
    err = capsys.readouterr().err
    assert "drawn; pass --seed" in err


def test_reroll_from_the_command_line(tmp_path, families, roster_path, capsys):
    out = str(tmp_path / "HW")
    assert main(["generate", "--roster", str(roster_path), "--out", out, "--seed", "3"]) == 0
    assert main(["generate", "--out", out, "--reroll", "bob", "--reroll", "alice"]) == 0
    assert "rerolled 2 student(s)" in capsys.readouterr().out


BAD_ROSTERS = {
    "no id column": ("name\nann\n", "no column 'id'"),
    "duplicate ids": ("id\nann\nbob\nann\n", "'ann' (line 2) and 'ann' (line 4)"),
    "path id": ("id\n../x\n", "line 2, column 'id'"),
    "empty roster": ("", "roster is empty"),
    "not utf-8": (b"id\nj\xfcrgen\n", "not UTF-8"),
}


@pytest.mark.parametrize(
    ("case", "extra", "fragment"),
    [
        *((name, [], frag) for name, (_, frag) in BAD_ROSTERS.items()),
        ("unknown problem", ["--problems", "rod,spinning_plate"],
         "unknown problem 'spinning_plate'; known: "),
        ("reroll with seed", ["--reroll", "ann", "--seed", "2"], "drop --roster, --seed"),
        ("no roster", ["--no-roster"], "--roster CSV is required"),
        ("missing roster", ["--missing-roster"], "cannot read the roster"),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(tmp_path, families, write_roster, capsys, case,
                                              extra, fragment):
    content = BAD_ROSTERS.get(case, (ROSTER,))[0]
    roster = write_roster(content)
    args = ["generate", "--out", str(tmp_path / "HW")]
    if "--missing-roster" in extra:
        args += ["--roster", str(tmp_path / "absent.csv")]
    elif "--no-roster" not in extra:
        args += ["--roster", str(roster)]
    args += [a for a in extra if not a.endswith("-roster")]
    before = sorted(os.listdir(tmp_path))
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("eulertop generate: ") and fragment in err
    if case in BAD_ROSTERS:
        assert str(roster) in err
    assert sorted(os.listdir(tmp_path)) == before


def test_existing_folder_exits_2_unless_forced(tmp_path, families, roster_path, capsys):
    out = tmp_path / "HW"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    args = ["generate", "--roster", str(roster_path), "--out", str(out), "--seed", "1"]
    assert main(args) == 2
    assert "already exists; pass --force" in capsys.readouterr().err
    assert main([*args, "--force"]) == 2  # --force never deletes files it did not write
    assert "also holds notes.txt" in capsys.readouterr().err
    (out / "notes.txt").unlink()
    assert main([*args, "--force"]) == 0


def test_failing_template_exits_1_and_writes_nothing(tmp_path, monkeypatch, roster_path, capsys):
    from problems import templates

    monkeypatch.setitem(templates.FAMILIES, "rod", make_rod_family("rod", fail_on_call=3))
    before = sorted(os.listdir(tmp_path))
    code = main(["generate", "--roster", str(roster_path), "--out", str(tmp_path / "HW"),
                 "--problems", "rod", "--seed", "1"])
    assert code == 1
    err = capsys.readouterr().err
    assert "template 'rod', student 'carol', question 1 failed" in err
    assert "test template exploded" in err and "nothing was written" in err
    assert sorted(os.listdir(tmp_path)) == before


def test_cli_module_imports_light():
    code = ("import sys, problems.cli; heavy = {'numpy', 'nbformat', 'sympy', 'scipy'}; "
            "print(sorted(heavy & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
