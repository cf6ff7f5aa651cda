"""The isolation tier of a run (floor 2; issue 22): the strongest this machine allows.

``world`` or ``bwrap-per-kernel`` (:func:`grader.sandbox.probe`), else — as root, where no user
namespace can be made — the ``container`` tier (:class:`grader.kernels.container.ContainerTier`);
else a refusal with the cause and its fix. ``eulertop grade`` and ``eulertop doctor`` ask here.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import os
from typing import Any

from grader.kernels.container import (
    ContainerTier,
    NoFreeUid,
    RunUids,
    check_interpreter,
    free_uids,
)


def choose_tier() -> Any:
    """The isolation ``eulertop grade`` uses here: :func:`grader.sandbox.probe`'s sandbox
    (``world`` or ``bwrap-per-kernel``); else, as root where no user namespace can be made,
    the :class:`ContainerTier`; else :class:`grader.sandbox.SandboxUnavailable` with the
    cause and fix (the container mode's own obstacle added where it was tried)."""
    from grader.sandbox import SandboxUnavailable, host, probe

    try:
        return probe()
    except SandboxUnavailable as err:
        refusal = err
    if os.geteuid() != 0:
        raise refusal
    if refusal.diagnosis.kind == "missing" and host.userns_possible()[0]:
        raise refusal  # a machine where bubblewrap would work: install it
    found = free_uids()
    uids = None if found is None else RunUids(*found)
    why = ("this root has no other uid to give a kernel (its user namespace maps too few)"
           if uids is None else _container_obstacle(uids))
    if why is None:
        return ContainerTier(uids, refusal.diagnosis.cause)
    diagnosis = refusal.diagnosis
    raise SandboxUnavailable(host.Diagnosis(
        diagnosis.kind, f"{diagnosis.cause}; and the container mode cannot run here either: "
        f"{why}", diagnosis.fix))


def _container_obstacle(uids: RunUids) -> str | None:
    """Why a kernel could not run as a uid of ``uids`` (its first: the run's own, never given
    again), or None."""
    try:
        return check_interpreter(uids.take())
    except NoFreeUid as err:
        return str(err)
