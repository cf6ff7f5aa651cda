"""What ``eulertop bench`` measures: work-precision, turning-point methods, invariant drift,
ranking, against independent references (composed in :func:`solver.bench.cli.run_bench`).

Pipeline (one stage, one input, one output):
measure (``work_precision``, ``scenes_table``, ``turning_point_methods``, ``invariant_drift``,
``solver.bench.stability``, ``fast_top_errors``) → rows (dicts) → CSV + PNG per chart and
``run.json`` → ``summary.md`` and, with ``--page FILE``, FILE's block, both rendered by
``solver.bench.summary`` from those files alone (so a test can render them again).

Errors are against references computed *independently* of the code under test: mpmath at 40
digits evaluating Landau–Lifshitz's R10 (``mp.ellipfun``) and R20 (``mp.polyroots`` of the cubic,
``mp.ellipf`` for the phase). Times are medians of repeats of ``time.perf_counter`` (3 repeats
for runs under 0.5 s, else 1 — recorded per row); every ratio in the summary is from one run.

Importing this module is cheap; matplotlib is imported by :func:`solver.bench.cli.run_bench`
only (Agg backend).
"""

from __future__ import annotations

import itertools
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import mpmath as mp
import numpy as np

from solver.asymmetric_top import asymmetric_top_period
from solver.heavy_top import (
    constants_of_motion,
    effective_potential,
    nutation_period,
    steady_precession_rates,
    turning_points,
)
from solver.methods import METHODS, solve
from solver.scenes import FreeBody, HeavyBody, choose_model
from solver.torque_free import invariants

__all__ = [
    "FREE_SCENE",
    "HEAVY_SCENE",
    "BenchConfig",
    "free_reference",
    "heavy_reference",
    "invariant_drift",
    "mp_cubic_roots",
    "rank_at_accuracy",
    "turning_point_methods",
    "work_precision",
]

# I1 < I2 < I3, L² > 2T I2 and ω2(0) = 0: Landau–Lifshitz's R10 as printed, phase zero.
FREE_SCENE = FreeBody(1.0, 2.0, 3.0, (0.5, 0.0, 1.0))
# A looping heavy top with nutation period ≈ 4.1 s.
HEAVY_SCENE = HeavyBody(1.0, 1.0, 0.6, 1.0, 0.8, 0.2, 0.5, 3.0)


@dataclass(frozen=True)
class BenchConfig:
    """How much to measure. ``full()`` is the documented run; ``quick()`` the test's (< 1 min)."""

    free_periods: int
    heavy_periods: int
    drift_periods: int
    rtols: tuple[float, ...]
    radau_min_rtol: float  # Radau's cost explodes below this; the sweep stops there
    steps_per_period: tuple[int, ...]
    drift_rtol: float = 1e-6
    drift_steps_per_period: int = 25
    drift_samples: int = 60
    radau_drift_periods: int = 1000  # Radau at 1e4 periods alone took 7 min (measured)
    samples: int = 8  # sampled times per work-precision error (never period multiples)
    horizons: tuple[int, ...] = (1, 10, 100, 1000)  # periods, for the scenes table

    @classmethod
    def full(cls) -> BenchConfig:
        return cls(100, 50, 10_000, tuple(10.0 ** -np.arange(3, 15)), 1e-9,
                   (10, 20, 40, 80, 160, 320, 640))

    @classmethod
    def quick(cls) -> BenchConfig:
        return cls(10, 5, 100, (1e-3, 1e-6, 1e-9, 1e-12), 1e-6, (20, 80, 320),
                   drift_samples=20, samples=4, horizons=(1, 10))


# --- independent references (mpmath, 40 digits) ---------------------------------------------


