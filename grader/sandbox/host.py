"""What this machine allows a sandbox (issue 22): the facts, and the cause and fix of a refusal.

Read-only looks at the host — the ``bwrap`` program, the sysctls that govern user namespaces
(Debian's ``kernel.unprivileged_userns_clone``, ``user.max_user_namespaces``, Ubuntu's
``kernel.apparmor_restrict_unprivileged_userns``), this process's uid map (root of a user
namespace that maps uid 0 alone has no other uid to give a kernel) and its seccomp mode — and
:func:`explain`, which turns what ``bwrap`` printed when it failed into a :class:`Diagnosis`:
the real cause, in words, and the fix for it. ``eulertop grade`` refuses with it;
``eulertop doctor`` prints the facts one line each.

Nothing here starts a sandbox (:func:`grader.sandbox.probe` does) or changes the machine.

Floor 1 of grader/ (one student, one disposable world; grader/API.md).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "APPARMOR_PROFILE",
    "INSTALL_BWRAP",
    "Diagnosis",
    "apparmor_restricted",
    "bwrap_version",
    "explain",
    "mapped_uids",
    "missing_bwrap",
    "seccomp_mode",
    "sysctl",
    "userns_possible",
]

APPARMOR_PROFILE = Path(__file__).with_name("apparmor") / "eulertop-bwrap"
"""The AppArmor profile shipped with eulertop that lets ``/usr/bin/bwrap`` (only) make user
namespaces under Ubuntu's restriction; the AppArmor refusal points to it."""

INSTALL_BWRAP = ("install bubblewrap (Debian/Ubuntu: 'sudo apt-get install bubblewrap'; "
                 "Fedora: 'sudo dnf install bubblewrap'; Arch: 'sudo pacman -S bubblewrap')")

NO_SANDBOX = ("or pass --no-sandbox to run student code without one (it can then read the "
              "answer key and anything else your user can)")
"""The last resort, named at the end of every refusal."""

SYSCTLS = ("kernel.apparmor_restrict_unprivileged_userns", "kernel.unprivileged_userns_clone",
           "user.max_user_namespaces")


@dataclass(frozen=True)
class Diagnosis:
    """Why no sandbox can start here: ``cause`` (what is wrong, in words) and ``fix`` (what
    to do about it); ``kind`` names the case (``missing``, ``apparmor``, ``userns-disabled``,
    ``debian-sysctl``, ``container``, ``other``)."""

    kind: str
    cause: str
    fix: str

    def message(self) -> str:
        """One paragraph for a person: cause, then fix."""
        return f"no sandbox for student code: {self.cause}. {self.fix}"


def sysctl(name: str) -> str | None:
    """The value of sysctl ``name`` (``kernel.x`` → ``/proc/sys/kernel/x``), None where this
    kernel has no such setting or it cannot be read."""
    try:
        return Path("/proc/sys", *name.split(".")).read_text().strip()
    except OSError:
        return None


def apparmor_restricted() -> bool:
    """Ubuntu's AppArmor restriction of unprivileged user namespaces is on."""
    return sysctl("kernel.apparmor_restrict_unprivileged_userns") == "1"


