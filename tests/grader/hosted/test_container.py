"""The container mode's parts that need no kernel: the kernel's user, ``protect``, the
isolation chosen, the group rules of Gradescope's metadata."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import pytest

from grader.assignment import load_assignment
from grader.hosted import gradescope
from grader.hosted.grading import HostedError, choose_isolation
from grader.kernels import container

needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="only root has other users to be")


@needs_root
@pytest.mark.parametrize(("wanted", "uid"), [(None, None), ("nobody", None), ("4242", 4242)])
def test_the_kernel_user_is_named_by_option_or_default(wanted, uid, monkeypatch):
    monkeypatch.delenv(container.USER_VARIABLE, raising=False)
    user = container.kernel_user(wanted)
    assert user.uid != 0 and (uid is None or user.uid == uid)


@needs_root
@pytest.mark.parametrize(("wanted", "why"), [("root", "is root"), ("0", "is root"),
                                             ("no-such-user-x", "no such user")])
def test_a_kernel_user_that_cannot_be_is_refused(wanted, why):
    with pytest.raises(container.KernelUserError, match=why):
        container.kernel_user(wanted)
    with pytest.raises(HostedError, match=why):
        choose_isolation("container", wanted)


def test_the_environment_names_the_kernel_user(monkeypatch):
    monkeypatch.setenv(container.USER_VARIABLE, "31337")
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    assert container.kernel_user().uid == 31337


def test_protect_leaves_the_owner_alone_and_no_one_else(tmp_path):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "a" / "b" / "key.json").write_text("{}")
    (tmp_path / "a" / "run").write_text("#!/bin/sh\n")
    for p, mode in ((tmp_path / "a", 0o755), (tmp_path / "a" / "b", 0o775),
                    (tmp_path / "a" / "b" / "key.json", 0o666), (tmp_path / "a" / "run", 0o755)):
        p.chmod(mode)
    container.protect([tmp_path / "a", tmp_path / "absent"])
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in [tmp_path / "a",
                                                               *(tmp_path / "a").rglob("*")]}
    assert modes == {"a": 0o700, "b": 0o700, "key.json": 0o600, "run": 0o700}


def test_an_unknown_mode_is_refused():
    with pytest.raises(HostedError, match="expected one of auto, bwrap, container"):
        choose_isolation("docker")


def test_a_group_is_graded_as_the_member_the_notebook_names(hosted_hw):
    a = load_assignment(hosted_hw.folder)
    users = [{"email": "ALICE@uni.edu", "name": "Alice A"}, {"email": "bob@uni.edu", "sid": ""},
             {"email": "eve@elsewhere.org", "name": "Eve"}]
    ids, unmatched = gradescope.submitters({"users": users}, a)
    assert ids == ["alice", "bob"]  # email compared without case
    assert unmatched == ["Eve (eve@elsewhere.org, SID -) is not on the roster"]
    assert gradescope.choose_student(ids, "bob") == "bob"
    assert gradescope.choose_student(ids, "carol") == "alice"
    assert gradescope.choose_student(ids, None) == "alice"


def test_run_autograder_as_a_program_writes_results(hosted_hw, public_tmp):
    """``python -m grader.hosted.gradescope`` (what ``run_autograder`` runs), in a root moved
    by ``$EULERTOP_GRADESCOPE_ROOT``; a submitter off the roster needs no kernel."""
    from tests.grader.hosted.test_gradescope import layout

    root = layout(public_tmp, hosted_hw, b"{}", [{"email": "eve@elsewhere.org"}])
    done = subprocess.run([sys.executable, "-m", "grader.hosted.gradescope"],
                          env={**os.environ, gradescope.ROOT_VARIABLE: str(root)},
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "not on the class roster" in (root / "results" / "results.json").read_text()
