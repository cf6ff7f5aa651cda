"""The generator: seeding, determinism, independence, rerolls, existing folders, atomicity."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from problems.answers import Answer, Mistake
from problems.generate import (
    GenerateError,
    TemplateError,
    generate_assignment,
    json_text,
    key_entry,
    key_entry_text,
    key_hash,
    pool_member,
    reroll_students,
    resolve_problems,
    student_answers,
    variant_seed,
)
from problems.roster import read_roster
from problems.variant import Variant

from .conftest import ROSTER, make_rod_family

PROBLEMS = ("rod", "rod2", "rod")


@pytest.fixture
def make_hw(tmp_path, families, write_roster):
    """``make_hw(name, roster_text=ROSTER, **kw) -> Path``: generate into ``tmp_path/name``."""

    def make(name="HW", roster_text=ROSTER, **kw):
        kw = {"problems": PROBLEMS, "seed": 7, "title": "HW 1", **kw}
        roster = read_roster(write_roster(roster_text, f"{name}.csv"))
        generate_assignment(roster, tmp_path / name, families, **kw)
        return tmp_path / name

    return make


def load(hw, name):
    return json.loads((hw / name).read_text(encoding="utf-8"))


def student_files(tree, sid):
    return {p: b for p, b in tree.items() if p.endswith(f"/{sid}.ipynb")}


def test_variant_seed_is_the_documented_sha256():
    # Guards the recipe itself: changing it would silently give every student a new problem.
    payload = '["eulertop-variant",1,7,"alice",2,"rod",0]'
    expected = int.from_bytes(hashlib.sha256(payload.encode()).digest(), "big")
    assert variant_seed(7, "alice", 2, "rod") == expected


def _sha256_of_json(payload: list) -> int:
    text = json.dumps(payload, ensure_ascii=False, separators=(",", ":"))
    return int.from_bytes(hashlib.sha256(text.encode("utf-8")).digest(), "big")


@settings(max_examples=200, deadline=None)
@given(st.integers(-2**70, 2**70), st.text(), st.integers(1, 99), st.text(),
       st.integers(0, 9) | st.booleans())
def test_seeds_hash_the_text_json_dumps_writes(seed, student_id, question, family, reroll):
    """The encoder made once writes what json.dumps writes, whatever the id and the family
    (quotes, backslashes, non-ASCII, control characters)."""
    assert variant_seed(seed, student_id, question, family, reroll) == _sha256_of_json(
        ["eulertop-variant", 1, seed, student_id, question, family, int(reroll)])
    pool = [family, student_id]
    assert pool_member(pool, seed, student_id, question, reroll) == pool[_sha256_of_json(
        ["eulertop-pool", 1, seed, student_id, question, pool, int(reroll)]) % 2]


@settings(max_examples=300, deadline=None)
@given(digest=st.binary(min_size=32, max_size=32), zeros=st.integers(0, 32))
def test_a_generator_seeded_with_the_seed_words_is_the_one_of_the_integer(digest, zeros):
    """variant_rng seeds numpy with the 32-bit words of the digest's integer (cheaper than the
    int): the same generator, leading zero words (numpy drops them) and zero included."""
    import numpy as np

    from problems.generate import seed_words

    digest = bytes(zeros) + digest[zeros:]
    by_words = np.random.default_rng(seed_words(digest)).bit_generator.state
    assert by_words == np.random.default_rng(int.from_bytes(digest, "big")).bit_generator.state


def test_variant_seed_does_not_depend_on_the_interpreter_run():
    code = "from problems.generate import variant_seed; print(variant_seed(7, 'bø', 2, 'rod', 1))"
    outputs = {
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                       env={**os.environ, "PYTHONHASHSEED": h}).stdout
        for h in ("1", "2")
    }
    assert outputs == {f"{variant_seed(7, 'bø', 2, 'rod', 1)}\n"}


@pytest.mark.parametrize(
    "change",
    [dict(seed=8), dict(student_id="bob"), dict(question=3), dict(family="rod2"), dict(reroll=1)],
)
def test_every_seed_input_matters(change):
    base = dict(seed=7, student_id="alice", question=2, family="rod", reroll=0)
    assert variant_seed(**base) != variant_seed(**{**base, **change})


def test_layout(make_hw, read_tree):
    tree = read_tree(make_hw())
    assert set(tree) == {"assignment.json", "key.json"} | {
        f"{d}/{s}.ipynb" for d in ("release", "solutions") for s in ("alice", "bob", "carol")
    }


def test_same_inputs_give_identical_bytes(make_hw, read_tree):
    assert read_tree(make_hw("A")) == read_tree(make_hw("B"))


def test_another_seed_changes_every_notebook(make_hw, read_tree):
    a, b = read_tree(make_hw("A", seed=1)), read_tree(make_hw("B", seed=2))
    assert all(a[p] != b[p] for p in a if p.endswith(".ipynb"))


def test_independent_of_roster_order_and_of_classmates(make_hw, read_tree):
    reordered = "id,name,email\ncarol,Carol Dee,carol@uni.example\nalice,Alice Ng,alice@uni." \
                "example\nbob,Bob Roy,bob@uni.example\ndan,Dan,dan@uni.example\n"
    base, other = make_hw("A"), make_hw("B", roster_text=reordered)
    tree_a, tree_b = read_tree(base), read_tree(other)
    for sid in ("alice", "bob", "carol"):
        assert student_files(tree_a, sid) == student_files(tree_b, sid)
        for name in ("assignment.json", "key.json"):
            assert load(base, name)["students"][sid] == load(other, name)["students"][sid]


def test_manifest_holds_resolved_questions_but_no_answers(make_hw):
    hw = make_hw()
    manifest = load(hw, "assignment.json")
    assert manifest["title"] == "HW 1" and manifest["seed"] == 7
    assert manifest["problems"] == list(PROBLEMS)
    assert manifest["roster"]["columns"] == ["id", "name", "email"]
    assert manifest["roster"]["rows"][0] == {"id": "alice", "name": "Alice Ng",
                                             "email": "alice@uni.example"}
    assert manifest["generator"]["name"] == "eulertop" and manifest["generator"]["version"]
    key = load(hw, "key.json")
    for sid, entry in manifest["students"].items():
        assert entry["reroll"] == 0
        assert [q["family"] for q in entry["questions"]] == list(PROBLEMS)
        for q, kq in zip(entry["questions"], key["students"][sid]["questions"], strict=True):
            assert set(q["params"]) == {"m", "L", "θ"}
            assert f"$m = {q['params']['m']}$" in q["statement"]
            assert "value" not in json.dumps(q) and "mistakes" not in json.dumps(q)
            assert [a["name"] for a in q["answers"]] == [a["name"] for a in kq["answers"]]


def test_key_entries_round_trip_and_hash(make_hw):
    key = load(make_hw(), "key.json")
    assert set(key["students"]) == {"alice", "bob", "carol"}
    for sid, entry in key["students"].items():
        assert entry["hash"] == key_hash(entry["questions"])
        answers = student_answers(key, sid)
        assert list(answers)[:2] == ["q1_I_c", "q1_I_tilt"] and "q3_I_expr" in answers
        for q in entry["questions"]:
            for a in q["answers"]:
                assert Answer.from_dict(a).to_dict() == a
    hashes = [e["hash"] for e in key["students"].values()]
    assert len(set(hashes)) == len(hashes)


def test_the_key_is_private_to_its_owner(make_hw):
    assert (make_hw() / "key.json").stat().st_mode & 0o077 == 0


def test_reroll_changes_one_student_only(make_hw, read_tree):
    hw = make_hw()
    before, manifest0, key0 = read_tree(hw), load(hw, "assignment.json"), load(hw, "key.json")
    (hw / "graded").mkdir()
    (hw / "graded" / "grades.csv").write_text("id,points\n")
    summary = reroll_students(hw, ["bob"], make_families())
    after, manifest1, key1 = read_tree(hw), load(hw, "assignment.json"), load(hw, "key.json")
    assert summary.students == ("bob",)
    assert after.pop("graded/grades.csv") == b"id,points\n"
    for sid in ("alice", "carol"):
        assert student_files(after, sid) == student_files(before, sid)
        assert manifest1["students"][sid] == manifest0["students"][sid]
        assert key1["students"][sid] == key0["students"][sid]
    assert all(after[p] != before[p] for p in student_files(before, "bob"))
    assert manifest1["students"]["bob"]["reroll"] == 1
    assert key1["students"]["bob"]["hash"] != key0["students"]["bob"]["hash"]
    reroll_students(hw, ["bob"], make_families())
    assert load(hw, "assignment.json")["students"]["bob"]["reroll"] == 2


@pytest.mark.parametrize("name", ["assignment.json", "key.json"])
def test_a_reroll_changes_one_line_of_each_json_file(make_hw, read_tree, name):
    hw = make_hw()
    before = (hw / name).read_text().splitlines()
    reroll_students(hw, ["carol"], make_families())
    after = (hw / name).read_text().splitlines()
    changed = [(a, b) for a, b in zip(before, after, strict=True) if a != b]
    assert len(changed) == 1 and changed[0][1].startswith('  "carol": {')


@pytest.mark.parametrize(
    "document",
    [{"b": [0.1, 1e-300], "a": "θ", "students": {"z": {"x": 1.5}, "a": {}}}, {"students": {}},
     {"title": "x"}],
)
def test_json_text_is_canonical_json(document):
    text = json_text(document)
    assert json.loads(text) == document
    assert text == json_text(json.loads(text))  # reading and rewriting changes no byte
    if document.get("students"):
        assert text.splitlines()[-4:] == ['  "a": {},', '  "z": {"x": 1.5}', " }", "}"]


def make_families(**failing):
    return {name: make_rod_family(name, **failing) for name in ("rod", "rod2")}


@pytest.mark.parametrize(
    ("ids", "fragment"), [(["zoe"], "not in the assignment's roster: zoe")],
)
def test_reroll_of_unknown_student(make_hw, read_tree, ids, fragment):
    hw = make_hw()
    before = read_tree(hw)
    with pytest.raises(GenerateError, match=fragment):
        reroll_students(hw, ids, make_families())
    assert read_tree(hw) == before


def test_reroll_needs_an_assignment(tmp_path):
    with pytest.raises(GenerateError, match="not a generated assignment"):
        reroll_students(tmp_path, ["bob"], make_families())


def test_existing_folder_is_refused_without_force(make_hw, read_tree):
    hw = make_hw()
    before = read_tree(hw)
    with pytest.raises(GenerateError, match="already exists; pass --force"):
        make_hw()
    assert read_tree(hw) == before


def test_force_keeps_seed_and_rerolls_so_a_late_student_changes_nobody(make_hw, read_tree):
    hw = make_hw()
    reroll_students(hw, ["bob"], make_families())
    before = read_tree(hw)
    late = ROSTER + "dan,Dan,dan@uni.example\n"
    make_hw(roster_text=late, force=True, seed=None)
    after = read_tree(hw)
    for sid in ("alice", "bob", "carol"):
        assert student_files(after, sid) == student_files(before, sid)
    assert load(hw, "assignment.json")["seed"] == 7
    assert load(hw, "assignment.json")["students"]["bob"]["reroll"] == 1
    assert "release/dan.ipynb" in after


def test_force_refuses_a_folder_with_foreign_files(make_hw, read_tree):
    hw = make_hw()
    (hw / "graded").mkdir()
    before = read_tree(hw)
    with pytest.raises(GenerateError, match="also holds graded"):
        make_hw(force=True)
    assert read_tree(hw) == before


def test_a_failing_template_leaves_nothing(tmp_path, write_roster):
    roster = read_roster(write_roster(ROSTER))
    before = sorted(os.listdir(tmp_path))
    # "rod" is questions 1 and 3, each drawn for the whole class in turn: its 5th call is
    # bob's question 3, half-way through
    with pytest.raises(TemplateError, match="'rod', student 'bob', question 3 failed"):
        generate_assignment(roster, tmp_path / "HW", make_families(fail_on_call=5),
                            problems=PROBLEMS, seed=7)
    assert sorted(os.listdir(tmp_path)) == before


def test_a_failing_replacement_keeps_the_old_assignment(make_hw, read_tree, tmp_path):
    hw = make_hw()
    before, listing = read_tree(hw), sorted(os.listdir(tmp_path))
    with pytest.raises(TemplateError):
        generate_assignment(read_roster(tmp_path / "input" / "HW.csv"), hw,
                            make_families(fail_on_call=5), problems=PROBLEMS, seed=9, force=True)
    assert read_tree(hw) == before and sorted(os.listdir(tmp_path)) == listing


def test_template_returning_garbage_is_a_template_error(tmp_path, write_roster):
    families = {"rod": make_rod_family("rod2")}  # generate() claims another family
    with pytest.raises(TemplateError, match="must return a Variant of family 'rod'"):
        generate_assignment(read_roster(write_roster(ROSTER)), tmp_path / "HW", families,
                            seed=1)
    assert not (tmp_path / "HW").exists()


@pytest.mark.parametrize(
    ("names", "expected"),
    [(None, ("rod", "rod2")), (["rod2"], ("rod2",)), ([" rod", "rod"], ("rod", "rod"))],
)
def test_resolve_problems(names, expected):
    assert resolve_problems(names, make_families()) == expected


@pytest.mark.parametrize(
    ("names", "families", "fragment"),
    [
        (["rod", "top"], make_families(), "unknown problem 'top'; known: rod, rod2"),
        (["rod", ""], make_families(), "empty problem name"),
        (None, {}, "no problem families are registered"),
    ],
)
def test_resolve_problems_refuses(names, families, fragment):
    with pytest.raises(GenerateError, match=fragment):
        resolve_problems(names, families)


def test_a_failed_swap_puts_the_old_assignment_back(make_hw, read_tree, tmp_path, monkeypatch):
    hw = make_hw()
    before, listing = read_tree(hw), sorted(os.listdir(tmp_path))
    real_rename, calls = os.rename, []

    def rename(src, dst):
        calls.append((src, dst))
        if len(calls) == 2:  # old moved aside; now the new one fails to take its place
            raise OSError("disk pulled out")
        real_rename(src, dst)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(OSError, match="disk pulled out"):
        make_hw(force=True, seed=99)
    monkeypatch.undo()
    assert read_tree(hw) == before and sorted(os.listdir(tmp_path)) == listing


CLASS = "id,name\n" + "".join(f"s{i:02d},Student {i}\n" for i in range(20))


def test_generating_in_parallel_gives_the_same_bytes(tmp_path, write_roster, read_tree):
    """Every real family, 20 students (enough for worker processes): two processes write
    exactly the files one process writes, and report progress in roster order."""
    from problems.generate import PARALLEL_MIN
    from problems.templates import FAMILIES

    roster = read_roster(write_roster(CLASS))
    assert len(roster.rows) >= PARALLEL_MIN
    seen = []
    generate_assignment(roster, tmp_path / "one", FAMILIES, seed=3, title="T", jobs=1)
    generate_assignment(roster, tmp_path / "two", FAMILIES, seed=3, title="T", jobs=2,
                        progress=lambda done, total: seen.append((done, total)))
    one, two = read_tree(tmp_path / "one"), read_tree(tmp_path / "two")
    assert len(one) == 2 + 2 * 20 and one == two
    assert seen == [(k, 20) for k in range(1, 21)]


@pytest.mark.parametrize("students, workers", [(0, 2), (17, 2), (150, 2), (300, 2), (401, 2),
                                               (1000, 3), (5, 1), (401, 1)])
def test_a_class_is_cut_into_even_batches_as_many_for_each_worker(students, workers):
    """Each batch at most BATCH students (a batch form's solver calls cost the same for few
    students as for many: the fewer batches the better), their number a multiple of the
    workers', sizes within one of each other, every student once in roster order."""
    from problems.generate import BATCH, _batch_tasks

    rows = [{"id": f"s{i}"} for i in range(students)]
    tasks = _batch_tasks(None, "T", rows, {}, workers)
    sizes = [len(task[2]) for task in tasks]
    assert [row for task in tasks for row in task[2]] == rows
    assert all(size <= BATCH for size in sizes)
    if students:
        assert len(tasks) % workers == 0
        assert (len(tasks) - workers) * BATCH < students  # one round fewer would not hold them
        assert set(sizes[:-1]) <= {sizes[0]} and sizes[0] - sizes[-1] < len(tasks)
        assert [task[4] for task in tasks] == [True] + [False] * (len(tasks) - 1)
    else:
        assert tasks == []


