"""A client of the mpm-fracture service's REST API (``/api/v1``).

Only the standard library's ``urllib`` is used for HTTP. Errors:

* the server not answering at all raises :class:`~mpm_fracture.ServerNotRunning`, whose
  message names the URL and how to start a server;
* an HTTP error raises :class:`~mpm_fracture.ApiError` carrying the API's error body
  (``error``, ``message``, ``details``).
"""

from __future__ import annotations

import http.client
import ipaddress
import json
import os
import shutil
import socket
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path
from typing import (
    IO,
    Any,
    Callable,
    Dict,
    Iterable,
    Iterator,
    List,
    Mapping,
    Optional,
    Sequence,
    Union,
)

import pandas as pd

from .errors import ApiError, FractureError, JobFailed, ServerNotRunning, WaitTimeout
from .run import Run, crack_tips_frame, energy_frame

__all__ = ["Client", "Job", "Event", "DEFAULT_URL", "TERMINAL_STATUSES", "DOWNLOADS"]

#: Where :class:`Client` looks when given no URL and ``FRACTURE_SERVER`` is not set
#: (``cargo run --release`` and ``fracture serve`` listen there).
DEFAULT_URL = "http://127.0.0.1:8080"

#: Job states after which nothing changes.
TERMINAL_STATUSES = frozenset({"completed", "failed", "cancelled"})

#: The files :meth:`Client.download` knows: file name -> (API route under the job, Accept).
DOWNLOADS: Dict[str, Sequence[str]] = {
    "summary.json": ("", "application/json"),
    "crack_tips.csv": ("/crack-tips", "text/csv"),
    "energy.csv": ("/energy", "text/csv"),
    "fields.mcap": ("/fields.mcap", "*/*"),
    "vtk.zip": ("/vtk.zip", "*/*"),
}

#: An event of a job's stream: ``{"event": name, "data": parsed JSON}``. Names:
#: ``progress`` (``{"step", "sim_time", "end_time", "fraction"}``), ``energy`` (a list of
#: energy rows), ``crack_tip`` (a list of crack-tip rows), ``snapshot`` (``{"index",
#: "time", "fields", "components"}``) and ``status`` (``{"id", "status", "attempts",
#: "message", "summary"}``; the last event once the job has ended).
Event = Dict[str, Any]

SceneLike = Union[Mapping[str, Any], str, "os.PathLike[str]"]
ProgressArg = Union[bool, Callable[["Job"], None], None]


