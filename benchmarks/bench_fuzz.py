"""Fuzz the heavy-top solver against the high-precision reference: ``eulertop bench --fuzz``.

    python benchmarks/bench_fuzz.py N [--seed S] [--jobs J] [--out docs]

Same as ``eulertop bench --fuzz N --seed S --jobs J --out DIR``; see ``solver/bench/fuzz.py``.
"""

from __future__ import annotations

import sys

from eulertop.cli import main

if __name__ == "__main__":
    args = sys.argv[1:]
    if not args or not args[0].isdigit():
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(["bench", "--fuzz", *args]))