def test_a_template_failing_in_a_worker_process_leaves_nothing(tmp_path, write_roster):
    roster = read_roster(write_roster(CLASS))
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(TemplateError, match=r"'rod'.*failed"):
        generate_assignment(roster, tmp_path / "HW", make_families(fail_on_call=3),
                            problems=PROBLEMS, seed=7, jobs=2)
    assert sorted(os.listdir(tmp_path)) == before


def test_entries_encoded_by_workers_are_written_as_the_parent_would(tmp_path):
    """Workers hand back each student's entries as encoded lines (UTF-8); the files are the
    same."""
    from problems.generate import _ENTRY_JSON, ASSIGNMENT, _write_json

    students = {"b": {"reroll": 0, "questions": [{"x": [0.1, 1e-300], "t": "θ\n\"q\""}]},
                "a": {"reroll": 2, "questions": []}}
    document = {"title": "T", "seed": 1, "students": students}
    encoded = {**document, "students": {k: _ENTRY_JSON.encode(v).encode("utf-8")
                                        for k, v in students.items()}}
    for folder, written in (("parent", document), ("workers", encoded)):
        (tmp_path / folder).mkdir()
        _write_json(tmp_path / folder, written, written)
    text = (tmp_path / "workers" / ASSIGNMENT).read_text(encoding="utf-8")
    assert text == (tmp_path / "parent" / ASSIGNMENT).read_text(encoding="utf-8")
    assert text == json_text(document)
    assert json.loads(text) == document


