//! The converged measurement: the paper's Table 1 (Sec. 4.2) of the converged
//! retinal images, each score with a 95% interval, to a stated precision.
//!
//! - [`sampler`]: Owen-scrambled Sobol points over each retina pixel x the pupil disk;
//! - [`estimator`]: the paired estimator (one eye ray for the ground truth and every method) and
//!   the per-replicate images;
//! - [`stats`], `ssim`: PSNR and SSIM from cross-replicate products (no noise bias), with
//!   jackknife intervals;
//! - [`adaptive`]: doubling the samples until every cell meets its target or the budget is spent;
//! - [`scores`]: the names of `[measurement] scores` (Table 1's pair, the luminance PSNR, the
//!   perceptual scores `crate::perception` computes) and how those count the eye's optics;
//! - [`spec`]: the experiment file's `[measurement]` table; `experiment::converged`: `assess`'s converged Table 1.

pub mod adaptive;
pub mod estimator;
pub mod sampler;
pub mod scores;
pub mod spec;
pub(crate) mod ssim;
pub mod stats;
