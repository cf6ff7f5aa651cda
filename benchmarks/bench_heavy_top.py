"""Benchmark: the heavy-top solver against its floor (issue 34), on 10^6 random tops.

Ours: one call of the public ``solver.heavy_top.nutation`` — validation, the cubic of R17, its
roots, the pole distances, the Carlson integrals of R20 and the NaN of quantities that do not
exist — giving β1, β2, the nutation period and the mean precession rate of every top.

The floor: the special functions that call rests on, on the same arguments — numpy's
trigonometric (Viète) roots of the same 10^6 cubics, and scipy's ``elliprf`` and ``elliprj`` on
exactly the arguments the solver passes them (recorded from one call of ours in this run).

Rounds alternate the two (:func:`speed_page.interleaved`); medians of the rounds, and the ratio
of the medians. Then one instrumented call of ours per round says where its time goes. The
tops: I1 about the tip in [1e-4, 1e-2] kg m², I3 in [0.1, 1.9]·I1, Mgl in [1e-3, 1] J, β0 in
(0, π), α̇0 ~ N(0, 5²), β̇0 ~ N(0, 2²) (zero for 30 %), ω3 log-uniform in [1, 5000] rad/s
with random sign (seed 0). Run from the repository root::

    python benchmarks/bench_heavy_top.py [--tops N] [--rounds R] [--record FILE] [--page FILE]

``--record docs/bench/heavy_top.json --page docs/speed.md`` is the run the speed page shows.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.special import elliprf, elliprj

sys.path.insert(0, str(Path(__file__).resolve().parent))
import speed_page

import solver.heavy_top as heavy_top
import solver.nutation as nutation_module

BENCH = "bench_heavy_top"
STAGES = ("validation", "cubic", "carlson", "integrals", "rest")
STAGE_NAMES = {
    "validation": "validation and broadcasting",
    "cubic": "the cubic: its coefficients, roots (Newton from the trigonometric root) and pole "
             "distances",
    "carlson": "scipy's `elliprf` and `elliprj` (the floor's share)",
    "integrals": "the integrals' arguments and the two forms of Δα around them",
    "rest": "angles, the mean rate and its NaN, the blocks",
}


def random_tops(n: int, seed: int = 0) -> list[np.ndarray]:
    """``n`` physically sensible heavy tops (see the module docstring), as the 7 state arrays."""
    rng = np.random.default_rng(seed)
    I1 = 10 ** rng.uniform(-4, -2, n)
    I3 = I1 * rng.uniform(0.1, 1.9, n)
    Mgl = 10 ** rng.uniform(-3, 0, n)
    beta0 = rng.uniform(0.01, np.pi - 0.01, n)
    alpha_dot0 = rng.normal(0.0, 5.0, n)
    beta_dot0 = rng.normal(0.0, 2.0, n) * (rng.random(n) < 0.7)
    omega3 = rng.choice([-1.0, 1.0], n) * 10 ** rng.uniform(0, np.log10(5000.0), n)
    gamma_dot0 = omega3 - alpha_dot0 * np.cos(beta0)
    return [I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0]


def trigonometric_roots(B, c2, c1, c0) -> list[np.ndarray]:
    """The three real roots of ``B w³ + c2 w² + c1 w + c0`` by Viète's trigonometric formula."""
    shift = c2 / (3.0 * B)
    a1 = c1 / B
    p = a1 - 3.0 * shift * shift
    q = shift * (2.0 * shift * shift - a1) + c0 / B
    with np.errstate(invalid="ignore", divide="ignore"):
        m = 2.0 * np.sqrt(-p / 3.0)
        third = np.arccos(np.clip(3.0 * q / (p * m), -1.0, 1.0)) / 3.0
    return [m * np.cos(third - 2.0 * np.pi * k / 3.0) - shift for k in range(3)]


def carlson_calls(state: list[np.ndarray]) -> dict[str, list[np.ndarray]]:
    """The arguments of every ``elliprf`` and ``elliprj`` call of one ``nutation(*state)``,
    concatenated: ``{"elliprf": [x, y, z], "elliprj": [x, y, z, p]}``."""
    calls: dict[str, list] = {"elliprf": [], "elliprj": []}

    def recorder(name, function):
        def record(*args):
            calls[name].append([np.broadcast_to(x, np.shape(args[1])) for x in args])
            return function(*args)
        return record

    nutation_module.elliprf = recorder("elliprf", elliprf)
    nutation_module.elliprj = recorder("elliprj", elliprj)
    try:
        heavy_top.nutation(*state)
    finally:
        nutation_module.elliprf, nutation_module.elliprj = elliprf, elliprj
    return {name: [np.concatenate(column) for column in zip(*args, strict=True)]
            for name, args in calls.items()}


