"""Issue 22: each kind of machine grades an honest class in full with the key out of a thief's
reach, in the isolation tier it allows — or is refused up front with the real cause and its
fix, exit 2, no traceback, nothing written.

The machines are emulated (:mod:`tests.grader.tiers_support`): a ``bwrap`` on ``PATH`` that
fails as AppArmor, a container or a disabled sysctl make the real one fail, or the real one
with ``--disable-userns`` (no nesting); root of a user namespace that maps uid 0 alone is a real
``bwrap --unshare-user --uid 0`` around the grader; the container mode runs where this Python is
not under a private folder (a root ``bwrap`` that lays the file system out as a container's,
as the hosted tests do). Every run is ``python -m eulertop`` in a subprocess, as root and as an
ordinary user where both apply. What is measured is the records, the exit status, stderr, and
the instructor's files byte for byte — never what the grader says of itself alone.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from nbformat.v4 import new_code_cell

from grader.sandbox import available, host
from tests.grader.tiers_support import (
    HONEST,
    THIEF,
    assert_graded_in_full_and_safe,
    eulertop,
    fake_bwrap,
    make_class,
    ordinary_user,
    private_venv,
    results,
)


@pytest.fixture(scope="module", autouse=True)
def _required_here():
    if os.geteuid() != 0:
        pytest.fail("these tests run as root (CI does), to act as root and as an ordinary user",
                    pytrace=False)
    if available() is None:
        pytest.fail("bubblewrap is not installed: `apt-get install bubblewrap` (README)",
                    pytrace=False)


@pytest.fixture
def public_tmp():
    folder = Path(tempfile.mkdtemp(prefix="eulertop-tiers-", dir="/tmp"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def _as(who: str) -> int | None:
    return None if who == "root" else ordinary_user()


def grade(cls: dict, who: str, *, bin_first: Path | None = None, prefix=(),
          extra=()) -> subprocess.CompletedProcess:
    uid = _as(who)
    return eulertop(["grade", "HW", "subs", "--jobs", "2", "--timeout", "60", *extra],
                    cwd=cls["base"], path_first=bin_first, uid=uid, reach=[str(cls["base"])],
                    prefix=list(prefix))


def _no_traceback(done: subprocess.CompletedProcess) -> None:
    assert "Traceback" not in done.stderr and "Traceback" not in done.stdout, done.stderr


def _nothing_written(cls: dict) -> None:
    assert not (cls["hw"] / "graded").exists(), sorted(
        str(p) for p in (cls["hw"] / "graded").rglob("*"))


# --------------------------------------------------------------------------------------------
# the tiers that grade


@pytest.mark.parametrize("who", ["root", "ordinary user"])
def test_the_world_tier_where_namespaces_nest(public_tmp, who):
    cls = make_class(public_tmp, 0 if who == "root" else ordinary_user())
    done = grade(cls, who)
    assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, "world")


@pytest.mark.parametrize("who", ["root", "ordinary user"])
def test_a_bwrap_per_kernel_where_namespaces_do_not_nest(public_tmp, who):
    cls = make_class(public_tmp, 0 if who == "root" else ordinary_user())
    done = grade(cls, who, bin_first=fake_bwrap(public_tmp, "no-nesting"))
    got = assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, "bwrap-per-kernel")
    assert "cannot make namespaces of their own" in got[HONEST[0]]["execution"]["isolation"] \
        or "cannot make a world of its own" in got[HONEST[0]]["execution"]["isolation"]


def test_root_of_a_one_uid_namespace_grades_as_that_uid(public_tmp):
    """``unshare -r``, a rootless container: uid 0 maps alone, so no uid of its own can be
    given to a sandbox (the traceback of round 2: ``os.chown`` EINVAL); sandboxes run as the
    grader's uid, as an ordinary user's do — and where a kernel cannot mount its own /proc
    inside, one bubblewrap per kernel."""
    cls = make_class(public_tmp)
    one_uid = [shutil.which("bwrap"), "--unshare-user", "--uid", "0", "--gid", "0",
               "--dev-bind", "/", "/", "--"]
    done = grade(cls, "root", prefix=one_uid)
    _no_traceback(done)
    tier = "world" if "isolation: world:" in done.stderr else "bwrap-per-kernel"
    got = assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, tier)
    assert "as your uid" in got[HONEST[0]]["execution"]["isolation"]


def test_the_container_tier_as_root_where_no_namespace_can_be_made(public_tmp):
    """Docker's default seccomp profile refuses bwrap its namespaces: as root, each kernel runs
    as a uid of its own, with rlimits and the seccomp filter, the instructor's folders private
    for the run; the key stays out of the thief's reach, and the folders' modes come back.
    Each notebook leaves a file named by its kernel's uid: three students, three uids."""
    from tests.grader.hosted.conftest import container_layout

    layout = container_layout()
    assert layout is not None, "bubblewrap could not lay out a container's file system"
    cls = make_class(public_tmp)
    drop = _uid_drop(cls)
    modes = {name: cls[name].stat().st_mode for name in ("hw", "subs")}
    done = grade(cls, "root", bin_first=fake_bwrap(public_tmp, "docker"), prefix=layout)
    got = assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, "container")
    assert "private to root during the run" in done.stderr
    assert {name: cls[name].stat().st_mode for name in ("hw", "subs")} == modes
    notes = {r["execution"]["isolation"] for r in got.values()}
    assert len(notes) == 1 and "given to no other kernel of the run" in notes.pop()
    uids = {p.name: p.stat().st_uid for p in drop.iterdir()}
    assert len(uids) == len(got) and len(set(uids.values())) == len(got), uids
    assert all(str(uid) == name and uid not in (0, os.geteuid()) for name, uid in uids.items())


