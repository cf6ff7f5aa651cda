"""Who may talk to the review desk: the token, the ``Host`` and the ``Origin`` (issue 31).

The desk listens on 127.0.0.1 only, and that is not enough: any web page the TA opens can make
their browser send requests to 127.0.0.1, and a name an attacker controls can be made to
resolve to it (DNS rebinding). So every request — page, static file, API call — is checked, in
this order, as Jupyter's server checks its own:

1. its ``Host`` is the desk's own address (``127.0.0.1:PORT`` or ``localhost:PORT``): a
   rebound name is refused;
2. its ``Origin``, where the browser sends one, is the desk's own (``http://`` + one of those);
   a change (POST) authenticated by the cookie must carry one (browsers send it with every
   POST), so that a form or script of another site cannot make changes with the TA's cookie;
3. it carries the token: ``Authorization: token …``, or the cookie the desk set when the TA
   opened the URL with ``?token=…`` (HttpOnly, SameSite=Strict, named after the port so that
   two desks on one machine keep theirs apart). A page opened with ``?token=…`` is answered
   with the cookie and a redirect to the same address without it.

The token is compared in constant time (:func:`hmac.compare_digest`).
"""

from __future__ import annotations

import hmac
import secrets
from dataclasses import dataclass, field

SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
"""Methods that change nothing on the desk."""


@dataclass(frozen=True)
class Asked:
    """What a request says of itself, as the guard reads it."""

    method: str
    host: str
    origin: str | None
    authorization: str | None
    cookie: str | None
    query_token: str | None = None


@dataclass(frozen=True)
class Refusal:
    """Why a request is refused: its HTTP status and a sentence for the person."""

    status: int
    message: str


@dataclass(frozen=True)
class Guard:
    """The desk's token and address (module docstring)."""

    port: int
    token: str = field(default_factory=lambda: secrets.token_urlsafe(32), repr=False)

    @property
    def hosts(self) -> frozenset[str]:
        """The ``Host`` values of the desk's own address."""
        return frozenset({f"127.0.0.1:{self.port}", f"localhost:{self.port}"})

    @property
    def origins(self) -> frozenset[str]:
        return frozenset(f"http://{h}" for h in self.hosts)

    @property
    def cookie(self) -> str:
        """The cookie's name: one per port (cookies do not tell ports apart)."""
        return f"eulertop-review-{self.port}"

    @property
    def url(self) -> str:
        """The address to open, token included (what ``eulertop review`` prints)."""
        return f"http://127.0.0.1:{self.port}/?token={self.token}"

    def matches(self, token: str | None) -> bool:
        """Whether ``token`` is the desk's (constant time)."""
        return token is not None and hmac.compare_digest(token.encode(), self.token.encode())

    def refusal(self, asked: Asked) -> Refusal | None:
        """Why ``asked`` is refused (module docstring), or None."""
        if asked.host not in self.hosts:
            return Refusal(403, f"Host {asked.host!r} is not this desk's address "
                           f"(127.0.0.1:{self.port}): refused")
        if asked.origin is not None and asked.origin not in self.origins:
            return Refusal(403, f"Origin {asked.origin!r} is not this desk: refused")
        by_header = self.matches(_header_token(asked.authorization))
        if not (by_header or self.matches(asked.cookie) or self.matches(asked.query_token)):
            return Refusal(401, "this desk needs its token: open the address 'eulertop "
                           "review' printed (…/?token=…), or send 'Authorization: token …'")
        if asked.method not in SAFE_METHODS and not by_header and asked.origin is None:
            return Refusal(403, "a change made with the desk's cookie must carry its Origin")
        return None


def _header_token(authorization: str | None) -> str | None:
    """The token of an ``Authorization: token …`` header, or None."""
    scheme, _, value = (authorization or "").partition(" ")
    return value.strip() if scheme.lower() == "token" else None
