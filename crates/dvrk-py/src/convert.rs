//! Conversions between numpy arrays and the library's buffers, and the two ways heavy
//! work runs without the GIL: per-sample loops in chunks with a signal check between
//! chunks, and whole calls on a worker thread that the caller polls for Ctrl-C.

use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use nalgebra::DMatrix;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

use crate::errors::{error, input, Kind};

/// Samples per chunk of the per-sample loops: between chunks the GIL is taken back and
/// pending signals (Ctrl-C) are handled. A PSM regressor chunk takes a few ms.
pub const CHUNK: usize = 1024;

/// How often a caller waiting for a worker thread checks for signals.
const POLL: Duration = Duration::from_millis(50);

/// Set by [`hold_computations`]: long computations stop making progress until it is
/// cleared, so a test can interrupt one whatever the machine's speed.
static HOLD: AtomicBool = AtomicBool::new(false);

/// Test hook (``dvrk_ident._hold_computations(True)``): while held, a per-sample loop
/// stops after its first chunk and a background computation before it starts, both
/// still answering Ctrl-C. Tests of the interrupt use it so that the computation cannot
/// finish before the signal arrives, however fast the machine.
#[pyfunction]
#[pyo3(name = "_hold_computations")]
pub fn hold_computations(hold: bool) {
    HOLD.store(hold, Ordering::SeqCst);
}

/// How many computations wait in the hold right now.
static HELD: AtomicUsize = AtomicUsize::new(0);

/// Test hook (``dvrk_ident._held_computations()``): how many computations are waiting
/// in the hold, so a test sends its interrupt only once the call is under way.
#[pyfunction]
#[pyo3(name = "_held_computations")]
pub fn held_computations() -> usize {
    HELD.load(Ordering::SeqCst)
}

/// Blocks the calling thread while [`HOLD`] is set, counted in [`HELD`].
fn block_while_held() {
    if HOLD.load(Ordering::SeqCst) {
        HELD.fetch_add(1, Ordering::SeqCst);
        while HOLD.load(Ordering::SeqCst) {
            std::thread::sleep(Duration::from_millis(5));
        }
        HELD.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Waits, without the GIL and answering signals, while [`HOLD`] is set.
fn wait_while_held(py: Python<'_>) -> PyResult<()> {
    if !HOLD.load(Ordering::SeqCst) {
        return Ok(());
    }
    HELD.fetch_add(1, Ordering::SeqCst);
    let mut r = Ok(());
    while HOLD.load(Ordering::SeqCst) {
        py.detach(|| std::thread::sleep(Duration::from_millis(5)));
        r = py.check_signals();
        if r.is_err() {
            break;
        }
    }
    HELD.fetch_sub(1, Ordering::SeqCst);
    r
}

/// A batch of samples: `rows` rows of `width` values, row-major. `single`: the input
/// was one 1-D sample, so outputs drop the batch axis.
#[derive(Clone, Debug)]
pub struct Rows {
    pub data: Vec<f64>,
    pub rows: usize,
    pub width: usize,
    pub single: bool,
}

impl Rows {
    pub fn row(&self, k: usize) -> &[f64] {
        &self.data[k * self.width..(k + 1) * self.width]
    }

    pub fn zeros_like(other: &Rows) -> Rows {
        Rows {
            data: vec![0.0; other.data.len()],
            ..other.clone()
        }
    }

    /// Output shape: `[rows, tail...]`, or `tail` alone for a single sample.
    pub fn shape(&self, tail: &[usize]) -> Vec<usize> {
        let mut s = Vec::with_capacity(tail.len() + 1);
        if !self.single {
            s.push(self.rows);
        }
        s.extend_from_slice(tail);
        s
    }
}

/// `numpy.asarray(obj, dtype=float64)` as a read-only float64 array.
pub fn float_array<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let asarray = ASARRAY.import(py, "numpy", "asarray")?;
    let arr = asarray
        .call1((obj, "float64"))
        .map_err(|e| input(format!("{name}: not convertible to a float64 array: {e}")))?;
    arr.cast_into::<PyArrayDyn<f64>>()
        .map_err(|e| input(format!("{name}: not a float64 array: {e}")))
}

fn check_finite(values: &[f64], width: usize, name: &str, labels: &[String]) -> PyResult<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let (k, j) = (i / width.max(1), i % width.max(1));
        let label = labels.get(j).map(|l| format!(" ({l})")).unwrap_or_default();
        return Err(input(format!(
            "{name}: non-finite value {} at sample {k}, column {j}{label}",
            values[i]
        )));
    }
    Ok(())
}

/// A batch of samples from a 1-D array of `width` values (one sample) or a 2-D array of
/// shape `(N, width)`; every value must be finite. `labels` name the columns in
/// messages.
pub fn rows(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    width: usize,
    name: &str,
    labels: &[String],
) -> PyResult<Rows> {
    let arr = float_array(py, obj, name)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    let shape = view.shape().to_vec();
    let (n_rows, single) = match shape.as_slice() {
        [w] if *w == width => (1, true),
        [r, w] if *w == width => (*r, false),
        _ => {
            return Err(input(format!(
                "{name}: expected shape ({width},) for one sample or (N, {width}), got {}",
                fmt_shape(&shape)
            )))
        }
    };
    let data: Vec<f64> = view.iter().copied().collect();
    check_finite(&data, width, name, labels)?;
    Ok(Rows {
        data,
        rows: n_rows,
        width,
        single,
    })
}

