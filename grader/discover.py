"""Which submission belongs to which student: the first stage of grading.

A submission is ``SUBMISSIONS/<id>.ipynb`` or ``SUBMISSIONS/<id>/<one>.ipynb``. The student
id — and so the variant the submission is graded against — comes from that file or folder name
alone, which the instructor's files control; nothing inside the notebook is consulted here
(``docs/security.md``, "Who is trusted").

What is found is sorted into four kinds, so that nothing is guessed and nothing is silent:

* a roster id with exactly one submission → a :class:`Submission` to grade;
* a roster id with none → ``missing``;
* a roster id with more than one candidate (``alice.ipynb`` *and* ``alice/``, or a folder with
  two notebooks) → a :class:`Problem` for that student (graded as failed, not guessed);
* a name that is not a roster id, or a folder without a notebook → a :class:`Problem` that is
  reported and not graded (an id differing from a roster id only in case is pointed out).

A file that stands for an archive entry refused unread (:mod:`grader.lms.archive`: too large, a
zip bomb, names that collide) makes only its own student's submission invalid, saying why.

Hidden entries (``.ipynb_checkpoints``, ``.DS_Store``) are ignored; other files that are not
notebooks are reported.

Not what students handed in (:func:`require_handed_in`): a SUBMISSIONS folder that is the
assignment's own ``release/`` or ``solutions/`` folder, or whose every submission is byte for
byte the notebook generated for its student (a copy of either), would grade everyone 0 or give
everyone full marks; ``eulertop grade`` refuses it unless told ``--yes``.

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from grader.assignment import UsageError
from grader.submission_file import InvalidSubmission, read_submission
from grader.submissions import SUFFIX, Discovery, Problem, Submission
from problems.generate import RELEASE, SOLUTIONS

    # (older uploads, several notebooks, entries refused from an archive): submissions.csv


def _candidates(folder: Path) -> dict[str, list[Path]]:
    """Every entry naming an id: ``{stem or folder name: [notebook or folder paths]}``."""
    found: dict[str, list[Path]] = {}
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith("."):
            continue
        if entry.is_dir() or (entry.is_symlink() and not entry.name.endswith(SUFFIX)):
            # a link to a folder is this student's entry too: refused in _resolve, not followed
            found.setdefault(entry.name, []).append(entry)
        elif entry.name.endswith(SUFFIX):
            found.setdefault(entry.name[: -len(SUFFIX)], []).append(entry)
        else:
            found.setdefault("", []).append(entry)  # not a notebook: reported below
    return found


def _notebooks_in(folder: Path) -> list[Path]:
    """The notebooks in a student's folder: what is named ``*.ipynb`` and is not a folder (a
    link or a FIFO so named is the submission, refused when it is read)."""
    try:
        return sorted(p for p in folder.iterdir() if p.name.endswith(SUFFIX)
                      and not p.name.startswith(".") and (p.is_symlink() or not p.is_dir()))
    except OSError:  # unreadable: reported as holding no notebook the grader can read
        return []


def _resolve(folder: Path, sid: str, entries: list[Path]) -> Submission | Problem:
    """One student's entries → their submission, or the reason there is none to grade."""
    for entry in entries:
        if entry.is_symlink() and not entry.name.endswith(SUFFIX):
            return Problem(entry, f"invalid submission: {entry.name} is a symbolic link, not "
                                  "a folder", sid)
    notebooks = sorted(n for e in entries for n in (_notebooks_in(e) if e.is_dir() else [e]))
    if len(notebooks) == 1:
        return Submission(sid, notebooks[0])
    if not notebooks:
        return Problem(entries[0], f"the folder {entries[0].name}/ holds no .ipynb notebook "
                                   "that can be read", sid)
    names = ", ".join(str(n.relative_to(folder)) for n in notebooks)
    return Problem(entries[0], f"{len(notebooks)} notebooks ({names}); submit exactly one — "
                               "not guessing which one to grade", sid)


def discover(folder: Path, roster_ids: Sequence[str],
             roster_rows: Sequence[Mapping[str, str]] = (),
             refused: Mapping[Path, str] | None = None) -> Discovery:
    """Sort the contents of ``folder`` (module docstring).

    Parameters
    ----------
    folder : Path
        The SUBMISSIONS folder (must be a readable folder: the caller checks).
    roster_ids : sequence of str
        The assignment's student ids.
    roster_rows : sequence of dict, optional
        The roster rows (``"id"`` and the class list's columns): a bulk download of Canvas,
        Moodle, Blackboard or Gradescope is matched through them (:mod:`grader.lms.download`).
    refused : dict, optional
        Files of ``folder`` that stand for archive entries refused unread, each with why
        (:attr:`grader.lms.archive.Extraction.refused`): the student such a file would be the
        submission of gets an invalid submission saying why; everyone else is unaffected.
    """
    from grader.lms.registry import discover_download

    refused = refused or {}
    lms = discover_download(Path(folder), roster_rows or [{"id": s} for s in roster_ids],
                            refused)
    found = lms if lms is not None else _discover_folder(Path(folder), roster_ids)
    return _refusals(found, refused) if refused else found