def free_reference(scene: FreeBody, t: float) -> np.ndarray:
    """ω(t) from Landau–Lifshitz §37 (R10) in mpmath; needs I1 < I2 < I3, L² > 2T I2, ω2(0) = 0
    and ω1(0), ω3(0) > 0 (then ω = (A1 cn, A2 sn, A3 dn)(λt), no phase)."""
    with mp.workdps(40):
        I1, I2, I3 = (mp.mpf(x) for x in (scene.I1, scene.I2, scene.I3))
        w1, w2, w3 = (mp.mpf(x) for x in scene.omega0)
        if not (I1 < I2 < I3 and w2 == 0 and w1 > 0 and w3 > 0):
            raise ValueError("scene: the reference covers only Landau–Lifshitz's printed case")
        two_T = I1 * w1**2 + I3 * w3**2
        L2 = I1**2 * w1**2 + I3**2 * w3**2
        lam = mp.sqrt((I3 - I2) * (L2 - two_T * I1) / (I1 * I2 * I3))
        m = (I2 - I1) * (two_T * I3 - L2) / ((I3 - I2) * (L2 - two_T * I1))
        u = lam * mp.mpf(t)
        amp = [mp.sqrt((two_T * I3 - L2) / (I1 * (I3 - I1))),
               mp.sqrt((two_T * I3 - L2) / (I2 * (I3 - I2))),
               mp.sqrt((L2 - two_T * I1) / (I3 * (I3 - I1)))]
        funcs = [mp.ellipfun(name, u, m=m) for name in ("cn", "sn", "dn")]
        return np.array([float(a * f) for a, f in zip(amp, funcs, strict=True)])


def mp_cubic_roots(state: tuple[float, ...]) -> list:
    """Roots u1 ≤ u2 ≤ u3 of R17's cubic from the exact binary state, in mpmath (40 digits)."""
    I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(x) for x in state)
    c, s = mp.cos(b0), mp.sin(b0)
    pg = I3 * (ad * c + gd)
    pa = I1 * ad * s**2 + pg * c
    E = (I1 * (bd**2 + ad**2 * s**2)) / 2 + Mgl * c
    a, b, A, B = pg / I1, pa / I1, 2 * E / I1, 2 * Mgl / I1
    roots = mp.polyroots([B, -(A + a * a), 2 * a * b - B, A - b * b], maxsteps=400,
                         extraprec=400)
    return sorted(mp.re(r) for r in roots)


def heavy_reference(scene: HeavyBody, t: float) -> float:
    """``u(t) = u1 + (u2 − u1) sn²(λt + φ, k)`` (R20) in mpmath, ``φ = ∓F(ψ0 | k²)``,
    ``sin²ψ0 = (u0 − u1)/(u2 − u1)``, sign opposite to ``β̇0``."""
    with mp.workdps(40):
        state = scene.heavy_top_state()
        u1, u2, u3 = mp_cubic_roots(state)
        B = 2 * mp.mpf(scene.Mgl) / mp.mpf(scene.I1)
        u0 = mp.cos(mp.mpf(scene.beta0))
        m = (u2 - u1) / (u3 - u1)
        psi0 = mp.asin(mp.sqrt(min(max((u0 - u1) / (u2 - u1), 0), 1)))
        phase = (-1 if scene.beta_dot0 > 0 else 1) * mp.ellipf(psi0, m)
        sn = mp.ellipfun("sn", mp.sqrt(B * (u3 - u1)) / 2 * mp.mpf(t) + phase, m=m)
        return float(u1 + (u2 - u1) * sn**2)


# --- measurements ----------------------------------------------------------------------------


def _timed(call: Callable[[], object]) -> tuple[object, float, int]:
    """(result, median wall time over repeats, repeats): 3 repeats if one run is < 0.5 s."""
    start = time.perf_counter()
    result = call()
    times = [time.perf_counter() - start]
    if times[0] < 0.5:
        for _ in range(2):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
    return result, statistics.median(times), len(times)


def _controls(method: str, period: float, config: BenchConfig) -> list[float | None]:
    control = METHODS[method].control
    if control == "rtol":
        floor = config.radau_min_rtol if method == "Radau" else 0.0
        return [r for r in config.rtols if r >= floor]
    if control == "step":
        return [period / n for n in config.steps_per_period]
    return [None]