def _uid_drop(cls: dict) -> Path:
    """A world-writable folder below ``cls``'s (whose own is not, so the kernels' clean-up
    keeps it), and a last cell in every submission that leaves there a file named by its
    kernel's uid."""
    drop = cls["base"] / "uids"
    drop.mkdir()
    drop.chmod(0o1777)
    cell = new_code_cell(f"import os; open(os.path.join({str(drop)!r}, str(os.getuid())), 'w')")
    for path in cls["subs"].glob("*.ipynb"):
        nb = json.loads(path.read_text())
        nb["cells"].append(cell)
        path.write_text(json.dumps(nb))
    return drop


def test_without_the_sandbox_the_thief_would_get_every_point(public_tmp):
    """Control of the tests above: the same thief, graded where it can read the key
    (``--no-sandbox``), gets every point — so its 0 above means the key was out of reach."""
    cls = make_class(public_tmp)
    done = grade(cls, "root", extra=["--no-sandbox"])
    assert done.returncode == 0, done.stderr[-2000:]
    got = results(cls["hw"] / "graded")
    assert got[THIEF]["points"] == cls["max_points"][THIEF]


# --------------------------------------------------------------------------------------------
# refused up front: the cause, its fix, exit 2, nothing written


def test_apparmor_is_named_with_both_fixes(public_tmp):
    cls = make_class(public_tmp, ordinary_user())
    done = grade(cls, "ordinary user", bin_first=fake_bwrap(public_tmp, "apparmor"))
    assert done.returncode == 2, done.stderr
    _no_traceback(done)
    _nothing_written(cls)
    err = " ".join(done.stderr.split())
    assert "AppArmor" in err and "setting up uid map: Permission denied" in err
    assert f"apparmor_parser -r /etc/apparmor.d/{host.APPARMOR_PROFILE.name}" in err
    assert str(host.APPARMOR_PROFILE) in err and host.APPARMOR_PROFILE.is_file()
    assert "sysctl -w kernel.apparmor_restrict_unprivileged_userns=0" in err
    assert "apt-get install bubblewrap" not in err  # it is installed


