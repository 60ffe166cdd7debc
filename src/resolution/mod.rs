//! Perceived resolution and focus cues (issue 13; the paper's abstract, "perceived spatial
//! resolution at different focused depths", and its conclusion's Fourier-domain analysis): MTF in
//! cycles per degree, through-focus contrast and the predicted accommodation response.

pub mod accommodation;
pub mod chart;
pub mod modulation;
pub mod study;
pub mod window;
pub mod limits;
pub mod report;
pub mod run;
pub mod command;
pub mod plots;
