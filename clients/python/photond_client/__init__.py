"""A client of the photond render daemon's HTTP API v1, for pipelines.

Standard library only (urllib), Python 3.9 or newer, fully typed (PEP 561). Install it with
``pip install ./clients/python`` (which also installs the ``photond-submit`` command, see
photond_client.submit), or copy this one file next to your script as photond_client.py::

    from photond_client import PhotondClient, PhotondError

    client = PhotondClient("http://127.0.0.1:8080")
    job_id = client.submit({"scene": {"builtin": "cornell-box"}, "preset": "preview"})
    status = client.wait(job_id, timeout=600)
    client.fetch_image(job_id, "cornell.exr")

Errors the daemon answers with (RFC 9457 problem+json) raise PhotondError with the problem's
status, title, detail and field; a daemon that cannot be reached raises PhotondError with
status 0 and a title naming its URL.
"""

from __future__ import annotations

import contextlib
import http.client
import json
import os
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Any, Callable, Dict, Generator, Iterator, List, Optional, Protocol

__all__ = ["PhotondClient", "PhotondError", "ServerEvent", "TERMINAL_STATES", "__version__"]

__version__ = "0.1.0"

#: States after which a job never changes again.
TERMINAL_STATES = frozenset({"done", "failed", "cancelled"})

_DEFAULT_TIMEOUT_S = 60.0
# A quiet event stream (a long photon pass) is reopened after this long, resuming with
# Last-Event-ID, so that a dead connection cannot hang a pipeline forever.
_STREAM_READ_TIMEOUT_S = 300.0
_POLL_INTERVAL_S = 0.25


class PhotondError(Exception):
    """An error answer of the daemon (problem+json), or a daemon that cannot be reached
    (status 0)."""

    def __init__(self, status: int, title: str, detail: str = "", field: Optional[str] = None,
                 type: str = "about:blank") -> None:  # noqa: A002 - the RFC 9457 member's name
        self.status = status
        self.title = title
        self.detail = detail
        self.field = field
        self.type = type
        super().__init__(str(self))

    def __str__(self) -> str:
        text = self.title
        if self.detail:
            text = f"{text}: {self.detail}" if text else self.detail
        if self.field:
            text += f" (field: {self.field})"
        return text


class ServerEvent:
    """One Server-Sent Event of a job: type ("state", "progress", "tile", "done", "failed",
    "cancelled"), id (a string, for Last-Event-ID) and data (parsed JSON, or the raw text when
    it is not JSON)."""

    __slots__ = ("type", "id", "data")

    type: str
    id: str
    data: Any

    def __init__(self, type: str, id: str, data: Any) -> None:  # noqa: A002
        self.type = type
        self.id = id
        self.data = data

    def __repr__(self) -> str:
        return f"ServerEvent(type={self.type!r}, id={self.id!r}, data={self.data!r})"


def _problem_from_http_error(error: urllib.error.HTTPError) -> PhotondError:
    body = b""
    try:
        body = error.read()
    except OSError:
        pass
    content_type = error.headers.get("Content-Type", "") if error.headers else ""
    document: Any = None
    if "json" in content_type.lower():
        try:
            document = json.loads(body.decode("utf-8"))
        except (ValueError, UnicodeDecodeError):
            document = None
    if isinstance(document, dict) and document.get("title"):
        field = document.get("field")
        return PhotondError(int(document.get("status", error.code)), str(document["title"]),
                            str(document.get("detail", "") or ""),
                            str(field) if field else None,
                            str(document.get("type", "about:blank")))
    detail = body.decode("utf-8", "replace").strip().replace("\n", " ")[:300]
    return PhotondError(error.code, f"{error.reason} (HTTP {error.code})", detail)


