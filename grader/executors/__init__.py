"""Where :func:`grader.grade_one.grade_one` runs (floor 6): this machine's threads and warm
kernels (:mod:`local`) or a Dask cluster (:mod:`dask`). Each hands every record back to the
run (``publish``), the one writer of records.

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations


class Interrupted(KeyboardInterrupt):
    """Ctrl-C: the run stopped; ``graded`` of ``total`` submissions have their records. Those
    in flight were stopped and have none (the next run grades them)."""

    def __init__(self, graded: int, total: int) -> None:
        super().__init__(f"{graded} of {total} graded")
        self.graded, self.total = graded, total
