"""``eulertop doctor``: what this machine allows the grader, one line each (issue 22).

For an instructor setting eulertop up, and for anyone reading a report of a run that refused:
where Python and eulertop are installed, bubblewrap and its version, whether user namespaces can
be made and whether they nest inside bubblewrap, Ubuntu's AppArmor restriction, seccomp, the
isolation tier ``eulertop grade`` would use (:func:`grader.kernels.isolation.choose_tier`) —
checked by starting one kernel exactly as a student's starts (:func:`grader.pipeline.preflight`)
— and what ``eulertop check`` would use. The fix is printed next to anything missing.

Exit status: 0 when grading can run safely here (a tier was found and its kernel ran), 1
otherwise.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path

WIDTH = 12
"""Width of the label column."""


def add_doctor_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop doctor`` takes no arguments."""


def run_doctor(args: argparse.Namespace) -> int:
    """Print the report (module docstring); 0 when grading can run safely, else 1."""
    ok = True
    for label, text, good in report():
        print(f"{label:<{WIDTH}} {text}", flush=True)
        ok = ok and good
    print("grading can run safely here" if ok else
          "grading cannot run safely here: see above")
    return 0 if ok else 1


def report() -> Iterator[tuple[str, str, bool]]:
    """``(label, what was found, whether grading can go on with it)``, line by line: the slow
    ones (a sandbox and a kernel started) last."""
    yield "python", _python(), True
    yield "eulertop", _eulertop(), True
    yield from _host_lines()
    yield from _tier_lines()


def _python() -> str:
    venv = sys.prefix != sys.base_prefix
    where = f"{sys.executable}" + (f" (virtual environment of {sys.base_prefix})" if venv
                                   else "")
    return f"{platform.python_version()} at {where}"


def _eulertop() -> str:
    from importlib import metadata

    import grader

    folder = Path(grader.__file__).resolve().parent.parent
    try:
        dist = metadata.distribution("eulertop")
        editable = (dist.read_text("direct_url.json") or "").find('"editable": true') >= 0
        return (f"{dist.version} from {folder}"
                + (" (editable install of that folder)" if editable else ""))
    except metadata.PackageNotFoundError:
        return f"not installed: run from the source folder {folder}"


def _host_lines() -> Iterator[tuple[str, str, bool]]:
    import shutil

    from grader.sandbox import UID_BASE, UID_SPAN, host, seccomp

    bwrap = shutil.which("bwrap")
    yield ("bubblewrap", f"{host.bwrap_version(bwrap)} at {bwrap}" if bwrap else
           f"not installed — fix: {host.INSTALL_BWRAP}", True)
    values = {name: host.sysctl(name) for name in host.SYSCTLS}
    shown = "; ".join(f"{name} = {value}" for name, value in values.items() if value is not None)
    possible, why = host.userns_possible()
    yield ("user ns", ("can be made" if possible else f"cannot be made ({why})")
           + (f" ({shown})" if shown else ""), True)
    restricted = host.apparmor_restricted()
    yield ("apparmor", "restricts unprivileged user namespaces "
           "(kernel.apparmor_restrict_unprivileged_userns = 1): bwrap needs a profile that "
           f"allows them — {host.APPARMOR_PROFILE} is one" if restricted else
           "no restriction of user namespaces", True)
    root = os.geteuid() == 0
    own = host.uids_mapped(UID_BASE, UID_SPAN)
    yield ("uid", "root, with uids to give each sandbox a user of its own" if root and own else
           "root of a user namespace that maps too few uids to give sandboxes their own: "
           "they run as it, as an ordinary user's do" if root else
           f"an ordinary user (uid {os.getuid()}): sandboxes run as it", True)
    try:
        seccomp.program()
        filtered = f"the kernels' filter refuses {len(seccomp.refused())} calls"
    except ValueError as err:
        filtered = f"no filter for the kernels ({err})"
    yield "seccomp", f"this process: {host.seccomp_mode()}; {filtered}", True


def _tier_lines() -> Iterator[tuple[str, str, bool]]:
    from grader.kernels.isolation import choose_tier
    from grader.sandbox import SandboxUnavailable, available

    try:
        tier = choose_tier()
    except SandboxUnavailable as err:
        yield "grade", f"refused: {err.diagnosis.cause}", False
        yield "fix", err.diagnosis.fix.removeprefix("Fix: "), False
        yield "check", _check_line(None), True
        return
    why = {"world": "each kernel makes a world of its own inside bubblewrap",
           "bwrap-per-kernel": "a bubblewrap per kernel: "
           + (getattr(tier, "why_per_kernel", "") or "namespaces do not nest here")}
    yield "grade", f"tier {tier.tier}" + (f" ({why[tier.tier]})" if tier.tier in why
                                          else ""), True
    yield "isolation", tier.describe(), True
    started, text = _start_one_kernel(tier)
    yield "preflight", text, started
    yield "check", _check_line(available()), True


def _check_line(sandbox: object | None) -> str:
    if sandbox is None:
        return ("eulertop check runs a notebook without a sandbox here (a student's own code "
                "on their own machine; no key is there to protect)")
    return f"eulertop check runs a notebook in the {sandbox.tier} tier, as grade does"


def _start_one_kernel(tier: object) -> tuple[bool, str]:
    """Start one kernel of ``tier`` as ``eulertop grade`` starts a student's, and run a cell."""
    from functools import partial

    from grader.assignment import UsageError
    from grader.execute import execute_submission
    from grader.limits import Limits
    from grader.pipeline import preflight
    from grader.sandbox import run_folder

    start = time.monotonic()
    with ExitStack() as stack:
        factory: Callable
        if getattr(tier, "tier", None) == "container":
            factory = tier.kernel_factory()
        else:
            from grader.kernels.pool import KernelPool

            stack.enter_context(run_folder())
            factory = stack.enter_context(KernelPool(1, prewarm=False, sandbox=tier)).kernel
        try:
            preflight(partial(execute_submission, kernel_factory=factory), Limits())
        except UsageError as err:
            return False, f"failed: {err}"
    return True, (f"a kernel started as a student's will and ran a cell "
                  f"({time.monotonic() - start:.1f} s)")
