//! Values between Python and the library: images as NumPy arrays (out without a copy, in with
//! their shape and dtype checked), `set={...}` as `--set` overrides, and serde values as Python
//! objects.

use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use inimtrace::overrides::Override;
use inimtrace::raster::RgbImage;

use crate::errors::{memory_error, value_error, IntoPy};

/// An image as a `(rows, columns, 3)` float32 array that owns the image's own buffer: the
/// pixels are reinterpreted in place (`[f32; 3]` -> 3 x `f32`), never copied.
pub fn image_to_numpy(py: Python<'_>, img: RgbImage) -> PyResult<Bound<'_, PyArray3<f32>>> {
    let (rows, columns) = (img.height, img.width);
    let flat: Vec<f32> = bytemuck::allocation::cast_vec(img.pixels);
    let array = Array3::from_shape_vec((rows, columns, 3), flat)
        .map_err(|e| value_error(format!("image of {columns} x {rows} pixels: {e}")))?;
    Ok(PyArray3::from_owned_array(py, array))
}

/// A depth plane as a `(rows, columns)` float32 array owning the buffer (no copy).
pub fn depth_to_numpy(
    py: Python<'_>,
    depth: Vec<f32>,
    rows: usize,
    columns: usize,
) -> PyResult<Bound<'_, PyArray2<f32>>> {
    let array = Array2::from_shape_vec((rows, columns), depth)
        .map_err(|e| value_error(format!("depth plane of {columns} x {rows} pixels: {e}")))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// Describes a Python object for an error message: `float64 array of shape (4, 4)`, `list`.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    let shape = obj.getattr("shape").ok().map(|s| s.to_string());
    let dtype = obj.getattr("dtype").ok().map(|d| d.to_string());
    match (dtype, shape) {
        (Some(d), Some(s)) => format!("a {d} array of shape {s}"),
        _ => format!("a {}", obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "value".into())),
    }
}

/// A `(rows, columns, 3)` float32 NumPy array as an image (one copy into the library's
/// layout). `name` and `expected` (e.g. the display's LCD) make the `ValueError` clear; `caller`
/// (`simulate()`) names the call in a memory refusal. Masked arrays are refused (the library
/// would ignore the mask), and the copy is checked against the memory budget before it is made
/// and allocated fallibly: an array too large is an `OutOfMemoryError` (a `MemoryError`).
pub fn numpy_to_image(
    obj: &Bound<'_, PyAny>,
    name: &str,
    expected: Option<(usize, usize)>,
    caller: &str,
) -> PyResult<RgbImage> {
    let want = match expected {
        Some((rows, columns)) => format!("({rows}, {columns}, 3)"),
        None => "(rows, columns, 3)".to_string(),
    };
    let bad = || {
        value_error(format!(
            "{name} must be a float32 array of shape {want} (rows, columns, RGB), got {}",
            describe(obj)
        ))
    };
    let array = obj.cast::<PyArray3<f32>>().map_err(|_| bad())?;
    let masked = obj.py().import("numpy.ma")?.getattr("MaskedArray")?;
    if obj.is_instance(&masked)? {
        return Err(value_error(format!(
            "{name} is a masked array (numpy.ma.MaskedArray), whose mask would be ignored; pass \
             {name}.filled(value) or a plain array"
        )));
    }
    let shape = array.shape().to_vec();
    if shape[2] != 3 || expected.is_some_and(|(r, c)| shape[0] != r || shape[1] != c) || shape[0] == 0 || shape[1] == 0
    {
        return Err(bad());
    }
    let count = shape[0].saturating_mul(shape[1]);
    inimtrace::budget::check_buffer(
        &format!("the copy of `{name}`"),
        name,
        count,
        std::mem::size_of::<[f32; 3]>() as u64,
        caller,
    )
    .py_err()?;
    let readonly = array.try_readonly().map_err(|e| value_error(format!("{name}: {e}")))?;
    let view = readonly.as_array();
    let mut pixels: Vec<[f32; 3]> = Vec::new();
    pixels.try_reserve_exact(count).map_err(|_| {
        memory_error(format!(
            "{caller}: cannot allocate {} for the copy of `{name}`: the system refused the memory",
            inimtrace::budget::Bytes((count as u64).saturating_mul(12))
        ))
    })?;
    match view.as_slice() {
        Some(flat) => pixels.extend_from_slice(bytemuck::cast_slice::<f32, [f32; 3]>(flat)),
        None => {
            for row in view.outer_iter() {
                pixels.extend(row.outer_iter().map(|p| [p[0], p[1], p[2]]));
            }
        }
    }
    // The CLI's EXR reader's rule: linear RGB is finite and non-negative.
    let bad = |(i, p): (usize, &[f32; 3])| {
        p.iter().enumerate().find_map(|(c, &v)| inimtrace::raster::bad_sample(v).map(|kind| (i, c, v, kind)))
    };
    if let Some((i, c, v, kind)) = pixels.iter().enumerate().find_map(bad) {
        return Err(value_error(format!(
            "{name}[{}, {}, {c}] is {kind} ({v}); linear RGB samples must be finite and non-negative",
            i / shape[1],
            i % shape[1]
        )));
    }
    Ok(RgbImage { width: shape[1], height: shape[0], pixels })
}

