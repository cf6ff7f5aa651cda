"""Reading a student's expression safely, and evaluating it numerically in bounded time.

An *expression* answer is a formula in named symbols (``"I1*beta_dot**2/2"``), graded by
evaluating it at random points. The text comes from a student, so nothing in it may ever run:
sympy's ``parse_expr`` and ``sympify`` call ``eval``. Before anything reaches them the text passes
three gates, each of which rejects with an :class:`ExpressionError` whose message names the
offending piece:

1. **Text**: a ``str`` of at most :data:`MAX_LENGTH` characters, on one line.
2. **Tokens** (Python's :mod:`tokenize`): only decimal numbers that are finite as floats, the
   operators ``+ - * / ** ^ ( ) ,`` (``^`` is read as a power, as on paper), and names that are
   either one of the answer's symbols or in the fixed whitelists :data:`FUNCTIONS` and
   :data:`CONSTANTS`. Attribute dots, brackets, strings, comments, keywords (``lambda``,
   ``import``), dunder names, builtins (``exec``, ``open``) are all unknown tokens.
3. **Syntax tree** (:func:`ast.parse`, which parses and runs nothing): one expression built only
   from numbers, allowed names, ``+ - * / **``, unary ``±`` and calls of whitelisted functions
   with their number of arguments; nested at most :data:`MAX_DEPTH` deep; every sub-expression
   without symbols (``9**9**9``) finite as a float.

Only then does :func:`parse_expression` hand the text to ``parse_expr``, with ``local_dict`` the
allowed symbols (the very :data:`solver.symbolic.SYMBOLS`, assumptions included), a
``global_dict`` holding nothing but the whitelisted sympy names and an empty ``__builtins__``,
no ``auto_symbol``/``lambda`` transformations, and ``evaluate=False`` so that no numeric
sub-expression is ever computed exactly (a power tower of integers would otherwise be).

**Time-safe evaluation.** Grading never evaluates the sympy object: :func:`evaluate_expression`
walks the checked syntax tree with float64 numpy arrays, one vectorised operation per node over
all sample points. Its cost is linear in the length of the text whatever the numbers are:
``I1**I1**I1**I1**1000`` overflows to ``inf`` in microseconds instead of building a huge exact
number. Non-finite results (division by zero, overflow, the square root or logarithm of a
negative number, i.e. a complex value) come back as ``nan``/``inf`` for the caller to judge.

**Sample points** (:func:`sample_points`) are drawn from a generator seeded by a text (the answer's
name and symbols), so grading is deterministic, in physically sensible ranges chosen from the
symbol's name (:data:`SAMPLE_RANGES`): principal moments in (1, 2) — any three such satisfy the
triangle inequality (R4) —, the nutation angle β in (0, π), other angles in (0, 2π),
``u = cos β`` in (−1, 1), anything else (masses, lengths, rates, momenta) in (0.5, 2).
"""

from __future__ import annotations

import ast
import hashlib
import io
import keyword
import math
import re
import tokenize
from collections.abc import Callable, Mapping, Sequence
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import sympy

# sympy's parser, imported on first use (reading numbers needs no sympy); module attributes, so
# that the tests can watch what reaches it.
parse_expr: Callable[..., Any] | None = None
auto_number: Callable[..., Any] | None = None

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "MAX_DEPTH",
    "MAX_LENGTH",
    "SAMPLE_RANGES",
    "ExpressionError",
    "check_symbol_names",
    "evaluate_expression",
    "parse_expression",
    "sample_points",
    "symbol_table",
]

MAX_LENGTH = 2000
"""Longest accepted expression text, in characters."""

MAX_DEPTH = 200
"""Deepest accepted nesting of the syntax tree (operators, calls, unary signs)."""


def _acot(x: NDArray) -> NDArray:
    # sympy's principal branch: acot(x) = atan(1/x), values in (-π/2, π/2].
    return np.arctan(1.0 / x)


def _log(x: NDArray, base: NDArray | None = None) -> NDArray:
    # sympy's log(x, b) is log(x)/log(b).
    return np.log(x) if base is None else np.log(x) / np.log(base)