SAMPLE_PHASE = 0.3819660112501051  # (3 − √5)/2: sample times are never period multiples


def sample_times(period: float, n_periods: float, samples: int) -> np.ndarray:
    """``samples`` times spread over ``(0, n_periods · period)``, each at a fraction
    ``SAMPLE_PHASE`` past a whole number of periods' grid (never a period multiple, where
    periodic errors vanish and would flatter a method), the last one within the horizon."""
    k = np.arange(samples) + SAMPLE_PHASE
    return period * n_periods * k / samples


def work_precision(scene, period: float, n_periods: int, reference: np.ndarray,
                   config: BenchConfig, times: np.ndarray | None = None) -> list[dict]:
    """Error over sampled times against ``reference`` (one row per time), with cost, for every
    method that answers ``scene`` and every control of the sweep.

    Error: the maximum over the sampled ``times`` (default ``sample_times``) of ``|ω(t) −
    ω_ref(t)|_∞ / |ω0|`` (free body) or ``|cos β(t) − cos β_ref(t)|`` (heavy body) — named
    ``ERROR_NAMES[kind]`` on the charts.
    """
    if times is None:
        times = sample_times(period, n_periods, config.samples)
    grid = np.r_[0.0, times]
    scale = np.linalg.norm(scene.omega0) if isinstance(scene, FreeBody) else 1.0
    rows = []
    for name, method in METHODS.items():
        if scene.kind not in method.kinds:
            continue
        for control in _controls(name, period, config):
            traj, seconds, repeats = _timed(lambda n=name, c=control: solve(scene, grid, n, c))
            error = (float(np.max(np.abs(np.asarray(traj.y[1:]) - reference))) / scale
                     if traj.success and len(traj.t) == len(grid) else math.nan)
            rows.append({"method": name, "control": control, "error": error,
                         "seconds": seconds, "repeats": repeats, "nfev": traj.nfev,
                         "nsteps": traj.nsteps, "success": traj.success})
    return rows


ERROR_NAMES = {
    "free": "max over sampled t of |ω(t) − ω_ref(t)|∞ / |ω0|",
    "heavy": "max over sampled t of |cos β(t) − cos β_ref(t)|",
}


def stall_points(rows: list[dict]) -> dict[str, dict]:
    """For each adaptive method, the smallest error its sweep reached and at which control:
    where tightening stops paying (the method stalls) is read off here, not guessed."""
    out = {}
    for name in dict.fromkeys(r["method"] for r in rows):
        pts = [r for r in rows if r["method"] == name and r["control"] is not None
               and np.isfinite(r["error"])]
        if pts:
            best = min(pts, key=lambda r: r["error"])
            out[name] = {"error": best["error"], "control": best["control"],
                         "tightest": min(r["control"] for r in pts)}
    return out


def _np_roots_betas(state) -> tuple[float, float]:
    pa, pg, e = constants_of_motion(*state)
    I1, Mgl = state[0], state[2]
    a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * Mgl / I1
    u = np.sort(np.roots([B, -A - a * a, 2 * a * b - B, A - b * b]).real)
    return float(np.arccos(np.clip(u[1], -1, 1))), float(np.arccos(np.clip(u[0], -1, 1)))


def _brentq_betas(state) -> tuple[float, float]:
    from scipy.optimize import brentq

    pa, pg, e = constants_of_motion(*state)
    I1, Mgl, b0 = state[0], state[2], state[3]

    def g(beta):
        return float(effective_potential(beta, I1, Mgl, pa, pg)) - float(e)

    lo, hi = 1e-12, math.pi - 1e-12
    return (brentq(g, lo, b0, xtol=1e-16, rtol=8.9e-16),
            brentq(g, b0, hi, xtol=1e-16, rtol=8.9e-16))


