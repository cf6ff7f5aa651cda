"""Extract the declared answer variables from the student's kernel as plain JSON.

Stage *extract* of the pipeline (``grader/API.md``). After the student's last cell, the grader
sends one more execute request that the student never saw: code that converts the declared
variables to plain JSON, and a ``user_expressions`` entry that returns the JSON text in the
kernel's *execute reply* (the shell channel), not in any printed or displayed output.

Conversion (in the kernel, :func:`kernel_extract`)
    ``None`` (unset or still None) → ``None``; ``bool`` and numpy/sympy booleans → ``bool``;
    integers → ``int`` (beyond 10**15 → ``float``); real numbers (Python, numpy, sympy numbers
    such as ``pi`` or ``Rational(1, 3)``, ``fractions``, mpmath) → ``float``, NaN and
    infinities kept as such (the comparison reports them); strings → ``str``; lists, tuples,
    numpy arrays and sympy matrices → lists (row or column matrices flat, as
    :mod:`problems.answers` reads them; shapes kept, the comparison judges them); sympy
    expressions with symbols → their ``str``. Anything else — a dict, a complex number, a
    function, a sympy equation, a too long string, a too large array — becomes the *marker*
    ``{"__invalid__": "<what it is>"}``, which the comparison reports as invalid
    (:func:`invalid_reason`).

One answer at a time (issue 30)
    Reading a value can run the student's code (a ``__float__``, a list subclass, a metaclass),
    which may never end. A value made only of Python's and numpy's own numbers, strings, lists
    and arrays is read in the kernel; the others are read in a child process the kernel forks,
    one line per answer, each given :data:`ANSWER_SECONDS`; one that does not come in time (or
    whose reading raised, or ended the child) is marked ``could not be read: …``
    (:data:`UNREADABLE`), the child is killed, and the rest are read in a new one. So one such
    answer is invalid alone, named, and every other answer is graded.

Trust
    The student's code runs in the same kernel before the extraction and may have replaced
    anything there: names in its namespace (``json = 3``, ``print = None``, ``float = str``),
    builtins, modules, IPython's formatters. So:

    * the extraction code looks up *no* name in the student's namespace: it imports
      ``builtins`` under a private, per-run name (the ``import`` statement needs no global
      name) and runs the converter with ``exec`` in a fresh namespace whose builtins are the
      module itself — a student who merely shadows ``json``, ``print``, ``float`` or
      ``list`` changes nothing;
    * the result travels in the execute reply of the grader's own request, stored under a
      variable named with a **nonce drawn at extraction time** (``secrets.token_hex``), so
      nothing the notebook printed or stored earlier can be taken for it;
    * whatever comes back is **untrusted** (:func:`parse_answers`): only the declared names
      are kept; only plain JSON of bounded size and depth, or a well-formed marker, is
      accepted per answer; anything else is marked invalid; a reply that cannot be read at all
      gives no answers. Nothing here can raise on a hostile reply.

    A student who deliberately patches the machinery the extraction does rely on (the
    ``builtins`` module, ``sys.modules["json"]``, IPython's display formatter, or a thread
    that rewrites the result) can make it report other values — but only for their *own*
    declared variables, which they could have set to those values directly. The kernel holds
    nothing of the key (the grader sends variable *names* only and compares in its own
    process), so forging gains nothing; breaking the extraction loses the student their own
    answers, never anyone else's.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import ast
import functools
import inspect
import keyword
import secrets
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

INVALID = "__invalid__"
"""Key of the marker dict that stands for a value the kernel could not turn into plain JSON."""

MAX_ELEMENTS = 10_000
"""Numbers, strings and booleans one answer may hold in all (a 100×100 array)."""

MAX_STRING = 10_000
"""Characters one string may hold (expressions are short)."""

MAX_DEPTH = 4
"""Nesting of lists in one answer (a 3×3 matrix is depth 2)."""

MAX_REPLY_CHARS = 16_000_000
"""Characters of the extraction reply read at all; more and no answer is read."""

MAX_REASON = 200
"""Characters of a marker's reason kept."""

