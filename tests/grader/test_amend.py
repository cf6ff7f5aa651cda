"""Amending a graded class without running a notebook again (issue 26): follow-through credit,
``eulertop rescore``, ``key set`` / ``rekey``, overrides and the audit trail.

The class is graded with a fake execution stage that reads each submission's answers as the
literals its code cell assigns (no kernel starts: the submissions here are data, and what is
under test is what happens to the answers once extracted). One question per family that declares a
follow-through chain; four students per chain scenario:

- ``right``: the key's values;
- ``follows``: a wrong earlier answer and the later one computed correctly from it;
- ``stray``: the same wrong earlier answer and a later one that follows from neither;
- ``blank``: the earlier answer left unset, the later one computed from a wrong value.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import stat
from pathlib import Path

import nbformat
import numpy as np
import pytest

from eulertop.cli import main
from grader import follow_through
from grader.assignment import UsageError
from grader.audit import read_trail, who
from grader.graded_folder import RESULTS
from grader.overrides import OVERRIDES
from grader.pipeline import grade_assignment
from grader.rescore import rescore
from grader.results import read_result
from problems.family_files import catalogue
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

CHAIN_FAMILIES = ("sleeping_top", "symmetric_free_top", "heavy_top_constants",
                  "inertia_tensor", "energy_momentum", "euler_rotation", "steady_precession",
                  "motion_type", "symbolic_derivation")
STUDENTS = ("right", "follows", "stray", "blank")
PROGRESS: dict[Path, dict[str, float]] = {}  # the points each grading run's progress showed


# -- what each student submits


def _key(hw: Path) -> dict:
    return json.loads((hw / "key.json").read_text())


def _manifest(hw: Path) -> dict:
    return json.loads((hw / "assignment.json").read_text())


def _wrong_earlier(name: str, value, later: dict, params: dict, consistent: bool):
    """A wrong value of the earlier answer ``name``. For a boolean or choice later answer it is
    chosen so that what follows from it differs from the key (``consistent``) or equals it."""
    if later["kind"] == "boolean":  # sleeping_top: the critical spin against the given one
        stable = params["omega3"] >= value
        if consistent:  # across the given spin: the other verdict follows
            return params["omega3"] * (1.5 if stable else 0.5)
        return value * (0.8 if stable else 1.2)  # wrong, but on the same side
    if isinstance(value, str):
        return f"2*({value})"
    if name == "R":
        return np.reshape(value, (3, 3)).T.ravel().tolist()  # transposed: the classic mistake
    if isinstance(value, list):
        out = list(value)
        out[0] += 0.2 * max(abs(v) for v in value)
        return out
    return value * 1.2


def _wrong_rate(values: dict, consistent: bool) -> tuple[str, float]:
    """motion_type: a wrong precession rate at a turning point (name, value) that changes the
    kind of motion (``consistent``: the student's own loops where the key has waves, …) or
    keeps it."""
    a1, a2 = values["alpha_dot1"], values["alpha_dot2"]
    zero = "alpha_dot1" if abs(a1) < abs(a2) else "alpha_dot2"
    other = a2 if zero == "alpha_dot1" else a1
    if values["motion"] == "cusps":  # one rate zero: a student's nonzero one makes waves
        return (zero, other) if consistent else \
            ("alpha_dot2" if zero == "alpha_dot1" else "alpha_dot1", other * 1.2)
    return ("alpha_dot2", -a2) if consistent else ("alpha_dot2", 1.2 * a2)


def _stray(later: dict, followed, key_value):
    """A later answer that is neither the key's nor what follows from the earlier one."""
    if later["kind"] == "boolean":
        return not key_value  # followed == key here: the other value matches neither
    if later["kind"] == "choice":
        return next(o for o in later["options"] if o not in (followed, key_value))
    if isinstance(followed, list):
        return [1.5 * x + 0.3 for x in followed]
    return 1.5 * followed + 0.3


def _chains(hw: Path, sid: str):
    """(question number, family, later answer record, earlier names, key values) of ``sid``."""
    manifest, key = _manifest(hw), _key(hw)
    for k, (question, entry) in enumerate(zip(manifest["students"][sid]["questions"],
                                              key["students"][sid]["questions"], strict=True),
                                          start=1):
        values = {a["name"]: a["value"] for a in entry["answers"]}
        for a in entry["answers"]:
            if a.get("depends_on"):
                yield k, question, a, a["depends_on"], values


def _submission(hw: Path, sid: str) -> dict:
    key = _key(hw)
    answers = {f"q{q['question']}_{a['name']}": a["value"]
               for q in key["students"][sid]["questions"] for a in q["answers"]}
    if sid == "right":
        return answers
    for k, question, later, names, values in _chains(hw, sid):
        family, params = question["family"], question["parameters"]
        earlier = dict(values)
        if family == "motion_type":
            first, earlier[first] = _wrong_rate(values, consistent=sid != "stray")
        else:
            first = names[0]
            earlier[first] = _wrong_earlier(first, values[first], later, params,
                                            consistent=sid != "stray")
        followed = FAMILIES[family].follow(later["name"], params,
                                           {n: earlier[n] for n in later["depends_on"]})
        followed = followed.tolist() if hasattr(followed, "tolist") else followed
        answers[f"q{k}_{first}"] = None if sid == "blank" else earlier[first]
        answers[f"q{k}_{later['name']}"] = (_stray(later, followed, values[later["name"]])
                                           if sid == "stray" else followed)
    return answers


def _notebook(answers: dict) -> str:
    """A submission setting each answer variable to a literal (what ``LiteralExecute`` reads
    as its kernel's value)."""
    code = "\n".join(f"{name} = {value!r}" for name, value in answers.items())
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))


