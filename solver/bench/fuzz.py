"""Fuzzing the heavy-top solver against the independent mpmath reference (issue 12).

``eulertop bench --fuzz N [--seed S] [--jobs J] [--out DIR]`` (or
``python benchmarks/bench_fuzz.py N``) draws ``N`` random heavy tops, stratified over
:data:`REGIONS`, solves them through the public API (:func:`solver.heavy_top.solve_heavy_top_many`,
one vectorised call) and through the batch CLI (:func:`solver.cli.solve_lines`, JSON in and
out), and compares ``β1, β2`` (absolute, rad), the nutation period and ``⟨α̇⟩`` (relative) and
the motion label with :func:`solver.bench.mp_reference.reference` at :data:`DPS` digits.

Acceptance (per case and quantity)
----------------------------------
``error ≤ max(FLOOR, K × condition)`` with ``FLOOR = 1e-10``, ``K = 10``. The condition is
*measured*: the reference is evaluated again at :data:`PERTURBATIONS` states whose nonzero
inputs are moved by up to :data:`ULPS` units in the last place (random, continuous,
seeded), and the
condition is the largest change of the quantity (same norm as the error). An ill-conditioned
case (a near-double root, ⟨α̇⟩ as a small difference of forward and backward precession) is so
judged by what its inputs determine.

A quantity the reference says does not exist (⟨α̇⟩ of a sleeping top, the period of an
unstable sleeping top at rest) must be NaN/inf with a reason in ``undefined`` (API) and ``null``
with the same reason (CLI); every other NaN, infinity, ``null`` or error line is a failure.

Labels: right if equal to the reference's label at the state **or at any perturbed state**
(the class boundary lies within the ulp perturbation), and, within the documented margin of a
boundary: ``"steady"`` is accepted when the reference width ``u2 − u1`` is at most ``K`` times
its measured condition, ``"cusps"`` (or the loops/waves flip) when ``α̇`` at a turning point is
within ``K`` times its condition of 0.

Every random draw comes from ``numpy.random.default_rng(seed)``; the seed is printed and
written with the table.
"""

from __future__ import annotations

import json
import math
import multiprocessing
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.random import Generator

from solver.bench.mp_reference import reference

__all__ = ["FLOOR", "REGIONS", "FuzzReport", "K", "draw_cases", "judge_cases", "run_fuzz"]

FLOOR = 1e-10
K = 10.0
DPS = 40
PERTURBATIONS = 3
ULPS = 4
QUANTITIES = ("beta1", "beta2", "nutation_period", "mean_precession_rate", "motion")
PATHS = ("api", "cli")


# --- the regions ----------------------------------------------------------------------------


def _moments(rng: Generator, n: int, lo: float = -3.0, hi: float = -1.0):
    """I1 (about the tip), I3 ≤ 2 I1 (a rigid body), Mgl, and the natural rate √(Mgl/I1)."""
    i1 = 10 ** rng.uniform(lo, hi, n)
    i3 = i1 * rng.uniform(0.2, 1.9, n)
    mgl = i1 * 10 ** rng.uniform(0.0, 2.5, n)
    return i1, i3, mgl, np.sqrt(mgl / i1)


def _tilt(rng: Generator, n: int, margin: float = 0.05):
    return rng.uniform(margin, np.pi - margin, n)


def _sometimes(rng: Generator, n: int, p: float):
    return rng.random(n) < p


