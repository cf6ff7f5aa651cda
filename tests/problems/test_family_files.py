"""Families from outside the package: a folder of files and packages, installed entry points,
`eulertop problems` saying where each comes from, and one clear message naming the file for
each way a family can be broken — with nothing written by `eulertop generate`."""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest

from eulertop.cli import main
from problems.family import FamilyError
from problems.family_files import catalogue, folder_families, load_family_file

from .conftest import ROSTER
from .family_sources import pendulum, write_family


@pytest.fixture
def folder(tmp_path):
    """A folder with a family file, a family package, and files that are not families."""
    root = tmp_path / "my_problems"
    write_family(root, "physical_pendulum.py", pendulum())
    package = root / "swing_pkg"
    write_family(package, "__init__.py", "from .body import *  # noqa: F403\n")
    write_family(package, "body.py", pendulum("swing"))
    write_family(root, "_helpers.py", "raise RuntimeError('not a family: never imported')\n")
    write_family(root, "notes.txt", "not Python\n")
    return root


def test_a_folder_holds_files_and_packages(folder):
    found = folder_families(folder)
    assert [f.name for f in found] == ["physical_pendulum", "swing"]
    assert found[0].origin == str(folder / "physical_pendulum.py")
    assert found[1].path == folder / "swing_pkg" / "__init__.py"
    v = found[1].generate(np.random.default_rng(0))
    L, g = v.params["L"], v.params["g"]
    assert v.answer("T").value == pytest.approx(2 * math.pi * math.sqrt(2 * L / (3 * g)),
                                                rel=1e-12)


def test_two_folders_may_both_hold_a_file_of_the_same_name(tmp_path):
    a = write_family(tmp_path / "a", "pendulum.py", pendulum("pendulum_a"))
    b = write_family(tmp_path / "b", "pendulum.py", pendulum("pendulum_b"))
    assert load_family_file(a).name == "pendulum_a" and load_family_file(b).name == "pendulum_b"