# name -> (numpy implementation, accepted numbers of arguments); every name here is also one
# that sympy's parse_expr(evaluate=False) passes evaluate=False to (its EvaluateFalseTransformer
# list), so the sympy object is never simplified numerically either.
_FUNCTION_TABLE: dict[str, tuple[Callable[..., NDArray], tuple[int, ...]]] = {
    "sin": (np.sin, (1,)),
    "cos": (np.cos, (1,)),
    "tan": (np.tan, (1,)),
    "cot": (lambda x: 1.0 / np.tan(x), (1,)),
    "sec": (lambda x: 1.0 / np.cos(x), (1,)),
    "csc": (lambda x: 1.0 / np.sin(x), (1,)),
    "asin": (np.arcsin, (1,)),
    "acos": (np.arccos, (1,)),
    "atan": (np.arctan, (1,)),
    "acot": (_acot, (1,)),
    "sinh": (np.sinh, (1,)),
    "cosh": (np.cosh, (1,)),
    "tanh": (np.tanh, (1,)),
    "coth": (lambda x: 1.0 / np.tanh(x), (1,)),
    "asinh": (np.arcsinh, (1,)),
    "acosh": (np.arccosh, (1,)),
    "atanh": (np.arctanh, (1,)),
    "sqrt": (np.sqrt, (1,)),
    "cbrt": (lambda x: np.power(x, 1.0 / 3.0), (1,)),  # principal root: nan below 0, as sympy
    "exp": (np.exp, (1,)),
    "log": (_log, (1, 2)),
    "ln": (np.log, (1,)),
    "Abs": (np.abs, (1,)),
    "sign": (np.sign, (1,)),
}

FUNCTIONS: tuple[str, ...] = tuple(_FUNCTION_TABLE)
"""Function names an expression may call (sympy's names; ``ln`` is ``log``)."""

_CONSTANT_TABLE = {"pi": math.pi, "E": math.e}
CONSTANTS: tuple[str, ...] = tuple(_CONSTANT_TABLE)
"""Named constants an expression may use: ``pi`` and ``E`` (Euler's number)."""

_OPERATORS = frozenset({"+", "-", "*", "/", "**", "^", "(", ")", ","})
_NUMBER = re.compile(r"(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_BINARY = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.divide,
    ast.Pow: np.power,
}
_UNARY = {ast.UAdd: np.positive, ast.USub: np.negative}

SAMPLE_RANGES: tuple[tuple[str, tuple[float, float]], ...] = (
    (r"I\d*", (1.0, 2.0)),  # principal moments: any three in (1, 2) obey I_i + I_j > I_k (R4)
    (r"(beta|theta)(_?\d+)?", (0.2, math.pi - 0.2)),  # nutation angle, in (0, π)
    (r"(alpha|gamma|phi|psi)(_?\d+)?", (0.2, 2 * math.pi - 0.2)),  # azimuths and spin angles
    (r"u(_?\d+)?", (-0.9, 0.9)),  # u = cos β (R17)
    (r".*", (0.5, 2.0)),  # masses, lengths, rates, momenta, energies: positive, order one
)
"""(regular expression for the whole symbol name, (low, high)) — the first match applies."""


class ExpressionError(ValueError):
    """The text is not an acceptable expression; the message is written for the student."""


def _short(text: str, limit: int = 40) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def check_symbol_names(symbols: Sequence[str]) -> tuple[str, ...]:
    """Return ``symbols`` as a tuple after checking that each can be an expression's symbol.

    A symbol name must be a Python identifier, not a keyword, not start with ``_`` (no dunder
    names ever reach ``eval``), and not clash with :data:`FUNCTIONS` or :data:`CONSTANTS`.

    Raises
    ------
    ValueError
        Naming the bad symbol (a template bug, not a student's).
    """
    names = tuple(symbols)
    for name in names:
        if not (isinstance(name, str) and name.isidentifier()) or keyword.iskeyword(name):
            raise ValueError(f"symbol {name!r} is not a Python identifier")
        if name.startswith("_") or name in _FUNCTION_TABLE or name in _CONSTANT_TABLE:
            raise ValueError(f"symbol {name!r} is reserved (underscore, function or constant)")
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate symbols in {names}")
    return names


