"""Exceptions raised by :mod:`mpm_fracture`.

Every exception derives from :class:`FractureError`, so ``except FractureError`` catches
all of them.
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional

__all__ = [
    "FractureError",
    "ServerNotRunning",
    "ApiError",
    "JobFailed",
    "WaitTimeout",
    "RunFormatError",
]


class FractureError(Exception):
    """Base class of every error of this package."""


class ServerNotRunning(FractureError):
    """The server does not answer at its URL (connection refused, unknown host, ...).

    The message names the URL and how to start a server there.
    """

    def __init__(self, url: str, reason: str) -> None:
        self.url = url
        self.reason = reason
        super().__init__(
            f"the fracture server is not running at {url} ({reason}). Start it with "
            "`cargo run --release` in the mpm-fracture checkout, or `fracture serve` "
            "(`fracture serve --bind HOST:PORT` for another address), or pass the "
            "right URL: Client(\"http://host:port\")."
        )


class ApiError(FractureError):
    """The API answered with an HTTP error.

    Attributes:
        status: the HTTP status code (e.g. 404, 422).
        error: the error kind of the body (``not_found``, ``invalid_scene``,
            ``limit_exceeded``, ...), or ``"http_error"`` when the body was not the API's.
        message: the body's human-readable message.
        details: the body's per-field problems, each ``{"path": ..., "message": ...}``.
        method, url: the request that failed.
    """

    def __init__(
        self,
        status: int,
        error: str,
        message: str,
        details: Optional[List[Dict[str, Any]]] = None,
        method: str = "",
        url: str = "",
    ) -> None:
        self.status = status
        self.error = error
        self.message = message
        self.details: List[Dict[str, Any]] = list(details or [])
        self.method = method
        self.url = url
        text = f"{method} {url}: {status} {error}: {message}".strip()
        for d in self.details:
            path = d.get("path", "")
            line = f"{path}: {d.get('message', '')}" if path else str(d.get("message", ""))
            if line not in message:
                text += f"\n  {line}"
        super().__init__(text)


class JobFailed(FractureError):
    """A waited-for job ended ``failed`` or ``cancelled`` (raised by
    :meth:`mpm_fracture.Client.wait` with ``check=True``).

    Attributes:
        job: the job in its final state (:class:`mpm_fracture.Job`).
    """

    def __init__(self, job: Any) -> None:
        self.job = job
        msg = f"job {job.id} ({job.name}) ended {job.status}"
        if job.message:
            msg += f": {job.message}"
        super().__init__(msg)


class WaitTimeout(FractureError):
    """A wait ran past its ``timeout`` before the job ended.

    Attributes:
        job: the job as last seen.
    """

    def __init__(self, job: Any, timeout: float) -> None:
        self.job = job
        self.timeout = timeout
        super().__init__(
            f"job {job.id} still {job.status} after {timeout:g} s (the job goes on on the server)"
        )


class RunFormatError(FractureError):
    """A run folder or one of its files is missing or malformed."""
