//! `shapeflow._shapeflow`: the library's run of a job for Python. The job spec is
//! the CLI's and the service's; a run releases the GIL, reports its checkpoints to
//! a callable, and stops between steps on Ctrl-C. The Python package
//! (`shapeflow/__init__.py`) wraps this module's `Run` as `shapeflow.Result`.

mod arrays;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use shapeflow::export::to_array_coordinates;
use shapeflow::flow::{Checkpoint, Progress};
use shapeflow::geometry::components;
use shapeflow::jobs::{
    output_files, parse_spec, prepare, result_state, run_with_frames, Frame, JobFailure, JobOutcome, PreparedJob,
    RunEvents, StateResults,
};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};

create_exception!(_shapeflow, SpecError, PyValueError, "A job spec (or an input it names) that cannot run: `.field` names the field as the CLI does, `.message` says what is wrong.");

fn spec_error(py: Python<'_>, e: shapeflow::jobs::SpecError) -> PyErr {
    let err = SpecError::new_err(e.to_string());
    let value = err.value(py);
    let _ = value.setattr("field", e.field.clone());
    let _ = value.setattr("message", e.message.clone());
    err
}

/// The file bytes of a C-contiguous array given as its raw bytes (a `uint8`
/// view), its dtype name, its shape and, for a volume, its spacing `(z, y, x)`.
#[pyfunction]
#[pyo3(signature = (name, dtype, shape, data, spacing=None))]
fn array_file<'py>(
    py: Python<'py>,
    name: &str,
    dtype: &str,
    shape: Vec<usize>,
    data: PyReadonlyArray1<'py, u8>,
    spacing: Option<[f64; 3]>,
) -> PyResult<Bound<'py, PyBytes>> {
    let bytes = data.as_slice().map_err(|e| PyValueError::new_err(format!("input {name:?}: {e}")))?;
    let file = arrays::array_file(dtype, &shape, bytes, spacing).map_err(|m| {
        spec_error(py, shapeflow::jobs::SpecError::new(format!("inputs['{name}']"), format!("the array {m}")))
    })?;
    Ok(PyBytes::new(py, &file))
}

/// Calls back into Python at every checkpoint, and looks for a signal (Ctrl-C)
/// after every iteration; an exception of either cancels the run and is kept.
struct Callbacks<'a> {
    progress: Option<Py<PyAny>>,
    cancel: &'a AtomicBool,
    error: Option<PyErr>,
    history: Vec<Progress>,
}

impl Callbacks<'_> {
    fn stop(&mut self, e: PyErr) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl RunEvents for Callbacks<'_> {
    fn progress(&mut self, p: &Progress) {
        self.history.push(*p);
        if self.error.is_none() {
            if let Err(e) = Python::attach(|py| py.check_signals()) {
                self.stop(e);
            }
        }
    }

    fn checkpoint(&mut self, c: &Checkpoint) {
        let Some(callback) = &self.progress else { return };
        if self.error.is_some() {
            return;
        }
        let last = self.history.last().filter(|p| p.iteration == c.iteration).copied();
        let called = Python::attach(|py| -> PyResult<()> {
            let d = PyDict::new(py);
            d.set_item("iteration", c.iteration)?;
            d.set_item("time", c.time)?;
            d.set_item("energy", c.energy)?;
            d.set_item("tau", c.tau)?;
            d.set_item("vertices", c.mesh.positions.len())?;
            if let Some(p) = last {
                d.set_item("components", p.components)?;
            }
            d.set_item("stage", c.stage)?;
            callback.call1(py, (d,))?;
            Ok(())
        });
        if let Err(e) = called {
            self.stop(e);
        }
    }
}

/// A finished run: the prepared job, its frames, its history and how it ended.
#[pyclass(module = "shapeflow._shapeflow", frozen)]
struct Run {
    job: PreparedJob,
    frames: Vec<Frame>,
    history: Vec<Progress>,
    last: Checkpoint,
    /// The state the results show ([`result_state`]).
    shown: Checkpoint,
    stop_reason: String,
    note: Option<String>,
    error: Option<String>,
}

/// Run the job `spec` (JSON text) with input files `files` (name → bytes),
/// calling `progress(dict)` at every checkpoint.
#[pyfunction]
#[pyo3(signature = (spec, files, progress=None))]
fn run(py: Python<'_>, spec: &str, files: HashMap<String, Vec<u8>>, progress: Option<Py<PyAny>>) -> PyResult<Run> {
    let parsed = parse_spec(spec).map_err(|e| spec_error(py, e))?;
    let job = py.detach(|| prepare(parsed, &files)).map_err(|e| spec_error(py, e))?;
    let cancel = AtomicBool::new(false);
    let mut events = Callbacks { progress, cancel: &cancel, error: None, history: Vec::new() };
    let (result, frames) = py.detach(|| run_with_frames(&job, None, &cancel, &mut events));
    if let Some(e) = events.error.take() {
        return Err(e);
    }
    let (last, stop_reason, note, error) = match result {
        Ok(JobOutcome { stop, note, last }) => (last, stop.as_str().to_string(), note.map(str::to_string), None),
        Err(failure) => {
            let JobFailure { error, last } = *failure;
            (last, "failed".to_string(), None, Some(error.to_string()))
        }
    };
    let shown = py.detach(|| result_state(&job, &last));
    Ok(Run { job, frames, history: events.history, last, shown, stop_reason, note, error })
}

#[pymethods]
impl Run {
    /// Why the run stopped (`converged`, `max_iterations`, `end_time`,
    /// `tau_min`, `pinch_off`, `vanished`, …; `failed` for a numeric failure).
    #[getter]
    fn stop_reason(&self) -> &str {
        &self.stop_reason
    }

