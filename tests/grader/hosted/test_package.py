"""``eulertop package``: the command, its wheel and pins, and its users' mistakes."""

from __future__ import annotations

import json
import zipfile
from importlib import metadata
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.hosted.grading import CONFIG


@pytest.fixture
def fake_wheel(tmp_path) -> Path:
    wheel = tmp_path / "eulertop-0.1.0-py3-none-any.whl"
    wheel.write_bytes(b"a stand-in: these tests do not install it")
    return wheel


@pytest.mark.slow
def test_gradescope_zip_carries_a_wheel_of_this_eulertop_and_its_pins(hosted_hw, tmp_path,
                                                                      capsys):
    out = tmp_path / "autograder.zip"
    status = main(["package", str(hosted_hw.folder), "--for", "gradescope", "--out", str(out),
                   "--visibility", "after_due_date", "--timeout", "90"])
    assert status == 0, capsys.readouterr().err
    with zipfile.ZipFile(out) as zf:
        [wheel_name] = [n for n in zf.namelist() if n.endswith(".whl")]
        pins = zf.read("constraints.txt").decode().split()
        config = json.loads(zf.read(CONFIG))
        wheel_bytes = zf.read(wheel_name)
    (tmp_path / wheel_name).write_bytes(wheel_bytes)
    with zipfile.ZipFile(tmp_path / wheel_name) as wheel:
        meta = next(wheel.read(n).decode() for n in wheel.namelist()
                    if n.endswith(".dist-info/METADATA"))
        packaged = {n.split("/")[0] for n in wheel.namelist()}
    assert "Name: eulertop" in meta and f"Version: {metadata.version('eulertop')}" in meta
    assert {"grader", "problems", "solver", "eulertop"} <= packaged
    assert "tests" not in packaged
    for dist in ("numpy", "ipykernel", "nbclient"):
        assert f"{dist}=={metadata.version(dist)}" in pins
    assert config["visibility"] == "after_due_date"
    assert config["limits"]["total_timeout"] == 90
    assert "Configure Autograder" in capsys.readouterr().out


def test_prairielearn_question_and_image_recipe(hosted_hw, tmp_path, fake_wheel, capsys):
    out = tmp_path / "course"
    args = ["package", str(hosted_hw.folder), "--for", "prairielearn", "--out", str(out),
            "--wheel", str(fake_wheel), "--variants", "2", "--image", "me/eulertop-grader"]
    assert main(args) == 0
    question = out / "questions" / "HW"
    assert sorted(p.name for p in (question / "variants").iterdir()) == ["v000.ipynb",
                                                                        "v001.ipynb"]
    assert sorted(p.name for p in (out / "solutions" / "HW").iterdir()) == ["v000.ipynb",
                                                                            "v001.ipynb"]
    assert not (question / "solutions").exists()
    info = json.loads((question / "info.json").read_text())
    assert info["externalGradingOptions"]["image"] == "me/eulertop-grader"
    dockerfile = (out / "grader-image" / "Dockerfile").read_text()
    assert fake_wheel.name in dockerfile and (out / "grader-image" / fake_wheel.name).is_file()
    capsys.readouterr()
    assert main(args) == 2  # never overwrites a question
    assert "exists already" in capsys.readouterr().err


@pytest.mark.parametrize(("extra", "message"), [
    (["--for", "gradescope", "--out", "autograder.txt"], "takes a .zip file"),
    (["--for", "gradescope", "--out", "a.zip", "--wheel", "notes.txt"], "not a wheel file"),
    (["--for", "gradescope", "--out", "a.zip", "--kernel-user", "root"], "unprivileged user"),
])
def test_mistakes_are_named_with_exit_2(hosted_hw, tmp_path, capsys, monkeypatch, extra,
                                        message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text("x")
    assert main(["package", str(hosted_hw.folder), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("eulertop package: ") and message in err and "Traceback" not in err


def test_no_assignment_folder_is_named(tmp_path, capsys):
    assert main(["package", str(tmp_path / "nope"), "--for", "gradescope", "--out",
                 str(tmp_path / "a.zip")]) == 2
    assert "no such assignment folder" in capsys.readouterr().err


def test_a_spec_s_pools_and_points_reach_the_prairielearn_variants(tmp_path, fake_wheel):
    """A question's variants are generated as the assignment was — from its spec (a pool, the
    points it sets), not from its problems' names alone (a pool's label, ``a|b``, is no
    family)."""
    (tmp_path / "roster.csv").write_text("id\nann\nbob\n")
    (tmp_path / "hw.toml").write_text(
        'title = "Tops"\nseed = 3\nroster = "roster.csv"\n\n'
        '[[questions]]\npool = ["sleeping_top", "steady_precession"]\npoints = 5\n')
    assert main(["generate", "--spec", str(tmp_path / "hw.toml"), "--out",
                 str(tmp_path / "HW")]) == 0
    out = tmp_path / "course"
    assert main(["package", str(tmp_path / "HW"), "--for", "prairielearn", "--out", str(out),
                 "--wheel", str(fake_wheel), "--variants", "4"]) == 0
    key = json.loads((out / "questions" / "HW" / "tests" / "assignment" / "key.json")
                     .read_text())
    families = {q["family"] for s in key["students"].values() for q in s["questions"]}
    points = {sum(a["points"] for q in s["questions"] for a in q["answers"])
              for s in key["students"].values()}
    assert len(key["students"]) == 4
    assert families <= {"sleeping_top", "steady_precession"} and points == {5}
