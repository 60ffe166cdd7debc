//! The radiance fields a sweep traces the scene with (Sec. 3.1's ray casting into the scene):
//! the same choice as `assess` makes, so that every point's scores are the ones `assess` gives
//! for it. The paper's kind of scene gets the fused planar kernel called directly (no virtual
//! call per ray); every other scene the backend [`with_fields`] builds.

use crate::accel::analytic::AnalyticRects;
use crate::error::Result;
use crate::render::backend::resolve;
use crate::render::{with_fields, BackendChoice, FacingPlanes, RadianceField};
use crate::scene::Scene;

/// Work that runs on a scene's fields: `shade` for radiance, `with_depth` for display images
/// (their hit distances), `name` for reports.
pub trait FieldUser {
    type Output;
    fn run<S: RadianceField + ?Sized, D: RadianceField + ?Sized>(
        self,
        shade: &S,
        with_depth: &D,
        name: &str,
    ) -> Result<Self::Output>;
}

/// Builds the fields of `scene` for `backend` as `assess` does and runs `user` on them.
pub fn with_scene_fields<U: FieldUser>(scene: &Scene, backend: BackendChoice, user: U) -> Result<U::Output> {
    if resolve(scene, backend) == BackendChoice::Analytic && scene.is_analytic() {
        let rects = AnalyticRects::new(scene)?;
        if let Some(fast) = FacingPlanes::new(scene, &rects) {
            return user.run(&fast, &fast, "analytic (fused planar kernel)");
        }
    }
    with_fields(scene, backend, |fields| user.run(fields.shade, fields.with_depth, fields.name))
}
