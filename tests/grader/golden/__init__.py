"""Golden bad notebooks: each builder turns a generated notebook into one failure mode.

A builder takes the student's generated notebooks (``solutions`` and ``release``, as nbformat v4
dicts), the public answer specs, and the assignment folder, and returns the submission's file
content (a notebook dict, or raw ``bytes`` for files that are not notebooks). Builders pick the
answers they modify by *kind* from the specs, so they keep working when templates change.

The expected outcome (the message a user sees) of each is asserted in
``tests/grader/test_execute.py``, ``test_notebook_load.py`` and ``test_check.py``.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

Builder = Callable[[dict, dict, Sequence[dict], Path], "dict | bytes"]

CANARY = "EULERTOP_TEST_CANARY"
"""Environment variable the tests set in the grader; it must not reach the kernel."""


def code_cell(source: str, cell_id: str) -> dict:
    """A v4 code cell."""
    return {"cell_type": "code", "id": cell_id, "metadata": {}, "source": source,
            "outputs": [], "execution_count": None}


def first_of_kind(specs: Sequence[Mapping], kind: str) -> str:
    """The first answer variable of ``kind`` in the specs."""
    return next(s["variable"] for s in specs if s["kind"] == kind)


def answer_cells(nb: Mapping) -> list[int]:
    """Indices of the generated answer cells (``q{k}-answer``)."""
    return [i for i, c in enumerate(nb["cells"]) if str(c.get("id", "")).endswith("-answer")]


def _insert_after_parameters(nb: dict, cells: Sequence[dict]) -> dict:
    nb = copy.deepcopy(nb)
    at = next(i for i, c in enumerate(nb["cells"]) if c.get("id") == "parameters") + 1
    nb["cells"][at:at] = list(cells)
    return nb


def all_correct(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """The solutions notebook itself: every answer is the key's."""
    return copy.deepcopy(solutions)


FAULTS = (
    ("def broken(:\n    pass", ("SyntaxError: invalid syntax (line 1)",)),
    ("x = 1 / 0", ("ZeroDivisionError: division by zero",)),
    ("import sys\nsys.exit()", ("SystemExit — sys.exit() and exit() stop a script",)),
    ("while True:\n    pass", ("timed out after 2 s and was interrupted",)),
    ("print('y' * 100_000_000)  # one 100 MB message", ()),
    ("for _ in range(100):\n    print('z' * 1_000_000)  # 100 MB in pieces", ()),
    ("import numpy as np\nbomb = [np.empty(10**8) for _ in range(1000)]",
     ("MemoryError: Unable to allocate", "— the memory limit is 1.5 GiB")),
)
"""(cell source, fragments of its cell_errors line — empty: no error) of :func:`faults`."""