/// Like [`rows`] for an optional argument that defaults to zeros shaped like `like`.
pub fn rows_or_zeros(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    like: &Rows,
    name: &str,
    like_name: &str,
    labels: &[String],
) -> PyResult<Rows> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Rows::zeros_like(like));
    };
    let r = rows(py, obj, like.width, name, labels)?;
    if r.rows != like.rows || r.single != like.single {
        return Err(input(format!(
            "{name} has shape {} but {like_name} has shape {}: give one sample per row of {like_name}",
            fmt_shape(&r.shape(&[r.width])),
            fmt_shape(&like.shape(&[like.width]))
        )));
    }
    Ok(r)
}

/// A 1-D float64 vector of length `len` (any length if `None`), finite values.
pub fn vector(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    len: Option<usize>,
    name: &str,
    labels: &[String],
) -> PyResult<Vec<f64>> {
    let arr = float_array(py, obj, name)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    let shape = view.shape().to_vec();
    match (shape.as_slice(), len) {
        ([l], Some(n)) if *l == n => {}
        ([_], None) => {}
        (_, Some(n)) => {
            return Err(input(format!(
                "{name}: expected shape ({n},), got {}",
                fmt_shape(&shape)
            )))
        }
        (_, None) => {
            return Err(input(format!(
                "{name}: expected a 1-D array, got shape {}",
                fmt_shape(&shape)
            )))
        }
    }
    let data: Vec<f64> = view.iter().copied().collect();
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        let label = labels.get(i).map(|l| format!(" ({l})")).unwrap_or_default();
        return Err(input(format!(
            "{name}: non-finite value {} at index {i}{label}",
            data[i]
        )));
    }
    Ok(data)
}

pub fn fmt_shape(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A new float64 array of `shape` that takes ownership of `data` (row-major).
pub fn array<'py>(py: Python<'py>, data: Vec<f64>, shape: &[usize]) -> Bound<'py, PyArrayDyn<f64>> {
    ArrayD::from_shape_vec(IxDyn(shape), data)
        .expect("buffer length matches the shape")
        .into_pyarray(py)
}

/// A matrix (samples × joints) as a new `(rows, cols)` float64 array.
pub fn matrix<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArrayDyn<f64>> {
    let (r, c) = m.shape();
    let mut data = Vec::with_capacity(r * c);
    for i in 0..r {
        data.extend(m.row(i).iter());
    }
    array(py, data, &[r, c])
}

/// Runs `f(sample, out_row)` for `rows` samples with `width` outputs each, without the
/// GIL, in chunks of [`CHUNK`] samples; between chunks pending signals are handled, so
/// Ctrl-C raises `KeyboardInterrupt` within one chunk.
pub fn per_sample<F>(py: Python<'_>, rows: usize, width: usize, mut f: F) -> PyResult<Vec<f64>>
where
    F: FnMut(usize, &mut [f64]) + Send,
{
    let mut out = vec![0.0; rows * width];
    if width == 0 {
        return Ok(out);
    }
    let mut start = 0;
    while start < rows {
        let end = (start + CHUNK).min(rows);
        let chunk = &mut out[start * width..end * width];
        // The last line of defence: a panic of the library becomes a `SolverError`
        // naming it, not pyo3's `PanicException` (a `BaseException`).
        py.detach(|| {
            std::panic::catch_unwind(AssertUnwindSafe(|| {
                for (k, o) in (start..end).zip(chunk.chunks_mut(width)) {
                    f(k, o);
                }
            }))
        })
        .map_err(internal_error)?;
        py.check_signals()?;
        wait_while_held(py)?;
        start = end;
    }
    Ok(out)
}

/// A caught panic as a `SolverError`: the library has a bug, and Python code catching
/// `DvrkError` (or `Exception`) still sees it.
fn internal_error(panic: Box<dyn std::any::Any + Send>) -> PyErr {
    let what = panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "unknown panic".into());
    error(
        Kind::Solver,
        format!("internal error (a bug of dvrk-ident, please report it): {what}"),
    )
}

/// A failure computed without the GIL, turned into an exception by the caller.
pub type Failure = (Kind, String);

/// Runs `f` on a worker thread and waits for it without the GIL, checking for signals
/// every 50 ms: Ctrl-C raises `KeyboardInterrupt` at once. The library has no
/// cancellation, so an interrupted computation finishes in the background and its
/// result is dropped.
pub fn background<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> Result<T, Failure> + Send + 'static,
{
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name("dvrk-ident".into())
        .spawn(move || {
            block_while_held();
            let r = std::panic::catch_unwind(AssertUnwindSafe(f));
            let _ = tx.send(r);
        })
        .map_err(|e| error(Kind::Solver, format!("cannot start a worker thread: {e}")))?;
    let mut rx = rx;
    loop {
        // `Receiver` is not `Sync`: move it into the GIL-free closure and back.
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match received {
            Ok(Ok(Ok(v))) => return Ok(v),
            Ok(Ok(Err((kind, message)))) => return Err(error(kind, message)),
            Ok(Err(panic)) => return Err(internal_error(panic)),
            Err(mpsc::RecvTimeoutError::Timeout) => py.check_signals()?,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(error(
                    Kind::Solver,
                    "internal error: the worker thread ended without a result",
                ))
            }
        }
    }
}

/// A Python string literal for `__repr__`.
pub fn py_str(s: &str) -> String {
    format!("'{}'", s.replace('\\', "\\\\").replace('\'', "\\'"))
}

/// `True` / `False`.
pub fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

/// A keyword argument naming an option of the library (`method="sdp"`, `criterion=...`,
/// `format=...`): parsed by the library ([`dvrk_ident::Named`]), as the command
/// line parses its flags, the error prefixed with the argument's name.
pub fn named<T: dvrk_ident::Named>(argument: &str, text: &str) -> PyResult<T> {
    T::parse_name(text).map_err(|e| crate::errors::input(format!("{argument}: {e}")))
}
