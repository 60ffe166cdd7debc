//! `inimtrace._inimtrace`, the extension module of the `inimtrace` Python package: the paper's
//! pipeline (Doronin et al., ICIP 2020, Sec. 2-4 and Table 1) with NumPy arrays in and out.
//! Every function runs the library code of the CLI command of the same name, so its outputs
//! equal the CLI's bit for bit. `python/inimtrace/__init__.py` is the package's pure-Python part (the `Assessment`
//! record, docstrings); `python/inimtrace/__init__.pyi` its type stubs.
//!
//! One concept per file: `errors.rs` (the exception classes), `convert.rs` (arrays, `set=`,
//! JSON-like values), `objects.rs` (`Display`, `Eye`, `Scene`, `Experiment`), `run.rs` (the
//! stages, the GIL, threads and progress).

use numpy::PyArrayMethods;
use pyo3::exceptions::PyImportError;
use pyo3::prelude::*;

mod convert;
mod errors;
mod objects;
mod run;

/// Imports NumPy and loads its C API now, so that a missing or unusable NumPy is an
/// `ImportError` at `import inimtrace` rather than a panic at the first array (the `numpy` crate
/// loads its APIs on first use, importing Python modules then, which a pending Ctrl-C would
/// interrupt).
fn load_numpy(py: Python<'_>) -> PyResult<()> {
    py.import("numpy").map_err(|e| PyImportError::new_err(format!("inimtrace needs NumPy (numpy>=1.21): {e}")))?;
    // The array API (`dtype`) and the borrow-checking API (a readonly borrow), both loaded on
    // first use.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        numpy::dtype::<f32>(py);
        drop(numpy::PyArray1::<f32>::zeros(py, 1, false).readonly());
    }))
    .map_err(|_| PyImportError::new_err("inimtrace cannot load the C API of the installed NumPy"))
}

#[pymodule]
fn _inimtrace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // First: a static text (no formatting), so that a CPU without what the build assumes gets
    // an ImportError rather than "illegal instruction" (see `inimtrace::cpu`).
    if inimtrace::cpu::lacks_assumed_features() {
        return Err(PyImportError::new_err(inimtrace::cpu::UNSUPPORTED));
    }
    load_numpy(m.py())?;
    errors::register(m)?;
    m.add_class::<objects::PyDisplay>()?;
    m.add_class::<objects::PyEye>()?;
    m.add_class::<objects::PyScene>()?;
    m.add_class::<objects::PyExperiment>()?;
    m.add_function(wrap_pyfunction!(run::render_display, m)?)?;
    m.add_function(wrap_pyfunction!(run::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run::ground_truth, m)?)?;
    m.add_function(wrap_pyfunction!(run::assess, m)?)?;
    m.add_function(wrap_pyfunction!(run::resolution, m)?)?;
    m.add_function(wrap_pyfunction!(run::compare, m)?)?;
    m.add_function(wrap_pyfunction!(run::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(run::read_replicates, m)?)?;
    m.add("__version__", inimtrace::version::TOOL.version)?;
    m.add("git_revision", inimtrace::version::TOOL.git_revision)?;
    m.add("has_embree", cfg!(feature = "embree"))?;
    Ok(())
}