ANSWER_SECONDS = 2.0
"""Seconds the kernel gives the reading of one answer (its conversion to plain JSON: a
``__float__`` or ``__repr__`` of the student's runs then); past them that answer is marked
"could not be read" and the next is read."""

UNREADABLE = "could not be read"
"""How the reason of a marker begins when the value itself could not be read (its reading
raised, did not end, or ended its process), as opposed to a value of the wrong kind."""

EXTRACTION_FAILED = "the notebook ran, but its answers could not be read"


# --------------------------------------------------------------------------------------------
# Kernel side: these two functions are shipped to the kernel as source (inspect.getsource) and
# run there in a fresh namespace; they use only their arguments, builtins and fresh imports.


def kernel_extract(namespace, names, limits):
    """JSON text {name: plain value or marker} for ``names`` read from ``namespace``.

    ``limits`` is ``(max_elements, max_string, max_depth, seconds_per_answer, max_line)``.
    Runs in the student's kernel. A value made only of Python's and numpy's own numbers,
    strings and lists (:func:`kernel_inert`: reading it runs none of the student's code) is
    read here; every other one on its own (:func:`kernel_read`) in a child process of the
    kernel (:func:`kernel_read_forked`), so that one whose reading does not end is stopped
    there and marked, and the next is read in a new child. Where no child can be started, the
    others are read here too.
    """
    import json
    import sys

    np = sys.modules.get("numpy")
    scalars = {id(t) for t in np.sctypeDict.values()} if np is not None else set()
    out = {}
    for name in names:
        if kernel_inert(namespace.get(name), limits, [limits[0]], 0, scalars):
            out[name] = kernel_read(namespace, name, limits)
    pending = [name for name in names if name not in out]
    while pending:
        read = kernel_read_forked(namespace, pending, limits)
        if read is None:  # no process to spare: read here, without a time bound
            out.update((name, kernel_read(namespace, name, limits)) for name in pending)
            break
        out.update(read)
        pending = [name for name in pending if name not in out]
    return json.dumps({name: out[name] for name in names}, allow_nan=True)


def kernel_inert(x, limits, budget, depth, scalars):
    """Is ``x`` made only of None, Python's own bool, int, float and str, exact lists and
    tuples of them, and numpy's own numeric arrays and scalars (``scalars``: their ids) — so
    that reading it runs no code of the student's? Types are told apart by identity alone:
    comparing or hashing a type of the student's could run its metaclass's code."""
    import sys

    kind = type(x)
    if x is None or kind is bool or kind is int or kind is float or kind is str \
            or id(kind) in scalars:
        return True
    if kind is list or kind is tuple:
        budget[0] -= len(x)
        return depth < limits[2] and budget[0] >= 0 and all(
            kernel_inert(item, limits, budget, depth + 1, scalars) for item in x)
    np = sys.modules.get("numpy")
    return np is not None and kind is np.ndarray and x.dtype.kind in "biuf" \
        and x.size <= limits[0]


def kernel_read(namespace, name, limits):
    """One answer as plain JSON, or a marker saying why it could not be read."""
    try:
        return kernel_plain(namespace.get(name), limits, [limits[0]], 0)
    except BaseException as err:  # a student's object that misbehaves when read
        return {"__invalid__": f"could not be read: reading it raised {type(err).__name__}"}


def kernel_read_forked(namespace, names, limits):
    """``{name: value}`` for ``names``, read in order in a child process — all of them, or up
    to the first that gave no value within ``limits[3]`` seconds or ended the child (marked
    so); None when no child process can be started. The child is killed and reaped."""
    import os
    import signal
    import warnings

    try:
        read_end, write_end = os.pipe()
    except OSError:
        return None
    try:
        with warnings.catch_warnings():  # fork() of a process with threads (Python ≥ 3.12)
            warnings.simplefilter("ignore", DeprecationWarning)
            pid = os.fork()
    except OSError:
        os.close(read_end)
        os.close(write_end)
        return None
    if pid == 0:  # the child: one line of JSON per answer, then gone, whatever happens
        try:
            os.close(read_end)
            kernel_send(write_end, namespace, names, limits)
        finally:
            os._exit(0)
    os.close(write_end)
    try:
        return kernel_collect(read_end, names, limits)
    finally:
        os.close(read_end)
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
        os.waitpid(pid, 0)