class Job:
    """A job of the service, as ``GET /api/v1/jobs/{id}`` returned it.

    The fields of the API's job object are attributes (``id``, ``status``, ``name``,
    ``labels``, ``priority``, ``created_at``, ``started_at``, ``finished_at``,
    ``attempts``, ``progress``, ``summary``, ``message``; ``scene`` for a single job);
    :attr:`raw` is the whole object. Methods act through the client that made it.
    """

    def __init__(self, client: "Client", data: Mapping[str, Any]) -> None:
        self.client = client
        #: The job object as the API sent it.
        self.raw: Dict[str, Any] = dict(data)

    # -- the API's fields
    @property
    def id(self) -> str:
        """Job id."""
        return str(self.raw["id"])

    @property
    def status(self) -> str:
        """``queued``, ``running``, ``completed``, ``failed`` or ``cancelled``."""
        return str(self.raw.get("status", ""))

    @property
    def name(self) -> str:
        """The scene's name (a sweep's jobs add their label)."""
        return str(self.raw.get("name", ""))

    @property
    def labels(self) -> Dict[str, str]:
        """Free labels of the job."""
        return dict(self.raw.get("labels") or {})

    @property
    def priority(self) -> int:
        """Higher runs first."""
        return int(self.raw.get("priority") or 0)

    @property
    def created_at(self) -> Optional[str]:
        """RFC 3339 UTC."""
        return self.raw.get("created_at")

    @property
    def started_at(self) -> Optional[str]:
        """RFC 3339 UTC, or ``None`` before a worker claimed the job."""
        return self.raw.get("started_at")

    @property
    def finished_at(self) -> Optional[str]:
        """RFC 3339 UTC, or ``None`` while unfinished."""
        return self.raw.get("finished_at")

    @property
    def attempts(self) -> int:
        """How many times a worker has claimed the job."""
        return int(self.raw.get("attempts") or 0)

    @property
    def progress(self) -> Optional[Dict[str, Any]]:
        """``{"step", "sim_time" (s), "end_time" (s), "fraction"}`` or ``None``."""
        p = self.raw.get("progress")
        return dict(p) if p else None

    @property
    def fraction(self) -> float:
        """Progress in [0, 1] (1 for a completed job)."""
        if self.status == "completed":
            return 1.0
        p = self.progress
        return float(p.get("fraction") or 0.0) if p else 0.0

    @property
    def summary(self) -> Optional[Dict[str, Any]]:
        """The run's ``summary.json`` once finished (see :attr:`mpm_fracture.Run.summary`)."""
        s = self.raw.get("summary")
        return dict(s) if s else None

    @property
    def message(self) -> Optional[str]:
        """Why the job failed or was cancelled."""
        return self.raw.get("message")

    @property
    def scene(self) -> Optional[Dict[str, Any]]:
        """The scene (only in a single job's answer, not in lists)."""
        s = self.raw.get("scene")
        return dict(s) if s else None

    @property
    def done(self) -> bool:
        """Whether the job has ended (``completed``, ``failed`` or ``cancelled``)."""
        return self.status in TERMINAL_STATUSES

    @property
    def url(self) -> str:
        """The job's page on the dashboard."""
        return f"{self.client.url}/#/runs/{self.id}"

    # -- actions
    def refresh(self) -> "Job":
        """Fetch the job again; updates this object and returns it."""
        self.raw = self.client.job(self.id).raw
        return self

    def wait(
        self,
        progress: ProgressArg = True,
        timeout: Optional[float] = None,
        check: bool = False,
    ) -> "Job":
        """Wait for the job to end: see :meth:`Client.wait`. Updates this object."""
        done = self.client.wait(self, progress=progress, timeout=timeout, check=check)
        self.raw = done.raw
        return self

    def events(self, timeout: Optional[float] = None) -> Iterator[Event]:
        """The job's event stream: see :meth:`Client.stream`."""
        return self.client.stream(self.id, timeout=timeout)

    def run(self, folder: Optional[Union[str, "os.PathLike[str]"]] = None, snapshots: bool = True) -> Run:
        """Download the results and open them as a :class:`~mpm_fracture.Run`
        (:meth:`Client.run`)."""
        return self.client.run(self.id, folder=folder, snapshots=snapshots)

    def download(
        self,
        folder: Union[str, "os.PathLike[str]"],
        files: Optional[Iterable[str]] = None,
    ) -> Dict[str, Path]:
        """Download result files into ``folder`` (:meth:`Client.download`)."""
        return self.client.download(self.id, folder, files)

    def cancel(self) -> "Job":
        """Cancel the job (:meth:`Client.cancel`); updates this object."""
        self.raw = self.client.cancel(self.id).raw
        return self

    def __repr__(self) -> str:
        extra = ""
        if self.status == "running":
            extra = f", {100 * self.fraction:.0f}%"
        return f"Job({self.id!r}, {self.name!r}, {self.status}{extra})"


