"""The seccomp filter of every student kernel (issue 11): the system calls it is refused.

Standard library only (it is bound into the sandbox beside :mod:`world` and the zygote). The
filter is a classic BPF program over ``struct seccomp_data``: anything but this machine's
native architecture is killed (no x32 or 32-bit entry points around the list), a listed call
fails with ``EPERM``, ``clone`` with a namespace flag fails with ``EPERM``, ``clone3`` with
``ENOSYS`` (its flags are behind a pointer, out of a filter's reach; the C library then falls
back to ``clone``), and everything else is allowed. Installed with ``SECCOMP_FILTER_FLAG_TSYNC``
on every thread of the kernel, after ``no_new_privs``; a filter cannot be removed.

Why each is refused
    ``ptrace``, ``process_vm_readv``/``writev``, ``kcmp``, ``pidfd_getfd``: reading or steering
    another process. ``mount`` and the new mount API, ``umount2``, ``pivot_root``, ``chroot``,
    ``unshare``, ``setns``, ``clone`` with a namespace flag: remaking the world the kernel was
    given. ``keyctl``, ``add_key``, ``request_key``: kernel keyrings outlive processes.
    ``bpf``, ``perf_event_open``, ``userfaultfd``, ``io_uring_*``: large kernel attack surface a
    notebook has no use for. ``memfd_create``, ``memfd_secret``: memory that no process
    limit counts. Module loading, ``kexec``, ``reboot``, ``swapon``/``swapoff``, clocks,
    ``acct``, ``quotactl``, ``syslog``, ``open_by_handle_at``: administration.
    With ``ipc`` (the ``bwrap-per-kernel`` tier, whose kernels cannot set the limits of their own
    IPC namespace, :mod:`grader.sandbox`): ``shmget`` and ``msgget`` too — SysV memory that no
    process limit counts and that outlives its maker until the sandbox ends.

Floor 1 of grader/ (one student, one disposable world; grader/API.md).
"""

from __future__ import annotations

import ctypes
import errno
import os
import platform
import struct

# (arch token, AUDIT_ARCH, {name: number})
_X86_64 = (0xC000003E, {
    "ptrace": 101, "process_vm_readv": 310, "process_vm_writev": 311, "kcmp": 312,
    "pidfd_getfd": 438, "mount": 165, "umount2": 166, "pivot_root": 155, "chroot": 161,
    "unshare": 272, "setns": 308, "open_tree": 428, "move_mount": 429, "fsopen": 430,
    "fsconfig": 431, "fsmount": 432, "fspick": 433, "mount_setattr": 442, "keyctl": 250,
    "add_key": 248, "request_key": 249, "bpf": 321, "perf_event_open": 298,
    "userfaultfd": 323, "io_uring_setup": 425, "io_uring_enter": 426,
    "io_uring_register": 427, "memfd_create": 319, "memfd_secret": 447, "init_module": 175,
    "finit_module": 313, "delete_module": 176, "kexec_load": 246, "kexec_file_load": 320,
    "reboot": 169, "swapon": 167, "swapoff": 168, "settimeofday": 164, "clock_settime": 227,
    "clock_adjtime": 305, "adjtimex": 159, "acct": 163, "quotactl": 179, "syslog": 103,
    "open_by_handle_at": 304, "name_to_handle_at": 303, "lookup_dcookie": 212,
    "fanotify_init": 300, "iopl": 172, "ioperm": 173, "personality": 135, "vhangup": 153,
    "process_madvise": 440, "migrate_pages": 256, "move_pages": 279,
}, 56, 435, 0x40000000)
_AARCH64 = (0xC00000B7, {
    "ptrace": 117, "process_vm_readv": 270, "process_vm_writev": 271, "kcmp": 272,
    "pidfd_getfd": 438, "mount": 40, "umount2": 39, "pivot_root": 41, "chroot": 51,
    "unshare": 97, "setns": 268, "open_tree": 428, "move_mount": 429, "fsopen": 430,
    "fsconfig": 431, "fsmount": 432, "fspick": 433, "mount_setattr": 442, "keyctl": 219,
    "add_key": 217, "request_key": 218, "bpf": 280, "perf_event_open": 241,
    "userfaultfd": 282, "io_uring_setup": 425, "io_uring_enter": 426,
    "io_uring_register": 427, "memfd_create": 279, "memfd_secret": 447, "init_module": 105,
    "finit_module": 273, "delete_module": 106, "kexec_load": 104, "kexec_file_load": 294,
    "reboot": 142, "swapon": 224, "swapoff": 225, "settimeofday": 170, "clock_settime": 112,
    "clock_adjtime": 266, "adjtimex": 171, "acct": 89, "quotactl": 60, "syslog": 116,
    "open_by_handle_at": 265, "name_to_handle_at": 264, "fanotify_init": 262,
    "personality": 92, "vhangup": 58, "process_madvise": 440, "migrate_pages": 238,
    "move_pages": 239,
}, 220, 435, None)
ARCHES = {"x86_64": _X86_64, "aarch64": _AARCH64}
IPC_CALLS = {"x86_64": {"shmget": 29, "msgget": 68}, "aarch64": {"shmget": 194, "msgget": 186}}
"""Refused as well with ``ipc`` (module docstring)."""

