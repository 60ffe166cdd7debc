//! Rendering: display images (paper Sec. 3) and retinal images (paper Sec. 2.3, 4), reading the
//! scene through the radiance-field interface ([`field`]).

pub mod adapting;
pub mod backend;
pub mod display_image;
pub mod display_stack;
pub mod display_thick;
pub mod field;
pub(crate) mod planar;
pub mod retina;
pub mod tracer;

pub use backend::{planar_kernel, with_fields, with_scene_fields, BackendChoice, FieldUser, Fields};
pub use display_image::{
    render_display_image, render_display_image_into, render_display_image_with_depth, DisplayRenderSettings, Method,
};
pub use field::{BundleSum, RadianceField, RayBundle, Sample};
pub use planar::FacingPlanes;
pub use retina::{ground_truth, simulate};
pub use tracer::{shade, SceneTracer};
