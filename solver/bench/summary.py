"""The text of ``eulertop bench``: ``summary.md`` and the site's page, rendered from its files.

Pipeline: the bench writes its CSVs and ``run.json`` (command, date, machine, wall time) →
:func:`load_results` reads them back → :func:`page_block` / :func:`summary_markdown` render
the text → :func:`replace_block` puts the block between ``BEGIN`` and ``END`` of a Markdown page
(``docs/speed.md``, the documentation site's "Speed against accuracy").
Rendering only from the files (never from the measurements in memory) is what lets a test
re-render the committed block from the committed CSVs and catch a hand edit: every number in the
text is one of the run's, formatted here. Where a method never reaches an accuracy the text says
where it stalls, not an extrapolated cost.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from solver.bench.work_precision import (
    ERROR_NAMES,
    FREE_SCENE,
    HEAVY_SCENE,
    SAMPLE_PHASE,
    SCENE_RTOL,
    TURNING_POINT_METHODS,
    BenchConfig,
    rank_at_accuracy,
    stall_points,
)
from solver.methods import METHODS
from solver.scenes import FreeBody, HeavyBody

__all__ = [
    "BEGIN",
    "CSV_FILES",
    "END",
    "RUN_FILE",
    "TARGETS",
    "BlockError",
    "current_block",
    "load_results",
    "markers_of",
    "page_block",
    "replace_block",
    "run_record",
    "summary_markdown",
]

BEGIN = "<!-- eulertop bench: begin -->"
END = "<!-- eulertop bench: end -->"
RUN_FILE = "run.json"
CSV_FILES = {"free": "wp_free.csv", "heavy": "wp_heavy.csv", "scenes": "scenes.csv",
             "turning": "turning_points.csv", "drift": "drift.csv", "stability": "stability.csv",
             "fast_top": "fast_top.csv"}
TARGETS = (1e-6, 1e-10, 1e-12)  # accuracies at which the methods are ranked


class BlockError(ValueError):
    """A page has no well-formed ``BEGIN`` … ``END`` block (the message names the file)."""


# --- the run's record and the files read back -----------------------------------------------


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what :mod:`platform` says."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def run_record(command: str, config: BenchConfig, wall_seconds: float,
               load_before: tuple[float, float, float]) -> dict:
    """What ``run.json`` holds: the command line, the UTC date, the machine (CPU model and count,
    Python, numpy, scipy, load averages before and after), the wall time and the config."""
    import scipy

    return {
        "command": command,
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "load_before": list(load_before),
        "load_after": list(os.getloadavg()),
        "wall_seconds": wall_seconds,
        "config": dataclasses.asdict(config),
    }


def _value(text: str) -> object:
    """A CSV cell back to what was written: "" → None, True/False, int, float, else the text."""
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def load_results(directory: Path) -> tuple[dict[str, list[dict]], dict]:
    """The rows of each CSV of a bench run in ``directory`` (values as written: floats round-trip
    exactly through ``repr``) and its ``run.json``."""
    results = {}
    for key, name in CSV_FILES.items():
        with (directory / name).open(newline="") as fh:
            results[key] = [{k: _value(v) for k, v in row.items()} for row in csv.DictReader(fh)]
    run = json.loads((directory / RUN_FILE).read_text())
    return results, run


def _config(run: dict) -> BenchConfig:
    fields = {k: tuple(v) if isinstance(v, list) else v for k, v in run["config"].items()}
    return BenchConfig(**fields)


# --- number formats (2 significant digits: one run's timings carry no more) -------------------


def _g(x: float) -> str:
    """An error or a plain number: ``3.7e-14``, ``1e-4``, ``0.0016``, ``0``."""
    if x is None or not math.isfinite(x):
        return "n/a"
    if abs(x) >= 10:
        return ("-" if x < 0 else "") + _count(abs(x))
    text = f"{x:.2g}" if x == 0 or abs(x) >= 1e-3 else f"{x:.1e}".replace(".0e", "e")
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}e{int(exponent)}"
    return text


def _signed(x: float) -> str:
    """``+2.5e-5``, ``−0.11`` (a typographic minus)."""
    return ("−" if x < 0 else "+") + _g(abs(x))


def _count(x: float) -> str:
    """A count or ratio to 2 significant digits, digits grouped: ``1 300``, ``4.5``."""
    if not math.isfinite(x):
        return "n/a"
    if x < 10:
        return f"{x:.2g}"
    return f"{float(f'{x:.2g}'):,.0f}".replace(",", " ")


def _seconds(x: float) -> str:
    """A wall time to 2 significant digits in µs, ms or s: ``360 µs``, ``4.9 ms``, ``37 s``."""
    if not math.isfinite(x):
        return "n/a"
    for scale, unit in ((1e-3, "µs"), (1.0, "ms")):
        if x < scale:
            return f"{_count(x / scale * 1e3)} {unit}"
    return f"{_count(x)} s"


def _moments(scene: FreeBody | HeavyBody) -> str:
    def num(x: float) -> str:
        return f"{x:g}"

    if isinstance(scene, FreeBody):
        return (f"`I = ({', '.join(num(x) for x in (scene.I1, scene.I2, scene.I3))})`, "
                f"`ω0 = ({', '.join(num(x) for x in scene.omega0)})`")
    return (f"`I1 = {num(scene.I1)}, I3 = {num(scene.I3)}, Mgl = {num(scene.Mgl)}, "
            f"β0 = {num(scene.beta0)}, α̇0 = {num(scene.alpha_dot0)}, "
            f"β̇0 = {num(scene.beta_dot0)}, γ̇0 = {num(scene.gamma_dot0)}`")


# --- the page's block -------------------------------------------------------------------------


def _header(run: dict, config: BenchConfig) -> list[str]:
    load = ", ".join(f"{x:.1f}" for x in run["load_before"])
    return [
        f"Measured by `{run['command']}` on {run['date']}: {run['cpu']}, {run['cpu_count']} "
        f"CPUs (shared), Python {run['python']}, numpy {run['numpy']}, scipy {run['scipy']}; "
        f"load average {load} at the start; the whole run took {run['wall_seconds']:.0f} s. "
        "Every number in this block was written by that run, from its CSVs. Times are medians of "
        "repeats in one run: compare within a table rather than across machines.",
        "",
        f"Errors are against mpmath (40 digits) at {config.samples} sampled times, none a period "
        f"multiple (`t_k = (k + {SAMPLE_PHASE:.3f}) × horizon / {config.samples}`): for the free "
        f"top the {ERROR_NAMES['free']}, for the heavy top the {ERROR_NAMES['heavy']}.",
        "",
    ]


def _exact_row(rows: list[dict]) -> dict:
    return next(r for r in rows if r["control"] is None)


def _model_table(results: dict, config: BenchConfig) -> list[str]:
    scenes = results["scenes"]
    longest = max(config.horizons)

    def exact(scene: str, periods: int) -> dict:
        return next(r for r in scenes if r["scene"] == scene and r["periods"] == periods
                    and r["control"] is None)

    sym = exact("free, symmetric (I1 = I2)", longest)
    sym_first = exact("free, symmetric (I1 = I2)", min(config.horizons))
    free, heavy = _exact_row(results["free"]), _exact_row(results["heavy"])
    free_long = exact("free, generic", longest)
    sep_long = exact("free, near the separatrix", longest)
    heavy_long = max((r for r in scenes if r["scene"].startswith("heavy")
                      and r["periods"] == longest and r["control"] is None),
                     key=lambda r: r["error"])
    n = config.samples
    return [
        "| scene | model | cost (measured) | accuracy (measured, against mpmath at 40 digits) |",
        "|---|---|---|---|",
        f"| free symmetric top (`I1 = I2`) | {sym['method']} closed form | "
        f"{_seconds(sym['seconds'])}, 0 rhs evaluations ({n} sampled times) | "
        f"{_g(sym_first['error'])} over {min(config.horizons)} period; {_g(sym['error'])} over "
        f"{longest} |",
        f"| free asymmetric top | {free['method']}, Jacobi elliptic functions | "
        f"{_seconds(free['seconds'])}, {free['nfev']} rhs evaluations ({n} sampled times) | "
        f"{_g(free['error'])} over {config.free_periods} periods; {_g(free_long['error'])} over "
        f"{longest}; {_g(sep_long['error'])} near the separatrix over {longest} |",
        f"| heavy symmetric top | {heavy['method']}, sn² with Carlson-stable roots | "
        f"{_seconds(heavy['seconds'])}, {heavy['nfev']} rhs evaluations | "
        f"{_g(heavy['error'])} over {config.heavy_periods} nutation periods; at most "
        f"{_g(heavy_long['error'])} over {longest} ({heavy_long['scene'].split(', ', 1)[1]}) |",
        "| sleeping top (`β0 = β̇0 = 0`) | `u ≡ 1` closed form | nothing to compute | exact |",
        "| torqued asymmetric body (`I1 ≠ I2`, gravity) | DOP853 on quaternions — the one scene "
        "that integrates | see the DOP853 rows of the heavy top below (same equations) | not "
        "measured by the bench (the tests check its energy and `p_α` conservation) |",
        "",
    ]


def _reach_cell(ranked: dict, fastest: float) -> str:
    if not math.isfinite(ranked["seconds"]):
        return "—"
    if ranked["nfev"] == 0:
        return _seconds(ranked["seconds"])
    return f"{_seconds(ranked['seconds'])} ({_count(ranked['seconds'] / fastest)} ×)"


def _floor_cell(stall: dict | None, step_methods: set[str], method: str) -> str:
    if stall is None:
        return "n/a"
    if method in step_methods:
        return f"{_g(stall['error'])} (finest step {_g(stall['tightest'])} s)"
    return f"{_g(stall['error'])} at rtol {_g(stall['control'])} (swept to {_g(stall['tightest'])})"


def _equal_accuracy(rows: list[dict], title: str, periods: str, scene, image: str) -> list[str]:
    """Cost of each method at each of ``TARGETS``; the smallest error of each sweep; and, for
    the tightest target, which integrators stall before it (from the data, never extrapolated)."""
    methods = list(dict.fromkeys(r["method"] for r in rows))
    ranks = {t: {r["method"]: r for r in rank_at_accuracy(rows, t)} for t in TARGETS}
    fastest = {t: min(r["seconds"] for r in ranks[t].values()) for t in TARGETS}
    stalls = stall_points(rows)
    step_methods = {m for m in methods if METHODS[m].control == "step"}
    exact = _exact_row(rows)
    order = sorted(methods, key=lambda m: tuple(
        ranks[t][m]["seconds"] if math.isfinite(ranks[t][m]["seconds"]) else math.inf
        for t in reversed(TARGETS)))
    head = " | ".join(f"error ≤ {t:g}" for t in TARGETS)
    lines = [f"{title}, {periods} ({_moments(scene)}): median wall time to reach each error "
             "(× the fastest), interpolated log–log along each method's sweep; `—` where the "
             "sweep never reached it.", "",
             f"| method | {head} | smallest error of the sweep |",
             "|---|" + "---|" * (len(TARGETS) + 1)]
    for m in order:
        cells = [_reach_cell(ranks[t][m], fastest[t]) for t in TARGETS]
        floor = (_g(exact["error"]) + " (exact model)" if m == exact["method"]
                 else _floor_cell(stalls.get(m), step_methods, m))
        lines.append(f"| {m} | {' | '.join(cells)} | {floor} |")
    tight = TARGETS[-1]
    integrators = [m for m in order if m != exact["method"]]
    reached = [m for m in integrators if math.isfinite(ranks[tight][m]["seconds"])]
    adaptive = [m for m in integrators if m not in reached and m in stalls
                and m not in step_methods]
    tightest = min((stalls[m]["tightest"] for m in adaptive), default=math.nan)
    stalled = sorted((m for m in adaptive if stalls[m]["tightest"] == tightest),
                     key=lambda m: stalls[m]["error"])
    cut = [m for m in adaptive if m not in stalled]
    if reached:
        verdict = f"At {tight:g}: reached by {', '.join(reached)}"
    else:
        verdict = f"**No integrator reaches {tight:g} over {periods}**"
    rtol_floor = 100 * np.finfo(float).eps  # scipy raises any smaller rtol to this
    if stalled and tightest <= rtol_floor:
        verdict += ("; " if reached else ": ") + ", ".join(
            f"{m} stalls at {_g(stalls[m]['error'])}" for m in stalled)
        verdict += (f" (rtol swept down to {_g(tightest)}; scipy raises any rtol below "
                    f"100 ε = {_g(rtol_floor)} to that)")
    elif stalled:  # a reduced sweep: no claim of a floor
        verdict += ("; " if reached else ": ") + ", ".join(
            f"{m} gets to {_g(stalls[m]['error'])}" for m in stalled)
        verdict += f" at the tightest rtol of this sweep, {_g(tightest)}"
    verdict += "".join(f"; {m}'s sweep stops at rtol {_g(stalls[m]['tightest'])} (its cost), "
                       f"error {_g(stalls[m]['error'])} there" for m in cut)
    verdict += f"; {exact['method']} is at {_g(exact['error'])}."
    lines += ["", verdict, "", f"![work-precision, {image}](IMG/wp_{image}_time.png) "
              f"![](IMG/wp_{image}_nfev.png)", ""]
    return lines


def _scenes(results: dict, config: BenchConfig) -> list[str]:
    rows = results["scenes"]
    horizons = sorted({r["periods"] for r in rows})
    longest = max(horizons)
    lines = [f"Initial states × horizons (DOP853 at rtol {SCENE_RTOL:g} against the exact "
             "model; error over the sampled times; periods of ω for a free top, nutation periods "
             "for a heavy top):", "",
             "| state | exact model: largest error | "
             + " | ".join(f"DOP853, {h} period{'s' if h > 1 else ''}" for h in horizons)
             + f" | DOP853 cost at {longest} |",
             "|---|---|" + "---|" * (len(horizons) + 1)]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        sub = [r for r in rows if r["scene"] == scene]
        exact = [r for r in sub if r["control"] is None]
        dop = {r["periods"]: r for r in sub if r["method"] == "DOP853"}
        last = dop[longest]
        lines.append(f"| {scene} | {exact[0]['method']} {_g(max(r['error'] for r in exact))} | "
                     + " | ".join(_g(dop[h]["error"]) for h in horizons)
                     + f" | {_seconds(last['seconds'])}, {_count(last['nfev'])} evaluations |")
    return [*lines, ""]


def _turning(results: dict) -> list[str]:
    rows = results["turning"]
    methods = list(TURNING_POINT_METHODS)
    lines = ["## Turning points (max error of β1, β2 in rad, against mpmath; median time)", "",
             "| top | " + " | ".join(methods) + " |",
             "|---|" + "---|" * len(methods)]
    for case in dict.fromkeys(r["case"] for r in rows):
        cells = {r["method"]: r for r in rows if r["case"] == case}
        lines.append(f"| {case} | " + " | ".join(
            f"{_g(cells[m]['error_rad'])}, {_seconds(cells[m]['seconds'])}" for m in methods)
            + " |")
    return [*lines, "", "![turning points](IMG/turning_points.png)", ""]


def _drift(results: dict, config: BenchConfig) -> list[str]:
    rows = results["drift"]
    lines = [f"## Invariant drift, free asymmetric top (adaptive at rtol {_g(config.drift_rtol)}, "
             f"fixed step period/{config.drift_steps_per_period})", "",
             f"Sampled {SAMPLE_PHASE:.3f} of a period past log-spaced whole periods (at whole "
             "periods a periodic energy error vanishes and would read as zero); Radau only to "
             f"{min(config.drift_periods, config.radau_drift_periods)} periods (its cost). "
             "Relative errors of the energy T and of |L|²; the largest over the first tenth of "
             "the samples against the largest over the last tenth shows growth or a bound:", "",
             "| method | energy, early | energy, late | \\|L\\|², late | last sample (periods) "
             "| wall time |",
             "|---|---|---|---|---|---|"]
    for method in dict.fromkeys(r["method"] for r in rows):
        sub = [r for r in rows if r["method"] == method]
        tenth = max(1, len(sub) // 10)
        early = max(r["energy_error"] for r in sub[:tenth])
        late = max(r["energy_error"] for r in sub[-tenth:])
        late_l2 = max(r["L2_error"] for r in sub[-tenth:])
        lines.append(f"| {method} | {_g(early)} | {_g(late)} | {_g(late_l2)} | "
                     f"{_count(sub[-1]['periods'])} | {_seconds(sub[-1]['seconds_total'])} |")
    return [*lines, "", "![drift](IMG/drift.png)", ""]


def _stability(results: dict) -> list[str]:
    rows = results["stability"]
    lines = ["## Stability battery", "",
             "Where a naive method fails and the project's does not, measured by "
             "`solver/bench/stability.py` against mpmath (40 digits) or a closed form; "
             "`tests/solver/test_stability.py` asserts the same phenomena.", "",
             "| where | method | measured |", "|---|---|---|"]
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        for method in dict.fromkeys(r["method"] for r in sub):
            mine = [r for r in sub if r["method"] == method]
            costs = {r["nfev"] for r in mine if not r["note"]}
            shared = len(mine) > 1 and len(costs) == 1 and None not in costs
            cells = []
            for r in mine:
                where = (r["parameter"] if r["value"] is None
                         else f"{r['parameter']} = {_g(r['value'])}")
                if r["note"]:
                    cells.append(f"{where}: fails ({r['note']})")
                    continue
                cost = ("" if r["nfev"] is None or shared
                        else f" ({_count(r['nfev'])} evaluations)")
                cells.append(f"{where}: {_g(r['error'])}{cost}")
            name = f"{method} ({_count(costs.pop())} evaluations)" if shared else method
            lines.append(_cells([case, name, "; ".join(cells)]))
    return [*lines, ""]


def _cells(cells: list[str]) -> str:
    """A table row, ``|`` inside a cell escaped."""
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


def _fast_top(results: dict) -> list[str]:
    rows = results["fast_top"]
    betas = list(dict.fromkeys(r["beta0"] for r in rows))
    head = " | ".join(f"{kind}, β0 = {b}" for b in betas for kind in ("slow", "fast"))
    lines = ["## When is the fast-top approximation good enough? (R21)", "",
             "Relative error of `fast_top_rates` against the exact steady rates "
             "(`solver.scenes.fast_top_error`), against `ε = 2 I1 Mgl/(I3 ω3)²` "
             "(`fast_top_parameter`). To first order both errors are `∓ ε cos β0 / 2`: an answer "
             "good to `rtol` needs `ε |cos β0| ≲ 2 rtol`.", "",
             f"| ε | {head} |", "|---|" + "---|" * (2 * len(betas))]
    for eps in dict.fromkeys(r["epsilon"] for r in rows):
        cells = []
        for b in betas:
            row = next(r for r in rows if r["epsilon"] == eps and r["beta0"] == b)
            cells += [_signed(row["slow_error"]), _signed(row["fast_error"])]
        note = " (R19's critical spin)" if math.isclose(eps, 0.5, rel_tol=1e-12) else ""
        lines.append(f"| {_g(eps)}{note} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def page_block(results: dict[str, list[dict]], run: dict, image_dir: str) -> str:
    """The measured part of the page "Speed against accuracy", between ``BEGIN`` and ``END``
    (markers included), its sections at heading level 2; ``image_dir`` prefixes the chart paths
    (``"bench/"`` in ``docs/speed.md``, ``""`` in ``summary.md``)."""
    config = _config(run)
    lines = [BEGIN,
             "<!-- Written by `eulertop bench --page`: edit the code in "
             "solver/bench/summary.py, not this text (tests/solver/test_bench_summary.py "
             "re-renders it from docs/bench and fails on a difference). -->", ""]
    lines += _header(run, config)
    lines += _model_table(results, config)
    lines += ["## At equal accuracy", ""]
    lines += _equal_accuracy(results["free"], "Free asymmetric top",
                             f"{config.free_periods} periods of ω", FREE_SCENE, "free")
    lines += _equal_accuracy(results["heavy"], "Heavy symmetric top",
                             f"{config.heavy_periods} nutation periods", HEAVY_SCENE, "heavy")
    lines += _scenes(results, config)
    lines += _turning(results)
    lines += _drift(results, config)
    lines += _stability(results)
    lines += _fast_top(results)
    lines.append(END)
    return "\n".join(lines).replace("IMG/", image_dir) + "\n"


# --- summary.md: the same text, then every table in full -------------------------------------


def _fmt(x) -> str:
    if x is None:
        return "—"
    if isinstance(x, float):
        return "n/a" if not math.isfinite(x) else f"{x:.2g}"
    return str(x)


def _table(rows: list[dict], keys: list[str]) -> str:
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def summary_markdown(results: dict[str, list[dict]], run: dict) -> str:
    """``summary.md``: the page block's text (charts beside it), then the full tables."""
    config = _config(run)
    out = [f"# eulertop bench — {'quick' if config.free_periods < 100 else 'full'} run", "",
           page_block(results, run, ""), "## Every table in full", ""]
    for key, title in (("free", "free asymmetric top"), ("heavy", "heavy symmetric top")):
        rows = results[key]
        out += [f"### Ranking at equal accuracy — {title}", ""]
        for target in TARGETS:
            ranked = rank_at_accuracy(rows, target)
            fastest = ranked[0]["seconds"]
            for r in ranked:
                r["× fastest"] = r["seconds"] / fastest
            out += [f"Error ≤ {target:g}:", "",
                    _table(ranked, ["method", "seconds", "nfev", "× fastest"]), ""]
        stalls = [{"method": k, **v} for k, v in stall_points(rows).items()]
        out += ["Smallest error each method's sweep reached, at which control (rtol, or step in "
                "s), and the tightest control swept:", "",
                _table(stalls, ["method", "error", "control", "tightest"]), "",
                "Every point of the sweep:", "",
                _table(rows, ["method", "control", "error", "seconds", "repeats", "nfev"]), ""]
    out += ["### Initial states × horizons", "",
            _table(results["scenes"], ["scene", "periods", "method", "error", "seconds",
                                       "nfev"]), "",
            "### Turning points", "",
            _table(results["turning"], ["case", "method", "error_rad", "seconds"]), "",
            f"### Invariant drift (last sample of each method; {len(results['drift'])} samples "
            "in `drift.csv`)", ""]
    last = {r["method"]: r for r in results["drift"]}
    out += [_table(list(last.values()), ["method", "periods", "energy_error", "L2_error",
                                         "seconds_total"]), ""]
    return "\n".join(out)


