"""`eulertop solve`: answer one rigid-body scene for a person, or a JSON-lines batch of them.

One case::

    eulertop solve heavy-top --I1 0.02 --I3 0.008 --Mgl 0.3 --beta0 0.5 \\
        --alpha_dot0 0 --beta_dot0 0 --gamma_dot0 150 [--json]

Many cases, one JSON object per line in and out, same order, all fields at the top level::

    eulertop solve --batch CASES.jsonl        # or - for standard input

Each batch line names its scene in ``"scene"`` (or the scene given on the command line applies to
every line) and may carry an ``"id"``, echoed back. Every input line gets exactly one output
line, in order — blank lines, lines that are not UTF-8 or not JSON included: a bad line is
answered with ``{"error": "..."}`` naming the line or the field, and the other lines are still
answered. Nothing in a line can stop the batch: an unexpected failure of the solver on one line
becomes that line's ``{"error": "internal error …"}``. A non-finite number is never printed as an
answer: quantities that do not exist for a case are ``null``, and the heavy top's
``"undefined"`` says why. Exit status: ``EXIT_STATUS``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, TextIO

import numpy as np

# Field kinds accepted on input: a number, a 3-vector, a number or a list of numbers, a list of
# numbers, a list of 3-vectors, or a string.
NUMBER, VECTOR3, NUMBER_OR_LIST, NUMBERS, VECTORS3, STRING = (
    "number", "3-vector", "number or list of numbers", "list of numbers", "list of 3-vectors",
    "string",
)


@dataclass(frozen=True)
class Scene:
    """One `eulertop solve` scene: its input fields, the solver call, and a built-in example."""

    name: str
    summary: str
    required: dict[str, str]
    optional: dict[str, str]
    solve: Callable[..., dict[str, Any]]
    example: dict[str, Any]
    units: dict[str, str] = field(default_factory=dict)


def _solve_heavy_top(**kw: Any) -> dict[str, Any]:
    from solver.heavy_top import solve_heavy_top

    return solve_heavy_top(**kw)


def _solve_free_top(**kw: Any) -> dict[str, Any]:
    from solver.asymmetric_top import solve_free_top

    out = solve_free_top(**kw)
    # R10: the period is infinite on the separatrix (and undefined for a steady spin): no finite
    # period exists, which the output contract writes as null.
    if out.get("period") is not None and not math.isfinite(float(out["period"])):
        out["period"] = None
    return out


def _solve_euler_angles(**kw: Any) -> dict[str, Any]:
    from solver.euler_angles import solve_euler_angles

    moments = [kw.get(k) for k in ("I1", "I2", "I3")]
    if any(m is not None for m in moments) and not all(m is not None for m in moments):
        missing = next(k for k, m in zip(("I1", "I2", "I3"), moments, strict=True) if m is None)
        raise _FieldError(missing, "give all three moments I1, I2, I3 (for T) or none")
    return solve_euler_angles(**kw)


def _solve_inertia(**kw: Any) -> dict[str, Any]:
    from solver.inertia import solve_inertia

    has_points = "masses" in kw or "positions" in kw
    has_shape = "shape" in kw
    if has_points and has_shape:
        raise _FieldError("shape", "give either masses and positions, or a shape — not both")
    if has_points:
        for name in ("masses", "positions"):
            if name not in kw:
                raise _FieldError(name, "missing (point masses need both masses and positions)")
    elif not has_shape:
        raise _FieldError("masses", "missing: give masses and positions, or a shape and its mass")
    return solve_inertia(**kw)


SCENES: dict[str, Scene] = {
    s.name: s
    for s in (
        Scene(
            "heavy-top",
            "heavy symmetric top on a fixed tip (R14–R21)",
            {k: NUMBER for k in
             ("I1", "I3", "Mgl", "beta0", "alpha_dot0", "beta_dot0", "gamma_dot0")},
            {},
            _solve_heavy_top,
            # A toy top: I1 about the tip, spinning at 150 rad/s, tilted 0.5 rad, released
            # without precession (so its axis traces cusps).
            {"I1": 2.0e-4, "I3": 1.0e-4, "Mgl": 0.02, "beta0": 0.5,
             "alpha_dot0": 0.0, "beta_dot0": 0.0, "gamma_dot0": 150.0},
            {"p_alpha": "kg m²/s", "p_gamma": "kg m²/s", "E_prime": "J", "beta1": "rad",
             "beta2": "rad", "alpha_dot_beta1": "rad/s", "alpha_dot_beta2": "rad/s",
             "nutation_period": "s", "mean_precession_rate": "rad/s",
             "omega3_critical": "rad/s", "steady_precession_rates": "rad/s"},
        ),
        Scene(
            "free-top",
            "torque-free rigid body, exact solution (R7–R10)",
            {"I1": NUMBER, "I2": NUMBER, "I3": NUMBER, "omega0": VECTOR3},
            {"t": NUMBER_OR_LIST},
            _solve_free_top,
            # A book-like box tossed mainly about its intermediate axis: it flips.
            {"I1": 1.0, "I2": 2.0, "I3": 3.0, "omega0": [0.01, 2.0, 0.01], "t": 1.0},
            {"omega": "rad/s", "T": "J", "L": "kg m²/s", "period": "s"},
        ),
        Scene(
            "euler-angles",
            "rotation matrix, body angular velocity and T from Euler angles (R11–R13)",
            {k: NUMBER for k in ("alpha", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot")},
            {"I1": NUMBER, "I2": NUMBER, "I3": NUMBER},
            _solve_euler_angles,
            {"alpha": 0.3, "beta": 0.7, "gamma": -1.2, "alpha_dot": 1.5, "beta_dot": 0.2,
             "gamma_dot": 20.0, "I1": 0.02, "I2": 0.02, "I3": 0.008},
            {"omega_body": "rad/s", "T": "J"},
        ),
        Scene(
            "inertia",
            "inertia tensor, principal moments and axes (R2–R5)",
            {},
            {"masses": NUMBERS, "positions": VECTORS3, "shape": STRING, "mass": NUMBER,
             "radius": NUMBER, "height": NUMBER, "length": NUMBER, "a": NUMBER, "b": NUMBER,
             "c": NUMBER},
            _solve_inertia,
            {"masses": [1.0, 2.0, 1.5],
             "positions": [[0.1, 0.0, 0.0], [0.0, 0.2, 0.05], [-0.1, -0.1, 0.1]]},
            {"tensor": "kg m²", "principal_moments": "kg m²"},
        ),
    )
}

RESERVED = ("scene", "id")

EXIT_STATUS = ("0: every line answered; 1: at least one line answered with an \"error\" object "
               "(all other lines still answered, one output line per input line, in order); "
               "2: usage error or unreadable input file (nothing solved)")


class _FieldError(ValueError):
    def __init__(self, field_name: str, message: str) -> None:
        super().__init__(f"{field_name}: {message}")
        self.field = field_name


def _check_value(name: str, kind: str, value: Any) -> Any:
    """Check one input field's JSON shape (numbers, vectors); physics checks are the solver's."""

    def is_num(x: Any) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    def vec3(x: Any) -> bool:
        return isinstance(x, list) and len(x) == 3 and all(is_num(e) for e in x)

    ok = {
        NUMBER: is_num(value),
        VECTOR3: vec3(value),
        NUMBER_OR_LIST: is_num(value)
        or (isinstance(value, list) and len(value) > 0 and all(is_num(e) for e in value)),
        NUMBERS: isinstance(value, list) and len(value) > 0 and all(is_num(e) for e in value),
        VECTORS3: isinstance(value, list) and len(value) > 0 and all(vec3(e) for e in value),
        STRING: isinstance(value, str),
    }[kind]
    if not ok:
        raise _FieldError(name, f"must be a {kind}, got {json.dumps(value)}")
    if kind != STRING and not all(math.isfinite(x) for x in _flatten(value)):
        raise _FieldError(name, "must be finite")
    return value


def _flatten(value: Any) -> Iterator[float]:
    if isinstance(value, list):
        for v in value:
            yield from _flatten(v)
    else:
        yield float(value)


def _plain(value: Any, name: str) -> Any:
    """Convert solver output to plain JSON; a stray non-finite number is an error, not output."""
    import numpy as np

    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v, name) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v, f"{name}.{k}") for k, v in value.items()}
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            raise _FieldError(name, "the solver produced a non-finite value (please report)")
        return float(value)
    raise TypeError(f"unexpected {type(value).__name__} in output field {name}")


def _prepare(case: dict[str, Any], default_scene: str | None) -> tuple[Scene, dict[str, Any]]:
    """The case's scene and checked input fields; :class:`_FieldError` naming a bad field."""
    scene_name = case.get("scene", default_scene)
    if scene_name is None:
        raise _FieldError("scene", f"missing: one of {', '.join(SCENES)}")
    if scene_name not in SCENES:
        raise _FieldError("scene", f"unknown scene {scene_name!r}; known: {', '.join(SCENES)}")
    scene = SCENES[scene_name]
    params = {k: v for k, v in case.items() if k not in RESERVED}
    known = {**scene.required, **scene.optional}
    for name in params:
        if name not in known:
            raise _FieldError(name, f"unknown field for {scene_name}; known: {', '.join(known)}")
    for name in scene.required:
        if name not in params:
            raise _FieldError(name, "missing")
    for name, value in params.items():
        _check_value(name, known[name], value)
    return scene, params


