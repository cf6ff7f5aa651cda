"""Where the notebook a kernel runs is saved, from what its front end says — never by asking
the front end to save it (issue 33: a forced save broke with each JupyterLab release).

In the order tried (:func:`find_notebook`):

``__vsc_ipynb_file__``
    VS Code's Jupyter extension puts the notebook's path in the kernel's namespace.
``JPY_SESSION_NAME``
    Jupyter Server (JupyterLab, Notebook 7) puts the session's path in the kernel's
    environment: absolute, or relative to the server's root.
the Jupyter server's sessions
    The kernel's id is in its connection file's name (``kernel-<id>.json``); every running
    server has a runtime file (``jpserver-<pid>.json``: its address, token and root), and its
    ``api/sessions`` names the notebook of each kernel.
Colab
    Colab has no notebook file in the kernel's machine: the notebook it holds is asked for
    (``google.colab._message.blocking_request("get_ipynb")``), as its own document.

Floor 8 of the grader's front ends (grader/API.md).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

SESSIONS_SECONDS = 2.0
"""Seconds one Jupyter server is given to list its sessions."""


class NotebookNotFound(LookupError):
    """No front end said where the notebook is; the message says what to do."""


@dataclass(frozen=True)
class Found:
    """Where the notebook is: a file (``path``), or, on Colab, its document (``document``)."""

    how: str  # for the student: where it was found
    path: Path | None = None
    document: dict | None = None


NOT_FOUND = ("could not tell which notebook this kernel runs (no Jupyter server, VS Code or "
             "Colab said): name it, eulertop_check.check(\"ada.ipynb\")")


def find_notebook(namespace: Mapping[str, Any], environ: Mapping[str, str] = os.environ,
                  cwd: Path | None = None) -> Found:
    """The notebook the kernel whose ``namespace`` and ``environ`` these are runs.

    Raises
    ------
    NotebookNotFound
        No front end said.
    """
    cwd = Path.cwd() if cwd is None else cwd
    for finder in (_vs_code, _session_name, _server_session):
        found = finder(namespace, environ, cwd)
        if found is not None:
            return found
    found = _colab()
    if found is None:
        raise NotebookNotFound(NOT_FOUND)
    return found


def _vs_code(namespace: Mapping[str, Any], environ: Mapping[str, str], cwd: Path) -> Found | None:
    path = namespace.get("__vsc_ipynb_file__")
    if isinstance(path, str) and Path(path).is_file():
        return Found("VS Code", Path(path))
    return None


def _session_name(namespace: Mapping[str, Any], environ: Mapping[str, str],
                  cwd: Path) -> Found | None:
    name = environ.get("JPY_SESSION_NAME", "")
    if not name.endswith(".ipynb"):
        return None
    for path in (Path(name), cwd / name, cwd / Path(name).name):
        if path.is_file():
            return Found("the Jupyter server (JPY_SESSION_NAME)", path.resolve())
    return None


def _server_session(namespace: Mapping[str, Any], environ: Mapping[str, str],
                    cwd: Path) -> Found | None:
    kernel = _kernel_id()
    if kernel is None:
        return None
    for server in _servers():
        for session in _sessions(server):
            if _kernel_of(session) == kernel:
                path = Path(server.get("root_dir") or server.get("notebook_dir") or cwd) / \
                    str(session.get("path", ""))
                if path.suffix == ".ipynb" and path.is_file():
                    return Found("the Jupyter server's sessions", path)
    return None


def _kernel_id() -> str | None:
    """This kernel's id: its connection file is ``kernel-<id>.json``."""
    try:
        from ipykernel import get_connection_file

        name = Path(get_connection_file()).name
    except Exception:  # not in an ipykernel, or one not started from a connection file
        return None
    if name.startswith("kernel-") and name.endswith(".json"):
        return name[len("kernel-"):-len(".json")]
    return None


def _servers() -> Iterator[dict]:
    """The running Jupyter servers' runtime files (``jpserver-*.json``, ``nbserver-*.json``)."""
    try:
        from jupyter_core.paths import jupyter_runtime_dir

        folder = Path(jupyter_runtime_dir())
        files = sorted([*folder.glob("jpserver-*.json"), *folder.glob("nbserver-*.json")])
    except Exception:
        return
    for file in files:
        try:
            server = json.loads(file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(server, dict) and isinstance(server.get("url"), str):
            yield server


def _sessions(server: Mapping[str, Any]) -> list:
    """The server's sessions (``GET api/sessions``), or [] when it does not answer."""
    from urllib.request import Request, urlopen

    url = server["url"].rstrip("/") + "/api/sessions"
    headers = {"Authorization": f"token {server['token']}"} if server.get("token") else {}
    try:
        with urlopen(Request(url, headers=headers), timeout=SESSIONS_SECONDS) as reply:
            sessions = json.loads(reply.read(1 << 20))
    except Exception:  # a server gone, another user's, or not answering: not ours
        return []
    return sessions if isinstance(sessions, list) else []


def _kernel_of(session: Any) -> str | None:
    kernel = session.get("kernel") if isinstance(session, dict) else None
    return kernel.get("id") if isinstance(kernel, dict) else None


def _colab() -> Found | None:
    """On Colab, the notebook Colab holds (there is no file of it on the kernel's machine)."""
    try:
        from google.colab import _message
    except ImportError:
        return None
    try:
        reply = _message.blocking_request("get_ipynb", request="", timeout_sec=30)
    except Exception:
        return None
    document = reply.get("ipynb") if isinstance(reply, dict) else None
    if not isinstance(document, dict):
        return None
    return Found("Colab", document=document)