def _write_submissions(hw: Path, folder: Path, students=STUDENTS) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for sid in students:
        (folder / f"{sid}.ipynb").write_text(_notebook(_submission(hw, sid)))
    return folder


@pytest.fixture(scope="module")
def chain_class(tmp_path_factory) -> tuple[Path, Path]:
    """A graded class (HW with HW/graded) and its submissions; copy before changing it."""
    root = tmp_path_factory.mktemp("amend")
    hw = root / "HW"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s.title()} for s in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=list(CHAIN_FAMILIES), seed=26)
    subs = _write_submissions(hw, root / "subs")
    shown = PROGRESS.setdefault(hw, {})
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=2,
                     progress=lambda r: shown.__setitem__(r.student_id, r.points))
    return hw, subs


@pytest.fixture
def graded(chain_class, tmp_path) -> tuple[Path, Path]:
    hw, subs = chain_class
    return Path(shutil.copytree(hw, tmp_path / "HW")), subs


def _records(hw: Path) -> dict:
    return {sid: read_result(hw / "graded" / RESULTS / f"{sid}.json") for sid in STUDENTS}


def _verdicts(hw: Path, sid: str) -> dict:
    return {a.variable: a.verdict for a in _records(hw)[sid].answers}


def _later_variables(hw: Path, sid: str) -> dict[str, tuple[str, str]]:
    """Each chained later answer's variable → (family, its first earlier variable)."""
    found = {}
    for k, question, later, names, _ in _chains(hw, sid):
        found[f"q{k}_{later['name']}"] = (question["family"], [f"q{k}_{n}" for n in names])
    return found


