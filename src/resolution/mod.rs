//! Perceived resolution and focus cues (issue 13; the paper's abstract, "perceived spatial
//! resolution at different focused depths", and its conclusion's Fourier-domain analysis): MTF in
//! cycles per degree, through-focus contrast and the predicted accommodation response.

pub mod accommodation;
pub mod chart;
pub mod command;
pub mod limits;
pub mod modulation;
pub mod plots;
pub mod report;
pub mod run;
pub mod study;
pub mod window;