/// How deep `set=` values may nest (lists and dicts inside each other): far beyond any setting,
/// and shallow enough that neither this conversion nor the TOML behind it can exhaust the stack.
pub const MAX_SET_DEPTH: usize = 64;

/// A Python value as a TOML value: bool, int, float, str, list/tuple, dict with str keys, nested
/// at most [`MAX_SET_DEPTH`] deep; a list or dict that contains itself is a `ValueError`.
pub fn to_toml(value: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    to_toml_in(value, key, &mut Vec::new())
}

/// [`to_toml`] inside the containers of `open` (their addresses, outermost first).
fn to_toml_in(value: &Bound<'_, PyAny>, key: &str, open: &mut Vec<usize>) -> PyResult<toml::Value> {
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        let i: i64 =
            value.extract().map_err(|_| value_error(format!("set: `{key}`: {value} does not fit in 64 bits")))?;
        return Ok(toml::Value::Integer(i));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract()?));
    }
    let is_dict = value.is_instance_of::<PyDict>();
    if is_dict || value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let id = value.as_ptr() as usize;
        if open.contains(&id) {
            return Err(value_error(format!("set: `{key}`: the value contains itself (a list or dict inside itself)")));
        }
        if open.len() == MAX_SET_DEPTH {
            return Err(value_error(format!("set: `{key}`: lists and dicts nested more than {MAX_SET_DEPTH} deep")));
        }
        open.push(id);
        let converted = if let Ok(d) = value.cast::<PyDict>() {
            let mut table = toml::Table::new();
            for (k, v) in d.iter() {
                let k: String =
                    k.extract().map_err(|_| value_error(format!("set: `{key}`: table keys must be strings")))?;
                let v = to_toml_in(&v, &format!("{key}.{k}"), open)?;
                table.insert(k, v);
            }
            toml::Value::Table(table)
        } else {
            let items = value.try_iter()?.map(|v| to_toml_in(&v?, key, open)).collect::<PyResult<Vec<_>>>()?;
            toml::Value::Array(items)
        };
        open.pop();
        return Ok(converted);
    }
    // NumPy scalars and other numbers: through float or int.
    if let Ok(i) = value.call_method0("__index__").and_then(|i| i.extract::<i64>()) {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(f) = value.call_method0("__float__").and_then(|f| f.extract::<f64>()) {
        return Ok(toml::Value::Float(f));
    }
    Err(value_error(format!(
        "set: `{key}`: cannot use {} as a setting (bool, int, float, str, list or dict)",
        describe(value)
    )))
}

/// `set=`: a dict of key -> value (`{"eye.pupil_diameter": 3}`), or a list of `KEY=VALUE`
/// strings exactly as `--set` takes them. The same overrides as the CLI's.
pub fn overrides(set: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Override>> {
    let Some(set) = set.filter(|s| !s.is_none()) else {
        return Ok(Vec::new());
    };
    if let Ok(d) = set.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in d.iter() {
            let key: String =
                k.extract().map_err(|_| value_error("set: keys must be strings such as \"eye.pupil_diameter\""))?;
            let value = to_toml(&v, &key)?;
            out.push(Override::new(&key, value).map_err(|e| value_error(format!("set: `{key}`: {e}")))?);
        }
        return Ok(out);
    }
    if set.is_instance_of::<PyString>() {
        return Err(value_error("set must be a dict {key: value} or a list of \"KEY=VALUE\" strings, not one string"));
    }
    let mut out = Vec::new();
    for item in
        set.try_iter().map_err(|_| value_error("set must be a dict {key: value} or a list of \"KEY=VALUE\" strings"))?
    {
        let text: String = item?.extract().map_err(|_| value_error("set: list items must be \"KEY=VALUE\" strings"))?;
        out.push(text.parse::<Override>().map_err(|e| value_error(format!("set: {e}")))?);
    }
    Ok(out)
}

/// A JSON value as the Python object `json.loads` would give (numbers stay exactly as they are).
pub fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        serde_json::Value::Null => py.None().into_bound(py),
        serde_json::Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        serde_json::Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        serde_json::Value::String(s) => PyString::new(py, s).into_any(),
        serde_json::Value::Array(items) => {
            PyList::new(py, items.iter().map(|v| json_to_py(py, v)).collect::<PyResult<Vec<_>>>()?)?.into_any()
        }
        serde_json::Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, v) in map {
                d.set_item(k, json_to_py(py, v)?)?;
            }
            d.into_any()
        }
    })
}

/// Any serializable library value as a Python object (through its JSON form).
pub fn to_py<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(value).map_err(|e| value_error(format!("cannot convert: {e}")))?;
    json_to_py(py, &json)
}
