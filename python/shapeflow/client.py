"""A client of the shapeflow service (``shapeflow serve``), on the standard
library only: submit a job with its inputs, follow its events, fetch results.

Every method maps to one operation of api/openapi.yaml (its ``operationId`` in
brackets); an HTTP error raises :class:`JobError` with the service's
problem+json ``detail``.
"""

from __future__ import annotations

import json
import os
import uuid
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Tuple, Union


class JobError(RuntimeError):
    """An HTTP error of the service: ``status`` (the HTTP code), ``detail`` (its message)."""

    def __init__(self, status: int, detail: str):
        super().__init__(f"HTTP {status}: {detail}")
        self.status = status
        self.detail = detail


class Client:
    """The service at ``url`` (e.g. ``http://127.0.0.1:8080``), with an API key or token if it needs one."""

    def __init__(self, url: str, token: Optional[str] = None, timeout: float = 60.0):
        self.url = url.rstrip("/")
        self.token = token
        self.timeout = timeout

    # -- plumbing
    def _request(
        self, method: str, path: str, body: Optional[bytes] = None, content_type: Optional[str] = None,
        timeout: Optional[float] = None,
    ):
        headers = {"Accept": "application/json, */*"}
        if self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        if content_type:
            headers["Content-Type"] = content_type
        req = urllib.request.Request(self.url + path, data=body, method=method, headers=headers)
        try:
            return urllib.request.urlopen(req, timeout=self.timeout if timeout is None else timeout)
        except urllib.error.HTTPError as e:
            text = e.read().decode("utf-8", "replace")
            try:
                detail = json.loads(text).get("detail", text)
            except ValueError:
                detail = text
            raise JobError(e.code, detail) from None

    def _json(self, method: str, path: str, body: Optional[bytes] = None, content_type: Optional[str] = None) -> Any:
        with self._request(method, path, body, content_type) as r:
            return json.loads(r.read())

    # -- operations
    def submit(self, spec: Union[Mapping[str, Any], str], inputs: Optional[Mapping[str, Any]] = None) -> str:
        """Create a job [createJob]; ``inputs`` maps the ``NAME`` of ``"input:NAME"`` to bytes, a file path
        or a numpy array (sent as the file :func:`shapeflow.run` would make of it). Returns the job's id."""
        text = spec if isinstance(spec, str) else json.dumps(spec)
        if not inputs:
            doc = self._json("POST", "/v1/jobs", text.encode(), "application/json")
            return doc["id"]
        from . import _file  # numpy arrays as the library's in-memory files

        boundary = "shapeflow-" + uuid.uuid4().hex
        parts = [_part(boundary, "spec", "spec.json", "application/json", text.encode())]
        for name, value in inputs.items():
            filename = os.path.basename(os.fspath(value)) if isinstance(value, (str, os.PathLike)) else name
            parts.append(_part(boundary, name, filename, "application/octet-stream", _file(name, value)))
        body = b"".join(parts) + f"--{boundary}--\r\n".encode()
        doc = self._json("POST", "/v1/jobs", body, f"multipart/form-data; boundary={boundary}")
        return doc["id"]

    def job(self, job: str) -> Dict[str, Any]:
        """The job's status and progress [getJob]."""
        return self._json("GET", f"/v1/jobs/{_id(job)}")

    def jobs(self) -> List[Dict[str, Any]]:
        """The jobs this key sees, newest first, every page [listJobs]."""
        out: List[Dict[str, Any]] = []
        token = None
        while True:
            query = "?" + urllib.parse.urlencode({"page_token": token}) if token else ""
            page = self._json("GET", f"/v1/jobs{query}")
            out.extend(page["jobs"])
            token = page.get("next_page_token")
            if not token:
                return out

    def events(self, job: str) -> Iterator[Tuple[str, Dict[str, Any]]]:
        """The job's Server-Sent Events as (event, data) pairs until the stream ends [jobEvents]."""
        with self._request("GET", f"/v1/jobs/{_id(job)}/events", timeout=None) as r:
            event, data = "message", []
            for raw in r:
                line = raw.decode("utf-8").rstrip("\r\n")
                if not line:
                    if data:
                        yield event, json.loads("\n".join(data))
                    event, data = "message", []
                elif line.startswith(":"):
                    continue
                else:
                    field, _, value = line.partition(":")
                    value = value[1:] if value.startswith(" ") else value
                    if field == "event":
                        event = value
                    elif field == "data":
                        data.append(value)

    def wait(self, job: str, progress: Optional[Callable[[Dict[str, Any]], Any]] = None) -> Dict[str, Any]:
        """Follow the job's events until it ends; ``progress`` gets every progress event's dict.
        Returns the final status (as :meth:`job`)."""
        for event, data in self.events(job):
            if event == "progress" and progress is not None:
                progress(data)
            elif event == "status":
                return data
        return self.job(job)

    def results(self, job: str) -> Dict[str, Any]:
        """The manifest of the result files available now [getResults]."""
        return self._json("GET", f"/v1/jobs/{_id(job)}/results")

    def download(self, job: str, name: str, to: Optional[Union[str, "os.PathLike[str]"]] = None) -> bytes:
        """The result file ``name`` (as the manifest lists it, e.g. ``shape.glb``, ``labels.tif``,
        ``evolution_vtk.zip``); written to ``to`` as well if given."""
        files = {f["name"]: f["href"] for f in self.results(job)["files"]}
        href = files.get(name, f"/v1/jobs/{_id(job)}/results/{urllib.parse.quote(name)}")
        with self._request("GET", href) as r:
            data = r.read()
        if to is not None:
            Path(to).write_bytes(data)
        return data

    def cancel(self, job: str) -> Dict[str, Any]:
        """Ask the job to stop [cancelJob]; its checkpoints are kept."""
        return self._json("POST", f"/v1/jobs/{_id(job)}/cancel")

    def delete(self, job: str) -> None:
        """Delete the job and everything stored for it [deleteJob]."""
        self._request("DELETE", f"/v1/jobs/{_id(job)}").close()


def _id(job: Union[str, Mapping[str, Any]]) -> str:
    return urllib.parse.quote(job["id"] if isinstance(job, Mapping) else str(job), safe="")


def _part(boundary: str, name: str, filename: str, media: str, data: bytes) -> bytes:
    head = (
        f"--{boundary}\r\nContent-Disposition: form-data; name=\"{name}\"; filename=\"{filename}\"\r\n"
        f"Content-Type: {media}\r\n\r\n"
    )
    return head.encode() + data + b"\r\n"
