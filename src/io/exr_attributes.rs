//! Typed OpenEXR header attributes: what the rendered and simulated images of the paper's
//! pipeline (Sec. 4, Fig. 2) carry about how they were made, so that downstream tools (Python,
//! OpenCV, Nuke) read numbers as numbers. Numeric values are written as OpenEXR `double`
//! (`f64`), `float` (`f32`) or `int` (`i32`) attributes, names and notes as `string`.

use std::fmt;

use exr::meta::attribute::{AttributeValue, Text};

/// One attribute value.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    /// An EXR `string`.
    Text(String),
    /// An EXR `double`.
    F64(f64),
    /// An EXR `float`.
    F32(f32),
    /// An EXR `int`.
    I32(i32),
}

impl AttrValue {
    /// The OpenEXR type name (`string`, `double`, `float`, `int`).
    pub fn type_name(&self) -> &'static str {
        match self {
            AttrValue::Text(_) => "string",
            AttrValue::F64(_) => "double",
            AttrValue::F32(_) => "float",
            AttrValue::I32(_) => "int",
        }
    }

    /// A count as an `int` attribute (saturating at `i32::MAX`).
    pub fn count(n: usize) -> Self {
        AttrValue::I32(i32::try_from(n).unwrap_or(i32::MAX))
    }

    /// The `exr` crate's value; `None` for text that is not Latin-1.
    pub(super) fn to_exr(&self) -> Option<AttributeValue> {
        Some(match self {
            AttrValue::Text(s) => AttributeValue::Text(Text::new_or_none(s)?),
            AttrValue::F64(v) => AttributeValue::F64(*v),
            AttrValue::F32(v) => AttributeValue::F32(*v),
            AttrValue::I32(v) => AttributeValue::I32(*v),
        })
    }

    /// From the `exr` crate's value, for the types this module writes.
    pub(super) fn from_exr(value: &AttributeValue) -> Option<Self> {
        Some(match value {
            AttributeValue::Text(t) => AttrValue::Text(t.to_string()),
            AttributeValue::F64(v) => AttrValue::F64(*v),
            AttributeValue::F32(v) => AttrValue::F32(*v),
            AttributeValue::I32(v) => AttrValue::I32(*v),
            _ => return None,
        })
    }
}

/// Text as it is; numbers as Rust prints them (shortest round-trip form: `300`, `2.5925`).
impl fmt::Display for AttrValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AttrValue::Text(s) => f.write_str(s),
            AttrValue::F64(v) => write!(f, "{v}"),
            AttrValue::F32(v) => write!(f, "{v}"),
            AttrValue::I32(v) => write!(f, "{v}"),
        }
    }
}

impl From<String> for AttrValue {
    fn from(s: String) -> Self {
        AttrValue::Text(s)
    }
}
impl From<&str> for AttrValue {
    fn from(s: &str) -> Self {
        AttrValue::Text(s.to_string())
    }
}
impl From<f64> for AttrValue {
    fn from(v: f64) -> Self {
        AttrValue::F64(v)
    }
}
impl From<f32> for AttrValue {
    fn from(v: f32) -> Self {
        AttrValue::F32(v)
    }
}
impl From<i32> for AttrValue {
    fn from(v: i32) -> Self {
        AttrValue::I32(v)
    }
}

/// An ordered list of `inimtrace:` attributes being assembled.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attributes(
    /// `(name, value)` pairs, in header order.
    pub Vec<(String, AttrValue)>,
);

impl Attributes {
    /// No attributes.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `name = value` (later values of the same name replace earlier ones when written).
    pub fn set(&mut self, name: impl Into<String>, value: impl Into<AttrValue>) -> &mut Self {
        self.0.push((name.into(), value.into()));
        self
    }

    /// Appends every attribute of `other`.
    pub fn extend(&mut self, other: Attributes) -> &mut Self {
        self.0.extend(other.0);
        self
    }

    /// The value of `name` (the last one given).
    pub fn get(&self, name: &str) -> Option<&AttrValue> {
        self.0.iter().rev().find(|(n, _)| n == name).map(|(_, v)| v)
    }
}