def _generic(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    return (i1, i3, mgl, _tilt(rng, n), rng.normal(0, 1, n) * w, rng.normal(0, 1, n) * w,
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(0, 1.5, n))


def _fast(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    spin = np.where(_sometimes(rng, n, 0.5), 1.0, -1.0) * w * 10 ** rng.uniform(2, 4, n)
    return (i1, i3, mgl, _tilt(rng, n), rng.normal(0, 1, n) * w,
            rng.normal(0, 1, n) * w * _sometimes(rng, n, 0.7), spin)


def _slow_hanging(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    return (i1, i3, mgl, rng.uniform(np.pi / 2, np.pi, n),
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(-3, 0, n),
            rng.normal(0, 0.3, n) * w * _sometimes(rng, n, 0.7),
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(-3, 0, n))


def _near_pole(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    gap = 10 ** rng.uniform(-9, -2, n)
    b0 = np.where(_sometimes(rng, n, 0.5), gap, np.pi - gap)
    ad = rng.normal(0, 1, n) * w
    gd = rng.normal(0, 1, n) * w * 10 ** rng.uniform(-1, 2, n)
    # a third with p_γ ≈ 0 (issue 12, defect 1: hanging, barely spinning)
    gd = np.where(_sometimes(rng, n, 1 / 3), -ad * np.cos(b0) * (1 + rng.normal(0, 1e-9, n)), gd)
    return (i1, i3, mgl, b0, ad,
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(-3, 0, n) * _sometimes(rng, n, 0.7), gd)


def _pendulum(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    b0 = _tilt(rng, n, 0.0)
    # β̇0² vs B (1 − cos β0): about half swing, half go over the top
    bd = rng.normal(0, 1, n) * w * rng.uniform(0, 3, n) * _sometimes(rng, n, 0.8)
    zero = np.zeros(n)
    return i1, i3, mgl, b0, zero, bd, zero


def _steady_rate(i1, mgl, b0, pg, which):
    """R21's slow (0) or fast (1) steady rate, cancellation-free (numpy; a generator only)."""
    u0 = np.cos(b0)
    q = pg + np.sign(pg) * np.sqrt(pg * pg - 4 * i1 * mgl * u0)
    return np.where(which == 0, 2 * mgl / q, q / (2 * i1 * np.where(u0 == 0, 1e-300, u0)))


def _near_steady(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    b0 = _tilt(rng, n)
    omega_c = 2 * np.sqrt(mgl * i1) / i3
    w3 = np.where(_sometimes(rng, n, 0.5), 1.0, -1.0) * omega_c * 10 ** rng.uniform(0.05, 3, n)
    which = np.where(np.abs(np.cos(b0)) < 1e-2, 0, rng.integers(0, 2, n))
    rate = _steady_rate(i1, mgl, b0, i3 * w3, which)
    nudge = np.where(_sometimes(rng, n, 0.5), 1, -1) * 10 ** rng.uniform(-13, -3, n)
    ad = rate * (1 + nudge * _sometimes(rng, n, 0.8))
    bd = np.where(_sometimes(rng, n, 0.7), 0.0, w * 10 ** rng.uniform(-10, -4, n))
    return i1, i3, mgl, b0, ad, bd, w3 - ad * np.cos(b0)


def _looping_near_pole(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    gap = 10 ** rng.uniform(-7, -2, n)
    b0 = np.where(_sometimes(rng, n, 0.5), gap, np.pi - gap)
    spin = np.where(_sometimes(rng, n, 0.5), 1.0, -1.0) * w * 10 ** rng.uniform(2, 4.5, n)
    return (i1, i3, mgl, b0, rng.normal(0, 1, n) * w * 10 ** rng.uniform(-2, 1, n),
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(-2, 1, n) * _sometimes(rng, n, 0.8),
            spin)


def _sleeping(rng, n):
    i1, i3, mgl, w = _moments(rng, n)
    omega_c = 2 * np.sqrt(mgl * i1) / i3
    side = np.where(_sometimes(rng, n, 0.5), 1.0, -1.0)
    w3 = np.where(_sometimes(rng, n, 0.5), 1.0, -1.0) * omega_c * (
        1 + side * 10 ** rng.uniform(-13, -1, n))
    ad = rng.normal(0, 1, n) * w * _sometimes(rng, n, 0.5)
    b0 = np.where(_sometimes(rng, n, 0.7), 0.0, 10 ** rng.uniform(-8, -4, n))
    return i1, i3, mgl, b0, ad, np.zeros(n), w3 - ad * np.cos(b0)


def _extreme_moments(rng, n):
    i1 = 10 ** rng.uniform(-4, 2, n)
    i3 = i1 * rng.uniform(0.05, 1.99, n)
    mgl = 10 ** rng.uniform(-3, 3, n)
    w = np.sqrt(mgl / i1)
    return (i1, i3, mgl, _tilt(rng, n, 0.01), rng.normal(0, 1, n) * w,
            rng.normal(0, 1, n) * w * _sometimes(rng, n, 0.7),
            rng.normal(0, 1, n) * w * 10 ** rng.uniform(-1, 3, n))


REGIONS: dict[str, Callable[[Generator, int], tuple]] = {
    "generic": _generic,
    "fast": _fast,
    "slow & hanging": _slow_hanging,
    "near a pole": _near_pole,
    "planar pendulum": _pendulum,
    "near steady": _near_steady,
    "looping near a pole": _looping_near_pole,
    "sleeping threshold": _sleeping,
    "moments 1e-4..1e2": _extreme_moments,
}


def draw_cases(n: int, seed: int) -> tuple[list[str], np.ndarray]:
    """``n`` states stratified over :data:`REGIONS` (equal shares): (region per case, (n, 7))."""
    rng = np.random.default_rng(seed)
    names, blocks = [], []
    share = [n // len(REGIONS) + (i < n % len(REGIONS)) for i in range(len(REGIONS))]
    for (name, sampler), m in zip(REGIONS.items(), share, strict=True):
        if m == 0:
            continue
        state = np.stack([np.broadcast_to(np.asarray(x, float), (m,)) for x in sampler(rng, m)],
                         axis=1)
        state[:, 3] = np.clip(state[:, 3], 0.0, np.pi)
        names += [name] * m
        blocks.append(state)
    return names, np.concatenate(blocks)


# --- the reference side (slow: mpmath, in worker processes) ---------------------------------


def _perturbed(state: tuple[float, ...], rng: Generator) -> tuple:
    """The state with each input multiplied by ``1 + δ``, ``δ`` uniform in ±``ULPS`` units of
    2⁻⁵² (continuous, in mpmath: no two inputs' shifts cancel exactly, as whole ulps could);
    zeros stay zero (a top released from rest is exact data)."""
    import mpmath as mp

    with mp.workdps(DPS + 10):
        return tuple(mp.mpf(x) * (1 + mp.mpf(float(rng.uniform(-ULPS, ULPS))) * mp.mpf(2) ** -52)
                     for x in state)


def _floats(ref) -> dict:
    def f(x):
        return None if x is None else float(x)

    return {"beta1": f(ref.beta1), "beta2": f(ref.beta2), "nutation_period": f(ref.period),
            "mean_precession_rate": f(ref.mean_rate), "gap": f(ref.gap),
            "rate1": f(ref.rates[0]), "rate2": f(ref.rates[1]), "motion": ref.label}


def reference_row(job: tuple[int, tuple[float, ...], int]) -> dict:
    """Reference values of one case, their measured conditions, and the acceptable labels."""
    index, state, seed = job
    rng = np.random.default_rng([seed, index])
    base = _floats(reference(state, DPS))
    others = [_floats(reference(_perturbed(state, rng), DPS))
              for _ in range(PERTURBATIONS)]
    cond = {}
    for key in ("beta1", "beta2", "gap", "rate1", "rate2"):
        cond[key] = max(abs(o[key] - base[key]) for o in others)
    for key in ("nutation_period", "mean_precession_rate"):
        cond[key] = max(_relative(o[key], base[key]) for o in others)
    labels = {base["motion"], *(o["motion"] for o in others)}
    if base["gap"] <= K * cond["gap"]:
        labels.add("steady")
    near_zero = [abs(base[r]) <= K * cond[r] for r in ("rate1", "rate2")]
    if any(near_zero):
        labels |= {"cusps", "loops", "waves"}
    return {"ref": base, "cond": cond, "labels": sorted(labels)}


def _relative(x, ref) -> float:
    if x is None or ref is None:
        return 0.0 if x is ref else math.inf
    if math.isinf(ref) or math.isinf(x):
        return 0.0 if x == ref else math.inf
    if ref == 0:
        return 0.0 if x == 0 else math.inf
    return abs(x / ref - 1)


# --- the solver side (fast: one vectorised call, one batch) ---------------------------------


def solve_api(states: np.ndarray) -> list[dict]:
    """The public API, vectorised over all states: one dict per case (floats, NaN kept)."""
    from solver.heavy_top import solve_heavy_top_many

    table = solve_heavy_top_many(*states.T)
    rows = []
    for i in range(len(states)):
        rows.append({k: (table[k][i] if k == "motion" else float(table[k][i]))
                     for k in QUANTITIES} | {"undefined": table["undefined"][i]})
    return rows


STATE_KEYS = ("I1", "I3", "Mgl", "beta0", "alpha_dot0", "beta_dot0", "gamma_dot0")


def solve_cli(states: np.ndarray) -> list[dict]:
    """The batch CLI's code path: JSON lines in, JSON lines out (``solver.cli.solve_lines``)."""
    from solver.cli import solve_lines

    lines = [json.dumps({"scene": "heavy-top", **dict(zip(STATE_KEYS, map(float, s),
                                                          strict=True))}) for s in states]
    return [json.loads(json.dumps(a)) for a in solve_lines(lines)]


# --- judging ---------------------------------------------------------------------------------


@dataclass
class Cell:
    """Worst error and failures of one region × quantity."""

    cases: int = 0
    failures: int = 0
    worst_error: float = 0.0
    worst_ratio: float = 0.0  # error / allowed


@dataclass
class FuzzReport:
    """What :func:`judge_cases` found: cells[(path, region, quantity)] and the failing cases."""

    cells: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)

    @property
    def total_failures(self) -> int:
        return sum(c.failures for c in self.cells.values())


def _judge_number(quantity, got, ref, cond, reason) -> tuple[bool, float, float]:
    """(ok, error, allowed) for one number; ``got`` None or non-finite needs a reason."""
    absolute = quantity in ("beta1", "beta2")
    allowed = max(FLOOR, K * cond)
    if ref is None or (ref is not None and math.isinf(ref)):
        ok = (got is None or not math.isfinite(got)) and bool(reason)
        return ok, 0.0 if ok else math.inf, allowed
    if got is None or not math.isfinite(got):
        return False, math.inf, allowed
    error = abs(got - ref) if absolute else _relative(got, ref)
    return error <= allowed, error, allowed


def judge_cases(regions: list[str], states: np.ndarray, refs: list[dict],
                answers: dict[str, list[dict]], report: FuzzReport | None = None) -> FuzzReport:
    """Compare each path's answers with the references; accumulate into ``report``."""
    report = report or FuzzReport()
    for path, rows in answers.items():
        for i, (region, ref, got) in enumerate(zip(regions, refs, rows, strict=True)):
            reasons = got.get("undefined") or {}
            for q in QUANTITIES:
                cell = report.cells.setdefault((path, region, q), Cell())
                cell.cases += 1
                if "error" in got:
                    ok, error, ratio = False, math.inf, math.inf
                elif q == "motion":
                    ok, error, ratio = got[q] in ref["labels"], 0.0, 0.0
                    if not ok:
                        error = ratio = 1.0
                else:
                    value = got[q]
                    value = None if value is None else float(value)
                    ok, error, allowed = _judge_number(q, value, ref["ref"][q], ref["cond"][q],
                                                       reasons.get(q))
                    ratio = error / allowed
                cell.worst_error = max(cell.worst_error, error)
                cell.worst_ratio = max(cell.worst_ratio, ratio)
                if not ok:
                    cell.failures += 1
                    report.failures.append({"path": path, "region": region, "quantity": q,
                                            "state": [float(x) for x in states[i]],
                                            "got": got.get(q, got.get("error")),
                                            "reference": ref["ref"][q] if q != "motion"
                                            else ref["labels"]})
    return report


# --- the command -----------------------------------------------------------------------------


def _chunks(n: int, size: int) -> Iterable[range]:
    for start in range(0, n, size):
        yield range(start, min(start + size, n))


def run_fuzz(n: int, seed: int, jobs: int = 2, out: Path | None = None,
             chunk: int = 500, stream=sys.stderr) -> FuzzReport:
    """Draw, solve, reference, judge ``n`` cases; write ``out/fuzz.md`` if ``out`` is given."""
    start = time.perf_counter()
    print(f"eulertop bench --fuzz {n} --seed {seed}: {len(REGIONS)} regions, references at "
          f"{DPS} digits, {PERTURBATIONS} perturbations of ≤ {ULPS} ulps, {jobs} process(es)",
          file=stream, flush=True)
    regions, states = draw_cases(n, seed)
    report = FuzzReport()
    solve_seconds = 0.0
    jobs_list = [(i, tuple(map(float, states[i])), seed) for i in range(n)]
    ctx = multiprocessing.get_context("fork" if sys.platform != "win32" else "spawn")
    with ctx.Pool(jobs) as pool:
        refs_iter = pool.imap(reference_row, jobs_list, chunksize=16)
        for block in _chunks(n, chunk):
            refs = [next(refs_iter) for _ in block]
            t0 = time.perf_counter()
            answers = {"api": solve_api(states[block.start:block.stop]),
                       "cli": solve_cli(states[block.start:block.stop])}
            solve_seconds += time.perf_counter() - t0
            judge_cases(regions[block.start:block.stop], states[block.start:block.stop], refs,
                        answers, report)
            print(f"  {block.stop}/{n} cases, {report.total_failures} failure(s), "
                  f"{time.perf_counter() - start:.0f} s", file=stream, flush=True)
            if out is not None:  # after every chunk: an interrupted run still leaves its table
                _write(out, fuzz_markdown(report, n, seed, jobs, time.perf_counter() - start,
                                          solve_seconds, done=block.stop))
    return report


def _write(out: Path, text: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    tmp = out / "fuzz.md.tmp"
    tmp.write_text(text)
    tmp.replace(out / "fuzz.md")


def _cell_text(cell: Cell) -> str:
    err = "—" if cell.worst_error == 0 else f"{cell.worst_error:.1e}"
    return f"{err} ({cell.worst_ratio:.2g}) {cell.failures}/{cell.cases}"


def fuzz_markdown(report: FuzzReport, n: int, seed: int, jobs: int, wall: float,
                  solve_seconds: float, done: int | None = None) -> str:
    """The regions × quantities table (per path) and the failing cases, as Markdown."""
    done = n if done is None else done
    status = "complete" if done == n else f"INTERRUPTED after {done} of {n} cases"
    lines = ["# Fuzzing the heavy-top solver", "",
             "Written by `eulertop bench --fuzz N --seed S` (`solver/bench/fuzz.py`; the method, "
             "the "
             "regions and the acceptance rule are in its docstring). References: "
             "`solver/bench/mp_reference.py` — mpmath from `docs/physics/index.md` alone "
             "(expanded cubic, "
             "Legendre K and Π), Legendre integrals evaluated with Arb (python-flint) when "
             f"installed; {DPS}+ digits, raised where poles or cancellation need it. "
             f"Acceptance: error ≤ max({FLOOR:g}, {K:g} × condition), the condition measured by "
             f"{PERTURBATIONS} reference evaluations at inputs moved by ≤ {ULPS} ulps.", "",
             f"Command: `eulertop bench --fuzz {n} --seed {seed} --jobs {jobs}` ({status}); "
             f"{done} cases judged, {report.total_failures} failure(s); wall time {wall:.0f} s "
             f"(solver under test: {solve_seconds:.1f} s for both paths, the rest is the mpmath "
             "reference).", ""]
    header = "| region | " + " | ".join(QUANTITIES) + " |"
    for path in PATHS:
        lines += [f"## Through the {'Python API' if path == 'api' else 'batch CLI'}", "",
                  "Each cell: worst error (worst error ÷ allowed) failures/cases. β1, β2 "
                  "absolute (rad); period and ⟨α̇⟩ relative; motion: 1 = a wrong label.", "",
                  header, "|" + "---|" * (len(QUANTITIES) + 1)]
        for region in REGIONS:
            cells = [report.cells.get((path, region, q)) for q in QUANTITIES]
            if cells[0] is None:
                continue
            lines.append(f"| {region} | " + " | ".join(_cell_text(c) for c in cells) + " |")
        lines.append("")
    if report.failures:
        lines += ["## Failing cases (first 20)", ""]
        lines += [f"- {json.dumps(f)}" for f in report.failures[:20]]
        lines.append("")
    return "\n".join(lines)
