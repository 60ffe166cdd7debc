//! Rendering: display images (paper Sec. 3) and retinal images (paper Sec. 2.3, 4).

pub mod display_image;
pub mod planar;
pub mod retina;

pub use display_image::{render_display_image, DisplayRenderSettings, Method, RadianceField, SceneTracer};
pub use planar::FacingPlanes;
pub use retina::{ground_truth, simulate};