def kernel_send(fd, namespace, names, limits):
    """In the child: each answer of ``names`` as one line of JSON (ASCII) written to ``fd``."""
    import json
    import os

    for name in names:
        data = (json.dumps(kernel_read(namespace, name, limits), allow_nan=True) + "\n").encode()
        while data:
            data = data[os.write(fd, data):]


def kernel_collect(fd, names, limits):
    """The child's lines read from ``fd``, one per name, each within ``limits[3]`` seconds of
    the one before: ``{name: value}`` up to the first that did not come (then a marker)."""
    import json

    got, pending = {}, [b""]
    for name in names:
        line = kernel_line(fd, pending, limits)
        if isinstance(line, str):  # why no line came
            got[name] = {"__invalid__": f"could not be read: {line}"}
            return got
        try:
            got[name] = json.loads(line)
        except (ValueError, RecursionError):  # the child ran the student's code: untrusted
            got[name] = {"__invalid__": "could not be read"}
            return got
    return got


def kernel_line(fd, pending, limits):
    """The next line from ``fd`` (``pending[0]``: what was read past the last one), as bytes;
    or, as a str, why none came: not within ``limits[3]`` s, the child ended, or it is longer
    than ``limits[4]`` bytes."""
    import os
    import select
    import time

    deadline = time.monotonic() + limits[3]
    poll = select.poll()  # select() cannot watch a descriptor numbered 1024 or more
    poll.register(fd, select.POLLIN)
    while b"\n" not in pending[0]:
        left = deadline - time.monotonic()
        if left <= 0 or not poll.poll(left * 1000):
            return (f"its value did not convert within {limits[3]:g} s (a loop that does not "
                    "end?)")
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return "reading it ended the process"
        if len(pending[0]) + len(chunk) > limits[4]:
            return "it is too large"
        pending[0] += chunk
    line, pending[0] = pending[0].split(b"\n", 1)
    return line


def kernel_plain(x, limits, budget, depth):
    """``x`` as plain JSON (None, bool, int, float, str, list) or an ``__invalid__`` marker."""
    import numbers
    import sys

    np, sp = sys.modules.get("numpy"), sys.modules.get("sympy")

    def invalid(reason):
        return {"__invalid__": str(reason)[:200]}

    if x is None or isinstance(x, bool):
        return x
    budget[0] -= 1
    if budget[0] < 0:
        return invalid(f"more than {limits[0]} numbers")
    if np is not None and isinstance(x, np.ndarray):
        if x.size > limits[0]:
            return invalid(f"an array of {x.size} elements (more than {limits[0]})")
        if x.dtype.kind == "c":
            return invalid("an array of complex numbers")
        budget[0] += 1
        return kernel_plain(x.tolist(), limits, budget, depth)
    if np is not None and isinstance(x, np.generic):
        budget[0] += 1
        return kernel_plain(x.item(), limits, budget, depth)
    if sp is not None and isinstance(x, sp.MatrixBase):
        budget[0] += 1
        flat = 1 in x.shape  # a row or column vector reads as a flat list
        return kernel_plain(list(x) if flat else x.tolist(), limits, budget, depth)
    if sp is not None and isinstance(x, sp.logic.boolalg.BooleanAtom):
        return bool(x)
    if sp is not None and isinstance(x, sp.Basic):
        if not isinstance(x, sp.Expr):
            return invalid(f"the sympy object {type(x).__name__}, not an expression")
        if x.is_number:
            try:
                return float(x)
            except (TypeError, ValueError):
                return invalid(f"the complex number {str(x)[:40]}")
        text = str(x)
        return text if len(text) <= limits[1] else invalid("a very long sympy expression")
    if isinstance(x, str):
        return x if len(x) <= limits[1] else invalid(f"a string of {len(x)} characters")
    if isinstance(x, numbers.Integral):
        if abs(int(x)) < 10**15:
            return int(x)
        try:
            return float(x)
        except OverflowError:
            return invalid("an integer too large for a float")
    if isinstance(x, numbers.Real):
        return float(x)
    if isinstance(x, numbers.Complex):
        return invalid(f"the complex number {complex(x):.4g}")
    if isinstance(x, (list, tuple)):
        if depth >= limits[2]:
            return invalid(f"a list nested more than {limits[2]} deep")
        budget[0] += 1
        items = []
        for i, item in enumerate(x, start=1):
            plain = kernel_plain(item, limits, budget, depth + 1)
            if isinstance(plain, dict):
                return invalid(f"a list whose element {i} is {plain['__invalid__']}")
            items.append(plain)
        return items
    kind = {dict: "a dict", set: "a set", frozenset: "a set", bytes: "bytes"}.get(type(x))
    if kind is None and callable(x):
        kind = "a function (call it to get the value)"
    return invalid(kind or f"a value of type {type(x).__name__}")


