//! Choosing the scene-intersection backend and the radiance field for a render (paper Sec. 3.1:
//! rays traced into the 3-D scene): the one home of that decision, [`with_scene_fields`], which
//! `assess`, `sweep`, the CLI's single-image commands and Python all go through (`bench`, which
//! times every backend, takes its fused kernel from [`planar_kernel`] too). `auto` picks the
//! exact analytic backend (with its fused planar kernel when the scene allows it) for scenes
//! made only of rectangles, and Embree otherwise. Mesh backends see every rectangle tessellated
//! into two triangles ([`Rect::to_mesh`]), so every scene renders with every mesh backend.

use std::borrow::Cow;
use std::fmt;
use std::str::FromStr;

use super::field::RadianceField;
use super::planar::FacingPlanes;
use super::tracer::SceneTracer;
use crate::accel::analytic::AnalyticRects;
use crate::accel::brute::BruteForce;
use crate::error::{Error, Result};
use crate::scene::{Mesh, Rect, Scene, Shape};

/// Largest scene (in triangles) the brute-force backend accepts: it tests every triangle for
/// every ray, so it is for small scenes and tests only.
pub const BRUTE_MAX_TRIANGLES: usize = 10_000;

/// The scene-intersection backend of a render (`--backend`; parsed by [`FromStr`], named by
/// [`Display`](fmt::Display)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BackendChoice {
    /// Analytic for rectangle-only scenes, else Embree.
    #[default]
    Auto,
    /// Exact f64 rectangles (the paper's kind of scene).
    Analytic,
    /// Intel Embree (triangles).
    Embree,
    /// The pure-Rust BVH (inimtrace's own 4-wide tree, f64 watertight triangle test).
    Bvh,
    /// Every triangle for every ray (small scenes only).
    /// (Also spelled `brute-force`.)
    Brute,
}

impl FromStr for BackendChoice {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "analytic" => Ok(Self::Analytic),
            "embree" => Ok(Self::Embree),
            "bvh" => Ok(Self::Bvh),
            "brute" | "brute-force" => Ok(Self::Brute),
            _ => Err(format!("unknown backend `{s}`: expected auto, analytic, embree, bvh or brute")),
        }
    }
}

impl fmt::Display for BackendChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Auto => "auto",
            Self::Analytic => "analytic",
            Self::Embree => "embree",
            Self::Bvh => "bvh",
            Self::Brute => "brute",
        })
    }
}

/// The fields a render uses: `shade` for radiance only (fastest), `with_depth` when hit
/// distances are wanted too (the display EXR's `Z` channel). For mesh backends and the
/// generic analytic path they are the same object; the fused planar kernel does not know
/// depths, so display images come from the generic analytic tracer (same radiance).
pub struct Fields<'a> {
    /// The field to use for radiance only (fastest).
    pub shade: &'a dyn RadianceField,
    /// The field to use when hit distances are wanted too.
    pub with_depth: &'a dyn RadianceField,
    /// What ran, for reports: "analytic (fused planar kernel)", "analytic", "embree", "brute".
    pub name: &'static str,
}

/// Resolves `auto`: analytic for rectangle-only scenes, else Embree (or an error without it).
pub fn resolve(scene: &Scene, choice: BackendChoice) -> BackendChoice {
    match choice {
        BackendChoice::Auto if scene.is_analytic() => BackendChoice::Analytic,
        BackendChoice::Auto => BackendChoice::Embree,
        other => other,
    }
}

/// Every object as a triangle mesh, paired with its object index (rectangles tessellated).
pub fn scene_meshes(scene: &Scene) -> Vec<(u32, Cow<'_, Mesh>)> {
    scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let mesh = match &o.shape {
                Shape::Rect(r) => Cow::Owned(Rect::to_mesh(r)),
                Shape::Mesh(m) => Cow::Borrowed(m.as_ref()),
            };
            (i as u32, mesh)
        })
        .collect()
}

/// Work that runs on a scene's radiance fields, called with their concrete types (no virtual
/// call per ray): `shade` for radiance, `with_depth` for display images (their hit distances),
/// `name` for reports (see [`Fields::name`]).
pub trait FieldUser {
    /// What the work returns.
    type Output;
    /// Runs the work on the chosen fields; `name` says which backend they are.
    fn run<S: RadianceField, D: RadianceField>(
        self,
        shade: &S,
        with_depth: &D,
        name: &'static str,
    ) -> Result<Self::Output>;
}

