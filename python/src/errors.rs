//! The Python exceptions of the library's errors (`inimtrace::Error`, which names the file and
//! field): one class per kind of input that was wrong, each carrying the CLI's message and, as
//! attributes, the file (`source`) and the field when the error names them. Memory refusals and
//! allocation failures are `OutOfMemoryError`, a subclass of both `inimtrace.Error` and Python's
//! `MemoryError`; a cancelled run is Python's `KeyboardInterrupt`. Warnings (a value valid but
//! implausible, most likely a unit mistake) are Python warnings (`UserWarning`), the CLI's text.

use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyMemoryError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

use inimtrace::Error as LibError;

pyo3::create_exception!(
    inimtrace,
    Error,
    PyException,
    "Base class of inimtrace's errors. `str(e)` is the message the CLI prints; `e.source` names the \
     file (or what stood for one, such as `Eye()`) and `e.field` the field, line or element when the error names them."
);
pyo3::create_exception!(
    inimtrace,
    ConfigError,
    Error,
    "An experiment, scene or display file (TOML, OpenCV YAML), a `set=` override or an argument is wrong."
);
pyo3::create_exception!(inimtrace, MeshError, Error, "A mesh file (OBJ/MTL, PLY, STL, glTF/GLB) is wrong.");
pyo3::create_exception!(
    inimtrace,
    ImageError,
    Error,
    "An image file (EXR, PNG, JPEG: display images, textures) is wrong or cannot be read or written."
);
pyo3::create_exception!(
    inimtrace,
    OpticsError,
    Error,
    "An optical configuration for which the computation has no answer (e.g. PupilCenter when the lenslet images the pupil centre onto the LCD)."
);

/// `OutOfMemoryError(Error, MemoryError)`: made when the module is loaded (a class with two bases,
/// which `create_exception!` cannot make).
static OUT_OF_MEMORY: PyOnceLock<Py<PyType>> = PyOnceLock::new();

const OUT_OF_MEMORY_DOC: &str = "Settings or arrays that need more memory than the budget allows (`--max-memory`, the \
     machine's free memory, the process's limits), refused before anything is allocated, or a buffer the system \
     would not allocate. A subclass of both `inimtrace.Error` and Python's `MemoryError`.";

/// Which exception class an error becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Base,
    Config,
    Mesh,
    Image,
    Optics,
    Memory,
    Cancelled,
}

const MESH_EXTENSIONS: [&str; 7] = ["obj", "mtl", "ply", "stl", "gltf", "glb", "bin"];
const IMAGE_EXTENSIONS: [&str; 4] = ["exr", "png", "jpg", "jpeg"];

/// The kind of file that `path` names, by its extension.
fn file_class(path: &str) -> Option<Class> {
    let ext = path.rsplit_once('.')?.1.to_ascii_lowercase();
    if MESH_EXTENSIONS.contains(&ext.as_str()) {
        Some(Class::Mesh)
    } else if IMAGE_EXTENSIONS.contains(&ext.as_str()) {
        Some(Class::Image)
    } else {
        None
    }
}

/// The class of an error: that of the innermost error of a chain of files naming files
/// (`outer.toml: field `scene`: cannot load `s.toml`: mesh.obj: line 3: ...` is a mesh error), by
/// its variant and the file it names, never by its message.
fn classify(e: &LibError) -> Class {
    match e.innermost() {
        LibError::Singular(_) | LibError::Lattice { .. } => Class::Optics,
        LibError::Alloc(_) | LibError::Memory { .. } => Class::Memory,
        LibError::Cancelled => Class::Cancelled,
        LibError::Embree { .. } | LibError::External { .. } | LibError::Incomplete(_) => Class::Base,
        LibError::Io { path, .. } | LibError::Parse { path, .. } | LibError::UnknownFormat { path, .. } => {
            file_class(&path.to_string_lossy()).unwrap_or(Class::Config)
        }
        LibError::Invalid { source_name, .. } => file_class(source_name).unwrap_or(Class::Config),
        LibError::Draw { .. } => Class::Image,
        _ => Class::Config,
    }
}

/// The Python exception of a library error: its class, the CLI's message, and the attributes
/// `source` and `field` (`None` where the error names none).
pub fn to_py(e: LibError) -> PyErr {
    let message = e.to_string();
    let (source, field) = e.source_and_field();
    Python::attach(|py| {
        let err = match classify(&e) {
            Class::Base => Error::new_err(message),
            Class::Config => ConfigError::new_err(message),
            Class::Mesh => MeshError::new_err(message),
            Class::Image => ImageError::new_err(message),
            Class::Optics => OpticsError::new_err(message),
            Class::Memory => match OUT_OF_MEMORY.get(py) {
                Some(class) => PyErr::from_type(class.bind(py).clone(), message),
                None => PyMemoryError::new_err(message),
            },
            Class::Cancelled => return PyKeyboardInterrupt::new_err(message),
        };
        let value = err.value(py);
        // Setting attributes on a fresh exception object cannot fail short of memory exhaustion;
        // the exception is raised either way.
        let _ = value.setattr("source", source);
        let _ = value.setattr("field", field);
        err
    })
}

/// An `OutOfMemoryError` of the module's own (an array input over the budget, a copy the system
/// refused), with `source` and `field` `None`.
pub fn memory_error(message: impl Into<String>) -> PyErr {
    to_py(LibError::Alloc(message.into()))
}

/// `Result<T, inimtrace::Error>` into a Python result.
pub trait IntoPy<T> {
    fn py_err(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for inimtrace::Result<T> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// A `ValueError` for an argument outside a closed set or of the wrong shape.
/// Issues each of `warnings` (the CLI's `warning:` lines, without the prefix) as a Python
/// `UserWarning` at the caller's line.
pub fn warn_all(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    for w in warnings {
        let text = std::ffi::CString::new(w.replace('\0', " ")).expect("no NUL left");
        PyErr::warn(py, &category, &text, 1)?;
    }
    Ok(())
}

pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Registers the exception classes in the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("MeshError", py.get_type::<MeshError>())?;
    m.add("ImageError", py.get_type::<ImageError>())?;
    m.add("OpticsError", py.get_type::<OpticsError>())?;
    let class = OUT_OF_MEMORY.get_or_try_init(py, || -> PyResult<Py<PyType>> {
        let bases = PyTuple::new(py, [py.get_type::<Error>(), py.get_type::<PyMemoryError>()])?;
        let namespace = PyDict::new(py);
        namespace.set_item("__doc__", OUT_OF_MEMORY_DOC)?;
        namespace.set_item("__module__", "inimtrace")?;
        let class = py.get_type::<PyType>().call1(("OutOfMemoryError", bases, namespace))?;
        Ok(class.cast_into::<PyType>()?.unbind())
    })?;
    m.add("OutOfMemoryError", class.bind(py))?;
    Ok(())
}
