"""Hosted autograders (issue 15): Gradescope and PrairieLearn, thin adapters over
:func:`grader.grade_one.grade_one`.

Each platform has one module for its paths, metadata and results format
(:mod:`grader.hosted.gradescope`, :mod:`grader.hosted.prairielearn`); both grade through
:func:`grader.hosted.grading.grade_notebook`, which picks how the kernel is confined
(:mod:`grader.kernels.container` where bubblewrap cannot start). ``eulertop package``
(:mod:`grader.hosted.package`) builds what each platform takes. ``docs/hosted.md`` describes the
formats and the documents they follow.

Floor 8 of grader/ (front ends; grader/API.md).
"""