@settings(max_examples=200, deadline=None)
@given(description=st.text(), feedback=st.text().filter(str.strip),
       value=st.floats(1e-300, 1e300), accepted=st.booleans())
def test_a_key_entry_text_is_the_key_entry_encoded(description, feedback, value, accepted):
    """key_entry_text marks json's separators to make the entry and its hash from one
    encoding: the same as encoding key_entry, whatever the texts hold (control characters,
    the mark itself, any script)."""
    answer = Answer("x", "scalar", value, description=description,
                    mistakes=(Mistake("m", 4 * value, feedback),),
                    accepted=(2 * value,) if accepted else ())
    variant = Variant("rod", "t", {"m": 0.5}, {"m": "kg"}, feedback, (answer,))
    variants = [variant, variant]
    assert key_entry_text(variants) == json.dumps(key_entry(variants), sort_keys=True,
                                                  ensure_ascii=False)


def prepared_families(calls: list[int], fail: bool = False) -> dict:
    """The rod families, with a prepare() that answers() relies on (as a real template's
    cached sympy work): a worker that did not inherit it fails."""
    families = make_families()
    for family in families.values():
        state = {"ready": False}

        def prepare(state=state):
            calls.append(os.getpid())
            if fail:
                raise RuntimeError("cannot derive")
            state["ready"] = True

        def answers(params, state=state, original=family.module.answers):
            if not state["ready"]:
                raise RuntimeError("answers() before prepare()")
            return original(params)

        family.module.prepare, family.module.answers = prepare, answers
    return families


