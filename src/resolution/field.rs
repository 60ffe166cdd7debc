//! The study's field (`field_deg`): the direction its charts face, off the axis
//! ([`Chart::at_field`], Fick's angles as the eye's gaze, [`crate::optics::eye::gaze`]). Checked
//! against the eye's range (at most 60 degrees) and the chart's size (the whole chart within 85
//! degrees of the axis, where its tangents stay finite), with a warning when the display's LCD,
//! seen from the pupil centre, does not reach the whole chart.

use super::chart::Chart;
use super::study::Study;
use crate::error::{Error, Result};

/// How far from the axis any part of an off-axis chart may reach, degrees.
const MAX_REACH_DEG: f64 = 85.0;

/// Checks the study's field; errors name `source` and `field_deg`.
pub(crate) fn check_field(study: &Study, source: &str) -> Result<()> {
    let field = study.field_deg;
    field.validate(source, "field_deg")?;
    if field.is_ahead() {
        return Ok(());
    }
    let chart = Chart::of_study(study);
    let reach = field.eccentricity_deg() + chart.reach_tangent().length().atan().to_degrees();
    if reach >= MAX_REACH_DEG {
        return Err(Error::invalid(
            source,
            "field_deg",
            format!(
                "the chart facing [{}, {}] reaches {reach:.1} degrees from the axis: at most {MAX_REACH_DEG} \
                 (a smaller field, or smaller windows and guards)",
                field.horizontal_deg, field.vertical_deg
            ),
        ));
    }
    Ok(())
}

/// A warning when an off-axis chart reaches beyond the display's LCD as the pupil centre sees it
/// (the methods show nothing there).
pub fn display_warning(study: &Study) -> Option<String> {
    let field = study.field_deg;
    if field.is_ahead() {
        return None;
    }
    let reach = Chart::of_study(study).eye_reach_tangent();
    let lcd = 0.5 * study.display.lcd.size / study.display.lcd_z();
    (reach.x > lcd.x || reach.y > lcd.y).then(|| {
        format!(
            "{}: field_deg: the chart facing [{}, {}] reaches tangents up to ({:.3}, {:.3}) from the pupil centre, \
             beyond the display's LCD at ({:.3}, {:.3}): the methods show nothing there",
            study.source, field.horizontal_deg, field.vertical_deg, reach.x, reach.y, lcd.x, lcd.y
        )
    })
}
