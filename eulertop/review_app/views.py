"""What each API call answers: :class:`grader.review.ReviewSession`'s readings and changes as
plain JSON values, and the requests' bodies checked field by field (issue 31).

Every function takes the session and what the request asked, and returns what the API sends
back; a request the desk cannot carry out raises :class:`grader.review.ReviewError` (one
sentence, naming the field at fault), which the server answers with status 400.

Anonymity: an answer is listed and read without its student unless the request asks for
names (``names=1``); the page asks only when the TA turns "Show names" on.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from grader.review import ReviewError, ReviewSession
from grader.statement_html import statement_html

REVIEW_FIELDS = {"id": str, "rubric": list, "adjust": (int, float), "comment": str}
RUBRIC_FIELDS = {"question": str, "item": int, "points": (int, float)}
COMMENT_FIELDS = {"question": str, "name": str, "text": (str, type(None))}
OVERRIDE_FIELDS = {"student": str, "answer": (str, type(None)), "points": (int, float, type(None)),
                   "reason": str, "remove": bool}
REQUIRED = {"review": ("id",), "rubric": ("question", "item", "points"),
            "comment": ("question", "name"), "override": ("student",)}


def fields(body: Any, allowed: Mapping[str, Any], what: str) -> dict:
    """``body`` checked against ``allowed`` (field → type): a JSON object, no unknown field,
    each known one of its type, the required ones there; ReviewError naming the first
    field at fault."""
    if not isinstance(body, dict):
        raise ReviewError(f"{what}: the body is a JSON object, got {type(body).__name__}")
    for name, value in body.items():
        if name not in allowed:
            raise ReviewError(f"{what}: unknown field {name!r} (known: {', '.join(allowed)})")
        if not isinstance(value, allowed[name]) or (isinstance(value, bool)
                                                     and allowed[name] is not bool):
            raise ReviewError(f"{what}: field {name!r} cannot be {value!r}")
    missing = [name for name in REQUIRED[what] if name not in body]
    if missing:
        raise ReviewError(f"{what}: field {missing[0]!r} is required")
    return body


def plain(value: Any) -> Any:
    """``value`` with every float that JSON cannot hold (NaN, ±∞) as its name in a string,
    so that the browser's ``JSON.parse`` reads every answer (a student may submit NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


def inline_html(text: str) -> str:
    """``text`` (Markdown and LaTeX) as :func:`~grader.statement_html.statement_html` renders
    it, without the paragraph around it where it is one (a rubric item sits in a label)."""
    out = statement_html(text).strip()
    if out.startswith("<p>") and out.endswith("</p>") and out.count("<p>") == 1:
        return out[3:-4]
    return out


def _question(q: dict, progress: Mapping[str, Any]) -> dict:
    """A written question as the page shows it: its prompt and rubric items also as HTML
    (the instructor's Markdown and LaTeX, rendered as the feedback pages render them)."""
    rubric = [{**r, "html": inline_html(r["item"])} for r in q["rubric"]]
    return {**q, "prompt_html": statement_html(q["prompt"]), "rubric": rubric,
            "progress": progress.get(q["question"], {})}


def questions(session: ReviewSession) -> list[dict]:
    """``GET /api/questions``: each written question with its progress."""
    progress = session.progress()
    return [_question(q, progress) for q in session.questions()]


def _names(session: ReviewSession) -> dict[str, str]:
    """Roster names by student id (empty where the roster has no ``name`` column)."""
    return {r["id"]: r.get("name") or "" for r in session.a.rows}


def _shown(answer: dict, names: dict[str, str] | None) -> dict:
    """``answer`` without its student unless ``names`` (then with the roster's name too)."""
    shown = {k: v for k, v in answer.items() if k != "student"}
    if names is not None:
        shown |= {"student": answer["student"], "name": names.get(answer["student"], "")}
    return shown


def written(session: ReviewSession, question: str, names: bool = False) -> list[dict]:
    """``GET /api/written?question=NAME[&names=1]``: every answer to ``question``."""
    roster = _names(session) if names else None
    return [_shown(a, roster) for a in session.written(question)]


def pending(session: ReviewSession, question: str) -> list[str]:
    """``GET /api/pending?question=NAME``: the ids of the answers that wait for a review
    now (another TA's reviews counted), in the order :func:`written` lists them."""
    return [a["id"] for a in session.written(question) if a["status"] == "pending"]


def answer(session: ReviewSession, answer_id: str, names: bool = False) -> dict:
    """``GET /api/answer?id=ID[&names=1]``: one answer, with its text as HTML."""
    found = session.answer(answer_id)
    return {**_shown(found, _names(session) if names else None),
            "html": session.html(answer_id)}


def review(session: ReviewSession, body: Any) -> dict:
    """``POST /api/review``: the review submitted; the answer as it now is, and every
    question's progress (another TA's reviews counted too)."""
    body = fields(body, REVIEW_FIELDS, "review")
    found = session.submit(body["id"], body.get("rubric", []), body.get("adjust", 0.0),
                           body.get("comment", ""))
    return {**_shown(found, None), "progress": session.progress()}


def rubric(session: ReviewSession, body: Any) -> dict:
    """``POST /api/rubric``: a rubric item's points changed (everyone who has it
    rescored); the question as it now is."""
    body = fields(body, RUBRIC_FIELDS, "rubric")
    changed = session.set_rubric(body["question"], body["item"], float(body["points"]))
    return _question(changed, session.progress())


def comments(session: ReviewSession, question: str) -> dict[str, str]:
    """``GET /api/comments?question=NAME``: the question's reusable comments."""
    if question not in session.a.written():
        raise ReviewError(f"no written question {question!r}")
    return session.comments(question)


def add_comment(session: ReviewSession, body: Any) -> dict[str, str]:
    """``POST /api/comments``: a reusable comment kept (``text`` null: taken back)."""
    body = fields(body, COMMENT_FIELDS, "comment")
    return session.add_comment(body["question"], body["name"], body.get("text"))


def flagged(session: ReviewSession) -> list[dict]:
    """``GET /api/flagged``: the answers the grader flagged for a look."""
    return plain(session.flagged())


def override(session: ReviewSession, body: Any) -> dict:
    """``POST /api/override``: the same override as ``eulertop override``."""
    body = fields(body, OVERRIDE_FIELDS, "override")
    return session.override(body["student"], body.get("answer"), body.get("points"),
                            body.get("reason", ""), remove=body.get("remove", False))