def test_prepare_runs_once_in_the_parent_and_the_workers_inherit_it(tmp_path, write_roster,
                                                                     read_tree):
    calls: list[int] = []
    roster = read_roster(write_roster(CLASS))
    generate_assignment(roster, tmp_path / "HW", prepared_families(calls), problems=PROBLEMS,
                        seed=7, title="T", jobs=2)
    assert calls == [os.getpid(), os.getpid()]  # one call per family, here, not per worker
    generate_assignment(roster, tmp_path / "one", make_families(), problems=PROBLEMS, seed=7,
                        title="T", jobs=1)
    assert read_tree(tmp_path / "HW") == read_tree(tmp_path / "one")


def test_a_failing_prepare_is_a_template_error_and_leaves_nothing(tmp_path, write_roster):
    roster = read_roster(write_roster(CLASS))
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(TemplateError, match=r"template 'rod': prepare\(\) failed: RuntimeError"):
        generate_assignment(roster, tmp_path / "HW", prepared_families([], fail=True),
                            problems=PROBLEMS, seed=7, jobs=2)
    assert sorted(os.listdir(tmp_path)) == before


def test_the_templates_that_prepare_do_all_their_sympy_work_there():
    from problems.templates import euler_kinetic_energy, symbolic_derivation

    euler_kinetic_energy.prepare()
    symbolic_derivation.prepare()
    assert symbolic_derivation._compiled.cache_info().currsize == len(
        symbolic_derivation.QUANTITIES)
    assert euler_kinetic_energy._expression_answer.cache_info().currsize == 1