def _is_loopback(host: str) -> bool:
    if host in ("localhost",) or host.endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class Client:
    """A client of one mpm-fracture server.

    Args:
        url: the server's base URL, e.g. ``http://127.0.0.1:8080`` (a trailing
            ``/api/v1`` is accepted too). Default: ``$FRACTURE_SERVER``, else
            :data:`DEFAULT_URL`.
        token: API token for submit, cancel and delete (``fracture serve --token``).
            Default: ``$FRACTURE_TOKEN``; reads need none.
        timeout: seconds to wait for an answer to one request (downloads and event
            streams reset it at every chunk or event).

    Example::

        from mpm_fracture import Client
        client = Client()                           # http://127.0.0.1:8080
        job = client.submit("scenes/center-crack.json")
        job.wait()                                  # prints a progress line
        run = job.run()                             # downloads into a temporary folder
        print(run.crack_tips.tail())
    """

    def __init__(
        self,
        url: Optional[str] = None,
        token: Optional[str] = None,
        timeout: float = 60.0,
    ) -> None:
        url = url or os.environ.get("FRACTURE_SERVER") or DEFAULT_URL
        if "://" not in url:
            url = "http://" + url
        url = url.rstrip("/")
        if url.endswith("/api/v1"):
            url = url[: -len("/api/v1")]
        #: Base URL of the server (without ``/api/v1``).
        self.url = url
        #: API token sent as ``Authorization: Bearer`` (``None``: none).
        self.token = token if token is not None else os.environ.get("FRACTURE_TOKEN") or None
        #: Timeout of one request (s).
        self.timeout = timeout
        host = urllib.parse.urlsplit(url).hostname or ""
        handlers: List[urllib.request.BaseHandler] = []
        if _is_loopback(host):
            # A proxy from the environment must not swallow requests to this machine.
            handlers.append(urllib.request.ProxyHandler({}))
        self._opener = urllib.request.build_opener(*handlers)

    def __repr__(self) -> str:
        return f"Client({self.url!r})"

    # ------------------------------------------------------------------ HTTP

    def _open(
        self,
        method: str,
        path: str,
        body: Optional[Any] = None,
        accept: str = "application/json",
        query: Optional[Sequence[Any]] = None,
        timeout: Optional[float] = None,
    ) -> http.client.HTTPResponse:
        url = f"{self.url}/api/v1{path}"
        if query:
            url += "?" + urllib.parse.urlencode([(k, v) for k, v in query if v is not None])
        data = None
        headers = {"Accept": accept, "User-Agent": "mpm-fracture-python"}
        if body is not None:
            data = json.dumps(body).encode("utf-8")
            headers["Content-Type"] = "application/json"
        if self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        req = urllib.request.Request(url, data=data, headers=headers, method=method)
        try:
            return self._opener.open(req, timeout=timeout or self.timeout)  # type: ignore[no-any-return]
        except urllib.error.HTTPError as e:
            raise self._api_error(e, method, url) from None
        except urllib.error.URLError as e:
            raise self._connection_error(e.reason, url) from None
        except (ConnectionError, socket.gaierror, http.client.RemoteDisconnected) as e:
            raise self._connection_error(e, url) from None

    def _connection_error(self, reason: Any, url: str) -> FractureError:
        if isinstance(reason, (ConnectionRefusedError, socket.gaierror, FileNotFoundError)):
            return ServerNotRunning(self.url, str(reason))
        if isinstance(reason, (socket.timeout, TimeoutError)):
            return FractureError(f"{url}: no answer within {self.timeout:g} s ({reason})")
        if isinstance(reason, OSError) and getattr(reason, "errno", None) in (
            111,  # ECONNREFUSED
            113,  # EHOSTUNREACH
            101,  # ENETUNREACH
            99,  # EADDRNOTAVAIL
        ):
            return ServerNotRunning(self.url, str(reason))
        return FractureError(f"request to {url} failed: {reason}")

    @staticmethod
    def _api_error(e: urllib.error.HTTPError, method: str, url: str) -> ApiError:
        raw = b""
        try:
            raw = e.read()
        except Exception:  # the body may be unreadable; the status still says something
            pass
        try:
            body = json.loads(raw)
        except ValueError:
            body = None
        if isinstance(body, dict) and "message" in body:
            return ApiError(
                e.code,
                str(body.get("error", "http_error")),
                str(body.get("message", "")),
                body.get("details") or [],
                method,
                url,
            )
        text = raw.decode("utf-8", "replace").strip()[:500] or str(e.reason)
        return ApiError(e.code, "http_error", text, [], method, url)

    def _json(
        self,
        method: str,
        path: str,
        body: Optional[Any] = None,
        query: Optional[Sequence[Any]] = None,
    ) -> Any:
        with self._open(method, path, body=body, query=query) as r:
            raw = r.read()
        return json.loads(raw) if raw else None

    # ------------------------------------------------------------------ service

    def health(self) -> Dict[str, Any]:
        """``GET /api/v1/health``: ``{"status": "ok", "workers", "queued", "running"}``."""
        return dict(self._json("GET", "/health"))

    def version(self) -> Dict[str, Any]:
        """``GET /api/v1/version``: ``{service, version, solver_version, git_commit,
        build_profile}``."""
        return dict(self._json("GET", "/version"))

    def example_scenes(self) -> List[Dict[str, Any]]:
        """``GET /api/v1/scenes``: the built-in example scenes, each ``{name,
        description, scene}``."""
        return list(self._json("GET", "/scenes"))

    def validate(self, scene: SceneLike) -> Dict[str, Any]:
        """``POST /api/v1/scenes/validate``: ``{valid, particles, grid_nodes, time_step
        (s), steps}`` for a valid scene; an invalid one raises :class:`ApiError`
        (422 ``invalid_scene`` with the field paths in ``details``)."""
        return dict(self._json("POST", "/scenes/validate", body=load_scene(scene)))

    # ------------------------------------------------------------------ jobs

    def submit(
        self,
        scene: SceneLike,
        *,
        priority: Optional[int] = None,
        labels: Optional[Mapping[str, str]] = None,
        cache: bool = True,
        max_attempts: Optional[int] = None,
        name: Optional[str] = None,
    ) -> Job:
        """Submit a scene (``POST /api/v1/jobs``) and return the queued job.

        Args:
            scene: the scene as a dict, or the path of a scene JSON file
                (e.g. ``"scenes/center-crack.json"``).
            priority: higher runs first (default 0).
            labels: free ``{key: value}`` labels (searchable with :meth:`jobs`).
            cache: ``False`` runs the scene even if the server already has a completed
                run of it (otherwise that run answers at once, ``cached_from`` set).
            max_attempts: claims before a lost worker fails the job.
            name: replaces the scene's ``name``.

        Raises:
            ApiError: 422 ``invalid_scene`` (``details`` name the fields) or
                ``limit_exceeded``; 401 without the server's token.
        """
        doc = dict(load_scene(scene))
        if name is not None:
            doc["name"] = name
        body: Dict[str, Any] = {"scene": doc}
        if priority is not None:
            body["priority"] = int(priority)
        if labels:
            body["labels"] = {str(k): str(v) for k, v in labels.items()}
        if not cache:
            body["cache"] = "force"
        if max_attempts is not None:
            body["max_attempts"] = int(max_attempts)
        return Job(self, self._json("POST", "/jobs", body=body))

    def job(self, job_id: Union[str, Job]) -> Job:
        """``GET /api/v1/jobs/{id}`` (with its scene). 404 raises :class:`ApiError`."""
        return Job(self, self._json("GET", f"/jobs/{_id(job_id)}"))

    def jobs(
        self,
        status: Optional[str] = None,
        label: Union[str, Sequence[str], Mapping[str, str], None] = None,
        q: Optional[str] = None,
        limit: Optional[int] = None,
        all_pages: bool = False,
    ) -> List[Job]:
        """``GET /api/v1/jobs``: jobs, newest first, without their scenes.

        Args:
            status: only jobs in this state.
            label: only jobs with this label ``"key:value"`` (or all of several: a list, or
                a ``{key: value}`` dict).
            q: only jobs whose name contains this text.
            limit: page size (server default 50, at most 500).
            all_pages: follow ``X-Next-Cursor`` to return every matching job.
        """
        labels: List[str] = []
        if isinstance(label, str):
            labels = [label]
        elif isinstance(label, Mapping):
            labels = [f"{k}:{v}" for k, v in label.items()]
        elif label is not None:
            labels = list(label)
        out: List[Job] = []
        cursor: Optional[str] = None
        while True:
            query: List[Any] = [("status", status), ("q", q), ("limit", limit), ("cursor", cursor)]
            query += [("label", lab) for lab in labels]
            with self._open("GET", "/jobs", query=query) as r:
                page = json.loads(r.read())
                cursor = r.headers.get("X-Next-Cursor")
            out.extend(Job(self, j) for j in page)
            if not all_pages or not cursor:
                return out

    def cancel(self, job_id: Union[str, Job]) -> Job:
        """``POST /api/v1/jobs/{id}/cancel``: cancel a queued or running job."""
        return Job(self, self._json("POST", f"/jobs/{_id(job_id)}/cancel"))

    def delete(self, job_id: Union[str, Job]) -> None:
        """``DELETE /api/v1/jobs/{id}``: remove a finished job and its files (409 while
        it is unfinished)."""
        with self._open("DELETE", f"/jobs/{_id(job_id)}") as r:
            r.read()

    def rerun(self, job_id: Union[str, Job]) -> Job:
        """``POST /api/v1/jobs/{id}/rerun``: a new queued job with the same scene."""
        return Job(self, self._json("POST", f"/jobs/{_id(job_id)}/rerun"))

    # ------------------------------------------------------------------ events and waiting

    def stream(self, job_id: Union[str, Job], timeout: Optional[float] = None) -> Iterator[Event]:
        """Iterate a job's Server-Sent Events (``GET /api/v1/jobs/{id}/events``), each as
        a dict ``{"event": name, "data": parsed JSON}`` (see :data:`Event`).

        The stream starts with the job's current ``progress`` and ``status`` and ends
        after a ``status`` event whose ``data["status"]`` is terminal (``completed``,
        ``failed``, ``cancelled``), or when the server closes it (e.g. at shutdown).

        Args:
            timeout: give up (raise :class:`FractureError`) when nothing, not even the
                server's keep-alive (every 10 s), arrives for this long. Default: the
                client's timeout.
        """
        resp = self._open(
            "GET", f"/jobs/{_id(job_id)}/events", accept="text/event-stream", timeout=timeout
        )
        return _sse_events(resp, f"{self.url}/api/v1/jobs/{_id(job_id)}/events")

    def wait(
        self,
        job: Union[str, Job],
        progress: ProgressArg = True,
        timeout: Optional[float] = None,
        check: bool = False,
        poll: float = 1.0,
        retry_seconds: float = 120.0,
    ) -> Job:
        """Wait until a job has ended and return it (as ``GET /api/v1/jobs/{id}``).

        Follows the job's event stream; if the stream drops (a server restart) it polls
        the job and opens the stream again.

        Args:
            job: the job or its id.
            progress: ``True`` prints a progress line to stderr (rewritten in place on a
                terminal, one line per 10 % otherwise); a callable is called with the
                :class:`Job` (its ``status`` and ``progress`` updated) at every progress or
                status event; ``False``/``None`` is silent.
            timeout: raise :class:`WaitTimeout` after this many seconds (the job goes
                on). Default: wait as long as it takes.
            check: raise :class:`JobFailed` if the job ends ``failed`` or ``cancelled``.
            poll: seconds between polls while the stream is unavailable.
            retry_seconds: while the server does not answer (a restart), keep retrying
                for this long, then raise :class:`ServerNotRunning`.
        """
        current = self.job(job)  # the state now, not that of an old Job object
        deadline = None if timeout is None else time.monotonic() + timeout
        report = _progress_printer(sys.stderr) if progress is True else progress or None
        if report is not None:
            report(current)
        down_since: Optional[float] = None

        def server_down(err: ServerNotRunning) -> None:
            nonlocal down_since
            now = time.monotonic()
            if down_since is None:
                down_since = now
                if progress is True:
                    sys.stderr.write(
                        f"\n{self.url} does not answer ({err.reason}); retrying for up to "
                        f"{retry_seconds:g} s\n"
                    )
            if now - down_since > retry_seconds or (deadline is not None and now > deadline):
                raise err
            time.sleep(poll)

        while not current.done:
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                raise WaitTimeout(current, float(timeout or 0))
            read_timeout = 30.0 if remaining is None else max(0.1, min(30.0, remaining))
            try:
                for ev in self.stream(current.id, timeout=read_timeout):
                    name, data = ev.get("event"), ev.get("data")
                    if name == "progress" and isinstance(data, dict):
                        current.raw["progress"] = data
                    elif name == "status" and isinstance(data, dict):
                        for k in ("status", "attempts", "message", "summary"):
                            if k in data:
                                current.raw[k] = data[k]
                    else:
                        continue
                    if report is not None:
                        report(current)
                    if current.done:
                        break
                    if deadline is not None and time.monotonic() > deadline:
                        break
            except ServerNotRunning as err:
                server_down(err)
                continue
            except FractureError:
                # Stream timed out or dropped: look at the job itself, then go on.
                pass
            if not current.done:
                try:
                    current = Job(self, self.job(current.id).raw)
                except ServerNotRunning as err:
                    server_down(err)
                    continue
                down_since = None
                if not current.done:
                    time.sleep(min(poll, 0.2))
        final = self.job(current.id)
        if report is not None and final.status != current.status:
            report(final)
        if check and final.status != "completed":
            raise JobFailed(final)
        return final

    # ------------------------------------------------------------------ results

    def crack_tips(self, job_id: Union[str, Job], since: Optional[float] = None) -> pd.DataFrame:
        """The crack-tip history as a DataFrame (``GET …/crack-tips``, JSON); columns and
        units as :attr:`mpm_fracture.Run.crack_tips`.

        Args:
            since: only rows with ``time`` greater than this (s).
        """
        return crack_tips_frame(
            self._json("GET", f"/jobs/{_id(job_id)}/crack-tips", query=[("since", since)])
        )

    def energy(self, job_id: Union[str, Job], since: Optional[float] = None) -> pd.DataFrame:
        """The energy history as a DataFrame (``GET …/energy``, JSON); columns and units
        as :attr:`mpm_fracture.Run.energy`."""
        return energy_frame(
            self._json("GET", f"/jobs/{_id(job_id)}/energy", query=[("since", since)])
        )

    def crack_tips_csv(self, job_id: Union[str, Job]) -> str:
        """The crack-tip history as the server's CSV text (``Accept: text/csv``)."""
        with self._open("GET", f"/jobs/{_id(job_id)}/crack-tips", accept="text/csv") as r:
            return str(r.read().decode("utf-8"))

    def energy_csv(self, job_id: Union[str, Job]) -> str:
        """The energy history as the server's CSV text (``Accept: text/csv``)."""
        with self._open("GET", f"/jobs/{_id(job_id)}/energy", accept="text/csv") as r:
            return str(r.read().decode("utf-8"))

    def snapshots(self, job_id: Union[str, Job]) -> List[Dict[str, Any]]:
        """The snapshot index: ``[{index, time (s), fields, components}, ...]``."""
        return list(self._json("GET", f"/jobs/{_id(job_id)}/snapshots"))

    def snapshot_png(
        self, job_id: Union[str, Job], index: int, field: str, **options: Any
    ) -> bytes:
        """A snapshot field as a PNG picture (``GET …/snapshots/{index}/{field}.png``).

        Args:
            field: a component (``sxx``, ``speed``, ``fringe``, ...) or a field kind
                (``stress`` renders ``sxx``).
            options: render options: ``px_per_cell``, ``width``, ``range=(lo, hi)`` (SI
                units), ``fringe_per_pa``, ``cracks``, ``legend`` (bools).
        """
        query: List[Any] = []
        for k, v in options.items():
            if isinstance(v, bool):
                v = "true" if v else "false"
            elif isinstance(v, (tuple, list)):
                v = ",".join(str(x) for x in v)
            query.append((k, v))
        path = f"/jobs/{_id(job_id)}/snapshots/{int(index)}/{urllib.parse.quote(field)}.png"
        with self._open("GET", path, accept="image/png", query=query) as r:
            return bytes(r.read())

    def download(
        self,
        job_id: Union[str, Job],
        folder: Union[str, "os.PathLike[str]"],
        files: Optional[Iterable[str]] = None,
    ) -> Dict[str, Path]:
        """Download a job's result files into ``folder`` (created if needed).

        Args:
            files: names among ``summary.json`` (the job's summary, once finished),
                ``crack_tips.csv``, ``energy.csv``, ``fields.mcap`` and ``vtk.zip`` (the
                snapshots as a zipped VTK series for ParaView). Default: all of them,
                leaving out those the job does not have (no summary yet, no snapshots);
                a file named explicitly that the job lacks raises :class:`ApiError`.

        Returns:
            ``{file name: path}`` of the files written.
        """
        jid = _id(job_id)
        explicit = files is not None
        names = list(files) if files is not None else list(DOWNLOADS)
        for n in names:
            if n not in DOWNLOADS:
                raise ValueError(f"unknown file {n!r}: choose among {', '.join(DOWNLOADS)}")
        dest = Path(folder)
        dest.mkdir(parents=True, exist_ok=True)
        out: Dict[str, Path] = {}
        job: Optional[Job] = None
        for n in names:
            target = dest / n
            if n == "summary.json":
                job = job or self.job(jid)
                if job.summary is None:
                    if explicit:
                        raise FractureError(f"job {jid} is {job.status}: it has no summary yet")
                    continue
                text = json.dumps(job.summary, indent=2).encode()
                _write_atomic(target, lambda f: f.write(text))
                out[n] = target
                continue
            route, accept = DOWNLOADS[n]
            try:
                resp = self._open("GET", f"/jobs/{jid}{route}", accept=accept)
            except ApiError as e:
                if e.status == 404 and not explicit and n in ("fields.mcap", "vtk.zip"):
                    continue
                raise
            with resp:
                _write_atomic(target, lambda f: shutil.copyfileobj(resp, f, 1 << 20))
            out[n] = target
        return out

    def run(
        self,
        job_id: Union[str, Job],
        folder: Optional[Union[str, "os.PathLike[str]"]] = None,
        snapshots: bool = True,
    ) -> Run:
        """Download a job's results into a run folder and open it as a
        :class:`~mpm_fracture.Run` (``run.job`` is the job object, with its scene).

        Args:
            folder: where to put ``summary.json``, ``crack_tips.csv``, ``energy.csv`` and
                ``fields.mcap``; default a new temporary folder.
            snapshots: also download ``fields.mcap`` (when the job has one).
        """
        job = self.job(job_id)
        if folder is None:
            folder = tempfile.mkdtemp(prefix=f"fracture-{job.id[:12]}-")
        files = ["summary.json", "crack_tips.csv", "energy.csv"]
        if snapshots:
            files.append("fields.mcap")
        dest = Path(folder)
        dest.mkdir(parents=True, exist_ok=True)
        if job.summary is not None:
            _write_atomic(dest / "summary.json", lambda f: f.write(json.dumps(job.summary, indent=2).encode()))
        for n in files[1:]:
            try:
                self.download(job.id, dest, [n])
            except ApiError as e:
                if not (e.status == 404 and n == "fields.mcap"):
                    raise
        return Run(dest, job=job.raw)

    # ------------------------------------------------------------------ sweeps

    def submit_sweep(
        self,
        scene: SceneLike,
        parameters: Mapping[str, Sequence[Any]],
        *,
        name: Optional[str] = None,
        priority: Optional[int] = None,
        labels: Optional[Mapping[str, str]] = None,
        max_concurrent: Optional[int] = None,
        cache: bool = True,
    ) -> Dict[str, Any]:
        """``POST /api/v1/sweeps``: one job per combination of parameter values.

        Args:
            parameters: ``{"cracks.0.propagation.toughness": [25, 100, 250], ...}``
                (dot-separated paths into the scene; the last parameter varies fastest).

        Returns:
            The sweep: ``{id, name, status, total, counts, progress, jobs: [{id, label,
            values, status, ...}], ...}``; each job is an ordinary job (:meth:`job`).
        """
        body: Dict[str, Any] = {
            "scene": dict(load_scene(scene)),
            "parameters": {k: list(v) for k, v in parameters.items()},
        }
        if name is not None:
            body["name"] = name
        if priority is not None:
            body["priority"] = int(priority)
        if labels:
            body["labels"] = dict(labels)
        if max_concurrent is not None:
            body["max_concurrent"] = int(max_concurrent)
        if not cache:
            body["cache"] = "force"
        return dict(self._json("POST", "/sweeps", body=body))

    def sweep(self, sweep_id: str) -> Dict[str, Any]:
        """``GET /api/v1/sweeps/{id}``: the sweep with its scene and jobs."""
        return dict(self._json("GET", f"/sweeps/{sweep_id}"))

    def sweeps(self, limit: Optional[int] = None) -> List[Dict[str, Any]]:
        """``GET /api/v1/sweeps``: sweeps, newest first (first page)."""
        return list(self._json("GET", "/sweeps", query=[("limit", limit)]))