class PhotondClient:
    """Calls of the daemon's HTTP API v1. `base_url` is "http://host:port" (a path prefix is
    kept); `token` is sent as a bearer token."""

    def __init__(self, base_url: str, token: Optional[str] = None,
                 timeout: float = _DEFAULT_TIMEOUT_S) -> None:
        if "://" not in base_url:
            base_url = "http://" + base_url
        self.base_url = base_url.rstrip("/")
        self.token = token
        self.timeout = timeout

    # -- plumbing ------------------------------------------------------------------------------

    def _url(self, path: str) -> str:
        return self.base_url + path

    def _job_path(self, job_id: str, suffix: str = "") -> str:
        return "/v1/jobs/" + urllib.parse.quote(job_id, safe=":@") + suffix

    def _open(self, method: str, path: str, body: Optional[bytes] = None,
              headers: Optional[Dict[str, str]] = None, timeout: Optional[float] = None,
              no_timeout: bool = False) -> http.client.HTTPResponse:
        request = urllib.request.Request(self._url(path), data=body, method=method)
        if self.token:
            request.add_header("Authorization", "Bearer " + self.token)
        for name, value in (headers or {}).items():
            request.add_header(name, value)
        try:
            # no_timeout: a request the server answers only when a job ends (?wait=true).
            response: http.client.HTTPResponse = urllib.request.urlopen(
                request, timeout=None if no_timeout else (timeout or self.timeout))
            return response
        except urllib.error.HTTPError as error:
            raise _problem_from_http_error(error) from None
        except (urllib.error.URLError, http.client.HTTPException, OSError) as error:
            reason = getattr(error, "reason", error)
            raise PhotondError(0, f"cannot connect to the server at {self.base_url}",
                               str(reason)) from None

    def _json(self, method: str, path: str, document: Any = None,
              headers: Optional[Dict[str, str]] = None) -> Any:
        body = None
        all_headers = dict(headers or {})
        if document is not None:
            body = json.dumps(document).encode("utf-8")
            all_headers["Content-Type"] = "application/json"
        with self._open(method, path, body, all_headers) as response:
            text = response.read()
        if not text:
            return {}
        try:
            return json.loads(text.decode("utf-8"))
        except (ValueError, UnicodeDecodeError):
            raise PhotondError(0, f"the server at {self.base_url} answered {method} {path} "
                                  "with a body that is not JSON") from None

    def _json_object(self, method: str, path: str) -> Dict[str, Any]:
        answer = self._json(method, path)
        if not isinstance(answer, dict):
            raise PhotondError(0, f"the server at {self.base_url} answered {method} {path} "
                                  "with JSON that is not an object")
        return answer

    # -- jobs ----------------------------------------------------------------------------------

    def submit(self, job: Dict[str, Any], idempotency_key: Optional[str] = None) -> str:
        """POST /v1/jobs; returns the new job's id (the same id again for a repeated
        idempotency key)."""
        headers = {"Idempotency-Key": idempotency_key} if idempotency_key else None
        answer = self._json("POST", "/v1/jobs", job, headers)
        job_id = answer.get("id") if isinstance(answer, dict) else None
        if not isinstance(job_id, str):
            raise PhotondError(0, "the server accepted the job but sent no job id")
        return job_id

    def submit_batch(self, job: Dict[str, Any], cameras: List[Dict[str, Any]]) -> List[str]:
        """POST /v1/batches: a job per camera, run in order, each view's irradiance cache
        starting from the one before; returns the views' job ids in order."""
        answer = self._json("POST", "/v1/batches", {"job": job, "cameras": cameras})
        jobs = answer.get("jobs") if isinstance(answer, dict) else None
        if not isinstance(jobs, list) or len(jobs) != len(cameras):
            raise PhotondError(0, "the server accepted the batch but sent no job ids")
        return [str(view["id"]) for view in jobs]

    def status(self, job_id: str) -> Dict[str, Any]:
        """GET /v1/jobs/{id}: state, progress, plan, timings, photons.cache, error."""
        return self._json_object("GET", self._job_path(job_id))

    def jobs(self) -> List[Dict[str, Any]]:
        """GET /v1/jobs: the daemon's jobs, newest first."""
        answer = self._json("GET", "/v1/jobs")
        if isinstance(answer, dict) and "jobs" in answer:
            return list(answer["jobs"])
        return list(answer)

    def cancel(self, job_id: str) -> Dict[str, Any]:
        """DELETE /v1/jobs/{id}; returns the job's status."""
        return self._json_object("DELETE", self._job_path(job_id))

    def events(self, job_id: str, last_event_id: Optional[str] = None,
               read_timeout: float = _STREAM_READ_TIMEOUT_S
               ) -> Generator[ServerEvent, None, None]:
        """GET /v1/jobs/{id}/events as a generator of ServerEvent, from the first event (or
        after `last_event_id`) until the server ends the stream (after done, failed or
        cancelled). A broken connection raises PhotondError with status 0; pass the last
        event's id to resume."""
        headers = {"Accept": "text/event-stream"}
        if last_event_id:
            headers["Last-Event-ID"] = str(last_event_id)
        response = self._open("GET", self._job_path(job_id, "/events"), None, headers,
                              timeout=read_timeout)
        with response:
            yield from _parse_sse(response, self.base_url)

    def wait(self, job_id: str, timeout: Optional[float] = None,
             on_event: Optional[Callable[[ServerEvent], None]] = None) -> Dict[str, Any]:
        """Waits until the job is done, failed or cancelled and returns its final status (it
        does not raise for a failed job: look at status["state"] and status.get("error")).
        Follows the event stream, resuming after breaks; polls when the stream is refused.
        Raises TimeoutError after `timeout` seconds (None: no limit). `on_event`, when given,
        is called with each event of the stream as it arrives (progress, tiles, states; each
        once, also across reconnections; none while polling or for a job already ended)."""
        deadline = None if timeout is None else time.monotonic() + timeout

        def remaining() -> Optional[float]:
            if deadline is None:
                return None
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"job {job_id} did not finish within {timeout} s")
            return left

        status = self.status(job_id)
        last_event_id: Optional[str] = None
        use_events = True
        while status.get("state") not in TERMINAL_STATES:
            left = remaining()
            if use_events:
                read_timeout = _STREAM_READ_TIMEOUT_S if left is None else \
                    max(0.1, min(left, _STREAM_READ_TIMEOUT_S))
                stream = self.events(job_id, last_event_id, read_timeout)
                ended = False
                try:
                    for event in stream:
                        last_event_id = event.id or last_event_id
                        if on_event is not None:
                            on_event(event)
                        if event.type in TERMINAL_STATES:
                            ended = True
                            break
                        remaining()
                except PhotondError as error:
                    if error.status != 0:
                        use_events = False  # refused: poll instead
                    else:
                        remaining()  # a timeout past the deadline raises TimeoutError
                finally:
                    stream.close()
                if not ended:
                    time.sleep(_POLL_INTERVAL_S)  # broken or cut short: resume after a breath
            else:
                time.sleep(min(_POLL_INTERVAL_S, left) if left is not None else _POLL_INTERVAL_S)
            status = self.status(job_id)
        return status

    def fetch_image(self, job_id: str, path: str, wait: bool = True) -> str:
        """GET /v1/jobs/{id}/image.exr (with wait: blocks until the job ends, however long
        that takes) into `path`, written to a temporary name first. Returns `path`."""
        suffix = "/image.exr?wait=true" if wait else "/image.exr"
        return self._download(self._job_path(job_id, suffix), path, "image", no_timeout=wait)

    def fetch_preview(self, job_id: str, path: str) -> str:
        """GET /v1/jobs/{id}/preview.png (the job's tone-mapped preview; of the tiles so far
        while it runs) into `path`, written to a temporary name first. Returns `path`."""
        return self._download(self._job_path(job_id, "/preview.png"), path, "preview")

    def _download(self, server_path: str, path: str, what: str,
                  no_timeout: bool = False) -> str:
        temporary = f"{path}.part"
        with self._open("GET", server_path, no_timeout=no_timeout) as response:
            try:
                out = open(temporary, "wb")
            except OSError as error:
                raise PhotondError(0, f"cannot write {path}", error.strerror or str(error)) \
                    from None
            try:
                with out:
                    while True:
                        chunk = response.read(1 << 16)
                        if not chunk:
                            break
                        out.write(chunk)
            except (OSError, http.client.HTTPException) as error:
                if os.path.exists(temporary):
                    os.remove(temporary)
                raise PhotondError(0, f"the {what} download from {self.base_url} broke",
                                   str(error)) from None
        try:
            os.replace(temporary, path)
        except OSError as error:
            with contextlib.suppress(OSError):
                os.remove(temporary)
            raise PhotondError(0, f"cannot write {path}", error.strerror or str(error)) from None
        return path

    def tile(self, job_id: str, tx: int, ty: int) -> bytes:
        """GET /v1/jobs/{id}/tiles/{tx}/{ty}.exr: one finished tile as a small EXR."""
        with self._open("GET", self._job_path(job_id, f"/tiles/{int(tx)}/{int(ty)}.exr")) as r:
            return r.read()

    # -- scenes --------------------------------------------------------------------------------

    def upload_scene(self, path: str) -> str:
        """POST /v1/scenes with a .glb, a self-contained .gltf, or a zip / tar / tar.gz bundle
        of a .gltf with its files; returns the scene's content id ("sha256:..."), used as
        {"scene": {"id": ...}}."""
        with open(path, "rb") as scene_file:
            body = scene_file.read()
        extension = os.path.splitext(path)[1].lower()
        binary = extension == ".glb" or (extension != ".gltf" and body[:4] == b"glTF")
        content_type = "model/gltf-binary" if binary else "model/gltf+json"
        # The server tells bundles apart by their magic bytes; the type is for proxies and logs.
        bundle_types = {".zip": "application/zip", ".tar": "application/x-tar",
                        ".gz": "application/gzip", ".tgz": "application/gzip"}
        content_type = bundle_types.get(extension, content_type)
        answer = self._json_body("POST", "/v1/scenes", body, content_type)
        if not isinstance(answer, dict) or "id" not in answer:
            raise PhotondError(0, "the server accepted the scene but sent no id")
        return str(answer["id"])

    # -- photon maps and render caches ---------------------------------------------------------

    _CACHE_KINDS = ("photon-maps", "render-caches")

    def export_cache(self, kind: str, key: str, path: str) -> str:
        """GET /v1/photon-maps/{key} or /v1/render-caches/{key} (kind "photon-maps" or
        "render-caches"; the keys are photons.key and statistics.irradiance_cache.key of a job's
        status) into a file; returns the path."""
        if kind not in self._CACHE_KINDS:
            raise ValueError(f"kind must be one of {self._CACHE_KINDS}")
        with self._open("GET", f"/v1/{kind}/{urllib.parse.quote(key, safe='')}") as response:
            data = response.read()
        with open(path, "wb") as out:
            out.write(data)
        return path

    def import_cache(self, kind: str, key: str, path: str) -> bool:
        """PUT the file exported by export_cache on another daemon; True when the key was new
        there, False when the same artifact was already kept (PhotondError 409 for another)."""
        if kind not in self._CACHE_KINDS:
            raise ValueError(f"kind must be one of {self._CACHE_KINDS}")
        with open(path, "rb") as source:
            body = source.read()
        answer = self._json_body("PUT", f"/v1/{kind}/{urllib.parse.quote(key, safe='')}", body,
                                 "application/octet-stream")
        return bool(answer.get("created")) if isinstance(answer, dict) else False

    def _json_body(self, method: str, path: str, body: bytes, content_type: str) -> Any:
        with self._open(method, path, body, {"Content-Type": content_type}) as response:
            text = response.read()
        return json.loads(text.decode("utf-8")) if text else {}


class _LineReader(Protocol):
    def readline(self, __limit: int = ...) -> bytes: ...


def _parse_sse(response: _LineReader, base_url: str) -> Iterator[ServerEvent]:
    """Server-Sent Events (WHATWG HTML 9.2.6) from a file-like response, line by line."""
    event_type = ""
    data_lines: List[str] = []
    last_id = ""
    while True:
        try:
            raw = response.readline()
        except (OSError, http.client.HTTPException, ValueError) as error:
            raise PhotondError(0, f"the event stream from {base_url} broke", str(error)) from None
        if not raw:
            return
        line = raw.decode("utf-8", "replace").rstrip("\r\n")
        if not line:
            if data_lines or event_type:
                text = "\n".join(data_lines)
                try:
                    data: Any = json.loads(text) if text else None
                except ValueError:
                    data = text
                yield ServerEvent(event_type or "message", last_id, data)
            event_type, data_lines = "", []
            continue
        if line.startswith(":"):
            continue
        field, _, value = line.partition(":")
        if value.startswith(" "):
            value = value[1:]
        if field == "event":
            event_type = value
        elif field == "data":
            data_lines.append(value)
        elif field == "id" and "\0" not in value:
            last_id = value
