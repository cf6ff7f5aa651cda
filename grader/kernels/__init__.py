"""Kernels (floor 2): the contract every kernel keeps (:mod:`base`), a cold ipykernel
(:mod:`local`), the warm pool of forked kernels (:mod:`pool`, with the scripts :mod:`zygote` and
:mod:`cell_server` that run in the sandbox, and :mod:`channel`, the grader's end of their
socket), what a class preloads (:mod:`preload`), the container mode's kernels
(:mod:`container`) and the choice of isolation tier (:mod:`isolation`). Nothing here knows
about verdicts: that is :mod:`grader.execute`'s.

Floor 2 of grader/ (one kernel; grader/API.md).
"""