def symbol_table(symbols: Sequence[str]) -> dict[str, sympy.Symbol]:
    """The sympy symbols for ``symbols``: those of :data:`solver.symbolic.SYMBOLS` when it names
    them (same assumptions, so expressions compare equal to the solver's), else real symbols."""
    import sympy  # here, not at the top: reading numbers (eulertop check) needs no sympy

    try:
        from solver.symbolic import SYMBOLS
    except ImportError:  # the solver's derivations are optional for reading expressions
        SYMBOLS = {}
    return {name: SYMBOLS.get(name) or sympy.Symbol(name, real=True) for name in symbols}


def _unknown_name(name: str, symbols: tuple[str, ...]) -> ExpressionError:
    if keyword.iskeyword(name) or name.startswith("_"):
        return ExpressionError(f"'{_short(name)}' is not allowed in an expression")
    allowed = ", ".join(symbols) if symbols else "none"
    return ExpressionError(
        f"unknown symbol '{_short(name)}' — allowed symbols: {allowed} "
        "(and functions such as sin, cos, sqrt, exp, log; constants pi, E)"
    )


def _check_text(text: object) -> str:
    if not isinstance(text, str):
        raise ExpressionError(f"expected an expression as text, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression too long ({len(text)} characters; at most {MAX_LENGTH})")
    text = text.strip()
    if not text:
        raise ExpressionError("empty expression")
    if any(c in text for c in "\r\n\f\v\x00"):
        raise ExpressionError("write the expression on a single line")
    return text


def _check_tokens(text: str, symbols: tuple[str, ...]) -> None:
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError) as err:
        raise ExpressionError(f"cannot read the expression: {err.args[0]}") from None
    for tok in tokens:
        if tok.type in (tokenize.NEWLINE, tokenize.NL, tokenize.ENDMARKER):
            continue
        value = tok.string
        if tok.type == tokenize.NUMBER:
            _check_number(value)
        elif tok.type == tokenize.OP and value in _OPERATORS:
            continue
        elif tok.type == tokenize.NAME:
            if value not in symbols and value not in _FUNCTION_TABLE and value not in CONSTANTS:
                raise _unknown_name(value, symbols)
        else:
            raise ExpressionError(
                f"'{_short(value)}' is not allowed in an expression (use numbers, symbols, "
                "+ - * / ** ( ) and functions such as sin, sqrt)"
            )


def _check_number(value: str) -> None:
    if not _NUMBER.fullmatch(value):
        raise ExpressionError(f"'{_short(value)}' is not a plain decimal number")
    if not math.isfinite(float(value)):
        raise ExpressionError(f"the number '{_short(value)}' is too large")


def _depth(node: ast.AST) -> int:
    # Iterative, so that a pathological tree cannot exhaust the recursion limit here.
    deepest, stack = 0, [(node, 1)]
    while stack:
        current, level = stack.pop()
        deepest = max(deepest, level)
        stack.extend((child, level + 1) for child in ast.iter_child_nodes(current))
    return deepest


def _check_node(node: ast.AST, symbols: tuple[str, ...]) -> None:
    if isinstance(node, ast.Constant):
        if type(node.value) not in (int, float):
            raise ExpressionError(f"'{node.value!r}' is not a real number")
    elif isinstance(node, ast.Name):
        if node.id not in symbols and node.id not in _CONSTANT_TABLE:
            if node.id in _FUNCTION_TABLE:
                raise ExpressionError(f"function '{node.id}' used without an argument")
            raise _unknown_name(node.id, symbols)
    elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        _check_node(node.left, symbols)
        _check_node(node.right, symbols)
    elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        _check_node(node.operand, symbols)
    elif isinstance(node, ast.Call):
        _check_call(node, symbols)
    elif isinstance(node, ast.Tuple):
        raise ExpressionError("several expressions separated by commas; give a single one")
    else:
        raise ExpressionError(f"'{type(node).__name__}' is not allowed in an expression")