def _with_id(case: dict[str, Any], fields: dict[str, Any]) -> dict[str, Any]:
    return {**({"id": case["id"]} if "id" in case else {}), **fields}


def solve_case(case: dict[str, Any], default_scene: str | None = None) -> dict[str, Any]:
    """Answer one case (a dict of input fields) or return ``{"error": ...}`` naming the field."""
    from solver.parameters import ParameterError

    try:
        scene, params = _prepare(case, default_scene)
        result = scene.solve(**params)
        return _with_id(case, {k: _plain(v, k) for k, v in result.items()})
    except (_FieldError, ParameterError) as exc:
        return _with_id(case, {"error": str(exc)})
    except Exception as exc:  # one case must never stop a batch
        return _with_id(case, {"error": _internal(exc)})


def _internal(exc: BaseException) -> str:
    return f"internal error of the solver (please report): {type(exc).__name__}: {exc}"


def _solve_heavy_tops(cases: list[dict[str, Any]], params: list[dict[str, Any]]) -> list[dict]:
    """Heavy-top cases in one vectorised call (R14–R21); one by one if any state is invalid,
    so that each bad line gets its own error naming its field."""
    from solver.heavy_top import heavy_top_record, solve_heavy_top_many

    names = SCENES["heavy-top"].required
    try:
        table = solve_heavy_top_many(*(np.array([p[n] for p in params], float) for n in names))
    except Exception:  # a bad state (or a solver failure): line by line
        return [solve_case(c, "heavy-top") for c in cases]
    answers = []
    for i, c in enumerate(cases):
        try:
            answers.append(_with_id(c, {k: _plain(v, k)
                                        for k, v in heavy_top_record(table, i).items()}))
        except Exception as exc:
            answers.append(_with_id(c, {"error": _internal(exc)}))
    return answers