def _refusals(found: Discovery, refused: Mapping[Path, str]) -> Discovery:
    """A submission whose file was refused → its student's invalid submission; any other
    problem about a refused file says why it was refused."""
    submissions, problems = [], []
    for s in found.submissions:
        if s.path in refused:
            problems.append(Problem(s.path, f"invalid submission: {refused[s.path]}",
                                    s.student_id))
        else:
            submissions.append(s)
    for p in found.problems:
        if p.path in refused and not p.message.startswith("invalid submission"):
            p = replace(p, message=f"{p.message} ({refused[p.path]})")
        problems.append(p)
    return replace(found, submissions=tuple(submissions), problems=tuple(problems))


def _discover_folder(folder: Path, roster_ids: Sequence[str]) -> Discovery:
    """A folder of ``<id>.ipynb`` or ``<id>/<notebook>.ipynb`` (module docstring)."""
    found = _candidates(folder)
    by_lower = {sid.lower(): sid for sid in roster_ids}
    submissions, missing, problems = [], [], []
    for sid in roster_ids:
        if sid not in found:
            missing.append(sid)
            continue
        outcome = _resolve(folder, sid, found[sid])
        (submissions if isinstance(outcome, Submission) else problems).append(outcome)
    for name, entries in found.items():
        if name in by_lower.values():
            continue
        for entry in entries:
            if name == "":
                problems.append(Problem(entry, f"{entry.name}: not a notebook (.ipynb) nor a "
                                               "folder; ignored", ignored=True))
                continue
            near = by_lower.get(name.lower())
            hint = f" (did you mean {near!r}? ids are case-sensitive)" if near else ""
            message = f"{entry.name}: {name!r} is not on the roster{hint}; not graded"
            problems.append(Problem(entry, message))
    return Discovery(tuple(submissions), tuple(missing), tuple(problems))


# --------------------------------------------------------------------------------------------
# not what students handed in

GENERATED = {RELEASE: ("the blank notebooks handed out", "every student 0"),
             SOLUTIONS: ("the key's answers filled in", "every student full marks")}
"""The generated folders: what each holds, and what grading it as submissions would give."""


def require_handed_in(hw: Path, submissions: Path, found: Discovery, yes: bool = False) -> None:
    """:class:`UsageError` when ``submissions`` is not what students handed in but the
    assignment's own notebooks: its ``release/`` or ``solutions/`` folder (by real path), or a
    folder whose every submission is, byte for byte, the notebook generated for its student.
    ``yes`` (``eulertop grade --yes``) grades it all the same."""
    if yes:
        return
    why = _generated_folder(Path(hw), Path(submissions)) or \
        _generated_copies(Path(hw), Path(submissions), found)
    if why:
        raise UsageError(f"{why}; pass the folder of the notebooks the students handed in, "
                         "or --yes to grade it all the same")


def _generated_folder(hw: Path, submissions: Path) -> str | None:
    """Why ``submissions`` is one of ``hw``'s generated folders, or None."""
    for kind, (holds, gives) in GENERATED.items():
        if os.path.realpath(submissions) == os.path.realpath(hw / kind):
            return (f"{submissions} is the assignment's {kind} folder ({holds}), not "
                    f"submissions: grading it would give {gives}")
    return None


def _generated_copies(hw: Path, submissions: Path, found: Discovery) -> str | None:
    """Why every submission ``found`` is its student's generated notebook, or None (some is
    not, or there is none)."""
    kinds = []
    for submission in found.submissions:  # a class that worked stops at its first notebook
        kinds.append(_generated_kind(hw, submission))
        if kinds[-1] is None:
            return None
    if not kinds:
        return None
    where = [f"{kinds.count(kind)} as in {hw / kind}" for kind in GENERATED if kind in kinds]
    gives = GENERATED[kinds[0]][1] if len(where) == 1 else "0 or full marks as they came"
    return (f"every submission in {submissions} ({len(kinds)}) is byte for byte the notebook "
            f"generated for its student ({', '.join(where)}: a copy?), not one a student "
            f"worked in: grading them would give {gives}")


def _generated_kind(hw: Path, submission: Submission) -> str | None:
    """``release`` or ``solutions`` when the submission's bytes are those of the notebook
    generated for its student in that folder; None otherwise (or when either is unreadable:
    links and FIFOs are read, and refused, by the run itself)."""
    for kind in GENERATED:
        try:
            generated = (hw / kind / f"{submission.student_id}{SUFFIX}").read_bytes()
            if read_submission(submission.path, len(generated)) == generated:
                return kind
        except (OSError, InvalidSubmission):
            continue
    return None