def faults(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """Every recoverable fault, one cell each, before the (correct) answer cells."""
    return _insert_after_parameters(
        solutions, [code_cell(src, f"fault-{i}") for i, (src, _) in enumerate(FAULTS)])


def ignores_interrupt(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """A loop that ignores the interrupt: only the whole-notebook deadline ends it.

    SIGINT is ignored at the OS level (`SIG_IGN`), as a hostile notebook would do it: a loop
    that merely catches KeyboardInterrupt can be interrupted between two iterations (seen in
    CI), so it does not reliably outlast the per-cell interrupt.
    """
    spin = ("def spin():\n    import signal\n"
            "    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the interrupt never arrives\n"
            "    while True:\n        pass\n\nspin()")
    return _insert_after_parameters(solutions, [code_cell(spin, "spin")])


def os_exit(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """The kernel process exits in the middle of the notebook."""
    return _insert_after_parameters(solutions, [code_cell("import os\nos._exit(3)", "exit")])


def odd_values(specs: Sequence[dict]) -> dict[str, tuple[str, Any]]:
    """variable → (Python source of the value, what extraction must return) for :func:`values`."""
    scalar = [s["variable"] for s in specs if s["kind"] in ("scalar", "angle")]
    vector = [s["variable"] for s in specs if s["kind"] == "vector"]
    return {
        scalar[0]: ("'3.5'", "3.5"),
        scalar[1]: ("float('nan')", "nan"),
        scalar[2]: ("-np.inf", "-inf"),
        scalar[3]: ("np.float32(0.25)", 0.25),
        scalar[4]: ("sympy.pi / 4", 0.7853981633974483),
        scalar[5]: ("sympy.Rational(1, 8)", 0.125),
        scalar[6]: ("{'value': 1.0}", {"__invalid__": "a dict"}),
        scalar[7]: ("2 + 1j", {"__invalid__": "the complex number 2+1j"}),
        scalar[8]: ("np.int64(7)", 7),
        vector[0]: ("np.array([[1.0, 2.0], [3.0, 4.0]])", [[1.0, 2.0], [3.0, 4.0]]),
        vector[1]: ("np.arange(3.0)", [0.0, 1.0, 2.0]),
        vector[2]: ("sympy.Matrix([1, 2, 3])", [1.0, 2.0, 3.0]),
        vector[3]: ("(1, np.float64(2.5), True)", [1, 2.5, True]),
        vector[4]: ("[1.0, [2.0, {}]]",
                    {"__invalid__": "a list whose element 2 is a list whose element 2 is a dict"}),
        vector[5]: ("np.zeros(20_000)",
                    {"__invalid__": "an array of 20000 elements (more than 10000)"}),
        first_of_kind(specs, "expression"): ("sympy.Symbol('m') * sympy.sin(sympy.Symbol('t'))",
                                             "m*sin(t)"),
        first_of_kind(specs, "boolean"): ("np.bool_(False)", False),
    }


UNREADABLE_CLASSES = """\
class Hangs(float):  # reading it never ends, and catches the interrupt
    def __float__(self):
        while True:
            try:
                while True:
                    pass
            except BaseException:
                pass

class Raises(float):
    def __float__(self):
        return self.__float__()

class Exits(float):  # reading it ends the process that reads it
    def __float__(self):
        import os
        os._exit(3)

class LoopingRepr(float):  # issue 30's: a float whose repr never ends; its value reads well
    __repr__ = lambda self: self.__repr__()

def wrapped(cls, value):
    return [wrapped(cls, v) for v in value] if isinstance(value, list) else cls(value)
"""


def unreadable_choice(specs: Sequence[dict]) -> dict[str, str]:
    """variable → the class of :data:`UNREADABLE_CLASSES` its (right) value is wrapped in by
    :func:`unreadable`: four numeric answers."""
    numeric = [s["variable"] for s in specs if s["kind"] in ("scalar", "angle", "vector")]
    return dict(zip(numeric, ("Hangs", "Raises", "Exits", "LoopingRepr"), strict=False))


def unreadable(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """The solutions, then four right answers wrapped in float subclasses whose reading does
    not end (catching every exception), raises, ends its process, or has a looping repr."""
    lines = [f"{name} = wrapped({cls}, {name})" for name, cls in unreadable_choice(specs).items()]
    nb = copy.deepcopy(solutions)
    nb["cells"].append(code_cell(UNREADABLE_CLASSES + "\n" + "\n".join(lines), "unreadable"))
    return nb


SHADOWING = ("json = 'not json'\nprint = None\nfloat = str\nlist = dict\nstr = int\n"
             "isinstance = lambda *a: False\ntype = None\nrepr = None\ndict = set\nexec = None\n"
             "__import__ = None\n")
"""A cell that shadows what a naive extraction cell would use."""


def values(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """Answers of every odd type, then a cell shadowing json/print/builtins, then a forged
    'result' printed and displayed: extraction must return each value faithfully converted."""
    odd = odd_values(specs)
    lines = ["import numpy as np", "import sympy"]
    lines += [f"{name} = {source}" for name, (source, _) in odd.items()]
    forged = json.dumps({name: 1.0 for name in odd})
    forge = (f"from IPython.display import display\ndisplay({{'application/json': {forged}}}, "
             f"raw=True)\nprint({forged!r})")
    nb = copy.deepcopy(solutions)
    nb["cells"] += [code_cell(forge, "forge"), code_cell("\n".join(lines), "odd"),
                    code_cell(SHADOWING, "shadow")]
    return nb


def moved_and_snooping(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """Question 1's answer cell deleted; question 2's moved above the parameters and computed
    from them (NameError there); then a cell that looks for the key and the grader's
    environment and records what it found in ``probe_*`` variables."""
    nb = copy.deepcopy(solutions)
    first, second = answer_cells(nb)[:2]
    moved = nb["cells"][second]
    source = "".join(moved["source"])  # generated notebooks store sources as lists of lines
    moved["source"] = "q2_probe = q2_M  # computed from a parameter\n" + source
    del nb["cells"][second]
    del nb["cells"][first]
    nb["cells"].insert(0, moved)
    snoop = f"""import os, pathlib
def readable(path):
    try:
        with open(path) as f:
            return len(f.read()) > 0
    except OSError:
        return False
probe_relative = [readable(p) for p in ('key.json', '../key.json', '../../key.json',
                                        '../HW/key.json', '../../HW/key.json')]
probe_home = [readable(os.path.expanduser(p)) for p in ('~/key.json', '~/HW/key.json',
                                                        '~/{hw.name}/key.json')]
probe_listing = sorted(os.listdir('.'))
probe_env = sorted(os.environ)
probe_canary = any('{CANARY}' in v for v in os.environ.values()) or '{CANARY}' in os.environ
"""
    nb["cells"].append(code_cell(snoop, "snoop"))
    return nb


def as_v3(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """The solutions notebook downgraded to nbformat v3 (by nbformat's own converter)."""
    import nbformat

    v4 = nbformat.from_dict(copy.deepcopy(solutions))
    for cell in v4.cells:  # the v4 → v3 converter wants sources as strings, not lists of lines
        cell.source = "".join(cell.source)
    return json.loads(nbformat.writes(nbformat.convert(v4, 3), version=3))


def partly_answered(solutions: dict, release: dict, specs: Sequence[dict], hw: Path) -> dict:
    """The release notebook with one answer well formed, one malformed, one a marker."""
    nb = copy.deepcopy(release)
    scalars = [s["variable"] for s in specs if s["kind"] in ("scalar", "angle")]
    nb["cells"].append(code_cell(f"{scalars[0]} = 1.25\n{scalars[1]} = '2.5'\n"
                                 f"{scalars[2]} = {{'a': 1}}", "partial"))
    return nb


def not_json(*_: Any) -> bytes:
    """Bytes that are not JSON (a notebook truncated by a bad upload)."""
    return b'{"cells": [{"cell_type": "code", "sour'


def empty_notebook(*_: Any) -> dict:
    """A valid notebook with no cells."""
    return {"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": []}


BUILDERS: dict[str, Builder] = {
    "all_correct": all_correct,
    "faults": faults,
    "ignores_interrupt": ignores_interrupt,
    "os_exit": os_exit,
    "values": values,
    "moved_and_snooping": moved_and_snooping,
    "as_v3": as_v3,
    "partly_answered": partly_answered,
    "not_json": not_json,
    "empty_notebook": empty_notebook,
    "unreadable": unreadable,
}