# --------------------------------------------------------------------------------------------
# Grader side


class ExtractionRequest(NamedTuple):
    """What the grader sends to the kernel: code, and the user expression returning the text."""

    code: str
    user_expressions: dict[str, str]


@functools.cache
def _kernel_program() -> str:
    """The source of :func:`kernel_plain` and :func:`kernel_extract` (read once: reading
    source is a few milliseconds, per submission otherwise)."""
    return "\n\n".join(inspect.getsource(f) for f in (
        kernel_plain, kernel_inert, kernel_read, kernel_send, kernel_line, kernel_collect,
        kernel_read_forked, kernel_extract))


def extraction_request(variables: Sequence[str], nonce: str | None = None) -> ExtractionRequest:
    """The extraction cell for ``variables`` (Python identifiers), tagged with a fresh nonce.

    Raises
    ------
    ValueError
        A variable name that is not a Python identifier (names are written into the code).
    """
    bad = [v for v in variables if not _identifier(v)]
    if bad:
        raise ValueError(f"answer variable names must be Python identifiers, got {bad!r}")
    nonce = nonce or secrets.token_hex(16)
    result = f"_eulertop_answers_{nonce}"
    program = _kernel_program()
    limits = (MAX_ELEMENTS, MAX_STRING, MAX_DEPTH, ANSWER_SECONDS, MAX_REPLY_CHARS)
    program += (f"\n\nnamespace[{result!r}] = kernel_extract(namespace, {tuple(variables)!r}, "
                f"{limits!r})\n")
    builtins = f"_eulertop_builtins_{nonce}"
    code = (f"import builtins as {builtins}\n"
            f"{builtins}.exec({program!r}, {{'__builtins__': {builtins}, "
            f"'__name__': '_eulertop_extract', 'namespace': {builtins}.globals()}})\n"
            f"del {builtins}\n")
    return ExtractionRequest(code, {"answers": result})


def parse_answers(
    reply: Mapping[str, Any], variables: Sequence[str]
) -> tuple[dict[str, Any], str | None]:
    """Read the untrusted execute reply of the extraction request.

    Parameters
    ----------
    reply : mapping
        The ``content`` of the kernel's ``execute_reply``.
    variables : sequence of str
        The declared answer variables; nothing else is kept.

    Returns
    -------
    answers : dict
        Every declared name → plain JSON value (``None`` if unset) or an ``__invalid__``
        marker; empty when nothing could be read.
    problem : str or None
        Why nothing could be read, for a person; None on success.
    """
    try:
        text = _reply_text(reply)
        document = _loads(text)
    except _Unreadable as err:
        return {}, f"{EXTRACTION_FAILED}: {err}"
    return {name: _checked(document.get(name)) for name in variables}, None


