"""Gradescope's ``run_autograder`` end to end, in a temporary root laid out as Gradescope lays
out ``/autograder`` (source = the extracted zip, submission/, submission_metadata.json), with
real kernels; results checked against Gradescope's documented format."""

from __future__ import annotations

import json
import os
import stat
import time
import zipfile
from pathlib import Path

import pytest

from grader.assignment import load_assignment
from grader.hosted import gradescope
from grader.hosted.grading import CONFIG
from grader.hosted.package import gradescope_zip
from grader.limits import Limits
from tests.grader.hosted.conftest import code_cell, run_entrypoint
from tests.grader.hosted.platform_formats import check_gradescope

LIMITS = {"cell_timeout": 10.0, "total_timeout": 60.0, "memory_bytes": 3 * 1024**3 // 2,
          "output_bytes": 100_000, "submission_bytes": 2 * 1024**2}


def layout(base: Path, hw, submission: bytes | None, users: list[dict], *,
           name: str = "homework.ipynb", sandbox: str = "container", **config) -> Path:
    """``base/autograder`` as Gradescope makes it: the zip extracted into ``source/`` (files
    0644, folders 0755, as ``unzip`` leaves them as root), the submission, the metadata."""
    root = base / "autograder"
    (root / "source").mkdir(parents=True)
    wheel = base / "eulertop-0.1.0-py3-none-any.whl"
    wheel.write_bytes(b"not used by run_autograder")
    settings = {"sandbox": sandbox, "kernel_user": None, "limits": LIMITS,
                "visibility": "after_published", **config}
    zip_path = gradescope_zip(load_assignment(hw.folder), base / "autograder.zip", wheel,
                              settings)
    with zipfile.ZipFile(zip_path) as zf:
        zf.extractall(root / "source")
    for path in [root, *root.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    (root / "submission").mkdir(mode=0o755)
    if submission is not None:
        (root / "submission" / name).write_bytes(submission)
    metadata = {"id": 123456, "created_at": "2026-11-20T14:22:32.365935-07:00",
                "assignment": {"title": "Tops", "id": 25828}, "submission_method": "upload",
                "users": users, "previous_submissions": []}
    (root / "submission_metadata.json").write_text(json.dumps(metadata))
    return root


ALICE = [{"email": "alice@uni.edu", "id": 1234, "name": "Alice A"}]


def run(root: Path, monkeypatch) -> tuple[dict, int]:
    """``run_autograder`` (:func:`gradescope.main`) with ``$EULERTOP_GRADESCOPE_ROOT``."""
    status = run_entrypoint(gradescope, gradescope.ROOT_VARIABLE, root, monkeypatch)
    return check_gradescope(root / "results" / "results.json"), status


def test_right_notebook_gets_every_point_in_container_mode(hosted_hw, notebooks, public_tmp,
                                                            kernel_uid, monkeypatch):
    root = layout(public_tmp, hosted_hw, notebooks.right("alice"), ALICE)
    results, status = run(root, monkeypatch)
    answers = hosted_hw.answers("alice")
    assert status == 0
    assert results["score"] == hosted_hw.max_points("alice")
    assert [t["max_score"] for t in results["tests"]] == [a["points"] for a in answers]
    assert all(t["score"] == t["max_score"] for t in results["tests"])
    assert all(t["visibility"] == "after_published" for t in results["tests"])
    assert all(a["variable"] in t["name"] for t, a in zip(results["tests"], answers, strict=True))
    assert f"ran as uid {kernel_uid}" in results["output"]
    assert "alice's variant" in results["output"]


def test_wrong_answers_lose_their_points_only(hosted_hw, notebooks, public_tmp, kernel_uid,
                                              monkeypatch):
    data, kept = notebooks.wrong("alice")
    assert 0 < kept < hosted_hw.max_points("alice")
    results, status = run(layout(public_tmp, hosted_hw, data, ALICE), monkeypatch)
    assert status == 0 and results["score"] == pytest.approx(kept)
    failed = [t for t in results["tests"] if t["score"] < t["max_score"]]
    assert failed and all(t["output"] for t in failed)  # each says why


def test_the_key_is_out_of_reach_of_the_notebook(hosted_hw, notebooks, public_tmp, kernel_uid,
                                                 monkeypatch):
    root = public_tmp / "autograder"
    key = root / "source" / "assignment" / "key.json"
    nb = json.loads(notebooks.key_reader("alice", key))
    results_folder = root / "results"  # and it tries to plant a results file of its own
    nb["cells"].append(code_cell(
        "import os\n"
        f"for _p in ({str(results_folder / 'results.json')!r}, {str(results_folder / 'x')!r}):\n"
        "    try:\n        os.makedirs(_p)\n    except OSError as _e:\n        print(_e)\n"))
    layout(public_tmp, hosted_hw, json.dumps(nb).encode(), ALICE)
    # as Gradescope extracts it, the key is readable by every user ...
    assert key.stat().st_mode & stat.S_IROTH
    results, _ = run(root, monkeypatch)
    # ... but run_autograder made it the grader's only, and the notebook ran as another uid
    assert results["score"] == 0
    assert not key.stat().st_mode & (stat.S_IRWXG | stat.S_IRWXO)
    assert sorted(p.name for p in results_folder.iterdir()) == ["results.json"]


def test_the_key_reader_would_get_every_point_with_the_key(hosted_hw, notebooks, public_tmp,
                                                         monkeypatch):
    """Control of the test above: the same notebook, run where it can read the key (the
    grader's own user, in the bubblewrap-free unprotected path), gets every point — so a score
    of 0 above means the key was out of reach, not that the notebook was broken."""
    from functools import partial

    from grader.execute import execute_submission
    from grader.grade_one import grade_one
    from grader.submissions import Submission

    key = hosted_hw.folder / "key.json"
    path = public_tmp / "alice.ipynb"
    path.write_bytes(notebooks.key_reader("alice", key))
    a = load_assignment(hosted_hw.folder)
    from grader.compare import key_answers

    result = grade_one(Submission("alice", path), key_answers(a.key, "alice"),
                       a.key_hash("alice"), Limits(**LIMITS),
                       partial(execute_submission, sandbox=False))
    assert result.points == hosted_hw.max_points("alice")


def test_no_process_of_the_notebook_outlives_it(hosted_hw, notebooks, public_tmp, kernel_uid,
                                               monkeypatch):
    nb = json.loads(notebooks.right("alice"))
    nb["cells"].append(code_cell("import subprocess\n"
                                 "subprocess.Popen(['sleep', '311.5'], start_new_session=True)"))
    results, _ = run(layout(public_tmp, hosted_hw, json.dumps(nb).encode(), ALICE),
                     monkeypatch)
    assert results["score"] == hosted_hw.max_points("alice")  # the cell ran
    from grader.kernels.container import processes_of

    deadline = time.monotonic() + 5  # SIGKILLed: gone as soon as the kernel has ended it
    while processes_of(kernel_uid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_of(kernel_uid) == set()


HOPPER = (
    "import subprocess, sys\n"
    "code = ('import os\\n'\n"
    "        'while True:\\n'  # never the same process for long: it forks, its parent leaves\n"
    "        '    if os.fork():\\n'\n"
    "        '        os._exit(0)\\n'\n"
    "        '    os.setsid()\\n')\n"
    "subprocess.Popen([sys.executable, '-c', code], start_new_session=True)\n"
)


AFTER_THE_ENTRYPOINT = (
    "import sys, time\n"
    "from grader.hosted import gradescope\n"
    "from grader.kernels.container import processes_of\n"
    "status = gradescope.main([])\n"
    "seen = set()\n"
    "for _ in range(20):  # a second after it returned: long enough for a chain to show\n"
    "    seen |= processes_of(int(sys.argv[1]))\n"
    "    time.sleep(0.05)\n"
    "print('left', len(seen), 'status', status)\n"
)


def test_a_chain_of_short_lived_processes_does_not_outlive_the_entrypoint(
        hosted_hw, notebooks, public_tmp, kernel_uid):
    """Issue 23: a snapshot of the kernel user's processes, then a kill of each, misses a
    process that has forked and left by then: round 2's kill let such a chain outlive the
    entrypoint. Here the entrypoint runs as in a container — a PID namespace whose PID 1
    reaps every orphan, as a container's init does, so the chain never stalls — and what is
    left of the kernel's user is looked at in that container, after the entrypoint returned.
    Killed until none is left (kill(-1) as that user), nothing is."""
    import shutil
    import subprocess
    import sys

    from tests.grader.hosted.conftest import REPO, container_layout

    nb = json.loads(notebooks.right("alice"))
    nb["cells"].append(code_cell(HOPPER))
    root = layout(public_tmp, hosted_hw, json.dumps(nb).encode(), ALICE)
    prefix = container_layout() or [shutil.which("bwrap"), "--dev-bind", "/", "/", "--"]
    prefix = [prefix[0], "--unshare-pid", *prefix[1:-1], "--proc", "/proc", "--"]
    env = {**os.environ, gradescope.ROOT_VARIABLE: str(root)}
    done = subprocess.run([*prefix, sys.executable, "-c", AFTER_THE_ENTRYPOINT,
                           str(kernel_uid)], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    results = check_gradescope(root / "results" / "results.json")
    assert results["score"] == hosted_hw.max_points("alice")  # the cell ran
    left = next(line for line in done.stdout.splitlines() if line.startswith("left "))
    assert left.split()[:2] == ["left", "0"], done.stdout


def test_a_python_other_users_cannot_run_is_named(public_tmp, kernel_uid, monkeypatch):
    import sys

    from grader.kernels.container import check_interpreter, kernel_user

    private = public_tmp / "private"
    private.mkdir(mode=0o700)
    (private / "python3").symlink_to(sys.executable)
    monkeypatch.setattr(sys, "executable", str(private / "python3"))
    why = check_interpreter(kernel_user())
    assert why is not None and str(private / "python3") in why and "every user" in why


def test_broken_notebook_scores_zero_and_says_why(hosted_hw, notebooks, public_tmp, monkeypatch):
    results, status = run(layout(public_tmp, hosted_hw, notebooks.broken(), ALICE,
                                 sandbox="auto"), monkeypatch)
    assert status == 0 and results["score"] == 0
    assert "not a valid notebook" in results["output"]
    assert all(t["score"] == 0 for t in results["tests"])


def test_oversized_notebook_is_refused_unread(hosted_hw, notebooks, public_tmp, monkeypatch):
    data = notebooks.oversized("alice", LIMITS["submission_bytes"] + 1)
    results, status = run(layout(public_tmp, hosted_hw, data, ALICE, sandbox="auto"),
                          monkeypatch)
    assert status == 0 and results["score"] == 0
    assert "invalid submission" in results["output"]


def test_submitter_not_on_the_roster_gets_zero_and_a_message(hosted_hw, notebooks, public_tmp,
                                                             monkeypatch):
    stranger = [{"email": "eve@elsewhere.org", "id": 9, "name": "Eve"}]
    results, status = run(layout(public_tmp, hosted_hw, notebooks.right("alice"), stranger),
                          monkeypatch)
    assert status == 0
    assert results["score"] == 0 and results["tests"] == []
    assert "not on the class roster" in results["output"]
    assert "Eve (eve@elsewhere.org" in results["output"]


def test_matched_by_sid_when_the_email_differs(hosted_hw, notebooks, public_tmp, kernel_uid,
                                               monkeypatch):
    users = [{"email": "b.personal@mail.org", "id": 7, "name": "Bob B", "sid": "bob"}]
    results, _ = run(layout(public_tmp, hosted_hw, notebooks.right("bob"), users), monkeypatch)
    assert "bob's variant" in results["output"]
    assert results["score"] == hosted_hw.max_points("bob")


def test_another_students_notebook_is_graded_against_the_submitters(hosted_hw, notebooks,
                                                                    public_tmp, kernel_uid,
                                                                    monkeypatch):
    results, _ = run(layout(public_tmp, hosted_hw, notebooks.right("bob"), ALICE), monkeypatch)
    assert "alice's variant" in results["output"]
    assert "names student 'bob'" in results["output"]
    assert "FLAGGED: this notebook was made for bob, not for alice" in results["output"]
    assert results["score"] < hosted_hw.max_points("alice")


@pytest.mark.parametrize(("files", "why"), [
    ({}, "no notebook"),
    ({"a.ipynb": b"{}", "b.ipynb": b"{}"}, "several notebooks"),
])
def test_no_single_notebook_is_a_message_not_a_crash(hosted_hw, public_tmp, monkeypatch, files,
                                                     why):
    root = layout(public_tmp, hosted_hw, None, ALICE)
    for name, data in files.items():
        (root / "submission" / name).write_bytes(data)
    results, status = run(root, monkeypatch)
    assert status == 0 and results["score"] == 0 and why in results["output"]


def test_a_package_without_its_assignment_says_so(hosted_hw, public_tmp, monkeypatch):
    root = layout(public_tmp, hosted_hw, b"{}", ALICE)
    (root / "source" / "assignment" / "key.json").unlink()
    results, status = run(root, monkeypatch)
    assert status == 1 and results["score"] == 0
    assert "could not grade" in results["output"] and "key.json" in results["output"]


def test_without_root_the_results_say_the_key_was_not_protected(monkeypatch):
    from grader.hosted.grading import choose_isolation
    from grader.kernels import container

    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    isolation = choose_isolation("container")
    assert not isolation.protected
    assert container.UNPROTECTED in isolation.note
    assert "can read" in container.UNPROTECTED or "could read" in container.UNPROTECTED


def test_the_zip_holds_what_gradescope_needs_at_its_root(hosted_hw, tmp_path):
    wheel = tmp_path / "eulertop-0.1.0-py3-none-any.whl"
    wheel.write_bytes(b"wheel")
    out = gradescope_zip(load_assignment(hosted_hw.folder), tmp_path / "autograder.zip", wheel,
                         {"sandbox": "auto"})
    with zipfile.ZipFile(out) as zf:
        names = set(zf.namelist())
        modes = {i.filename: i.external_attr >> 16 for i in zf.infolist()}
        setup = zf.read("setup.sh").decode()
        config = json.loads(zf.read(CONFIG))
    assert names == {"setup.sh", "run_autograder", wheel.name, "constraints.txt", CONFIG,
                     "assignment/assignment.json", "assignment/key.json"}
    assert modes["setup.sh"] & 0o111 and modes["run_autograder"] & 0o111
    assert f"./{wheel.name}" in setup and "--constraint constraints.txt" in setup
    assert config == {"sandbox": "auto"}


def test_a_kernel_that_cannot_start_is_not_the_students_zero(hosted_hw, notebooks, public_tmp,
                                                            monkeypatch):
    from grader.execute import Execution
    from grader.hosted.grading import Isolation

    def no_kernel(path, variables, limits):
        return Execution("error", "could not start a Python kernel (test)", {}, (), 0.0, False,
                         retry=True)

    monkeypatch.setattr(gradescope, "choose_isolation",
                        lambda *a: Isolation("container", "test", True, no_kernel))
    results, status = run(layout(public_tmp, hosted_hw, notebooks.right("alice"), ALICE),
                          monkeypatch)
    assert status == 1 and results["tests"] == []
    assert "not your fault" in results["output"] and "could not start" in results["output"]
