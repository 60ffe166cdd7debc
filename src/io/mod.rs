//! File input and output: OpenEXR images, PNG previews, figures and configuration files.

pub mod config;
pub mod exr;
pub mod figure;
pub mod input;
pub mod output;
pub mod png;