def _integrated_betas(state) -> tuple[float, float]:
    """Integrate R14 in Euler angles (DOP853, rtol 1e-10) until β̇ = 0 twice."""
    from scipy.integrate import solve_ivp

    from solver.integrators import heavy_top_euler_rhs

    rhs = heavy_top_euler_rhs(state[0], state[1], state[2])

    def turning(t, y):
        return y[4]

    turning.terminal = 2
    period = float(nutation_period(*state))
    sol = solve_ivp(rhs, (0.0, 2.0 * period), [0.0, state[3], 0.0, *state[4:]],
                    method="DOP853", rtol=1e-10, atol=1e-12, events=turning)
    betas = sorted(float(y[1]) for y in sol.y_events[0])
    return betas[0], betas[-1]


TURNING_POINT_METHODS: dict[str, Callable] = {
    "ours (cubic in w = u − u0)": lambda s: tuple(float(x) for x in turning_points(*s)),
    "np.roots (expanded cubic)": _np_roots_betas,
    "brentq on V_eff": _brentq_betas,
    "integrate to β̇ = 0": _integrated_betas,
}


def turning_point_cases() -> dict[str, tuple[float, ...]]:
    """Generic, fast and nearly steady tops (all with β̇0 ≠ 0, so every method applies)."""
    slow, _ = steady_precession_rates(1.0, 0.6, 1.0, 0.8, 0.6 * 60.0)
    return {
        "generic": HEAVY_SCENE.heavy_top_state(),
        "fast top (ω3 = 200)": (1.0, 0.6, 1.0, 0.8, 0.0, 0.1, 200.0),
        "near steady (β̇0 = 1e-6)": (1.0, 0.6, 1.0, 0.8, float(slow), 1e-6,
                                     60.0 - float(slow) * math.cos(0.8)),
    }


def turning_point_methods() -> list[dict]:
    """Max error of (β1, β2) against mpmath roots, and median time, per case and method."""
    rows = []
    for case, state in turning_point_cases().items():
        with mp.workdps(40):
            u1, u2, _ = mp_cubic_roots(state)
            ref = (float(mp.acos(u2)), float(mp.acos(u1)))
        for name, method in TURNING_POINT_METHODS.items():
            try:
                (b1, b2), seconds, repeats = _timed(lambda m=method, s=state: m(s))
                error = max(abs(b1 - ref[0]), abs(b2 - ref[1]))
            except (ValueError, IndexError) as exc:  # no bracket / no event: a result, not a crash
                error, seconds, repeats = math.nan, math.nan, 0
                print(f"eulertop bench: {name} failed on {case}: {exc}")
            rows.append({"case": case, "method": name, "error_rad": error,
                         "seconds": seconds, "repeats": repeats})
    return rows


def invariant_drift(scene: FreeBody, period: float, config: BenchConfig) -> list[dict]:
    """Relative errors of T and L² at log-spaced times up to ``drift_periods`` periods
    (Radau: ``radau_drift_periods``, its cost being ~40× the others')."""
    T0, L20 = invariants(scene.I1, scene.I2, scene.I3, scene.omega0)
    rows = []
    for name, method in METHODS.items():
        if scene.kind not in method.kinds:
            continue
        last = min(config.drift_periods, config.radau_drift_periods) if name == "Radau" else (
            config.drift_periods)
        # never at period multiples (where a periodic energy error vanishes): + SAMPLE_PHASE
        times = period * (np.unique(np.round(np.geomspace(1.0, last, config.drift_samples)))
                          - 1 + SAMPLE_PHASE)
        control = {"rtol": config.drift_rtol, "step": period / config.drift_steps_per_period,
                   None: None}[method.control]
        start = time.perf_counter()
        traj = solve(scene, times, name, control)
        seconds = time.perf_counter() - start
        T, L2 = invariants(scene.I1, scene.I2, scene.I3, traj.y)
        for t, dT, dL in zip(traj.t, np.abs(T / T0 - 1), np.abs(L2 / L20 - 1), strict=True):
            rows.append({"method": name, "control": control, "periods": t / period,
                         "energy_error": float(dT), "L2_error": float(dL),
                         "seconds_total": seconds})
    return rows