def _check_call(node: ast.Call, symbols: tuple[str, ...]) -> None:
    if not isinstance(node.func, ast.Name) or node.func.id not in _FUNCTION_TABLE:
        what = node.func.id if isinstance(node.func, ast.Name) else "this"
        raise ExpressionError(f"'{_short(what)}' cannot be called; it is not a function")
    name = node.func.id
    arities = _FUNCTION_TABLE[name][1]
    if node.keywords or len(node.args) not in arities:
        count = " or ".join(map(str, arities))
        raise ExpressionError(f"{name} takes {count} argument(s)")
    for arg in node.args:
        if isinstance(arg, ast.Starred):
            raise ExpressionError(f"{name} takes plain arguments")
        _check_node(arg, symbols)


def _check_constants(node: ast.AST, symbols: tuple[str, ...]) -> NDArray | None:
    """The float value of ``node`` if it holds no symbol, else None; raise if such a constant
    part is not finite. One post-order pass: each node is computed once, from its operands."""
    if isinstance(node, ast.Name) and node.id in symbols:
        return None
    if isinstance(node, ast.Constant | ast.Name):
        return _leaf(node, {})
    values = [_check_constants(operand, symbols) for operand in _operands(node)]
    if any(v is None for v in values):
        return None
    with np.errstate(all="ignore"):
        value = _apply(node, values)
    if not np.all(np.isfinite(value)):
        raise ExpressionError(
            f"the constant '{_short(ast.unparse(node))}' is not a finite number "
            "(too large, a division by zero or a complex value)"
        )
    return value


@lru_cache(maxsize=4096)
def _checked_tree(text: str, symbols: tuple[str, ...]) -> ast.Expression:
    """Gates 2 and 3 of the module docstring; the tree is cached, never mutated."""
    _check_tokens(text, symbols)
    try:
        tree = ast.parse(text.replace("^", "**"), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        raise ExpressionError(
            "not a valid expression: check the operators and parentheses "
            "(write products with *, powers with **)"
        ) from None
    if _depth(tree) > MAX_DEPTH:
        raise ExpressionError(f"expression nested too deeply (more than {MAX_DEPTH} levels)")
    _check_node(tree.body, symbols)
    _check_constants(tree.body, symbols)
    return tree


def _tree(text: object, symbols: Sequence[str]) -> tuple[str, ast.Expression]:
    clean = _check_text(text)
    return clean, _checked_tree(clean, tuple(symbols))


def parse_expression(text: str, symbols: Sequence[str]) -> sympy.Expr:
    """Parse a student's expression into sympy, without ever executing the student's text.

    Parameters
    ----------
    text : str
        The expression, Python syntax (``^`` accepted for powers), e.g. ``"I1*sin(beta)**2"``.
    symbols : sequence of str
        The names it may use (the answer's ``symbols``); see :func:`check_symbol_names`.

    Returns
    -------
    sympy.Expr
        Unevaluated (``evaluate=False``), in the symbols of :func:`symbol_table`.

    Raises
    ------
    ExpressionError
        With a message for the student naming what is wrong (see the module docstring).

    Examples
    --------
    >>> parse_expression("I1*beta^2", ["I1", "beta"])
    I1*beta**2
    >>> parse_expression("theta + 1", ["beta"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    problems.expressions.ExpressionError: unknown symbol 'theta' — allowed symbols: beta (...)
    """
    symbols = check_symbol_names(symbols)
    clean, _ = _tree(text, symbols)  # gates 1–3: nothing below runs on unchecked text
    return _sympy_expression(clean.replace("^", "**"), symbols)


@lru_cache(maxsize=1024)
def _sympy_expression(text: str, symbols: tuple[str, ...]) -> sympy.Expr:
    global parse_expr, auto_number
    import sympy

    if parse_expr is None:  # each on its own: a test may have replaced the other
        from sympy.parsing.sympy_parser import parse_expr
    if auto_number is None:
        from sympy.parsing.sympy_parser import auto_number

    global_dict: dict[str, object] = {"__builtins__": {}}
    for name in ("Integer", "Float", "Rational", "Add", "Mul", "Pow", *FUNCTIONS, *CONSTANTS):
        global_dict[name] = getattr(sympy, name)
    try:
        expr = parse_expr(
            text,
            local_dict=symbol_table(symbols),
            global_dict=global_dict,
            transformations=(auto_number,),
            evaluate=False,
        )
    except Exception as err:  # anything sympy refuses is the student's format error
        raise ExpressionError(f"sympy cannot read the expression ({type(err).__name__})") from None
    if not isinstance(expr, sympy.Expr):
        raise ExpressionError("not a single mathematical expression")
    return expr


# Only node types admitted by _check_node reach the three functions below.
def _operands(node: ast.AST) -> list[ast.AST]:
    if isinstance(node, ast.BinOp):
        return [node.left, node.right]
    if isinstance(node, ast.UnaryOp):
        return [node.operand]
    return list(node.args) if isinstance(node, ast.Call) else []


def _leaf(node: ast.AST, points: Mapping[str, NDArray]) -> NDArray:
    if isinstance(node, ast.Constant):
        return np.float64(node.value)
    return points[node.id] if node.id in points else np.float64(_CONSTANT_TABLE[node.id])


def _apply(node: ast.AST, values: list[NDArray]) -> NDArray:
    """The operation of ``node`` applied to its operands' values."""
    if isinstance(node, ast.BinOp):
        return _BINARY[type(node.op)](*values)
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](*values)
    return _FUNCTION_TABLE[node.func.id][0](*values)