def live_answers(namespace: Mapping[str, Any], variables: Sequence[str]) -> dict[str, Any]:
    """The answers of ``variables`` read from ``namespace`` in *this* process, exactly as the
    grader reads them in its kernel (:func:`kernel_extract` under the same limits, then the
    same checks as :func:`parse_answers`): what ``eulertop_check.check()`` reads in a
    student's live kernel (issue 33)."""
    limits = (MAX_ELEMENTS, MAX_STRING, MAX_DEPTH, ANSWER_SECONDS, MAX_REPLY_CHARS)
    names = tuple(v for v in variables if _identifier(v))
    document = _loads(kernel_extract(namespace, names, limits))
    return {name: _checked(document.get(name)) for name in names}


def invalid_reason(value: Any) -> str | None:
    """The reason in an ``__invalid__`` marker (``"a dict"``), or None if ``value`` is no marker.

    Examples
    --------
    >>> invalid_reason({"__invalid__": "a dict"})
    'a dict'
    >>> invalid_reason([1.0, 2.0]) is None
    True
    """
    if isinstance(value, dict) and set(value) == {INVALID} and isinstance(value[INVALID], str):
        return value[INVALID]
    return None


class _Unreadable(Exception):
    """The extraction reply cannot be read; the message says why."""


def _identifier(name: object) -> bool:
    return isinstance(name, str) and name.isidentifier() and not keyword.iskeyword(name)


def _reply_text(reply: Mapping[str, Any]) -> str:
    if not isinstance(reply, Mapping):
        raise _Unreadable("the kernel's reply is malformed")
    if reply.get("status") != "ok":
        ename = _short(reply.get("ename", "an error"))
        evalue = _short(reply.get("evalue", ""))
        raise _Unreadable(f"the grader's extraction raised {ename}: {evalue} (did the notebook "
                          "replace Python's builtins or modules?)")
    expressions = reply.get("user_expressions")
    entry = expressions.get("answers") if isinstance(expressions, Mapping) else None
    data = entry.get("data") if isinstance(entry, Mapping) else None
    plain = data.get("text/plain") if isinstance(data, Mapping) else None
    if not isinstance(plain, str):
        raise _Unreadable("the kernel returned no answers (was the namespace tampered with?)")
    if len(plain) > MAX_REPLY_CHARS:
        raise _Unreadable("the kernel's reply is too large")
    try:
        text = ast.literal_eval(plain)  # the repr of a str; literal_eval runs no code
    except (ValueError, SyntaxError, MemoryError, RecursionError, TypeError):
        text = None
    if not isinstance(text, str):
        raise _Unreadable("the kernel's reply is not the grader's answer text")
    return text


def _loads(text: str) -> dict:
    import json

    try:
        document = json.loads(text)
    except (ValueError, RecursionError) as err:
        raise _Unreadable(f"the kernel's reply is not JSON ({type(err).__name__})") from None
    if not isinstance(document, dict):
        raise _Unreadable("the kernel's reply is not a JSON object")
    return document


def _checked(value: Any) -> Any:
    """``value`` if it is plain JSON within the limits (or a marker), else a marker."""
    try:
        if _plain_json(value, MAX_DEPTH, [MAX_ELEMENTS]):
            return value
    except RecursionError:
        pass
    reason = invalid_reason(value)
    if reason is not None:
        return {INVALID: reason[:MAX_REASON]}
    return {INVALID: "a value the grader could not read"}


def _plain_json(value: Any, depth: int, budget: list[int]) -> bool:
    if value is None or isinstance(value, bool):
        return True
    budget[0] -= 1
    if budget[0] < 0:
        return False
    if isinstance(value, int):
        return abs(value) < 10**15
    if isinstance(value, float):
        return True  # NaN and infinities too: the comparison reports them
    if isinstance(value, str):
        return len(value) <= MAX_STRING
    if isinstance(value, list):
        return depth > 0 and all(_plain_json(v, depth - 1, budget) for v in value)
    return False


def _short(text: object, limit: int = 120) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 1] + "…"