def _workers() -> list[int]:
    """This process's children that are follow-through workers (none may outlive a run)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            command = (entry / "cmdline").read_bytes()
        except (OSError, ValueError, IndexError):
            continue
        if ppid == os.getpid() and b"grader.follow_through" in command:
            found.append(int(entry.name))
    return found


# -- follow-through credit


def test_every_chain_family_asks_a_chained_answer(chain_class):
    hw, _ = chain_class
    families = {family for family, _ in _later_variables(hw, "follows").values()}
    assert families == set(CHAIN_FAMILIES)


@pytest.mark.parametrize("family", CHAIN_FAMILIES)
def test_follow_through_credit_per_chain(chain_class, family):
    hw, _ = chain_class
    for sid in STUDENTS:
        verdicts = _verdicts(hw, sid)
        for variable, (fam, earlier) in _later_variables(hw, sid).items():
            if fam != family:
                continue
            v = verdicts[variable]
            if sid == "right":
                assert v.status == "correct"
            elif sid == "follows":
                assert v.status == "follows", (variable, v.message)
                assert v.points == v.max_points > 0
                assert re.search(r"follows from your .*q\d+_\w+ = ", v.message), v.message
                assert any(e in v.message for e in earlier)
            else:  # stray (follows from nothing), blank (nothing to follow from)
                assert v.status == "wrong", (sid, variable, v.message)
                assert v.points == 0
                assert "follows from" not in v.message


def test_follow_through_is_counted_in_the_outputs(chain_class):
    hw, _ = chain_class
    out = hw / "graded"
    follows = sum(v.status == "follows" for v in _verdicts(hw, "follows").values())
    assert follows >= len(CHAIN_FAMILIES)
    assert PROGRESS[hw] == {sid: r.points for sid, r in _records(hw).items()}  # as recorded
    with open(out / "answers.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["id"] == "follows"]
    assert sum(r["status"] == "follows" for r in rows) == follows
    page = (out / "feedback" / "follows.html").read_text()
    assert page.count("follows from your") == follows
    with open(out / "report_items.csv", newline="") as f:
        items = [r for r in csv.DictReader(f) if r["answer"]]
    assert sum(int(r["follows"]) for r in items) == follows  # the only one who follows
    assert "<th>follows</th>" in (out / "report.html").read_text()


@pytest.mark.parametrize("fraction", [0.5, 0.0])
def test_follow_through_fraction(graded, fraction):
    hw, _ = graded
    manifest = _manifest(hw)
    manifest["follow_through"] = fraction
    (hw / "assignment.json").write_text(json.dumps(manifest))
    rescore(hw)
    assert _workers() == []  # the rescore's worker stopped with it
    for variable in _later_variables(hw, "follows"):
        v = _verdicts(hw, "follows")[variable]
        if fraction:
            assert (v.status, v.points) == ("follows", 0.5 * v.max_points)
        else:
            assert (v.status, v.points) == ("wrong", 0.0)


def test_spec_sets_the_fraction(tmp_path, capsys):
    roster = tmp_path / "roster.csv"
    roster.write_text("id,name\nada,Ada\n")
    spec = tmp_path / "hw.toml"
    spec.write_text('roster = "roster.csv"\nseed = 3\nfollow_through = 0.25\n\n'
                    '[[questions]]\nfamily = "sleeping_top"\n')
    assert main(["generate", "--spec", str(spec), "--out", str(tmp_path / "HW")]) == 0
    assert _manifest(tmp_path / "HW")["follow_through"] == 0.25
    spec.write_text(spec.read_text().replace("0.25", "1.5"))
    assert main(["generate", "--spec", str(spec), "--out", str(tmp_path / "HW2")]) == 2
    err = capsys.readouterr().err
    assert "hw.toml:3: follow_through: must be a fraction from 0 to 1" in err
    assert not (tmp_path / "HW2").exists()


FAMILY_FILE = '''
import time

from eulertop.family import Answer, Parameter, follows_from

NAME = "slow_chain"
TITLE = "A chain whose recomputation can hang"
SUMMARY = "b = a + 1, computed from a = 2 x"
PARAMETERS = {"x": Parameter(low=1.0, high=2.0, figures=3)}


def answers(params):
    a = 2 * params["x"]
    return (Answer("a", "scalar", a), follows_from(Answer("b", "scalar", a + 1), "a"))


def statement(params):
    return "Compute $a = 2x$, then $b = a + 1$ from your $a$."


def follow(name, params, earlier):
    if earlier["a"] < 0:
        time.sleep(600)  # stands for a recomputation that never ends
    return earlier["a"] + 1
'''


def test_a_recomputation_that_hangs_earns_nothing_and_stops_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(follow_through, "FOLLOW_SECONDS", 2.0)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "slow_chain.py").write_text(FAMILY_FILE)
    hw = tmp_path / "HW"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in ("stuck", "fine")))
    generate_assignment(roster, hw, catalogue([tmp_path / "mine"]), problems=["slow_chain"],
                        seed=1)
    subs = tmp_path / "subs"
    subs.mkdir()
    for sid, a in (("stuck", -1.0), ("fine", 7.0)):
        (subs / f"{sid}.ipynb").write_text(_notebook({"q1_a": a, "q1_b": a + 1}))
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1)
    assert _workers() == []  # the stuck one killed, its successor stopped with the run
    stuck = {a.variable: a.verdict for a in read_result(hw / "graded/results/stuck.json")
             .answers}
    fine = {a.variable: a.verdict for a in read_result(hw / "graded/results/fine.json").answers}
    assert stuck["q1_b"].status == "wrong" and stuck["q1_b"].points == 0
    assert fine["q1_b"].status == "follows" and fine["q1_b"].points == 1.0


# -- rescore


def _snapshot(out: Path) -> dict[str, str]:
    """Every file a grading run or a rescore writes, timestamps and run times blanked."""
    stamp = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?(\+00:00|Z)?|"
                       r"\d{4}-\d\d-\d\d \d\d:\d\d(:\d\d)?( UTC)?")
    files = {}
    for path in sorted(out.rglob("*")):
        name = str(path.relative_to(out))
        if path.is_dir() or name in ("audit.jsonl", "run.log") or name.startswith(".") \
                or "/." in name:
            continue
        text = path.read_text(errors="replace")
        if path.suffix == ".json":
            record = json.loads(text)
            record.pop("graded_at", None)
            text = json.dumps(record, sort_keys=True)
        files[name] = stamp.sub("<time>", text)
    return files


def test_rescore_equals_a_forced_regrade_and_starts_no_kernel(graded, tmp_path, monkeypatch):
    hw, subs = graded
    key = _key(hw)
    for entry in key["students"].values():  # a key change: tolerances, points, accepted
        for q in entry["questions"]:
            for a in q["answers"]:
                if a["kind"] == "scalar":  # wide enough for a 20 % slip (and its mistakes)
                    a["rtol"], a["points"], a["mistakes"] = 0.3, 2.0, []
    (hw / "key.json").write_text(json.dumps(key))
    forced = Path(shutil.copytree(hw, tmp_path / "forced"))

    def no_kernel(*args, **kwargs):
        raise AssertionError("a rescore started a kernel")

    import grader.grade_one
    import grader.kernels.local

    monkeypatch.setattr(grader.grade_one, "run_one", no_kernel)
    monkeypatch.setattr(grader.kernels.local.LocalKernel, "start", no_kernel, raising=False)
    report = rescore(hw)
    monkeypatch.undo()
    assert report.changes  # the wider tolerance and the new points changed grades
    execute = LiteralExecute()
    grade_assignment(forced, subs, limits="LIMITS", execute=execute, jobs=2, force=True)
    assert execute.calls == len(STUDENTS)
    assert _snapshot(hw / "graded") == _snapshot(forced / "graded")


def test_rescore_dry_run_writes_nothing(graded):
    hw, _ = graded
    key = _key(hw)
    key["students"]["right"]["questions"][0]["answers"][-1]["points"] = 5.0
    (hw / "key.json").write_text(json.dumps(key))
    before = {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()}
    report = rescore(hw, dry_run=True)
    assert report.dry_run and report.changes
    after = {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()}
    assert after == before


def test_a_key_edited_into_nonsense_is_refused_by_name(graded):
    hw, subs = graded
    key = _key(hw)
    answer = key["students"]["blank"]["questions"][2]["answers"][0]
    answer["rtol"] = 0.5  # its known mistakes now within the tolerance: not a key
    (hw / "key.json").write_text(json.dumps(key))
    before = {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()}
    for run in (lambda: rescore(hw), lambda: grade_assignment(
            hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=2, force=True)):
        with pytest.raises(UsageError, match=r"key.json: blank's entry cannot be read: .*"
                                             r"indistinguishable"):
            run()
    assert {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()} == before


def test_rescore_without_records_is_a_usage_error(tmp_path):
    hw = tmp_path / "HW"
    roster = Roster(("id", "name"), ({"id": "ada", "name": "Ada"},))
    generate_assignment(roster, hw, FAMILIES, problems=["sleeping_top"], seed=1)
    with pytest.raises(UsageError, match="no result records here"):
        rescore(hw)


# -- key set, rekey


def _cli(capsys, *argv) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_key_set_rescores_and_keeps_the_old_key(graded, capsys):
    hw, _ = graded
    variable = next(iter(_later_variables(hw, "stray")))
    was = {a.variable: a.verdict.max_points for a in _records(hw)["stray"].answers}[variable]
    old = (hw / "key.json").read_bytes()
    code, out, _ = _cli(capsys, "key", "set", str(hw), f"stray:{variable}", "--points", "3")
    assert code == 0
    assert f"stray  {variable}" in out.replace("  ", "  ")
    assert "rescored" in out
    kept = [p for p in hw.iterdir() if p.name.startswith("key.json.")]
    assert len(kept) == 1 and kept[0].read_bytes() == old
    assert stat.S_IMODE(kept[0].stat().st_mode) == 0o600
    assert stat.S_IMODE((hw / "key.json").stat().st_mode) == 0o600
    record = read_result(hw / "graded" / RESULTS / "stray.json")
    assert {a.variable: a.verdict.max_points for a in record.answers}[variable] == 3.0
    assert record.max_points == read_result(hw / "graded" / RESULTS / "right.json").max_points \
        + 3.0 - was


def test_key_set_accept_gives_the_points(graded, capsys):
    hw, _ = graded
    variable, _ = next((v, f) for v, f in _later_variables(hw, "stray").items()
                                 if f[0] == "symmetric_free_top")
    given = next(a.submitted for a in _records(hw)["stray"].answers if a.variable == variable)
    code, out, _ = _cli(capsys, "key", "set", str(hw), f"stray:{variable}", "--accept",
                        json.dumps(given))
    assert code == 0, out
    assert _verdicts(hw, "stray")[variable].status == "correct"
    assert re.search(rf"stray\s+{variable}\s+0 → 1", out), out


@pytest.mark.parametrize(("argv", "message"), [
    (["q9_nothing", "--rtol", "0.1"], "no answer 'q9_nothing' in the key"),
    (["nobody:q1_stable", "--rtol", "0.1"], "no student 'nobody' in the key"),
    (["q1_stable"], "nothing to change"),
])
def test_key_set_refusals(graded, capsys, argv, message):
    hw, _ = graded
    before = (hw / "key.json").read_bytes()
    code, _, err = _cli(capsys, "key", "set", str(hw), *argv)
    assert code == 2
    assert message in err and "Traceback" not in err
    assert (hw / "key.json").read_bytes() == before


def test_key_set_dry_run(graded, capsys):
    hw, _ = graded
    before = (hw / "key.json").read_bytes()
    trail = read_trail(hw / "graded")
    variable = next(iter(_later_variables(hw, "stray")))
    code, out, _ = _cli(capsys, "key", "set", str(hw), variable, "--points", "4", "--dry-run")
    assert code == 0 and "nothing written (--dry-run)" in out
    assert (hw / "key.json").read_bytes() == before
    assert read_trail(hw / "graded") == trail
    assert not [p for p in hw.iterdir() if p.name.startswith("key.json.")]


def test_rekey_restores_a_wrong_key_value(graded, capsys):
    hw, _ = graded
    code, out, _ = _cli(capsys, "rekey", str(hw))
    assert code == 0 and "nothing changed" in out
    key = _key(hw)
    answer = key["students"]["right"]["questions"][0]["answers"][0]
    good = answer["value"]
    answer["value"] = good * 1.1 if isinstance(good, float) else good  # an old solver's bug
    assert isinstance(good, float)
    (hw / "key.json").write_text(json.dumps(key))
    rescore(hw)
    variable = f"q1_{answer['name']}"
    assert _verdicts(hw, "right")[variable].status == "wrong"
    code, out, _ = _cli(capsys, "rekey", str(hw))
    assert code == 0
    assert "1 value(s) of the key differ" in out and variable in out
    assert _key(hw)["students"]["right"]["questions"][0]["answers"][0]["value"] == good
    assert _verdicts(hw, "right")[variable].status == "correct"


# -- overrides and the audit trail


def test_override_survives_resume_and_force_and_the_trail_says_so(graded, capsys):
    """An override kept through a resumed and a forced grading run, then taken back; the audit
    trail has a line for each of those and for a key change before them."""
    hw, subs = graded
    out = hw / "graded"
    assert [e["event"] for e in read_trail(out)] == ["graded"] * len(STUDENTS) + ["grade"]
    variable = next(iter(_later_variables(hw, "stray")))
    code, _, _ = _cli(capsys, "key", "set", str(hw), f"right:{variable}", "--points", "2")
    assert code == 0
    most = {a.variable: a.verdict.max_points for a in _records(hw)["stray"].answers}[variable]
    points_before = _records(hw)["stray"].points
    code, said, _ = _cli(capsys, "override", str(hw), "stray", variable, "--points", str(most),
                         "--reason", "the statement's g was misprinted")
    assert code == 0, said
    assert "tomllib" not in (hw / "graded" / OVERRIDES).read_text()

    def overridden() -> tuple[float, dict, list[dict]]:
        record = read_result(hw / "graded" / RESULTS / "stray.json")
        with open(hw / "graded" / "grades.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        points = {a.variable: a.verdict.points for a in record.answers}[variable]
        return points, record.overridden, rows

    for run in ("now", "resume", "force"):
        if run != "now":
            grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=2,
                             force=run == "force")
        points, notes, rows = overridden()
        assert points == most, run
        assert notes[variable]["reason"] == "the statement's g was misprinted"
        assert notes[variable]["was"] == 0.0
        row = next(r for r in rows if "stray" in r.values())
        assert row["overridden"] and variable in row["overridden"], (run, row)
        assert all(not r["overridden"] for r in rows if "stray" not in r.values())
        page = (hw / "graded" / "feedback" / "stray.html").read_text()
        assert "Changed by your instructor" in page and "misprinted" in page
    code, _, _ = _cli(capsys, "override", str(hw), "stray", variable, "--remove")
    assert code == 0
    points, notes, _ = overridden()
    assert points == 0.0 and not notes

    everything = read_trail(out)
    trail = [e for e in everything if e["event"] != "graded"]  # each student graded: below
    assert [e["event"] for e in trail] == ["grade", "key set", "override", "grade", "grade",
                                           "override removed"]
    assert all(e["who"] == who() and e["who"] for e in everything)
    assert all(re.fullmatch(r"\d{4}-\d\d-\d\dT\S+", e["when"]) for e in everything)
    key_set = trail[1]
    assert {(c["student"], c["answer"]) for c in key_set["changes"]} == \
        {("right", variable), ("right", "total")}
    assert key_set["key_changes"][0]["field"] == "points"
    assert key_set["old_key"].startswith("key.json.")
    override = trail[2]
    assert override["why"] == "the statement's g was misprinted"
    assert {(c["student"], c["answer"], c["after"]) for c in override["changes"]} == \
        {("stray", variable, most), ("stray", "total", points_before + most)}
    resumed, forced = trail[3], trail[4]

    def graded_in(run: dict) -> list[dict]:
        return [c for e in everything if e["event"] == "graded" and e["run"] == run["run"]
                for c in e["changes"]]

    assert resumed["graded"] == 0 and graded_in(resumed) == []  # submissions, key unchanged
    assert forced["graded"] == len(STUDENTS)
    assert {c["student"] for c in graded_in(forced)} == set(STUDENTS)
    assert all(c["before"] == c["after"] for c in graded_in(forced))
    assert forced["notebooks"].keys() == set(STUDENTS)
    assert {(c["student"], c["answer"], c["after"]) for c in trail[5]["changes"]} == \
        {("stray", variable, 0.0), ("stray", "total", points_before)}
    lines = (out / "audit.jsonl").read_text().splitlines()
    assert len(lines) == len(everything)  # one line per event, appended


def test_override_of_a_total(graded, capsys):
    hw, _ = graded
    trail = hw / "graded" / "audit.jsonl"
    first = trail.read_bytes()
    most = read_result(hw / "graded" / RESULTS / "blank.json").max_points
    code, _, _ = _cli(capsys, "override", str(hw), "blank", "--points", str(most),
                      "--reason", "excused")
    assert code == 0
    record = read_result(hw / "graded" / RESULTS / "blank.json")
    assert record.points == most and record.overridden["total"]["reason"] == "excused"
    stored = json.loads((hw / "graded" / RESULTS / "blank.json").read_text())
    assert stored["overridden"]["total"]["points"] == most  # and it reads back the same
    assert record.overridden == stored["overridden"]
    assert trail.read_bytes().startswith(first)  # the trail appended to, never rewritten
    assert os.stat(trail).st_size > len(first)


@pytest.mark.parametrize(("argv", "message"), [
    (["nobody", "q1_stable", "--points", "1", "--reason", "x"], "no student 'nobody'"),
    (["stray", "q1_nothing", "--points", "1", "--reason", "x"], "no such answer"),
    (["stray", "q1_stable", "--points", "99", "--reason", "x"], "outside 0…"),
    (["stray", "q1_stable", "--points", "1"], "give --points P and --reason TEXT"),
    (["stray", "q1_stable", "--remove"], "no override of stray's q1_stable to remove"),
])
def test_override_refusals(graded, capsys, argv, message):
    hw, _ = graded
    code, _, err = _cli(capsys, "override", str(hw), *argv)
    assert code == 2 and message in err and "Traceback" not in err
    assert not (hw / "graded" / OVERRIDES).exists()


def test_a_bad_overrides_file_stops_grading_before_it_writes(graded, capsys):
    hw, subs = graded
    (hw / "graded" / OVERRIDES).write_text(
        '[[override]]\nstudent = "stray"\nanswer = "q1_nope"\npoints = 1\nreason = "x"\n')
    before = {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()}
    with pytest.raises(UsageError, match=r"overrides.toml: override 1: stray has no such answer"):
        grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=2,
                         force=True)
    assert {p: p.read_bytes() for p in (hw / "graded").rglob("*") if p.is_file()} == before