def _parse_line(number: int, line: str | bytes) -> dict[str, Any]:
    if isinstance(line, bytes):
        try:
            line = line.decode("utf-8")
        except UnicodeDecodeError:
            raise _FieldError(f"line {number}", "not UTF-8 text") from None
    if not line.strip():
        raise _FieldError(f"line {number}", "blank (expected a JSON object)")
    try:
        case = json.loads(line)
    except json.JSONDecodeError as exc:
        raise _FieldError(
            f"line {number}", f"not valid JSON ({exc.msg} at column {exc.colno})"
        ) from None
    if not isinstance(case, dict):
        raise _FieldError(f"line {number}", f"expected a JSON object, got {type(case).__name__}")
    return case


def solve_lines(
    lines: Iterable[str | bytes], default_scene: str | None = None, chunk: int = 2048
) -> Iterator[dict]:
    """Answer a JSON-lines stream, one output object per input line, in order.

    A blank line, a line that is not UTF-8 (``bytes`` input) or not a JSON object is answered
    with ``{"error": "line N: ..."}``. Lines are read in chunks; the heavy tops of a chunk are
    solved in one vectorised call (the per-call overhead of numpy on scalars would otherwise
    dominate), everything else per line.
    """
    numbered = enumerate(lines, start=1)
    while batch := list(itertools.islice(numbered, chunk)):
        answers: list[dict | None] = [None] * len(batch)
        heavy: list[tuple[int, dict, dict]] = []
        for slot, (number, line) in enumerate(batch):
            try:
                case = _parse_line(number, line)
            except _FieldError as exc:
                answers[slot] = {"error": str(exc)}
                continue
            try:
                scene, params = _prepare(case, default_scene)
            except _FieldError as exc:
                answers[slot] = _with_id(case, {"error": str(exc)})
                continue
            except Exception as exc:  # e.g. an unhashable "scene" value
                answers[slot] = _with_id(case, {"error": _internal(exc)})
                continue
            if scene.name == "heavy-top":
                heavy.append((slot, case, params))
            else:
                answers[slot] = solve_case(case, default_scene)
        if heavy:
            solved = _solve_heavy_tops([h[1] for h in heavy], [h[2] for h in heavy])
            for (slot, _, _), answer in zip(heavy, solved, strict=True):
                answers[slot] = answer
        yield from answers  # type: ignore[misc]


# --- the command ---------------------------------------------------------------------------