# --- the page --------------------------------------------------------------------------------


def replace_block(text: str, block: str, name: str = "the page",
                  markers: tuple[str, str] = (BEGIN, END)) -> str:
    """``text`` with everything from ``BEGIN`` to ``END`` (markers included) replaced by
    ``block``; raises :class:`BlockError` naming ``name`` unless each marker occurs once, in
    order, each on a line of its own. ``markers`` names another block of the page (each
    benchmark of ``benchmarks/`` that writes into the page has its own, :func:`markers_of`)."""
    begin, end = markers
    lines = text.splitlines(keepends=True)
    starts = [i for i, line in enumerate(lines) if line.strip() == begin]
    ends = [i for i, line in enumerate(lines) if line.strip() == end]
    if len(starts) != 1 or len(ends) != 1 or ends[0] < starts[0]:
        raise BlockError(f"{name}: needs one line '{begin}' followed by one line '{end}' "
                         f"(found {len(starts)} and {len(ends)}); the bench writes its "
                         "numbers between them")
    return "".join(lines[:starts[0]]) + block + "".join(lines[ends[0] + 1:])


def current_block(text: str, name: str = "the page",
                  markers: tuple[str, str] = (BEGIN, END)) -> str:
    """The ``BEGIN`` … ``END`` block of ``text`` (or that of ``markers``), markers included."""
    replace_block(text, "", name, markers)  # validates
    lines = text.splitlines(keepends=True)
    start = next(i for i, line in enumerate(lines) if line.strip() == markers[0])
    end = next(i for i, line in enumerate(lines) if line.strip() == markers[1])
    return "".join(lines[start:end + 1])


def markers_of(bench: str) -> tuple[str, str]:
    """The lines around the block that ``benchmarks/<bench>.py --page`` writes."""
    return f"<!-- {bench}: begin -->", f"<!-- {bench}: end -->"
