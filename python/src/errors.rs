//! pgt's errors as Python exceptions of the hierarchy in `pgt/_errors.py`: `pgt.Error` at the
//! root, `InputError` (also a `ValueError`) for bad input and arguments, `FileError` (also an
//! `OSError`, with `errno`) for a file that cannot be read or written, `GpuError` (also a
//! `RuntimeError`) and its `NoAdapterError` for the GPU side. The message is the CLI's
//! (`pgt::error::error_message`), so a Python user reads what a shell user reads.

use pgt::PgtError;
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The class `name` of `pgt._errors`.
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyType>> {
    Ok(py
        .import("pgt._errors")?
        .getattr(name)?
        .cast_into::<PyType>()?)
}

/// An exception of class `name` with `message`, `errno` set where given.
fn exception(py: Python<'_>, name: &str, message: String, errno: Option<i32>) -> PyErr {
    let made = class(py, name).and_then(|c| {
        let e = c.call1((message.clone(),))?;
        if let Some(n) = errno {
            e.setattr("errno", n)?;
        }
        Ok(PyErr::from_value(e))
    });
    made.unwrap_or_else(|e| e)
}

/// Which class an error of the library belongs to (the innermost cause decides).
fn class_name(e: &PgtError) -> &'static str {
    match e {
        PgtError::Input { .. } | PgtError::Usage(_) => "InputError",
        PgtError::Io { .. } => "FileError",
        PgtError::Gpu(m) if m == pgt::approx::NO_ADAPTER => "NoAdapterError",
        PgtError::Gpu(_) => "GpuError",
        PgtError::Interrupted => "Error",
        PgtError::Context { source, .. } => class_name(source),
    }
}

/// The OS error number of an I/O error, where there is one.
fn errno(e: &PgtError) -> Option<i32> {
    match e {
        PgtError::Io { source, .. } => source.raw_os_error(),
        PgtError::Context { source, .. } => errno(source),
        _ => None,
    }
}

/// A library error as a Python exception with the CLI's message.
pub fn to_py(py: Python<'_>, e: PgtError) -> PyErr {
    if matches!(e, PgtError::Interrupted) {
        return PyKeyboardInterrupt::new_err("interrupted");
    }
    let name = class_name(&e);
    let errno = errno(&e);
    exception(
        py,
        name,
        pgt::error::error_message(&anyhow::Error::from(e)),
        errno,
    )
}

/// An error of the CLI's functions (an `anyhow` chain): classified by the first library error
/// or I/O error in the chain, an `InputError` otherwise.
pub fn anyhow_to_py(py: Python<'_>, e: anyhow::Error) -> PyErr {
    let message = pgt::error::error_message(&e);
    let (name, errno) = e
        .chain()
        .find_map(|c| {
            if let Some(p) = c.downcast_ref::<PgtError>() {
                Some((class_name(p), errno(p)))
            } else {
                c.downcast_ref::<std::io::Error>()
                    .map(|io| ("FileError", io.raw_os_error()))
            }
        })
        .unwrap_or(("InputError", None));
    exception(py, name, message, errno)
}

/// An `InputError` with `message` (bad arguments found by the package itself: arrays of the
/// wrong shape, dtype or with NaN).
pub fn input_error(py: Python<'_>, message: impl Into<String>) -> PyErr {
    exception(py, "InputError", message.into(), None)
}

/// A `pgt.Error` for what cannot happen unless pgt has a bug (a panic in a worker thread).
pub fn internal_error(py: Python<'_>, message: impl Into<String>) -> PyErr {
    exception(py, "Error", message.into(), None)
}

/// `Result<T, PgtError>` to `PyResult<T>`.
pub trait IntoPy<T> {
    fn py_err(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPy<T> for pgt::Result<T> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}

impl<T> IntoPy<T> for anyhow::Result<T> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| anyhow_to_py(py, e))
    }
}

/// Emits a `pgt.PgtWarning` (a `UserWarning`) with `message`. `stacklevel` 1 names the Python
/// line that called into the extension; 2 its caller (past one of the package's wrappers).
pub fn warn(py: Python<'_>, message: &str, stacklevel: i32) -> PyResult<()> {
    let category = class(py, "PgtWarning")?;
    let text = std::ffi::CString::new(message.replace('\0', " "))
        .unwrap_or_else(|_| c"warning".to_owned());
    PyErr::warn(py, category.as_any(), &text, stacklevel)
}