    /// A sentence on the stop (with `tau_min` or `vanished`), or the numeric error of a failed run.
    #[getter]
    fn note(&self) -> Option<String> {
        self.error.clone().or_else(|| self.note.clone())
    }

    #[getter]
    fn dimension(&self) -> usize {
        self.shown.mesh.dimension
    }

    #[getter]
    fn is_image(&self) -> bool {
        self.job.image.is_some()
    }

    /// The shown state's vertices, flat: image jobs in the image's array order
    /// and physical units, the others in the job's coordinates.
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let image = self.job.image.as_deref();
        let flat: Vec<f64> = self
            .shown
            .mesh
            .positions
            .iter()
            .flat_map(|p| match image {
                Some(img) => to_array_coordinates(img, p),
                None => p.clone(),
            })
            .collect();
        PyArray1::from_vec(py, flat)
    }

    /// The cells (segments or triangles), flat.
    fn cells<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let flat: Vec<i64> = self.shown.mesh.elements.iter().flatten().map(|&v| v as i64).collect();
        PyArray1::from_vec(py, flat)
    }

    /// The component of each vertex (0, 1, …).
    fn components<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let m = &self.shown.mesh;
        let n = m.positions.len();
        let labels = if m.dimension == 2 {
            components(n, &m.elements.iter().map(|e| [e[0], e[1]]).collect::<Vec<_>>()).0
        } else {
            components(n, &m.elements.iter().map(|e| [e[0], e[1], e[2]]).collect::<Vec<_>>()).0
        };
        PyArray1::from_vec(py, labels.into_iter().map(|l| l as i64).collect())
    }

    /// The history: one list per column (`iteration`, `time`, `tau`, `energy`,
    /// `vertices`, `components`).
    fn energy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let h = &self.history;
        d.set_item("iteration", PyArray1::from_vec(py, h.iter().map(|p| p.iteration as i64).collect()))?;
        d.set_item("time", PyArray1::from_vec(py, h.iter().map(|p| p.time).collect()))?;
        d.set_item("tau", PyArray1::from_vec(py, h.iter().map(|p| p.tau).collect()))?;
        d.set_item("energy", PyArray1::from_vec(py, h.iter().map(|p| p.energy).collect()))?;
        d.set_item("vertices", PyArray1::from_vec(py, h.iter().map(|p| p.vertices as i64).collect()))?;
        d.set_item("components", PyArray1::from_vec(py, h.iter().map(|p| p.components as i64).collect()))?;
        Ok(d)
    }

    /// An image job's results: `shape`, `mask` (flat bool), `labels` (flat
    /// uint16) and `objects` (columns); `None` for other jobs.
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(a) = py.detach(|| StateResults::new(&self.job, &self.shown).image_arrays()) else { return Ok(None) };
        let d = PyDict::new(py);
        d.set_item("shape", a.shape.clone())?;
        d.set_item("mask", PyArray1::from_vec(py, a.mask))?;
        d.set_item("labels", PyArray1::from_vec(py, a.labels))?;
        let dim = a.shape.len();
        let o = PyDict::new(py);
        let rows = &a.objects;
        let f64s =
            |f: &dyn Fn(&shapeflow::export::ObjectRow) -> f64| PyArray1::from_vec(py, rows.iter().map(f).collect());
        let i64s =
            |f: &dyn Fn(&shapeflow::export::ObjectRow) -> i64| PyArray1::from_vec(py, rows.iter().map(f).collect());
        o.set_item("label", i64s(&|r| r.label as i64))?;
        o.set_item("area", i64s(&|r| r.num_pixels as i64))?;
        for k in 0..dim {
            o.set_item(format!("centroid-{k}"), f64s(&|r| r.array_centroid[k]))?;
        }
        for k in 0..2 * dim {
            o.set_item(format!("bbox-{k}"), i64s(&|r| r.array_bbox[k] as i64))?;
        }
        o.set_item("num_pixels", i64s(&|r| r.num_pixels as i64))?;
        let (size, boundary) = if dim == 2 {
            ("area_subpixel", "perimeter_subpixel")
        } else {
            ("volume_subpixel", "surface_area_subpixel")
        };
        o.set_item(size, f64s(&|r| r.size))?;
        o.set_item(boundary, f64s(&|r| r.boundary))?;
        // the shape's own centroid in the array's order (2D: rows from the top)
        for k in 0..dim {
            o.set_item(format!("centroid_subpixel-{k}"), f64s(&|r| r.centroid[dim - 1 - k]))?;
        }
        o.set_item("mean_intensity", f64s(&|r| r.mean_intensity))?;
        o.set_item("pixels_covered", i64s(&|r| r.pixels as i64))?;
        d.set_item("objects", o)?;
        Ok(Some(d))
    }

    /// shape.json of the shown state, as text.
    fn shape_json(&self) -> String {
        let doc = StateResults::new(&self.job, &self.shown).shape_document();
        serde_json::to_string_pretty(&doc).unwrap_or_default()
    }

    /// Every file the CLI writes for this run, as (relative path, bytes).
    fn files<'py>(&self, py: Python<'py>, title: &str) -> PyResult<Bound<'py, PyList>> {
        let files = py.detach(|| output_files(&self.job, &self.frames, &self.history, &self.last, title));
        let items: Vec<(String, Bound<'py, PyBytes>)> =
            files.into_iter().map(|(name, bytes)| (name, PyBytes::new(py, &bytes))).collect();
        PyList::new(py, items)
    }
}

#[pymodule]
fn _shapeflow(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SpecError", m.py().get_type::<SpecError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(array_file, m)?)?;
    m.add_class::<Run>()?;
    Ok(())
}
