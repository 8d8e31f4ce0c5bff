"""shapeflow from Python: run a job in this process (:func:`run`) or drive a
``shapeflow serve`` over HTTP (:class:`Client`).

The job spec is the one the CLI and the service take (docs/job-spec.md), as a
dict or as JSON text. Image results are numpy arrays in the image's own axis
order: 2D ``(row, column)`` with rows from the top, volumes ``(z, y, x)``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable, Dict, Mapping, Optional, Union

import numpy as np

from . import _shapeflow
from ._shapeflow import SpecError
from .client import Client, JobError

__all__ = ["run", "Result", "SpecError", "Client", "JobError", "__version__"]
__version__ = _shapeflow.__version__

Input = Union[np.ndarray, bytes, bytearray, str, "os.PathLike[str]", tuple]


def _spec_error(field: str, message: str) -> SpecError:
    e = SpecError(f"{field}: {message}")
    e.field, e.message = field, message
    return e


def _file(name: str, value: Any) -> bytes:
    """The bytes of one input: a file's, or an array's as an in-memory image."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    if isinstance(value, (str, os.PathLike)):
        try:
            return Path(value).read_bytes()
        except OSError as e:
            raise _spec_error(f"inputs[{name!r}]", f"cannot read {os.fspath(value)!r}: {e.strerror}") from e
    spacing = None
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], np.ndarray):
        value, spacing = value
        spacing = tuple(float(s) for s in spacing)
        if len(spacing) != 3:
            raise _spec_error(f"inputs[{name!r}]", "the spacing is (z, y, x): three numbers")
    if not isinstance(value, np.ndarray):
        raise _spec_error(
            f"inputs[{name!r}]", f"give a numpy array, (array, spacing), bytes or a file path, not {type(value).__name__}"
        )
    a = value
    if a.dtype == np.bool_:
        a = a.astype(np.uint8) * 255
    elif a.dtype in (np.float64, np.float16):
        a = a.astype(np.float32)
    elif a.dtype.kind in "iu" and a.dtype not in (np.uint8, np.uint16):
        if a.size and (a.min() < 0 or a.max() > 65535):
            raise _spec_error(f"inputs[{name!r}]", "integer samples must lie in 0..65535 (uint16)")
        a = a.astype(np.uint16)
    a = np.ascontiguousarray(a)
    if a.dtype.byteorder not in "=|":
        a = a.astype(a.dtype.newbyteorder("="))
    raw = a.reshape(-1).view(np.uint8)
    return _shapeflow.array_file(name, a.dtype.name, list(a.shape), raw, spacing)


def run(
    spec: Union[Mapping[str, Any], str],
    inputs: Optional[Mapping[str, Input]] = None,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> "Result":
    """Run the job ``spec`` here and return its :class:`Result`.

    ``inputs`` maps the ``NAME`` of ``"input:NAME"`` to a numpy array (a 2D
    image ``(rows, columns[, channels])``, a volume ``(z, y, x)``, or
    ``(volume, (dz, dy, dx))`` with its spacing), the bytes of a file, or a file
    path. ``progress`` is called at every checkpoint with a dict of at least
    ``iteration``, ``time`` and ``energy``. The GIL is released while the flow
    runs; Ctrl-C (KeyboardInterrupt) stops it between steps and is raised here.
    A bad spec or input raises :class:`SpecError` naming the field.
    """
    text = spec if isinstance(spec, str) else json.dumps(spec)
    files = {name: _file(name, value) for name, value in (inputs or {}).items()}
    return Result(_shapeflow.run(text, files, progress))


class Result:
    """The end of a run: the shape its results show, the history and, for image
    jobs, the mask, the label image and the table of objects."""

    def __init__(self, run: "_shapeflow.Run"):
        self._run = run
        d = run.dimension
        self.dimension: int = d
        """2 for curves, 3 for surfaces."""
        self.vertices: np.ndarray = run.vertices().reshape(-1, d)
        """N×2 or N×3: image jobs in the image's axis order ((row, column) or (z, y, x)) and physical units."""
        self.cells: np.ndarray = run.cells().reshape(-1, d)
        """M×2 segments (curves) or M×3 triangles (surfaces), indices into ``vertices``."""
        self.components: np.ndarray = run.components()
        """The component (0, 1, …) of each vertex."""
        self.energy: Dict[str, np.ndarray] = run.energy()
        """The history: ``iteration``, ``time``, ``tau``, ``energy``, ``vertices``, ``components``."""
        self.stop_reason: str = run.stop_reason
        """``converged``, ``max_iterations``, ``end_time``, ``tau_min``, ``pinch_off``, ``vanished``, … or ``failed``."""
        self.note: Optional[str] = run.note
        """A sentence on the stop, or the numeric error of a failed run."""
        image = run.image()
        self.mask: Optional[np.ndarray] = None
        """Image jobs: inside (True) / outside, the input's shape and axis order."""
        self.labels: Optional[np.ndarray] = None
        """Image jobs: uint16 labels 1..n (0 background), the input's shape and axis order."""
        self.objects: Optional[Dict[str, np.ndarray]] = None
        """Image jobs: scikit-image's regionprops_table columns of ``labels`` and shapeflow's own measures."""
        if image is not None:
            shape = tuple(image["shape"])
            self.mask = image["mask"].reshape(shape)
            self.labels = image["labels"].reshape(shape)
            self.objects = image["objects"]

    @property
    def segments(self) -> Optional[np.ndarray]:
        """The cells of a curve (M×2), None for a surface."""
        return self.cells if self.dimension == 2 else None

    @property
    def triangles(self) -> Optional[np.ndarray]:
        """The cells of a surface (M×3), None for a curve."""
        return self.cells if self.dimension == 3 else None

    def shape_json(self) -> Dict[str, Any]:
        """shape.json of the result, as a dict."""
        return json.loads(self._run.shape_json())

    def save(self, directory: Union[str, "os.PathLike[str]"]) -> list:
        """Write every file the CLI writes (shape.json, shape.glb, shape.vtp,
        evolution.glb, evolution.pvd with evolution/*.vtp, the image results,
        energy.csv and .svg, checkpoint.json) into ``directory``; the names written."""
        out = Path(directory)
        names = []
        for name, data in self._run.files(str(out)):
            p = out / name
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)
            names.append(name)
        return names

    def __repr__(self) -> str:
        cells = "segments" if self.dimension == 2 else "triangles"
        objects = "" if self.objects is None else f", {len(self.objects['label'])} objects"
        return f"<shapeflow.Result {self.stop_reason}: {len(self.vertices)} vertices, {len(self.cells)} {cells}{objects}>"
