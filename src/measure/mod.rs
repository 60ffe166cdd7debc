//! The converged measurement (issue 11).

pub mod estimator;
pub mod sampler;
pub mod ssim;
pub mod stats;
