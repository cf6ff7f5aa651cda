"""``eulertop bench``: run the measurements of :mod:`solver.bench.work_precision`, write their CSV
files and charts, and render the summary (:mod:`solver.bench.summary`); ``--fuzz`` runs the
solver against its mpmath reference instead (:mod:`solver.bench.fuzz`)."""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from solver.asymmetric_top import asymmetric_top_period
from solver.bench.work_precision import (
    ERROR_NAMES,
    FREE_SCENE,
    HEAVY_SCENE,
    TURNING_POINT_METHODS,
    BenchConfig,
    fast_top_errors,
    invariant_drift,
    reference_at,
    sample_times,
    scenes_table,
    stall_points,
    turning_point_methods,
    work_precision,
)
from solver.heavy_top import nutation_period


def _write_csv(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _plot_work_precision(plt, rows, cost: str, title: str, path: Path,
                         error_name: str = "error") -> None:
    fig, ax = plt.subplots(figsize=(7, 5))
    for name in dict.fromkeys(r["method"] for r in rows):
        # in sweep order (loose → tight), not sorted by cost: a noisy timing must not reorder
        pts = [(r[cost], r["error"]) for r in rows if r["method"] == name
               and np.isfinite(r["error"]) and r[cost] > 0]
        if not pts:
            continue
        x, y = zip(*pts, strict=True)
        ax.loglog(x, np.maximum(y, 1e-17), "o-" if len(x) > 1 else "*", label=name,
                  markersize=5 if len(x) > 1 else 12)
    ax.set_xlabel({"seconds": "median wall time (s)", "nfev": "right-hand-side evaluations"}[cost])
    ax.set_ylabel(error_name)
    stall = stall_points(rows).get("DOP853")
    if stall is not None:
        ax.axhline(stall["error"], color="grey", lw=0.6, ls=":")
        ax.annotate(f"DOP853's floor {stall['error']:.1e} (rtol {stall['control']:.0e}; "
                    f"swept to {stall['tightest']:.0e})", xy=(0.02, 0.02),
                    xycoords="axes fraction", fontsize=7)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_drift(plt, rows, path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharex=True)
    for name in dict.fromkeys(r["method"] for r in rows):
        sub = [r for r in rows if r["method"] == name]
        x = [r["periods"] for r in sub]
        for ax, key in zip(axes, ("energy_error", "L2_error"), strict=True):
            ax.loglog(x, np.maximum([r[key] for r in sub], 1e-17), label=name)
    for ax, label in zip(axes, ("|T/T0 − 1|", "|L²/L²0 − 1|"), strict=True):
        ax.set_xlabel("time (periods of ω)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Invariant drift, free asymmetric top, sampled off period multiples "
                 "(floor 1e-17 = exact to rounding)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_turning_points(plt, rows, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 5))
    for name in TURNING_POINT_METHODS:
        sub = [r for r in rows if r["method"] == name]
        ax.loglog([r["seconds"] for r in sub], [max(r["error_rad"], 1e-17) for r in sub], "o",
                  label=name, markersize=7)
    ax.set_xlabel("median wall time (s)")
    ax.set_ylabel("max error of β1, β2 (rad)")
    ax.set_title("Turning points: three tops (generic, fast, near steady)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def add_bench_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop bench [--out DIR] [--quick] [--page FILE]`` or ``eulertop bench --fuzz N
    [--seed S]``."""
    parser.add_argument("--out", type=Path, default=Path("bench-results"),
                        help="directory for the PNG charts, their CSV data and summary.md "
                        "(with --fuzz: for fuzz.md)")
    parser.add_argument("--page", type=Path, metavar="FILE",
                        help="also write the measured text into the Markdown page FILE between "
                        "the lines '<!-- eulertop bench: begin -->' and "
                        "'<!-- eulertop bench: end -->' (the documentation site's "
                        "docs/speed.md; the same text opens summary.md)")
    parser.add_argument("--quick", action="store_true",
                        help="a reduced sweep (< 1 min; what the tests run)")
    parser.add_argument("--fuzz", type=int, metavar="N",
                        help="instead of the charts: fuzz the heavy-top solver (API and batch "
                        "CLI) on N random tops against the high-precision reference, write "
                        "OUT/fuzz.md (regions × quantities, worst errors); exit 1 on a failure")
    parser.add_argument("--seed", type=int, help="seed of the fuzz draw (default: a fresh one, "
                        "printed)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                        help="processes computing the fuzz references (default: all cores)")


def run_bench(args: argparse.Namespace) -> int:
    """Measure everything, write charts, CSVs and ``summary.md`` into ``args.out``; or, with
    ``--fuzz N``, run :func:`solver.bench.fuzz.run_fuzz`."""
    if args.fuzz is not None:
        return _run_fuzz(args)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from solver.bench import summary as bench_summary

    page = getattr(args, "page", None)
    if page is not None:  # fail before minutes of measuring, not after
        try:
            bench_summary.replace_block(page.read_text(encoding="utf-8"), "", str(page))
        except (OSError, UnicodeDecodeError, bench_summary.BlockError) as exc:
            print(f"eulertop bench: --page {page}: {exc}", file=sys.stderr)
            return 2
    config = BenchConfig.quick() if args.quick else BenchConfig.full()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    command = " ".join(["eulertop bench", "--out", str(out), *(["--quick"] if args.quick else []),
                        *(["--page", str(page)] if page is not None else [])])
    load_before = os.getloadavg()
    start = time.perf_counter()
    free_period = float(asymmetric_top_period(FREE_SCENE.I1, FREE_SCENE.I2, FREE_SCENE.I3,
                                              FREE_SCENE.omega0))
    heavy_period = float(nutation_period(*HEAVY_SCENE.heavy_top_state()))
    free_times = sample_times(free_period, config.free_periods, config.samples)
    heavy_times = sample_times(heavy_period, config.heavy_periods, config.samples)
    stages = {
        "free": ("free asymmetric top, work-precision", lambda: work_precision(
            FREE_SCENE, free_period, config.free_periods,
            reference_at(FREE_SCENE, free_times), config, free_times)),
        "heavy": ("heavy top, work-precision", lambda: work_precision(
            HEAVY_SCENE, heavy_period, config.heavy_periods,
            reference_at(HEAVY_SCENE, heavy_times), config, heavy_times)),
        "scenes": ("initial states × horizons", lambda: scenes_table(config)),
        "turning": ("turning points, four ways", turning_point_methods),
        "drift": ("invariant drift", lambda: invariant_drift(FREE_SCENE, free_period, config)),
        "stability": ("stability battery", _stability_battery),
        "fast_top": ("fast-top approximation (R21)", fast_top_errors),
    }
    results = {}
    for i, (key, (label, stage)) in enumerate(stages.items(), start=1):
        # Progress on stderr: the full run takes minutes.
        print(f"eulertop bench [{i}/{len(stages)}] {label} "
              f"({time.perf_counter() - start:.0f} s so far)", file=sys.stderr, flush=True)
        results[key] = stage()
    for key in ("free", "heavy"):
        _write_csv(out / f"wp_{key}.csv", results[key])
        for cost in ("seconds", "nfev"):
            name = "time" if cost == "seconds" else cost
            _plot_work_precision(plt, results[key], cost, f"Work-precision, {key} top",
                                 out / f"wp_{key}_{name}.png", ERROR_NAMES[key])
    _write_csv(out / "scenes.csv", results["scenes"])
    _write_csv(out / "turning_points.csv", results["turning"])
    _plot_turning_points(plt, results["turning"], out / "turning_points.png")
    _write_csv(out / "drift.csv", results["drift"])
    _plot_drift(plt, results["drift"], out / "drift.png")
    _write_csv(out / "stability.csv", results["stability"])
    _write_csv(out / "fast_top.csv", results["fast_top"])
    record = bench_summary.run_record(command, config, time.perf_counter() - start, load_before)
    (out / bench_summary.RUN_FILE).write_text(json.dumps(record, indent=1) + "\n")
    # The text is rendered from the files just written, as the tests re-render it.
    results, record = bench_summary.load_results(out)
    (out / "summary.md").write_text(bench_summary.summary_markdown(results, record))
    written = f"{out}/summary.md and charts"
    if page is not None:
        block = bench_summary.page_block(results, record, _relative_dir(out, page))
        text = page.read_text(encoding="utf-8")
        page.write_text(bench_summary.replace_block(text, block, str(page)), encoding="utf-8")
        written += f", and its block in {page}"
    print(f"eulertop bench: wrote {written} in {record['wall_seconds']:.0f} s")
    return 0


def _stability_battery() -> list[dict]:
    from solver.bench.stability import stability_battery

    return stability_battery()


def _relative_dir(out: Path, page: Path) -> str:
    """``out`` as a link prefix from ``page``'s folder (``"bench/"`` from ``docs/speed.md``)."""
    relative = os.path.relpath(out.resolve(), page.resolve().parent)
    return "" if relative == "." else Path(relative).as_posix() + "/"


def _run_fuzz(args: argparse.Namespace) -> int:
    import secrets

    from solver.bench.fuzz import run_fuzz

    if args.fuzz < 1:
        print("eulertop bench: --fuzz needs a positive number of cases", file=sys.stderr)
        return 2
    seed = args.seed if args.seed is not None else secrets.randbelow(2**31)
    print(f"eulertop bench: fuzz seed {seed}", flush=True)
    report = run_fuzz(args.fuzz, seed, jobs=max(1, args.jobs), out=args.out)
    print(f"eulertop bench: {args.fuzz} cases, seed {seed}, {report.total_failures} failure(s); "
          f"table in {args.out}/fuzz.md")
    return 1 if report.total_failures else 0
