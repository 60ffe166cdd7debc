//! Rendering: display images (paper Sec. 3) and retinal images (paper Sec. 2.3, 4).

pub mod backend;
pub mod display_image;
pub mod planar;
pub mod retina;

pub use backend::{with_fields, BackendChoice, Fields};
pub use display_image::{
    render_display_image, render_display_image_with_depth, DisplayRenderSettings, Method, RadianceField, Sample,
    SceneTracer,
};
pub use planar::FacingPlanes;
pub use retina::{ground_truth, simulate};
