"""A forked kernel's cell server (grader/kernels/cell_server.py, grader/kernels/channel.py)
against a
Jupyter kernel.

Reference: ipykernel itself. Every notebook here runs twice, in a cold
:class:`~grader.kernels.local.LocalKernel` (ipykernel driven by nbclient, as nbgrader and Jupyter
run it) and in a kernel forked from a zygote (IPython's shell behind the cell server), and the
two records must agree: status, each cell's error line, answers, output truncation. Then what
only the cell server has: a kernel that writes junk, overlong lines or forged replies into its
own channel, and an interrupt between two requests.
"""

from __future__ import annotations

import asyncio
import textwrap
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import execute_submission
from grader.kernels.local import LocalKernel
from grader.kernels.pool import KernelPool, fork_available
from grader.limits import Limits
from grader.sandbox import fresh_folder, run_folder

LIMITS = Limits(cell_timeout=2.0, total_timeout=30.0, output_bytes=100_000)

CASES = {
    "plain": (["x = 1 + 1"], ("x",)),
    "exception": (["x = 1", "1 / 0", "y = 2"], ("x", "y")),
    "syntax error": (["x = (1,\n2 +", "y = 2"], ("x", "y")),
    "sys.exit": (["import sys\nsys.exit(3)", "y = 2"], ("y",)),
    "exit()": (["exit()", "y = 2"], ("y",)),
    "interrupt from inside": (["import os, signal\nos.kill(os.getpid(), signal.SIGINT)\n"
                               "import time\ntime.sleep(5)", "y = 2"], ("y",)),
    "magics": (["%time x = 3", "y = %time 4"], ("x", "y")),
    "top-level await": (["import asyncio\nawait asyncio.sleep(0)\nx = 5"], ("x",)),
    "long print": (["print('p' * 300_000)", "x = 1"], ("x",)),
    "long display": (["from IPython.display import display\n"
                      "display({'text/plain': 'd' * 300_000}, raw=True)", "x = 1"], ("x",)),
    "matplotlib": (["import matplotlib.pyplot as plt\nplt.plot([1, 2, 3])\nplt.show()\n"
                    "x = len(plt.get_fignums())"], ("x",)),
    "the shell": (["ip = get_ipython()\nx = ip.user_ns['__name__']\ny = __name__"],
                  ("x", "y")),
    "inline figures": (["%matplotlib inline\nimport matplotlib.pyplot as plt\n"
                        "fig, ax = plt.subplots()\nax.plot([1, 2])\ndisplay(fig)", "x = 1"],
                       ("x",)),
    "cell magic, shell, stderr, warnings": (["%%time\nx = 1", "!echo hello", "import sys\n"
                                             "print('e', file=sys.stderr)\nimport warnings\n"
                                             "warnings.warn('careful')\ny = 2"], ("x", "y")),
    "cell timeout": (["import time\nwhile True:\n    time.sleep(0.01)", "x = 1"], ("x",)),
}


@pytest.fixture(scope="module")
def pool():
    if not fork_available():
        pytest.fail("forked kernels need Linux fork", pytrace=False)
    with KernelPool(1, preload=("numpy",)) as warm:
        yield warm


def notebook(tmp_path: Path, cells: list[str]) -> Path:
    path = tmp_path / f"n{len(list(tmp_path.iterdir()))}" / "alice.ipynb"
    path.parent.mkdir()
    nbformat.write(new_notebook(cells=[new_code_cell(c) for c in cells]), path)
    return path


def record(execution) -> dict:
    return {"status": execution.status, "cell_errors": execution.cell_errors,
            "answers": execution.answers, "output_truncated": execution.output_truncated}


@pytest.mark.parametrize("case", CASES)
def test_a_forked_kernel_records_what_a_jupyter_kernel_records(case, pool, tmp_path):
    cells, variables = CASES[case]
    path = notebook(tmp_path, cells)
    jupyter = execute_submission(path, variables, LIMITS, kernel_factory=LocalKernel)
    forked = execute_submission(path, variables, LIMITS, kernel_factory=pool.kernel)
    assert jupyter.status == "ok", jupyter.message  # the reference ran
    assert record(forked) == record(jupyter)