def test_problems_lists_where_each_family_comes_from(folder, capsys):
    assert main(["problems", "--families", str(folder)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:2] == ["inertia_tensor", "built-in"]
    assert lines[-2].split()[:3] == ["physical_pendulum", str(folder / "physical_pendulum.py"),
                                     "-"]
    assert lines[-1].split()[:2] == ["swing", str(folder / "swing_pkg")]


def test_generate_takes_families_from_a_folder(tmp_path, folder, write_roster):
    out = tmp_path / "HW"
    assert main(["generate", "--roster", str(write_roster(ROSTER)), "--out", str(out),
                 "--seed", "3", "--families", str(folder),
                 "--problems", "sleeping_top,physical_pendulum,swing"]) == 0
    manifest = json.loads((out / "assignment.json").read_text())
    assert manifest["problems"] == ["sleeping_top", "physical_pendulum", "swing"]
    recorded = manifest["families"]
    assert set(recorded) == {"physical_pendulum", "swing"}  # the built-in is not recorded
    assert recorded["physical_pendulum"]["file"] == os.path.join(
        "..", "my_problems", "physical_pendulum.py")
    nb = json.loads((out / "release" / "alice.ipynb").read_text())
    cell = next(c for c in nb["cells"] if c["id"] == "parameters")
    assert any(line.startswith("q2_L = ") for line in cell["source"])


def _error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err  # one line, no traceback
    return err


BROKEN = {
    "syntax error": ("bad.py", "NAME = 'bad'\ndef answers(p)\n    return ()\n",
                     "bad.py:2: syntax error"),
    "fails on import": ("boom.py", "NAME = 'boom'\nx = 1 / 0\n",
                        "boom.py:2: the family failed when imported: ZeroDivisionError"),
    "missing names": ("half.py", "NAME = 'half'\nTITLE = 'Half'\nSUMMARY = 'half a family'\n",
                      "half.py: a family must define PARAMETERS, answers, statement"),
    "clash with a built-in": ("clash.py", pendulum("turning_points"),
                              "clash.py: NAME 'turning_points' is a built-in family"),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_a_broken_family_is_one_message_naming_its_file_and_nothing_is_written(
        case, tmp_path, write_roster, capsys):
    file, text, fragment = BROKEN[case]
    folder = tmp_path / "fams"
    write_family(folder, file, text)
    roster = write_roster(ROSTER)
    before = sorted(os.listdir(tmp_path))
    code = main(["generate", "--roster", str(roster), "--out", str(tmp_path / "HW"),
                 "--families", str(folder), "--problems", "sleeping_top"])
    assert code == 2
    err = _error(capsys)
    assert err.startswith("eulertop generate: ") and fragment in err
    assert str(folder / file) in err
    assert sorted(os.listdir(tmp_path)) == before


def test_two_families_of_one_name_name_both_files(tmp_path, capsys):
    write_family(tmp_path / "a", "one.py", pendulum("twin"))
    write_family(tmp_path / "b", "two.py", pendulum("twin"))
    assert main(["problems", "--families", str(tmp_path / "a"),
                 "--families", str(tmp_path / "b")]) == 2
    err = _error(capsys)
    assert str(tmp_path / "b" / "two.py") in err and str(tmp_path / "a" / "one.py") in err


def test_a_missing_folder_is_named(tmp_path):
    with pytest.raises(FamilyError, match=f"{tmp_path / 'nowhere'}: no such folder"):
        catalogue([tmp_path / "nowhere"])


@pytest.fixture
def installed(tmp_path, monkeypatch):
    """A distribution on sys.path offering a family through the entry-point group."""
    site = tmp_path / "site"
    write_family(site / "swing_dist", "__init__.py", "")
    write_family(site / "swing_dist", "rod.py", pendulum("installed_rod"))
    info = site / "swing_dist-1.0.dist-info"
    write_family(info, "METADATA", "Metadata-Version: 2.1\nName: swing-dist\nVersion: 1.0\n")
    write_family(info, "entry_points.txt",
                 "[eulertop.families]\ninstalled_rod = swing_dist.rod\n")
    monkeypatch.syspath_prepend(str(site))
    return site


def test_an_installed_package_offers_a_family(installed, capsys):
    families = catalogue()
    found = families["installed_rod"]
    assert found.origin == "entry point installed_rod (swing-dist)"
    assert found.generate(np.random.default_rng(1)).family == "installed_rod"
    assert main(["problems"]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("installed_rod") and "entry point installed_rod (swing-dist)" in last


def test_an_installed_family_that_cannot_be_imported_is_named(installed):
    write_family(installed / "swing_dist", "broken.py", "import no_such_module\n")
    entry = installed / "swing_dist-1.0.dist-info" / "entry_points.txt"
    entry.write_text("[eulertop.families]\nbroken = swing_dist.broken\n")
    with pytest.raises(FamilyError, match=r"entry point broken \(swing-dist\): "
                                          r"swing_dist.broken cannot be imported"):
        catalogue()


def test_an_outside_family_is_graded_like_a_built_in(tmp_path, folder, write_roster, capsys):
    """Its solutions notebooks, handed in, get full marks from `eulertop grade`; a wrong period
    is recognised as the family's own known mistake."""
    import csv
    import shutil

    out, subs = tmp_path / "HW", tmp_path / "subs"
    roster = write_roster("id\nann\nbob\n")
    assert main(["generate", "--roster", str(roster), "--out", str(out), "--seed", "5",
                 "--families", str(folder), "--problems", "physical_pendulum,sleeping_top"]) == 0
    subs.mkdir()
    shutil.copy(out / "solutions" / "ann.ipynb", subs / "ann.ipynb")
    nb = json.loads((out / "solutions" / "bob.ipynb").read_text())
    cell = next(c for c in nb["cells"] if c["id"] == "q1-answer")
    L = json.loads((out / "assignment.json").read_text())["students"]["bob"]["questions"][0][
        "params"]["L"]
    point_mass = 2 * math.pi * math.sqrt(L / 9.81)  # the simple pendulum's period
    cell["source"] = [line if not line.startswith("q1_T") else f"q1_T = {point_mass!r}\n"
                      for line in cell["source"]]
    (subs / "bob.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    assert main(["grade", str(out), str(subs)]) == 0
    with open(out / "graded" / "grades.csv", newline="") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    assert rows["ann"]["total"] == rows["ann"]["maximum"] == "3.5"  # 1 + 1, then 1 + 0.5
    assert rows["bob"]["total"] == "2.5"
    bob = json.loads((out / "graded" / "results" / "bob.json").read_text())
    verdict = next(a for a in bob["answers"] if a["variable"] == "q1_T")["verdict"]
    assert (verdict["status"], verdict["mistake"]) == ("wrong", "simple_pendulum")