def floor_parts(state, calls) -> dict[str, Callable[[], object]]:
    """The floor's three parts, each a call on arrays prepared beforehand."""
    cubic = nutation_module.nutation_cubic(*state)
    coefficients = (cubic.B, cubic.c2, cubic.c1, cubic.c0)
    return {"trigonometric roots": lambda: trigonometric_roots(*coefficients),
            "elliprf": lambda: elliprf(*calls["elliprf"]),
            "elliprj": lambda: elliprj(*calls["elliprj"])}


def where_time_goes(state) -> dict[str, float]:
    """One call of ours with clocks around the pieces it calls: wall seconds per stage."""
    spent = dict.fromkeys(STAGES, 0.0)
    originals = {(heavy_top, "_state"): "validation", (heavy_top, "nutation_cubic"): "cubic",
                 (heavy_top, "nutation_integrals"): "integrals",
                 (nutation_module, "elliprf"): "carlson", (nutation_module, "elliprj"): "carlson"}
    saved = {key: getattr(*key) for key in originals}

    def clocked(function, stage):
        def run(*args):
            start = time.perf_counter()
            try:
                return function(*args)
            finally:
                spent[stage] += time.perf_counter() - start
        return run

    for (module, name), stage in originals.items():
        setattr(module, name, clocked(saved[module, name], stage))
    try:
        start = time.perf_counter()
        heavy_top.nutation(*state)
        total = time.perf_counter() - start
    finally:
        for (module, name), function in saved.items():
            setattr(module, name, function)
    spent["integrals"] -= spent["carlson"]
    spent["rest"] = total - sum(spent[s] for s in STAGES if s != "rest")
    return spent


def measure(tops: int, rounds: int, command: str) -> dict:
    """Every timing of the run, as the record holds them."""
    record = {"bench": BENCH, "command": command, "date": speed_page.now(),
              "machine": speed_page.machine(), "tops": tops, "rounds": rounds}
    state = random_tops(tops)
    calls = carlson_calls(state)
    record["calls"] = {name: int(args[1].size) for name, args in calls.items()}
    parts = floor_parts(state, calls)

    def floor():
        for part in parts.values():
            part()

    heavy_top.nutation(*state)  # warm
    record["times"] = speed_page.interleaved(
        {"floor": floor, "ours": lambda: heavy_top.nutation(*state)}, rounds)
    record["floor_parts"] = speed_page.interleaved(parts, rounds)
    record["stages"] = [where_time_goes(state) for _ in range(rounds)]
    record["load_after"] = [round(x, 2) for x in os.getloadavg()]
    return record


def render(record: dict) -> list[str]:
    """The page's text, from the record alone."""
    floor, ours = record["times"]["floor"], record["times"]["ours"]
    ratio = {clock: speed_page.median(ours, clock) / speed_page.median(floor, clock)
             for clock in ("wall", "cpu")}
    parts = ", ".join(f"{name} {speed_page.seconds(speed_page.median(times))}"
                      for name, times in record["floor_parts"].items())
    stages = "; ".join(
        f"{STAGE_NAMES[s]} {speed_page.seconds(statistics.median(r[s] for r in record['stages']))}"
        for s in STAGES)
    calls = record["calls"]
    return [
        speed_page.header(record),
        "",
        f"`solver.heavy_top.nutation` on {record['tops']:,} random tops (validation, the cubic,"
        " its roots, the Carlson integrals, the NaN of what does not exist), against its floor:"
        f" numpy's trigonometric roots of the same {record['tops']:,} cubics, and scipy's "
        f"`elliprf` ({calls['elliprf']:,} calls) and `elliprj` ({calls['elliprj']:,} calls) on "
        "exactly the arguments the solver passes them, recorded from the same run. Medians of "
        f"{record['rounds']} rounds, floor and ours in turn:",
        "",
        "| clock | floor | `nutation` | `nutation` / floor |",
        "|---|---|---|---|",
        *(f"| {label} | {speed_page.seconds(speed_page.median(floor, clock))} | "
          f"{speed_page.seconds(speed_page.median(ours, clock))} | **{ratio[clock]:.2f}** |"
          for clock, label in (("wall", "wall time"), ("cpu", "CPU time of the process"))),
        "",
        f"The target: at most 1.5. The floor's parts: {parts}. Where `nutation`'s time "
        f"goes (one call per round with a clock around each piece, medians): {stages}.",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tops", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--record", type=Path, help="write every timing into this JSON file")
    parser.add_argument("--page", type=Path, help=f"write the text into this page's {BENCH} "
                        "block (docs/speed.md)")
    args = parser.parse_args()
    speed_page.check_page(args.page, BENCH)
    command = " ".join(["python benchmarks/bench_heavy_top.py", *sys.argv[1:]])
    record = measure(args.tops, args.rounds, command)
    if args.record:
        speed_page.write_record(args.record, record)
    lines = render(record)
    if args.page:
        speed_page.write_block(args.page, BENCH, lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