# ---------------------------------------------------------------------- helpers


def load_scene(scene: SceneLike) -> Dict[str, Any]:
    """A scene as a dict: a mapping is copied, a path (``str`` or ``Path``) is read as
    JSON."""
    if isinstance(scene, Mapping):
        return dict(scene)
    p = Path(os.fspath(scene))
    try:
        with open(p, encoding="utf-8") as f:
            doc = json.load(f)
    except FileNotFoundError:
        raise FileNotFoundError(f"no scene file at {p}") from None
    if not isinstance(doc, dict):
        raise ValueError(f"{p} is not a scene: its JSON is not an object")
    return doc


def _id(job: Union[str, Job]) -> str:
    return job.id if isinstance(job, Job) else urllib.parse.quote(str(job), safe="")


def _write_atomic(target: Path, write: Callable[[IO[bytes]], Any]) -> None:
    tmp = target.with_name(target.name + ".part")
    with open(tmp, "wb") as f:
        write(f)
    os.replace(tmp, target)


def _sse_events(resp: http.client.HTTPResponse, url: str) -> Iterator[Event]:
    """Parse a ``text/event-stream`` response into events (see :data:`Event`)."""
    name: Optional[str] = None
    data: List[str] = []
    ev_id: Optional[str] = None
    try:
        while True:
            try:
                raw = resp.readline()
            except (socket.timeout, TimeoutError) as e:
                raise FractureError(f"{url}: no event within the timeout ({e})") from None
            except (ConnectionError, http.client.HTTPException, OSError) as e:
                raise FractureError(f"{url}: the event stream broke ({e})") from None
            if not raw:
                return
            line = raw.decode("utf-8").rstrip("\r\n")
            if line == "":
                if data or name:
                    text = "\n".join(data)
                    try:
                        parsed: Any = json.loads(text) if text else None
                    except ValueError:
                        parsed = text
                    ev: Event = {"event": name or "message", "data": parsed}
                    if ev_id is not None:
                        ev["id"] = ev_id
                    yield ev
                name, data, ev_id = None, [], None
                continue
            if line.startswith(":"):
                continue  # a comment: the keep-alive
            key, _, value = line.partition(":")
            if value.startswith(" "):
                value = value[1:]
            if key == "event":
                name = value
            elif key == "data":
                data.append(value)
            elif key == "id":
                ev_id = value
    finally:
        resp.close()