def test_the_shipped_apparmor_profile_lets_bwrap_alone_make_user_namespaces():
    text = host.APPARMOR_PROFILE.read_text()
    rules = [line.strip() for line in text.splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    assert "profile eulertop-bwrap /usr/bin/bwrap flags=(unconfined) {" in rules
    assert "userns," in rules and rules[-1] == "}"


@pytest.mark.parametrize(("kind", "cause", "fix"), [
    ("no-userns", "user namespaces cannot be made here", "user.max_user_namespaces"),
    ("docker", "refuses the namespaces bubblewrap makes", "seccomp=unconfined"),
])
def test_an_ordinary_user_without_namespaces_is_refused_with_the_cause(public_tmp, kind, cause,
                                                                        fix):
    cls = make_class(public_tmp, ordinary_user())
    done = grade(cls, "ordinary user", bin_first=fake_bwrap(public_tmp, kind))
    assert done.returncode == 2, done.stderr
    _no_traceback(done)
    _nothing_written(cls)
    err = " ".join(done.stderr.split())
    assert cause in err and fix in err and "--no-sandbox" in err
    assert "apt-get install bubblewrap" not in err


def test_only_a_missing_bwrap_is_told_to_install_it(public_tmp):
    cls = make_class(public_tmp, ordinary_user())
    empty = public_tmp / "empty-bin"
    empty.mkdir(mode=0o755)
    done = eulertop(["grade", "HW", "subs", "--jobs", "1"], cwd=cls["base"],
                    uid=ordinary_user(), reach=[str(cls["base"])],
                    env={"PATH": f"{empty}:{Path(sys.executable).parent}"})
    assert done.returncode == 2, done.stderr
    _no_traceback(done)
    _nothing_written(cls)
    assert "'bwrap' is not installed" in done.stderr and "apt-get install bubblewrap" in \
        done.stderr


def test_root_where_the_container_mode_cannot_run_either_is_refused(public_tmp):
    """A Python in a private folder (a virtual environment in a 0700 folder) that no kernel
    user could run: both obstacles are named."""
    private = public_tmp / "private"
    private.mkdir(mode=0o700)
    python, _ = private_venv(private, source=True)
    cls = make_class(public_tmp / "class")
    done = eulertop(["grade", "HW", "subs", "--jobs", "2"], python=str(python),
                    cwd=cls["base"], path_first=fake_bwrap(public_tmp, "docker"))
    assert done.returncode == 2, done.stderr
    _no_traceback(done)
    _nothing_written(cls)
    assert "the container mode cannot run here either" in done.stderr
    assert str(python) in done.stderr and "every user may read and run" in done.stderr


@pytest.mark.parametrize("who", ["root", "ordinary user"])
def test_when_no_kernel_can_start_the_preflight_refuses_before_any_record(public_tmp, who):
    """The probe passes, but every kernel's sandbox fails to start: one preflight kernel
    says so, exit 2, and no student is recorded as failed (round 2 wrote 24 failed records)."""
    cls = make_class(public_tmp, 0 if who == "root" else ordinary_user())
    done = grade(cls, who, bin_first=fake_bwrap(public_tmp, "no-kernel"))
    assert done.returncode == 2, done.stderr
    _no_traceback(done)
    _nothing_written(cls)
    assert "no kernel could start here" in done.stderr and "eulertop doctor" in done.stderr
    assert "Can't mount proc" in done.stderr  # the sandbox's own words, as the cause


# --------------------------------------------------------------------------------------------
# eulertop doctor


def _doctor(public_tmp: Path, who: str, kind: str | None = None):
    bin_first = fake_bwrap(public_tmp, kind) if kind else None
    done = eulertop(["doctor"], cwd=public_tmp, path_first=bin_first, uid=_as(who),
                    reach=[str(public_tmp)])
    _no_traceback(done)
    lines = {line.split(maxsplit=1)[0]: line.split(maxsplit=1)[1]
             for line in done.stdout.splitlines() if " " in line}
    return done, lines


@pytest.mark.parametrize("who", ["root", "ordinary user"])
def test_doctor_says_grading_can_run_and_which_tier(public_tmp, who):
    done, lines = _doctor(public_tmp, who)
    assert done.returncode == 0, done.stdout + done.stderr
    for label in ("python", "eulertop", "bubblewrap", "user", "apparmor", "uid", "seccomp",
                  "grade", "isolation", "preflight", "check"):
        assert label in lines, (label, done.stdout)
    assert lines["grade"].startswith("tier world")
    assert lines["preflight"].startswith("a kernel started")
    assert shutil.which("bwrap") in lines["bubblewrap"]
    assert ("ordinary user" in lines["uid"]) == (who != "root")


def test_doctor_names_the_per_kernel_tier_where_namespaces_do_not_nest(public_tmp):
    done, lines = _doctor(public_tmp, "ordinary user", "no-nesting")
    assert done.returncode == 0, done.stdout
    assert lines["grade"].startswith("tier bwrap-per-kernel")


def test_doctor_fails_with_the_fix_under_apparmor(public_tmp):
    done, lines = _doctor(public_tmp, "ordinary user", "apparmor")
    assert done.returncode == 1, done.stdout
    assert lines["grade"].startswith("refused: AppArmor")
    assert "apparmor_parser" in lines["fix"] and "sysctl" in lines["fix"]
    assert "without a sandbox" in lines["check"]


def test_doctor_fails_where_no_kernel_starts(public_tmp):
    done, lines = _doctor(public_tmp, "root", "no-kernel")
    assert done.returncode == 1, done.stdout
    assert lines["preflight"].startswith("failed:") and "Can't mount proc" in lines["preflight"]
