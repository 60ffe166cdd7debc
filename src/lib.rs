//! inimtrace: simulates how a near-eye integral-imaging (InIm) light-field display looks to a
//! human eye, and scores the ways of rendering its display image (LensletCenter, PupilCenter,
//! LensletAverage), after O. Doronin, E. Sahin, R. Bregovic and A. Gotchev, "A framework for
//! assessing rendering techniques for near-eye integral imaging displays", ICIP 2020.
//!
//! Conventions (see README): millimetres; the eye's pupil centre is the origin; +z points from
//! the eye toward the display and the scene, +x right, +y up; images are stored with row 0 at
//! the top. Optics is computed in `f64`.
//!
//! Layers, bottom up (a module imports only from layers below it; `tests/layers.rs` holds the
//! table): `error`, `count`, `ray` and the other leaves; `budget`, `progress`; `optics` (eq. (1))
//! and `raster`; `metrics` and `scene`; `accel` (intersection backends), `info`; `render`;
//! `measure` (the converged estimator); `perception` and `io` (file formats); `optimize` and
//! `provenance`; `methods` (a method's display image, routed once); `experiment`; `resolution`,
//! `bench` and `settings`; `sweep`.
//!
//! `unsafe` code is denied everywhere except in the Embree wrapper (`accel::embree`).
//!
//! # Entry points
//!
//! - An experiment (scene, display, methods, eye cases; Sec. 4.1): [`settings::load_experiment`]
//!   (what `inimtrace assess` loads), then [`experiment::assess`] (writes every output) or
//!   [`experiment::assess_images`] (keeps the images), and [`experiment::table_markdown`] for
//!   Table 1.
//! - The pieces of one assessment: [`render::render_display_image`] (a method's display image),
//!   [`render::simulate`] (what the eye perceives of it through the lenslets),
//!   [`render::ground_truth`] (the eye looking straight at the scene) and
//!   [`metrics::psnr`] / [`metrics::ssim`].
//! - Eq. (1), the paraxial ray transfer: [`optics::transfer`].
//! - Sweeps over settings: [`sweep::execute`]; MTF studies: [`resolution`].
//!
//! The `examples/` folder runs the paper's assessment (`assess_paper`), a mesh scene with Embree
//! (`mesh_embree`) and a small sweep (`small_sweep`): `cargo run --release --example assess_paper`.
//!
//! # Example
//!
//! The paper's scene on the paper's display, at toy sizes: the LensletCenter display image, what
//! a pinhole eye perceives of it, and the eye looking at the scene directly.
//!
//! ```
//! use glam::DVec2;
//! use inimtrace::metrics::{psnr, ssim, SsimConstants};
//! use inimtrace::optics::transfer::{eye_to_lcd, lcd_to_eye};
//! use inimtrace::optics::{Display, Eye, Focus, Retina};
//! use inimtrace::progress::Progress;
//! use inimtrace::render::{ground_truth, render_display_image, simulate, with_fields, BackendChoice};
//! use inimtrace::render::{DisplayRenderSettings, Method};
//! use inimtrace::scene::Scene;
//!
//! // Eq. (1): a thin-lens eye focused at 300 mm images retina tangent t at -v0 t on the retina
//! // (v0 = 17 mm), and tracing back from the LCD point through the same lenslet point lands on
//! // the same retina point.
//! let mut display = Display::paper();
//! let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
//! let t = DVec2::new(0.1, -0.05);
//! let trace = eye_to_lcd(&display, &eye, t, DVec2::new(1.0, 0.5));
//! assert!((trace.retina + eye.retina_distance * t).length() < 1e-12);
//! let (_, back) = lcd_to_eye(&display, &eye, trace.lcd, trace.lenslet.position);
//! assert!((back - trace.retina).length() < 1e-9);
//!
//! // Table 1's pieces for one cell (pinhole eye, LC) at a 540 x 540 LCD and a 32 x 32 retina.
//! display.lcd.resolution = [540, 540];
//! let (scene, eye, retina) = (Scene::paper(), Eye::pinhole(), Retina { resolution: 32, ..Retina::default() });
//! let progress = Progress::hidden();
//! let (perceived, truth) = with_fields(&scene, BackendChoice::Auto, |fields| {
//!     let settings = DisplayRenderSettings::default();
//!     let shown = render_display_image(&display, Method::LensletCenter, &settings, fields.shade, &progress)?;
//!     assert_eq!((shown.width, shown.height), (540, 540));
//!     let perceived = simulate(&display, &eye, &retina, &[&shown], &progress)?.remove(0);
//!     Ok((perceived, ground_truth(&eye, &retina, fields.shade, &progress)))
//! })?;
//! let (p, s) = (psnr(&perceived, &truth)?, ssim(&perceived, &truth, SsimConstants::Wang2004)?);
//! // The light field shows the scene, imperfectly: a finite PSNR, a positive SSIM below 1.
//! assert!(p.mean.is_finite() && p.mean > 10.0, "PSNR {}", p.mean);
//! assert!(s.mean > 0.0 && s.mean < 1.0, "SSIM {}", s.mean);
//! # Ok::<(), inimtrace::Error>(())
//! ```

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod bench;
pub mod budget;
pub mod count;
pub mod cpu;
pub mod error;
pub mod experiment;
#[doc(hidden)]
pub mod fixtures;
pub mod info;
pub mod io;
pub mod long_run;
pub mod measure;
pub mod methods;
pub mod metrics;
pub mod optics;
pub mod optimize;
pub mod overrides;
pub mod perception;
pub mod progress;
pub mod provenance;
pub mod raster;
pub mod ray;
pub mod render;
pub mod report;
pub mod resolution;
pub mod scene;
pub mod settings;
pub mod sweep;
pub mod version;

pub use error::{Error, Result};