def bwrap_version(bwrap: str) -> str:
    """What ``bwrap --version`` prints (``bubblewrap 0.8.0``), or why it could not say."""
    try:
        done = subprocess.run([bwrap, "--version"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError) as err:
        return f"unknown ({err})"
    return (done.stdout.strip() or done.stderr.strip() or "unknown").splitlines()[0]


def mapped_uids() -> list[tuple[int, int]]:
    """The uid ranges ``[first, first + count)`` that exist in this process's user namespace
    (``/proc/self/uid_map``; the whole 32-bit range where it cannot be read)."""
    try:
        lines = Path("/proc/self/uid_map").read_text().splitlines()
    except OSError:
        return [(0, 2**32 - 1)]
    ranges = []
    for line in lines:
        fields = line.split()
        if len(fields) == 3:
            ranges.append((int(fields[0]), int(fields[2])))
    return ranges


def uids_mapped(first: int, count: int) -> bool:
    """Every uid of ``[first, first + count)`` exists in this user namespace."""
    return any(lo <= first and first + count <= lo + n for lo, n in mapped_uids())


def seccomp_mode() -> str:
    """This process's seccomp mode from ``/proc/self/status``: ``none``, ``strict`` or
    ``filter`` (a container's profile, say), or ``unknown``."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Seccomp:"):
                return {"0": "none", "1": "strict", "2": "filter"}.get(line.split()[1],
                                                                       "unknown")
    except OSError:
        pass
    return "unknown"


def userns_possible() -> tuple[bool, str]:
    """Can this user make a user namespace at all (outside any sandbox)? ``(yes, why not)``,
    tried in a child process so this one stays as it is."""
    code = ("import ctypes, os, sys\n"
            "libc = ctypes.CDLL(None, use_errno=True)\n"
            "if libc.unshare(0x10000000) != 0:\n"
            "    sys.exit(os.strerror(ctypes.get_errno()))\n")
    try:
        done = subprocess.run([sys.executable, "-I", "-c", code], capture_output=True,
                              text=True, timeout=30, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError) as err:
        return False, str(err)
    return done.returncode == 0, done.stderr.strip()


def missing_bwrap() -> Diagnosis:
    """The refusal where ``bwrap`` is not installed (the one case that says "install")."""
    return Diagnosis("missing", "the bubblewrap program 'bwrap' is not installed",
                     f"Fix: {INSTALL_BWRAP}, {NO_SANDBOX}.")


def _apparmor(last: str) -> Diagnosis:
    profile = APPARMOR_PROFILE
    return Diagnosis(
        "apparmor",
        f"AppArmor forbids bubblewrap the user namespace it needs ({last}): Ubuntu ≥ 23.10 "
        "restricts unprivileged user namespaces to programs with an AppArmor profile that "
        "allows them (kernel.apparmor_restrict_unprivileged_userns = 1), and bwrap has none "
        "here",
        "Fix, either: (1) let bwrap alone make them, with the profile shipped with eulertop: "
        f"'sudo install -m 644 {profile} /etc/apparmor.d/eulertop-bwrap && sudo "
        "apparmor_parser -r /etc/apparmor.d/eulertop-bwrap' (every other program stays "
        "restricted); or (2) lift the restriction for every program: 'sudo sysctl -w "
        "kernel.apparmor_restrict_unprivileged_userns=0' (until the next boot; a file in "
        "/etc/sysctl.d/ keeps it), which gives back to all programs the kernel interfaces "
        f"the restriction hides; {NO_SANDBOX}.")


def explain(stderr: str, *, root: bool | None = None) -> Diagnosis:
    """The cause and fix of a ``bwrap`` that failed to start a sandbox, from what it printed
    on ``stderr`` and the sysctls of this machine. ``root``: the grader runs as root (default:
    as this process does) — as root, :func:`grader.sandbox.probe`'s caller may still grade in
    the container mode."""
    root = os.geteuid() == 0 if root is None else root
    last = next((line.strip() for line in reversed(stderr.strip().splitlines())
                 if line.strip()), "no message")
    text = stderr.lower()
    if "permission denied" in text and ("uid map" in text or apparmor_restricted()):
        return _apparmor(last)
    if sysctl("kernel.unprivileged_userns_clone") == "0" and not root:
        return Diagnosis(
            "debian-sysctl",
            f"unprivileged user namespaces are switched off here ({last}; "
            "kernel.unprivileged_userns_clone = 0)",
            "Fix: 'sudo sysctl -w kernel.unprivileged_userns_clone=1' (a file in "
            f"/etc/sysctl.d/ keeps it after a reboot); {NO_SANDBOX}.")
    if sysctl("user.max_user_namespaces") == "0" or "no space left on device" in text \
            or "enospc" in text:
        return Diagnosis(
            "userns-disabled",
            f"user namespaces cannot be made here ({last}; user.max_user_namespaces = "
            f"{sysctl('user.max_user_namespaces') or 'unknown'}): the system or the container "
            "this runs in allows none",
            "Fix: 'sudo sysctl -w user.max_user_namespaces=15000' on the host (a file in "
            "/etc/sysctl.d/ keeps it), or grade as root in the container image (README, "
            f"'Grading on macOS, Windows or in a container'); {NO_SANDBOX}.")
    if re.search(r"operation not permitted", text):
        return Diagnosis(
            "container",
            f"this system refuses the namespaces bubblewrap makes ({last}); a container's "
            "seccomp profile (Docker's default) does this",
            "Fix: grade as root in the container image (README, 'Grading on macOS, Windows or "
            "in a container'), where eulertop uses its container mode, or run the container "
            f"with --security-opt seccomp=unconfined; {NO_SANDBOX}.")
    return Diagnosis("other", f"bwrap failed to start a sandbox ({last})",
                     f"Run 'eulertop doctor' for what this machine allows; {NO_SANDBOX}.")
