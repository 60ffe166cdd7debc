//! Perceived resolution (the paper's abstract: comparing rendering methods "in terms
//! of perceived spatial resolution at different focused depths", and its conclusion's
//! Fourier-domain analysis): the MTF of the retinal image in cycles per degree.
//!
//! - [`defocus`]: the analytic MTF of the eye (defocus blur disk times the retina pixel's box);
//! - [`grating`]: the modulation of a grating image at the grating's own frequency, without
//!   noise bias, with a jackknife interval (the one grating analysis, of any window);
//! - [`edge`]: the ISO 12233 slanted-edge MTF and MTF50, with jackknife intervals (the one
//!   edge analysis, of any window);
//! - [`measure`]: the retinal images of a target, through the converged estimator.
//!
//! The targets themselves are scene materials ([`crate::scene::target`]).

pub mod defocus;
pub mod edge;
pub mod grating;
pub mod measure;

// The study (`inimtrace resolution`): its file, chart (on the axis or off it, `field`),
// measurement over the chart's windows, accommodation, display limits, files and plots. Its
// windows are measured by `grating` and `edge` above.
pub(crate) mod accommodation;
pub mod chart;
pub mod command;
pub mod field;
pub mod limits;
pub(crate) mod plots;
pub mod report;
pub mod run;
pub mod study;
pub mod values;
pub mod window;
