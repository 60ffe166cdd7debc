//! What PupilCenter knows of the pupil when the eye turns (issue #50; the eye's pose of
//! `optics::eye::gaze`): PupilCenter renders its display image for one pupil centre (paper
//! Sec. 3, its "pupil-centred" camera rays), and an eye that looks away moves its pupil by about
//! `10 mm x sin(gaze)`. `display_render.pupil_tracking` states which centre it renders for:
//!
//! - `"ideal"` (the default): the true turned pupil of `[eye] gaze_deg` (an ideal eye tracker),
//!   moved by `display_render.tracking_error_mm` when given (a tracker with that error);
//! - `"none"`: the pupil straight ahead, `eye.position` (no tracking).
//!
//! PupilCenter renders one display image for every eye case, so it knows the `[eye]` table's gaze;
//! an eye case with its own `gaze_deg` sees that image. A stated `display_render.eye_position`
//! is where PupilCenter renders, whatever the gaze.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::optics::eye::settings::{pose_of, BaseEye};
use crate::optics::eye::EyePose;

use super::DisplayRenderSpec;

/// The pupil centre PupilCenter renders for, when the tracking settings move it from `stated`
/// (`display_render.eye_position`, or `eye.position`); `None`: `stated`. Errors name `source`
/// and the field.
pub(super) fn pc_pupil(dr: &DisplayRenderSpec, base: &BaseEye, source: &str) -> Result<Option<DVec3>> {
    let offset = tracking_offset(dr.pupil_tracking.as_deref(), dr.tracking_error_mm, source)?;
    if dr.eye_position.is_some() {
        for (given, field) in
            [(dr.pupil_tracking.is_some(), "pupil_tracking"), (dr.tracking_error_mm.is_some(), "tracking_error_mm")]
        {
            if given {
                return Err(Error::invalid(
                    source,
                    format!("display_render.{field}"),
                    "is not read with display_render.eye_position (PupilCenter renders for that pupil)",
                ));
            }
        }
        return Ok(None);
    }
    if offset.is_none() {
        return Ok(None);
    }
    let pose = pose_of(&base.optics.model, base.gaze, base.centre_of_rotation, base.position, source)?;
    tracked_pupil(dr.pupil_tracking.as_deref(), dr.tracking_error_mm, pose.as_ref(), base.position, source)
}

/// The tracker's offset of `tracking` (`"ideal"`, the default, or `"none"`) and `error` (mm,
/// only with `"ideal"`): `Some` (zero without an error) when PupilCenter follows the pupil,
/// `None` without tracking. Errors name `source` and the field.
fn tracking_offset(tracking: Option<&str>, error: Option<[f64; 3]>, source: &str) -> Result<Option<DVec3>> {
    let ideal = match tracking {
        None | Some("ideal") => true,
        Some("none") => false,
        Some(other) => {
            return Err(Error::invalid(
                source,
                "display_render.pupil_tracking",
                format!("`{other}` is not one of \"ideal\" or \"none\""),
            ))
        }
    };
    match error.map(DVec3::from_array) {
        Some(_) if !ideal => Err(Error::invalid(
            source,
            "display_render.tracking_error_mm",
            "is only read with pupil_tracking = \"ideal\" (a tracker's error)",
        )),
        Some(e) if !e.is_finite() => {
            Err(Error::invalid(source, "display_render.tracking_error_mm", "must be finite mm"))
        }
        e => Ok(ideal.then(|| e.unwrap_or(DVec3::ZERO))),
    }
}

/// The pupil centre PupilCenter renders for under `tracking` (`"ideal"`, the default, or
/// `"none"`) with a tracker's `error` (mm, only with `"ideal"`), for an eye whose pupil centre is
/// at `position` straight ahead and which is turned to `pose` (`None`: straight ahead). `None`
/// when that is `position` itself (no turn and no tracking error, or no tracking). Errors name
/// `source` and `display_render.pupil_tracking` or `display_render.tracking_error_mm`; an
/// experiment and a resolution study both read it.
pub fn tracked_pupil(
    tracking: Option<&str>,
    error: Option<[f64; 3]>,
    pose: Option<&EyePose>,
    position: DVec3,
    source: &str,
) -> Result<Option<DVec3>> {
    let Some(offset) = tracking_offset(tracking, error, source)? else { return Ok(None) };
    let pupil = pose.map_or(position, |p| p.pupil_centre);
    Ok((pose.is_some() || error.is_some()).then_some(pupil + offset))
}
