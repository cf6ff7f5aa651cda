"""Raw HTTP to a desk for the tests: :mod:`http.client`, so that the path is sent as written
(never normalised) and the ``Host``, ``Origin`` and ``Cookie`` headers are the test's."""

from __future__ import annotations

import http.client
import json
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit


@dataclass
class Reply:
    status: int
    headers: http.client.HTTPMessage
    body: bytes

    def json(self) -> Any:
        return json.loads(self.body)

    @property
    def text(self) -> str:
        return self.body.decode("utf-8", "replace")


def port_of(url: str) -> int:
    return urlsplit(url).port


def token_of(url: str) -> str:
    return url.rsplit("token=", 1)[1]


def ask(url: str, method: str, path: str, body: Any = None, *, token: str | None = "",
        headers: dict | None = None, raw: bytes | None = None) -> Reply:
    """``method path`` to the desk at ``url`` (its printed address): with its token in the
    ``Authorization`` header unless ``token`` is None (another token where given), ``body``
    as JSON, ``headers`` added (``Host`` among them replaces the right one)."""
    port = port_of(url)
    sent = {"Host": f"127.0.0.1:{port}", **(headers or {})}
    if token is not None:
        sent["Authorization"] = f"token {token or token_of(url)}"
    data = raw
    if body is not None:
        data = json.dumps(body).encode()
        sent.setdefault("Content-Type", "application/json")
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    try:
        connection.request(method, path, body=data, headers=sent)
        response = connection.getresponse()
        return Reply(response.status, response.headers, response.read())
    finally:
        connection.close()