def _near_pole_scene() -> HeavyBody:
    """A stable spinning top (ω3 = 10 > ω_c) whose axis passes within ~3e-4 rad of the vertical
    (p_α = p_γ (1 + 1e-3))."""
    b0, w3 = 0.3, 10.0
    ad0 = 0.6 * w3 * (1 - math.cos(b0)) / math.sin(b0) ** 2 * (1 + 1e-3)
    return HeavyBody(1.0, 1.0, 0.6, 1.0, b0, ad0, 0.0, w3 - ad0 * math.cos(b0))


def _separatrix_scene() -> FreeBody:
    """I = (1, 2, 3), ω0 = (1, 0, w3) with L² − 2T I2 = 1e-6 relative above the separatrix
    (``I1 (I2 − I1) w1² = I3 (I3 − I2) w3²`` at ``w3 = 1/√3``)."""
    return FreeBody(1.0, 2.0, 3.0, (1.0, 0.0, (1 + 1e-6) / math.sqrt(3.0)))


SYMMETRIC_SCENE = FreeBody(2.0, 2.0, 3.0, (0.5, 0.0, 1.0))


def free_symmetric_reference(scene: FreeBody, t: float) -> np.ndarray:
    """ω(t) of a free symmetric top (``I1 = I2``, Landau–Lifshitz §33) in mpmath: ω3 constant,
    ``ω1 + iω2`` turning at ``Ω = (I3 − I1) ω3 / I1``."""
    with mp.workdps(40):
        I1, I3 = mp.mpf(scene.I1), mp.mpf(scene.I3)
        w1, w2, w3 = (mp.mpf(x) for x in scene.omega0)
        turned = mp.mpc(w1, w2) * mp.expj((I3 - I1) * w3 / I1 * mp.mpf(t))
        return np.array([float(turned.real), float(turned.imag), float(w3)])


def scene_states() -> dict[str, FreeBody | HeavyBody]:
    """The initial states of the scenes table: generic, near a pole, near the separatrix, fast,
    and a free symmetric top (R8)."""
    return {
        "heavy, generic": HEAVY_SCENE,
        "heavy, near the vertical": _near_pole_scene(),
        "heavy, fast (ω3 = 200)": HeavyBody(1.0, 1.0, 0.6, 1.0, 0.8, 0.0, 0.1, 200.0),
        "free, generic": FREE_SCENE,
        "free, near the separatrix": _separatrix_scene(),
        "free, symmetric (I1 = I2)": SYMMETRIC_SCENE,
    }


def _period_of(scene) -> float:
    if isinstance(scene, FreeBody) and scene.kind == "free_symmetric":
        return 2 * math.pi * scene.I1 / abs((scene.I3 - scene.I1) * scene.omega0[2])
    if isinstance(scene, FreeBody):
        return float(asymmetric_top_period(scene.I1, scene.I2, scene.I3, scene.omega0))
    return float(nutation_period(*scene.heavy_top_state()))


def reference_at(scene, times: np.ndarray) -> np.ndarray:
    if isinstance(scene, FreeBody) and scene.kind == "free_symmetric":
        return np.array([free_symmetric_reference(scene, float(t)) for t in times])
    if isinstance(scene, FreeBody):
        return np.array([free_reference(scene, float(t)) for t in times])
    return np.array([heavy_reference(scene, float(t)) for t in times])


SCENE_RTOL = 1e-13