def test_input_fails_at_once(pool, tmp_path):
    """``input()`` raises ipykernel's own error at once, where ipykernel under nbclient waits
    for an answer that never comes until the cell's time limit (measured here)."""
    path = notebook(tmp_path, ["name = input('who? ')", "y = 2"])
    forked = execute_submission(path, ("name", "y"), LIMITS, kernel_factory=pool.kernel)
    jupyter = execute_submission(path, ("name", "y"), LIMITS, kernel_factory=LocalKernel)
    assert forked.answers == jupyter.answers == {"name": None, "y": 2}
    assert forked.cell_errors == ("cell 1 (`name = input('who? ')`): StdinNotImplementedError: "
                                  "raw_input was called, but this frontend does not support "
                                  "input requests. — input() waits for someone to type, and "
                                  "no one types while the grader runs the notebook: write the "
                                  "value into the code instead",)
    assert jupyter.cell_errors == ("cell 1 (`name = input('who? ')`): timed out after 2 s and "
                                   "was interrupted",)
    assert forked.duration < LIMITS.cell_timeout <= jupyter.duration


def test_the_shell_is_ipython_and_not_a_jupyter_kernel(pool, tmp_path):
    """What differs, plainly: the shell's class (``get_ipython().kernel`` does not exist)."""
    path = notebook(tmp_path, ["ip = get_ipython()\nname = type(ip).__name__\n"
                               "kernel = hasattr(ip, 'kernel')"])
    forked = execute_submission(path, ("name", "kernel"), LIMITS, kernel_factory=pool.kernel)
    jupyter = execute_submission(path, ("name", "kernel"), LIMITS, kernel_factory=LocalKernel)
    assert forked.answers == {"name": "InteractiveShell", "kernel": False}
    assert jupyter.answers == {"name": "ZMQInteractiveShell", "kernel": True}


CHANNEL_ABUSE = textwrap.dedent("""\
    import json, os, socket, stat
    sent = 0
    for fd in map(int, os.listdir('/proc/self/fd')):
        try:
            if not stat.S_ISSOCK(os.fstat(fd).st_mode):
                continue
            s = socket.socket(fileno=os.dup(fd))
            if s.family != socket.AF_UNIX:
                continue
        except OSError:
            continue
        junk = [b'x' * (9 * 1024**2) + b'\\n', b'{not json\\n', b'[1, 2]\\n', b'\\n',
                json.dumps({'n': 999, 'reply': {'status': 'ok'}}).encode() + b'\\n',
                json.dumps({'n': 'a', 'reply': 3, 'output': -5}).encode() + b'\\n',
                b'y' * (5 * 1024**2)]  # and an overlong line left without its end
        for chunk in junk:
            s.sendall(chunk)
        s.sendall(b'\\n')
        sent += 1
    """)


def test_junk_in_its_own_channel_harms_no_one(pool, tmp_path):
    """A kernel writing overlong lines, non-JSON and replies to no request into its channel:
    each is dropped, the grader's memory is bounded by a line, and the real replies after
    them are read (cells and answers)."""
    path = notebook(tmp_path, [CHANNEL_ABUSE, "x = 41 + 1"])
    done = execute_submission(path, ("sent", "x"), LIMITS, kernel_factory=pool.kernel)
    assert done.status == "ok", done.message
    assert done.answers["sent"] >= 1 and done.answers["x"] == 42 and done.cell_errors == ()


def test_an_interrupt_between_requests_is_ignored(pool):
    """SIGINT while no request runs does nothing (as in ipykernel); the next request runs."""
    async def scenario(kernel):
        channel = await kernel.start()
        try:
            n = channel.send("execute", "x = 1")
            assert (await channel.reply(n))[0] == {"status": "ok"}
            for _ in range(3):
                await kernel.interrupt()
            await asyncio.sleep(0.2)
            assert kernel.exit_status() is None
            n = channel.send("answers", "y = x + 1", user_expressions={"y": "y"})
            reply, _ = await channel.reply(n)
            return reply
        finally:
            await kernel.stop()

    with run_folder() as run:
        kernel = pool.kernel(fresh_folder(run, "w"), fresh_folder(run, "c"), LIMITS)
        reply = asyncio.run(scenario(kernel))
    assert reply["status"] == "ok"
    assert reply["user_expressions"]["y"]["data"]["text/plain"] == "2"