def add_solve_arguments(parser: argparse.ArgumentParser) -> None:
    scenes = "; ".join(
        f"{s.name}: {', '.join(list(s.required) + [f'[{o}]' for o in s.optional])}"
        for s in SCENES.values()
    )
    parser.epilog = (
        f"Scenes and their fields — {scenes}. Vectors as JSON, e.g. --omega0 '[0.1, 2, 0.1]'. "
        "With no --field given, a built-in example of the scene is solved."
    )
    parser.add_argument("scene", nargs="?", choices=list(SCENES), help="the scene to solve")
    parser.add_argument("--batch", metavar="CASES.jsonl",
                        help="JSON-lines input file, or - for standard input: one JSON object "
                        "out per line in, in order, {\"error\": ...} for a bad line. Exit "
                        f"status: {EXIT_STATUS}".replace("%", "%%"))
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("params", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)


def _parse_params(tokens: list[str]) -> dict[str, Any]:
    params: dict[str, Any] = {}
    it = iter(tokens)
    for token in it:
        if not token.startswith("--") or len(token) == 2:
            raise _FieldError(token, "expected --field value")
        name, _, inline = token[2:].partition("=")
        raw = inline if inline else next(it, None)
        if raw is None:
            raise _FieldError(name, "has no value")
        try:
            params[name] = json.loads(raw)
        except json.JSONDecodeError:
            params[name] = raw  # a bare word, e.g. --shape solid_cone
    return params


def _print_table(scene: str, result: dict[str, Any], stream: TextIO) -> None:
    units = SCENES[scene].units
    width = max(map(len, result), default=0)
    for key, value in result.items():
        text = "—" if value is None else json.dumps(value) if isinstance(value, list) else value
        if isinstance(value, float):
            text = f"{value:.12g}"
        unit = units.get(key, "") if value is not None else ""
        print(f"{key:<{width}}  {text} {unit}".rstrip(), file=stream)


def _hoist_options(args: argparse.Namespace) -> None:
    """Options written after the scene land in ``params`` (argparse.REMAINDER): take them back."""
    rest = list(args.params)
    if "--json" in rest:
        rest.remove("--json")
        args.json = True
    if "--batch" in rest:
        i = rest.index("--batch")
        args.batch = rest[i + 1] if i + 1 < len(rest) else args.batch
        del rest[i : i + 2]
    args.params = rest


def run_solve(args: argparse.Namespace) -> int:
    _hoist_options(args)
    if args.batch is not None:
        if args.params:
            print("eulertop solve: --batch takes its fields from the file, not the command line",
                  file=sys.stderr)
            return 2
        return _run_batch(args.batch, args.scene)
    if args.scene is None:
        print(f"eulertop solve: name a scene ({', '.join(SCENES)}) or give --batch FILE",
              file=sys.stderr)
        return 2
    try:
        params = _parse_params(args.params)
    except _FieldError as exc:
        print(f"eulertop solve: {exc}", file=sys.stderr)
        return 2
    if not params:
        params = dict(SCENES[args.scene].example)
        if not args.json:
            shown = ", ".join(f"{k}={json.dumps(v)}" for k, v in params.items())
            print(f"(no fields given: solving the built-in example {shown})", file=sys.stderr)
    result = solve_case(params, args.scene)
    if "error" in result:
        print(f"eulertop solve {args.scene}: {result['error']}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(result))
    else:
        _print_table(args.scene, result, sys.stdout)
    return 0


def _lines(stream) -> Iterator[str | bytes]:
    """The lines of a binary or text stream without their line ends (binary: undecoded, so a
    line that is not UTF-8 is that line's error, not the batch's)."""
    for line in stream:
        yield line.rstrip(b"\r\n") if isinstance(line, bytes) else line.rstrip("\r\n")


def _run_batch(path: str, default_scene: str | None) -> int:
    try:
        if path == "-":
            stream = getattr(sys.stdin, "buffer", sys.stdin)
        else:
            stream = open(path, "rb")  # closed below
    except OSError as exc:
        print(f"eulertop solve: cannot read {path}: {exc.strerror}", file=sys.stderr)
        return 2
    failed = 0
    try:
        for answer in solve_lines(_lines(stream), default_scene):
            failed += "error" in answer
            sys.stdout.write(json.dumps(answer) + "\n")
    except OSError as exc:
        print(f"eulertop solve: reading {path} failed: {exc}", file=sys.stderr)
        return 2
    finally:
        if path != "-":
            stream.close()
    if failed:
        print(f"eulertop solve: {failed} line(s) failed (see their \"error\" fields)",
              file=sys.stderr)
    return 1 if failed else 0