def _evaluate_node(node: ast.AST, points: Mapping[str, NDArray]) -> NDArray:
    if isinstance(node, ast.Constant | ast.Name):
        return _leaf(node, points)
    return _apply(node, [_evaluate_node(operand, points) for operand in _operands(node)])


def evaluate_expression(
    text: str, symbols: Sequence[str], points: Mapping[str, NDArray]
) -> NDArray[np.float64]:
    """Evaluate an expression in float64 at sample points, in time linear in its length.

    Parameters
    ----------
    text : str
        The expression (checked exactly as in :func:`parse_expression`).
    symbols : sequence of str
        The names it may use.
    points : mapping of str to array
        A value array for every symbol, all of one shape ``(n,)``.

    Returns
    -------
    ndarray, shape (n,)
        The values; ``nan`` or ``±inf`` where the expression is undefined, complex or overflows
        (no warning is raised — the caller judges non-finite values).

    Raises
    ------
    ExpressionError
        The text is not an acceptable expression.

    Examples
    --------
    >>> evaluate_expression("sin(b)^2 + cos(b)**2", ["b"], {"b": np.array([0.3, 1.2])})
    array([1., 1.])
    """
    symbols = check_symbol_names(symbols)
    _, tree = _tree(text, symbols)
    shape = np.broadcast_shapes(*(np.shape(points[s]) for s in symbols)) if symbols else ()
    with np.errstate(all="ignore"):
        try:
            values = _evaluate_node(tree.body, {s: np.asarray(points[s], float) for s in symbols})
        except RecursionError:  # MAX_DEPTH keeps well below the limit; a deep caller might not
            raise ExpressionError("expression nested too deeply to evaluate") from None
        return np.broadcast_to(np.asarray(values, dtype=float), shape).copy()


def _sample_range(name: str) -> tuple[float, float]:
    return next(bounds for pattern, bounds in SAMPLE_RANGES if re.fullmatch(pattern, name))


def sample_points(symbols: Sequence[str], seed_text: str, n: int) -> dict[str, NDArray]:
    """``n`` random values of each symbol, reproducible from ``seed_text``.

    Each symbol is drawn uniformly in its range of :data:`SAMPLE_RANGES`; the generator is seeded
    from the SHA-256 of ``seed_text`` and the symbols' names, so the points are the same on every
    run and platform, whatever ``PYTHONHASHSEED`` is.

    Returns
    -------
    dict of str to ndarray, shape (n,)
        Read-only arrays (they may be shared through caches).

    Examples
    --------
    >>> pts = sample_points(["I1", "beta"], "q1", 4)
    >>> bool(np.all((1 < pts["I1"]) & (pts["I1"] < 2) & (0 < pts["beta"]) & (pts["beta"] < np.pi)))
    True
    """
    symbols = tuple(symbols)
    digest = hashlib.sha256("\x1f".join((seed_text, *symbols)).encode()).digest()
    rng = np.random.default_rng(int.from_bytes(digest[:8], "little"))
    points = {}
    for name in symbols:
        low, high = _sample_range(name)
        values = rng.uniform(low, high, size=n)
        values.flags.writeable = False
        points[name] = values
    return points