def scenes_table(config: BenchConfig) -> list[dict]:
    """DOP853 at rtol ``SCENE_RTOL`` and the exact model, per initial state and horizon
    (``config.horizons`` periods), error over ``config.samples`` sampled times."""
    rows = []
    for label, scene in scene_states().items():
        period = _period_of(scene)
        exact = choose_model(scene)
        for horizon in config.horizons:
            times = sample_times(period, horizon, config.samples)
            reference = reference_at(scene, times)
            grid = np.r_[0.0, times]
            scale = np.linalg.norm(scene.omega0) if isinstance(scene, FreeBody) else 1.0
            for method, control in (("DOP853", SCENE_RTOL), (exact, None)):
                traj, seconds, _ = _timed(lambda m=method, c=control, sc=scene, g=grid:
                                          solve(sc, g, m, c))
                error = (float(np.max(np.abs(np.asarray(traj.y[1:]) - reference))) / scale
                         if traj.success else math.nan)
                rows.append({"scene": label, "periods": horizon, "method": method,
                             "control": control, "error": error, "seconds": seconds,
                             "nfev": traj.nfev})
    return rows


FAST_TOP_EPSILONS = (1e-4, 1e-3, 0.01, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5)


def fast_top_errors() -> list[dict]:
    """R21's approximation against the exact steady rates: relative errors of the slow and fast
    rate (``solver.scenes.fast_top_error``) for ``ε`` in ``FAST_TOP_EPSILONS`` (``ε = ½`` is R19's
    critical spin), at β0 = 0 and π/3; ``ε`` recomputed by ``fast_top_parameter`` from the top."""
    from solver.scenes import fast_top_error, fast_top_parameter

    I1, I3, Mgl = 1.0, 0.6, 1.0
    rows = []
    for eps in FAST_TOP_EPSILONS:
        p_gamma = math.sqrt(2 * I1 * Mgl / eps)
        for label, beta0 in (("0", 0.0), ("π/3", math.pi / 3)):
            slow, fast = fast_top_error(I1, I3, Mgl, beta0, p_gamma)
            rows.append({"epsilon": float(fast_top_parameter(I1, I3, Mgl, p_gamma / I3)),
                         "beta0": label, "beta0_rad": beta0, "slow_error": float(slow),
                         "fast_error": float(fast)})
    return rows


def rank_at_accuracy(rows: list[dict], target: float) -> list[dict]:
    """Cost of each method to reach ``target`` error, by log–log interpolation of its sweep.

    Returns rows sorted by wall time: method, seconds, nfev at ``target`` (NaN if the sweep
    never reached it). Exact models (a single point) qualify if their error ≤ target.
    """
    ranked = []
    for name in dict.fromkeys(r["method"] for r in rows):
        pts = sorted((r["error"], r["seconds"], r["nfev"]) for r in rows
                     if r["method"] == name and np.isfinite(r["error"]) and r["error"] > 0)
        exact = [r for r in rows if r["method"] == name and r["control"] is None]
        if exact:
            ok = exact[0]["error"] <= target
            ranked.append({"method": name, "seconds": exact[0]["seconds"] if ok else math.nan,
                           "nfev": 0 if ok else math.nan})
            continue
        ranked.append({"method": name, **_interpolate_cost(pts, target)})
    return sorted(ranked, key=lambda r: (math.isnan(r["seconds"]), r["seconds"]))


def _interpolate_cost(pts, target) -> dict:
    """Interpolate log(cost) against log(error) between the sweep points bracketing target."""
    for (e_lo, s_lo, n_lo), (e_hi, s_hi, n_hi) in itertools.pairwise(pts):
        if e_lo <= target <= e_hi:
            w = (math.log(target) - math.log(e_hi)) / (math.log(e_lo) - math.log(e_hi))
            return {"seconds": math.exp((1 - w) * math.log(s_hi) + w * math.log(s_lo)),
                    "nfev": math.exp((1 - w) * math.log(max(n_hi, 1)) + w * math.log(max(n_lo, 1)))}
    if pts and pts[0][0] <= target:  # only one point, already good enough
        return {"seconds": pts[0][1], "nfev": pts[0][2]}
    return {"seconds": math.nan, "nfev": math.nan}


# --- output ----------------------------------------------------------------------------------
