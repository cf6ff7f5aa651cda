"""An assignment spec drives points, tolerances, parameters and pools (`eulertop generate --spec`):
the issue's own example, byte-for-byte reproducibility, rerolls, and one message naming the
file, line and key for each kind of bad input, with nothing written."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from eulertop import family_example
from eulertop.cli import main
from problems.spec import SpecError, key_line, read_spec

from .family_sources import pendulum, write_family

EXAMPLE = """\
title = "PHY 711 HW 9"
seed = 7
roster = "roster.csv"              # paths relative to this file
families = ["my_problems"]         # folders of extra families

[[questions]]
family = "turning_points"
points = 6                         # the question's total, spread by the answers' weights

[[questions]]
family = "physical_pendulum"
[questions.answers.T]
points = 2
rtol = 5e-3
[questions.parameters]
L = 0.75                           # fixed for everyone
m = [0.2, 0.5]                     # drawn in this range instead of the family's

[[questions]]
pool = ["sleeping_top", "steady_precession"]   # each student gets one, from the seed
points = 4
"""

CLASS = "id\n" + "".join(f"s{i:02d}\n" for i in range(16))


@pytest.fixture
def course(tmp_path):
    """A course folder: the spec, its roster, its folder of families."""
    root = tmp_path / "course"
    write_family(root / "my_problems", "physical_pendulum.py", pendulum())
    write_family(root, "roster.csv", CLASS)
    write_family(root, "assignment.toml", EXAMPLE)
    return root


def generate(spec, out, *extra) -> int:
    return main(["generate", "--spec", str(spec), "--out", str(out), *extra])


def load(out, name):
    return json.loads((out / name).read_text(encoding="utf-8"))


def test_the_spec_drives_points_tolerances_parameters_and_pools(course, capsys):
    out = course / "HW"
    assert generate(course / "assignment.toml", out) == 0
    assert "generated 16 student(s) × 3 question(s)" in capsys.readouterr().out
    manifest, key = load(out, "assignment.json"), load(out, "key.json")
    assert manifest["title"] == "PHY 711 HW 9" and manifest["seed"] == 7
    assert manifest["problems"] == ["turning_points", "physical_pendulum",
                                    "sleeping_top|steady_precession"]
    pooled = set()
    for sid, student in key["students"].items():
        q1, q2, q3 = student["questions"]
        assert [a["points"] for a in q1["answers"]] == [2.0, 2.0, 2.0]  # 6 over 3 equal weights
        answers = {a["name"]: a for a in q2["answers"]}
        assert (answers["T"]["points"], answers["T"]["rtol"]) == (2.0, 5e-3)
        assert (answers["I"]["points"], answers["I"]["rtol"]) == (1.0, 1e-3)  # the family's
        params = manifest["students"][sid]["questions"][1]["params"]
        assert params["L"] == 0.75 and 0.2 <= params["m"] <= 0.5
        period = 2 * math.pi * math.sqrt(2 * 0.75 / (3 * 9.81))  # R2 and the parallel axes
        assert answers["T"]["value"] == pytest.approx(period, rel=1e-12)
        assert sum(a["points"] for a in q3["answers"]) == pytest.approx(4.0)
        pooled.add(q3["family"])
    assert pooled == {"sleeping_top", "steady_precession"}
    # the tolerance the spec set is the one the student's notebook states
    nb = json.loads((out / "release" / "s00.ipynb").read_text())
    cell = "".join(next(c for c in nb["cells"] if c["id"] == "q2-statement")["source"])
    assert "`q2_T`: within 0.5 %" in cell and "`q2_I`: within 0.1 %" in cell


def test_the_spec_is_copied_and_recorded(course):
    out = course / "HW"
    assert generate(course / "assignment.toml", out) == 0
    assert (out / "assignment.toml").read_bytes() == (course / "assignment.toml").read_bytes()
    manifest = load(out, "assignment.json")
    assert manifest["spec"]["file"] == "assignment.toml"
    question = manifest["questions"][1]
    assert question["settings"]["parameters"] == {"L": {"value": 0.75},
                                                  "m": {"range": [0.2, 0.5]}}
    assert manifest["families"]["physical_pendulum"]["file"] == os.path.join(
        "..", "my_problems", "physical_pendulum.py")


def test_the_same_spec_and_seed_give_the_same_files_byte_for_byte(course, read_tree):
    assert generate(course / "assignment.toml", course / "HW") == 0
    first = read_tree(course / "HW")
    os.rename(course / "HW", course / "first")
    assert generate(course / "assignment.toml", course / "HW") == 0
    assert read_tree(course / "HW") == first
    assert generate(course / "assignment.toml", course / "other", "--seed", "8") == 0
    assert load(course / "other", "key.json") != load(course / "HW", "key.json")


def test_command_line_options_override_the_spec(course, write_roster):
    roster = write_roster("id\nzed\n")
    out = course / "HW"
    assert generate(course / "assignment.toml", out, "--roster", str(roster), "--seed", "9",
                    "--title", "Other") == 0
    manifest = load(out, "assignment.json")
    assert (manifest["seed"], manifest["title"], list(manifest["students"])) == (9, "Other",
                                                                                 ["zed"])


def test_a_reroll_draws_with_the_spec_settings_and_families(course, read_tree):
    out = course / "HW"
    assert generate(course / "assignment.toml", out) == 0
    before = read_tree(out)
    assert main(["generate", "--out", str(out), "--reroll", "s03"]) == 0
    after = read_tree(out)
    changed = {p for p in after if after[p] != before.get(p)}
    assert changed == {"assignment.json", "key.json", "release/s03.ipynb",
                       "solutions/s03.ipynb"}
    manifest = load(out, "assignment.json")
    params = manifest["students"]["s03"]["questions"][1]["params"]
    assert params["L"] == 0.75 and 0.2 <= params["m"] <= 0.5
    points = [a["points"] for a in manifest["students"]["s03"]["questions"][0]["answers"]]
    assert points == [2.0, 2.0, 2.0]


BAD = {
    "unknown top-level key": ('colour = "red"\n', ("colour =",), "colour: unknown key"),
    "unknown question key": ('[[questions]]\nfamily = "sleeping_top"\nweight = 2\n',
                             ("weight =",), "questions[1].weight: unknown key"),
    "unknown family": ('[[questions]]\nfamily = "turning_pointz"\n', ('family = "turning_pointz"',),
                       "questions[1].family: unknown family 'turning_pointz'; known: "),
    "zero points": ('[[questions]]\nfamily = "sleeping_top"\npoints = 0\n', ("points = 0",),
                    "questions[1].points: must be a number > 0"),
    "negative answer points": ('[[questions]]\nfamily = "sleeping_top"\n'
                               '[questions.answers.omega3_c]\npoints = -1\n', ("points = -1",),
                               "questions[1].answers.omega3_c.points: must be a number > 0"),
    "range outside the family's": (
        '[[questions]]\nfamily = "physical_pendulum"\n[questions.parameters]\nm = [0.2, 5.0]\n',
        ("m = [0.2, 5.0]",),
        "questions[1].parameters.m: the range [0.2, 5] is outside what physical_pendulum "
        "accepts for m, [0.1, 1]"),
    "a fixed value with too many figures": (
        '[[questions]]\nfamily = "physical_pendulum"\nparameters = { L = 0.7512 }\n',
        ("parameters = { L = 0.7512 }",), "questions[1].parameters.L: physical_pendulum.L: "
                                          "0.7512 has more than 3 significant figures"),
    "a derived parameter": ('[[questions]]\nfamily = "sleeping_top"\n[questions.parameters]\n'
                            'omega3 = 100\n', ("omega3 = 100",),
                            "questions[1].parameters.omega3: sleeping_top derives 'omega3'"),
    "an unknown label": ('[[questions]]\nfamily = "sleeping_top"\n[questions.parameters]\n'
                         'top = "spinning_plate"\n', ('top = "spinning_plate"',),
                         "questions[1].parameters.top: sleeping_top.top is one of 'disc'"),
    "a range where no draw is well posed": (
        '[[questions]]\nfamily = "projectile"\n[questions.parameters]\ntheta = [0.78, 0.79]\n',
        ("[questions.parameters]",),
        "questions[1].parameters: no well-posed draw of projectile in 400 tries"),
    "an answer the question does not ask": (
        '[[questions]]\nfamily = "physical_pendulum"\n[questions.answers.X]\npoints = 2\n',
        ("[questions.answers.X]",), "questions[1].answers.X: no such answer; the question "
                                    "asks for I, T"),
    "a tolerance on a boolean": (
        '[[questions]]\nfamily = "sleeping_top"\n[questions.answers.stable]\nrtol = 0.01\n',
        ("[questions.answers.stable]",), "a boolean answer has no tolerance"),
    "answer points beyond the total": (
        '[[questions]]\nfamily = "physical_pendulum"\npoints = 1\n'
        '[questions.answers.T]\npoints = 2\n', ("points = 1",),
        "questions[1].points: the answers' own points add up to 2"),
    "family and pool": ('[[questions]]\nfamily = "a"\npool = ["b"]\n', ("[[questions]]",),
                        "questions[1]: give either family"),
    "a seed that is text": ('seed = "seven"\n[[questions]]\nfamily = "sleeping_top"\n',
                            ('seed = "seven"',), "seed: must be a whole number"),
    "not TOML": ('[[questions]\nfamily = "x"\n', ("[[questions]",), "not valid TOML"),
    "a folder of families that is not there": (
        'families = ["my_problems", "nowhere"]\n[[questions]]\nfamily = "sleeping_top"\n',
        ("families = [",), "families[2]: "),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_is_one_message_naming_file_line_and_key_and_nothing_is_written(
        case, course, capsys):
    body, (marker,), fragment = BAD[case]
    write_family(course / "fams", "projectile.py",
                 Path(family_example.__file__).read_text(encoding="utf-8"))
    folders = "" if body.startswith("families") else 'families = ["my_problems", "fams"]\n'
    text = 'roster = "roster.csv"\n' + folders + body
    spec = write_family(course, "bad.toml", text)
    line = next(i for i, t in enumerate(text.splitlines(), 1) if t.startswith(marker))
    before = sorted(os.listdir(course))
    assert generate(spec, course / "HW") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"eulertop generate: {spec}:{line}: "), err
    assert fragment in err, err
    assert sorted(os.listdir(course)) == before


def test_questions_by_spec_or_by_problems_not_both(course, capsys):
    assert generate(course / "assignment.toml", course / "HW", "--problems",
                    "sleeping_top") == 2
    assert "either in --spec or by --problems" in capsys.readouterr().err


def test_a_missing_spec_file_is_named(tmp_path, capsys):
    assert generate(tmp_path / "absent.toml", tmp_path / "HW") == 2
    assert f"{tmp_path / 'absent.toml'}: cannot read the spec" in capsys.readouterr().err


@pytest.mark.parametrize(("key", "expected"), [
    (("title",), 1),
    (("questions", 0), 4),
    (("questions", 0, "family"), 5),
    (("questions", 1, "parameters"), 9),
    (("questions", 1, "parameters", "m"), 11),
    (("questions", 1, "parameters", "L"), 9),  # inline: the table's line
    (("questions", 1, "answers", "T", "rtol"), 14),
    (("questions", 2, "pool"), 17),
    (("questions", 2, "points"), 16),  # not written: the question's own line
    (("nowhere",), 1),
])
def test_key_line_finds_tables_arrays_of_tables_dotted_and_inline_keys(key, expected):
    text = ('title = "x"\n'
            'seed = 1\n'
            '\n'
            '[[questions]]\n'
            'family = "a"   # a comment, [brackets] = too\n'
            'points = 2\n'
            '\n'
            '[[questions]]\n'
            'parameters = { L = 0.75, n = [1,\n'
            '  2] }\n'
            'parameters.m = [0.2, 0.5]\n'
            'family = "b"\n'
            '[questions.answers.T]\n'
            'rtol = 1e-2\n'
            '\n'
            '[[questions]]\n'
            'pool = ["c", "d"]\n')
    assert key_line(text, key) == expected


def test_read_spec_resolves_paths_against_the_spec_file(course):
    spec = read_spec(course / "assignment.toml")
    assert spec.roster == course / "roster.csv"
    assert spec.families == (course / "my_problems",)
    assert [q.pool for q in spec.questions] == [("turning_points",), ("physical_pendulum",),
                                                ("sleeping_top", "steady_precession")]
    with pytest.raises(SpecError, match="give at least one"):
        read_spec(write_family(course, "empty.toml", 'title = "x"\n'))


def test_every_key_is_recomputed_from_the_recorded_parameters_and_settings(course):
    """What assignment.json records is enough: each student's key entry and manifest entry,
    recomputed without drawing, are the ones written."""
    from problems.family_files import catalogue
    from problems.generate import key_entry, manifest_entry, recorded_variants

    out = course / "HW"
    assert generate(course / "assignment.toml", out) == 0
    manifest, key = load(out, "assignment.json"), load(out, "key.json")
    families = catalogue([course / "my_problems"])
    for sid in manifest["students"]:
        variants = recorded_variants(manifest, families, sid)
        assert key_entry(variants) == key["students"][sid]
        assert manifest_entry(variants, 0) == manifest["students"][sid]


def test_a_plain_assignment_of_every_family_is_recomputed_too(tmp_path):
    from problems.generate import generate_assignment, key_entry, recorded_variants
    from problems.roster import Roster
    from problems.templates import FAMILIES

    out = tmp_path / "HW"
    generate_assignment(Roster(("id",), ({"id": "a"}, {"id": "b"}, {"id": "c"})), out,
                        FAMILIES, seed=21)
    manifest, key = load(out, "assignment.json"), load(out, "key.json")
    for sid in manifest["students"]:
        assert key_entry(recorded_variants(manifest, FAMILIES, sid)) == key["students"][sid]
