"""Benchmark: turning points + nutation period + mean precession for 10^5 heavy tops (R17, R20).

One vectorised call of the public ``solver.heavy_top.nutation`` (validation, the cubic, its roots,
Carlson's R_F/R_J), and for comparison the bare numerical core in ``solver.nutation``, over random,
physically sensible tops: I1 about the tip in [1e-4, 1e-2] kg m², I3 in [0.1, 1.9]·I1,
Mgl in [1e-3, 1] J, β0 in (0, π), α̇0 ~ N(0, 5²), β̇0 ~ N(0, 2²) (zero for 30 %),
ω3 log-uniform in [1, 5000] rad/s with random sign. Run by hand::

    python benchmarks/bench_heavy_top.py [N] [REPEATS]
"""

from __future__ import annotations

import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from solver.heavy_top import nutation
from solver.nutation import (
    nutation_cubic,
    nutation_period_of,
    precession_angle_of,
)


def random_tops(n: int, seed: int = 0) -> list[np.ndarray]:
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


def core_pass(state: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    cubic = nutation_cubic(*state)
    period = nutation_period_of(cubic)
    return cubic.beta[:, :2], period, precession_angle_of(cubic) / period


def public_pass(state: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    out = nutation(*state)
    return out["beta1"], out["nutation_period"], out["mean_precession_rate"]


def timed(fn, state, repeats: int) -> tuple[list[float], tuple]:
    result = fn(state)  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn(state)
        times.append(time.perf_counter() - start)
    return times, result


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    state = random_tops(n)
    print(f"heavy top: turning points + T_nut + <alpha_dot> for {n} tops, {repeats} repeats")
    for label, fn in (("solver.heavy_top.nutation (public, validated)", public_pass),
                      ("solver.nutation core (no validation)", core_pass)):
        times, (_, period, mean) = timed(fn, state, repeats)
        median = statistics.median(times)
        print(f"  {label}: median {median * 1e3:.1f} ms, per case {median / n * 1e9:.0f} ns"
              f"   (min {min(times) * 1e3:.1f} ms, max {max(times) * 1e3:.1f} ms);"
              f" finite periods {np.isfinite(period).sum()} / {n},"
              f" finite means {np.isfinite(mean).sum()} / {n}")
    print(f"  machine: {platform.platform()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, Python {platform.python_version()}, numpy {np.__version__}")


if __name__ == "__main__":
    main()