def _progress_printer(stream: IO[str]) -> Callable[[Job], None]:
    """The ``progress=True`` reporter of :meth:`Client.wait`."""
    tty = bool(getattr(stream, "isatty", lambda: False)())
    state: Dict[str, Any] = {"decile": -1, "status": "", "width": 0}

    def line(job: Job) -> str:
        p = job.progress or {}
        text = f"job {job.id[:12]} ({job.name}): {job.status}"
        if job.status == "running" or (p and not job.done):
            text += f" {100 * job.fraction:5.1f}%"
            if p:
                text += f"  t = {float(p.get('sim_time') or 0):.4g} of {float(p.get('end_time') or 0):.4g} s, step {p.get('step')}"
        elif job.done:
            s = job.summary or {}
            if s.get("wall_seconds") is not None:
                text += f" in {float(s['wall_seconds']):.2f} s ({s.get('steps')} steps, {s.get('particles')} particles)"
            if job.message:
                text += f": {job.message}"
        return text

    def report(job: Job) -> None:
        text = line(job)
        if tty:
            pad = max(0, int(state["width"]) - len(text))
            stream.write("\r" + text + " " * pad)
            state["width"] = len(text)
            if job.done:
                stream.write("\n")
        else:
            decile = int(job.fraction * 10)
            if job.status != state["status"] or decile != state["decile"]:
                stream.write(text + "\n")
            state["decile"] = decile
        state["status"] = job.status
        stream.flush()

    return report