NAMESPACE_FLAGS = 0x7E020080  # CLONE_NEWNS|NEWCGROUP|NEWUTS|NEWIPC|NEWUSER|NEWPID|NEWNET|NEWTIME

SECCOMP_RET_KILL_PROCESS, SECCOMP_RET_ERRNO, SECCOMP_RET_ALLOW = 0x80000000, 0x00050000, 0x7FFF0000
PR_SET_NO_NEW_PRIVS, SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_TSYNC = 38, 1, 1
SYS_SECCOMP = {"x86_64": 317, "aarch64": 277}

# classic BPF opcodes
_LD_W_ABS, _JEQ_K, _JGE_K, _JSET_K, _RET_K = 0x20, 0x15, 0x35, 0x45, 0x06


def _insn(code: int, jt: int, jf: int, k: int) -> bytes:
    return struct.pack("HBBI", code, jt, jf, k & 0xFFFFFFFF)


def _calls(machine: str, ipc: bool) -> dict[str, int]:
    return {**ARCHES[machine][1], **(IPC_CALLS[machine] if ipc else {})}


def refused(ipc: bool = False) -> tuple[str, ...]:
    """Names of the system calls the filter refuses on this machine (empty: no filter here);
    ``ipc``: the SysV calls too (module docstring)."""
    machine = platform.machine()
    if machine not in ARCHES:
        return ()
    return (*sorted(_calls(machine, ipc)), "clone(namespace flags)", "clone3")


def program(machine: str | None = None, ipc: bool = False) -> bytes:
    """The filter as raw ``struct sock_filter`` instructions for ``machine`` (default: this
    one); ValueError for an architecture without a table."""
    machine = machine or platform.machine()
    if machine not in ARCHES:
        raise ValueError(f"no seccomp table for {machine}")
    audit, _, clone, clone3, x32 = ARCHES[machine]
    calls = _calls(machine, ipc)
    def errno_of(e):
        return (SECCOMP_RET_ERRNO | e)
    out = [_insn(_LD_W_ABS, 0, 0, 4),                    # A = arch
           _insn(_JEQ_K, 1, 0, audit),
           _insn(_RET_K, 0, 0, SECCOMP_RET_KILL_PROCESS),
           _insn(_LD_W_ABS, 0, 0, 0)]                    # A = syscall number
    if x32 is not None:
        out += [_insn(_JGE_K, 0, 1, x32), _insn(_RET_K, 0, 0, SECCOMP_RET_KILL_PROCESS)]
    for number in sorted(set(calls.values())):
        out += [_insn(_JEQ_K, 0, 1, number), _insn(_RET_K, 0, 0, errno_of(errno.EPERM))]
    out += [_insn(_JEQ_K, 0, 1, clone3), _insn(_RET_K, 0, 0, errno_of(errno.ENOSYS)),
            _insn(_JEQ_K, 0, 3, clone),
            _insn(_LD_W_ABS, 0, 0, 16),                  # A = low 32 bits of args[0]
            _insn(_JSET_K, 0, 1, NAMESPACE_FLAGS),
            _insn(_RET_K, 0, 0, errno_of(errno.EPERM)),
            _insn(_RET_K, 0, 0, SECCOMP_RET_ALLOW)]
    return b"".join(out)


class _Fprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


def install(ipc: bool = False) -> str:
    """``no_new_privs``, then the filter on every thread of this process; what was done
    ("on: N calls refused", or why there is none on this architecture)."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_NO_NEW_PRIVS)")
    try:
        code = program(ipc=ipc)
    except ValueError as err:
        return f"off ({err})"
    buffer = ctypes.create_string_buffer(code, len(code))
    prog = _Fprog(len(code) // 8, ctypes.cast(buffer, ctypes.c_void_p))
    nr = SYS_SECCOMP[platform.machine()]
    libc.syscall.restype = ctypes.c_long
    result = libc.syscall(ctypes.c_long(nr), ctypes.c_long(SECCOMP_SET_MODE_FILTER),
                          ctypes.c_long(SECCOMP_FILTER_FLAG_TSYNC), ctypes.byref(prog))
    if result != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"seccomp: {os.strerror(err)} (thread {result})")
    return f"on: {len(refused(ipc))} calls refused"
