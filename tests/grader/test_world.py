"""The pieces of one kernel's world (issue 11), on their own: the seccomp filter's program,
read by a small BPF interpreter written here from the kernel's documentation, and the keeper's
measure of memory against what a process really holds."""

from __future__ import annotations

import errno
import struct
import subprocess
import sys
import time

import pytest

from grader.sandbox import seccomp
from grader.sandbox.world import resident_bytes

X86_64, AARCH64 = 0xC000003E, 0xC00000B7
RET_ALLOW, RET_KILL = 0x7FFF0000, 0x80000000


def run_filter(code: bytes, nr: int, arch: int, arg0: int = 0) -> int:
    """Classic BPF over ``struct seccomp_data`` (nr, arch, ip, args): the action returned."""
    data = struct.pack("<iIQ6Q", nr, arch, 0, arg0, 0, 0, 0, 0, 0)
    insns = [struct.unpack("HBBI", code[i:i + 8]) for i in range(0, len(code), 8)]
    pc, acc = 0, 0
    while True:
        op, jt, jf, k = insns[pc]
        if op == 0x20:  # BPF_LD | BPF_W | BPF_ABS
            acc = struct.unpack_from("<I", data, k)[0]
        elif op == 0x06:  # BPF_RET | BPF_K
            return k
        elif op in (0x15, 0x35, 0x45):  # JEQ, JGE, JSET with K
            hit = {0x15: acc == k, 0x35: acc >= k, 0x45: bool(acc & k)}[op]
            pc += jt if hit else jf
        else:
            raise AssertionError(f"unexpected opcode {op:#x}")
        pc += 1


@pytest.mark.parametrize(("machine", "arch"), [("x86_64", X86_64), ("aarch64", AARCH64)])
def test_every_listed_call_fails_with_eperm_and_ordinary_calls_pass(machine, arch):
    code = seccomp.program(machine)
    calls = seccomp.ARCHES[machine][1]
    for name, nr in calls.items():
        assert run_filter(code, nr, arch) == 0x00050000 | errno.EPERM, name
    listed = set(calls.values()) | {seccomp.ARCHES[machine][2], seccomp.ARCHES[machine][3]}
    for nr in range(0, 460):  # read, write, openat, mmap, futex, …: everything else passes
        if nr not in listed:
            assert run_filter(code, nr, arch) == RET_ALLOW, nr


@pytest.mark.parametrize(("machine", "arch"), [("x86_64", X86_64), ("aarch64", AARCH64)])
def test_clone_is_refused_only_with_a_namespace_flag_and_clone3_falls_back(machine, arch):
    code = seccomp.program(machine)
    clone, clone3 = seccomp.ARCHES[machine][2], seccomp.ARCHES[machine][3]
    thread_flags = 0x3D0F00  # what pthread_create passes
    assert run_filter(code, clone, arch, thread_flags) == RET_ALLOW
    assert run_filter(code, clone, arch, 0x11) == RET_ALLOW  # fork: SIGCHLD only
    for flag in (0x20000, 0x10000000, 0x20000000, 0x40000000, 0x08000000, 0x04000000,
                 0x02000000, 0x80):
        assert run_filter(code, clone, arch, thread_flags | flag) == 0x00050000 | errno.EPERM
    assert run_filter(code, clone3, arch) == 0x00050000 | errno.ENOSYS


def test_another_architecture_or_the_x32_entry_points_are_killed():
    code = seccomp.program("x86_64")
    assert run_filter(code, 0, 0x40000003) == RET_KILL  # i386
    assert run_filter(code, 0x40000000 + 101, X86_64) == RET_KILL  # x32 ptrace


def test_no_table_for_an_unknown_machine():
    with pytest.raises(ValueError, match="no seccomp table for sparc"):
        seccomp.program("sparc")


def test_the_keeper_counts_a_process_and_its_children():
    code = ("import os, time\n"
            "b = bytearray(300 * 2**20)\n"
            "for i in range(0, len(b), 4096): b[i] = 1\n"
            "if os.fork() == 0:\n"
            "    c = bytearray(200 * 2**20)\n"
            "    for i in range(0, len(c), 4096): c[i] = 1\n"
            "print('ready', flush=True)\n"
            "time.sleep(30)\n")
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        for _ in range(2):
            assert child.stdout.readline().strip() == "ready"
        time.sleep(0.2)
        held = resident_bytes(child.pid)  # the 300 MiB shared after fork: counted twice
        assert 800 * 2**20 < held < 1000 * 2**20, held
        truly = resident_bytes(child.pid, proportional=True)  # shared pages divided
        assert 500 * 2**20 < truly < 620 * 2**20, truly
    finally:
        subprocess.run(["pkill", "-KILL", "-P", str(child.pid)], check=False)
        child.kill()
        child.wait()