/// The fused planar kernel of a rectangle-only scene, when the scene allows it (eye-facing
/// axis-aligned rectangles, flat materials, no light): the field the analytic backend renders
/// with, bit-identical in radiance to the generic analytic tracer and faster.
pub fn planar_kernel<'a>(scene: &'a Scene, backend: &'a AnalyticRects) -> Option<FacingPlanes<'a>> {
    if scene.light.is_some() {
        return None;
    }
    FacingPlanes::new(scene, backend)
}

/// Builds the backend `choice` asks for and runs `user` with its fields: the one place that
/// decides which radiance field a scene is traced with (assess, sweep, the CLI and Python).
///
/// Errors: `analytic` on a scene with meshes, `brute` on a scene over
/// [`BRUTE_MAX_TRIANGLES`], `embree` in a build without the `embree` feature
/// ([`Error::Backend`]), and backend construction errors.
pub fn with_scene_fields<U: FieldUser>(scene: &Scene, choice: BackendChoice, user: U) -> Result<U::Output> {
    match resolve(scene, choice) {
        BackendChoice::Analytic | BackendChoice::Auto => {
            if !scene.is_analytic() {
                return Err(Error::Backend {
                    scene: scene.name.clone(),
                    message: format!(
                        "scene `{}` has triangle meshes, which the analytic backend cannot intersect: use --backend embree (or auto)",
                        scene.name
                    ),
                });
            }
            let backend = AnalyticRects::new(scene)?;
            match planar_kernel(scene, &backend) {
                // The fused kernel returns radiance bit-identical to the generic analytic tracer
                // (tests/pipeline.rs checks), depths included (its fallback tracer).
                Some(fast) => user.run(&fast, &fast, "analytic (fused planar kernel)"),
                None => {
                    let tracer = SceneTracer { scene, backend: &backend };
                    user.run(&tracer, &tracer, "analytic")
                }
            }
        }
        BackendChoice::Brute => {
            let n = scene.triangle_count();
            if n > BRUTE_MAX_TRIANGLES {
                return Err(Error::Backend {
                    scene: scene.name.clone(),
                    message: format!(
                        "the brute-force backend is for small scenes (at most {BRUTE_MAX_TRIANGLES} triangles); scene `{}` has {n}: use --backend embree",
                        scene.name
                    ),
                });
            }
            let meshes = scene_meshes(scene);
            let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
            let backend = BruteForce::new(&refs)?;
            let tracer = SceneTracer { scene, backend: &backend };
            user.run(&tracer, &tracer, "brute")
        }
        BackendChoice::Embree => with_embree(scene, user),
        BackendChoice::Bvh => {
            let meshes = scene_meshes(scene);
            let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
            let backend = crate::accel::bvh::BvhIntersector::new(&refs)?;
            let tracer = SceneTracer { scene, backend: &backend };
            user.run(&tracer, &tracer, "bvh")
        }
    }
}

/// [`with_scene_fields`] with the fields as trait objects ([`Fields`]), for callers outside the
/// hot loops.
pub fn with_fields<T>(scene: &Scene, choice: BackendChoice, f: impl FnOnce(Fields<'_>) -> Result<T>) -> Result<T> {
    struct Dynamic<F>(F);
    impl<T, F: FnOnce(Fields<'_>) -> Result<T>> FieldUser for Dynamic<F> {
        type Output = T;
        fn run<S: RadianceField, D: RadianceField>(self, shade: &S, with_depth: &D, name: &'static str) -> Result<T> {
            (self.0)(Fields { shade, with_depth, name })
        }
    }
    with_scene_fields(scene, choice, Dynamic(f))
}

#[cfg(feature = "embree")]
fn with_embree<U: FieldUser>(scene: &Scene, user: U) -> Result<U::Output> {
    use crate::accel::embree::{BuildQuality, EmbreeIntersector};
    let meshes = scene_meshes(scene);
    let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
    // Embree's own errors (out of memory, invalid geometry) name the scene and its objects.
    let backend = EmbreeIntersector::new(&refs, BuildQuality::Medium).map_err(|e| match e {
        crate::error::Error::Embree { code, message } => crate::error::Error::invalid(
            format!("scene `{}`", scene.name),
            "objects",
            format!(
                "Embree could not build the scene of {}: {code}: {message}",
                crate::count::count(scene.triangle_count(), "triangle")
            ),
        ),
        other => other,
    })?;
    drop(refs);
    drop(meshes);
    let tracer = SceneTracer { scene, backend: &backend };
    user.run(&tracer, &tracer, "embree")
}

#[cfg(not(feature = "embree"))]
fn with_embree<U: FieldUser>(scene: &Scene, _user: U) -> Result<U::Output> {
    Err(Error::Backend {
        scene: scene.name.clone(),
        message: format!(
            "scene `{}` needs the Embree backend, but this build has no Embree (rebuild with the default `embree` feature)",
            scene.name
        ),
    })
}
