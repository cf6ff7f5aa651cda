"""File formats of learning-management systems — no grading here.

Each LMS has one module (:mod:`~grader.lms.canvas`, :mod:`~grader.lms.moodle`,
:mod:`~grader.lms.blackboard`, :mod:`~grader.lms.gradescope`) holding what that LMS writes and
reads: its class list (a :class:`~grader.lms.classlist.ClassListFormat`), how its bulk download of
submissions names files (``recognises``, ``match_download``) and the gradebook file its import takes
(``write_import``). What they share is in :mod:`~grader.lms.classlist` (the roster record and
detection from the header), :mod:`~grader.lms.download` (turning matched files into the
``(student id, notebook)`` pairs of :mod:`grader.discover`) and :mod:`~grader.lms.archive`
(reading a downloaded ``.zip`` safely). :mod:`~grader.lms.registry` lists them;
:mod:`~grader.lms.export` is ``eulertop export``.

Which sources each format follows is written in ``docs/lms.md``.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""
