"""The guard's decisions, one request at a time (:mod:`eulertop.review_app.guard`): the table
of who is let in is written here from the rules the docs state, not from the code."""

from __future__ import annotations

import pytest

from eulertop.review_app.guard import Asked, Guard

GUARD = Guard(8123, "s3cret-token")
OWN = "http://127.0.0.1:8123"
COOKIE = "s3cret-token"


def _asked(method="GET", host="127.0.0.1:8123", origin=None, authorization=None, cookie=None,
           query_token=None) -> Asked:
    return Asked(method, host, origin, authorization, cookie, query_token)


@pytest.mark.parametrize("asked, status", [
    (_asked(authorization="token s3cret-token"), None),
    (_asked(authorization="Token s3cret-token"), None),  # the scheme is case-insensitive
    (_asked(host="localhost:8123", cookie=COOKIE), None),
    (_asked(query_token="s3cret-token"), None),
    (_asked("POST", origin=OWN, cookie=COOKIE), None),
    (_asked("POST", authorization="token s3cret-token"), None),  # a script: no Origin
    (_asked(), 401),
    (_asked(authorization="token wrong"), 401),
    (_asked(authorization="Bearer s3cret-token"), 401),
    (_asked(cookie="s3cret-token-but-longer"), 401),
    (_asked(query_token=""), 401),
    (_asked(host="evil.example:8123", cookie=COOKIE), 403),  # DNS rebinding
    (_asked(host="127.0.0.1:8124", cookie=COOKIE), 403),  # another port
    (_asked(host="127.0.0.1", cookie=COOKIE), 403),
    (_asked(host="", cookie=COOKIE), 403),
    (_asked(origin="http://evil.example", cookie=COOKIE), 403),
    (_asked(origin="null", cookie=COOKIE), 403),
    (_asked(origin="https://127.0.0.1:8123", cookie=COOKIE), 403),
    (_asked("POST", origin="http://evil.example", authorization="token s3cret-token"), 403),
    (_asked("POST", cookie=COOKIE), 403),  # a change with the cookie and no Origin
])
def test_who_is_let_in(asked, status):
    refusal = GUARD.refusal(asked)
    assert (refusal.status if refusal else None) == status


def test_the_token_is_long_random_and_each_desk_has_its_own():
    one, two = Guard(1), Guard(1)
    assert one.token != two.token and len(one.token) >= 40
    assert one.url == f"http://127.0.0.1:1/?token={one.token}"
    assert Guard(2).cookie != Guard(3).cookie  # two desks on one machine keep their cookies
