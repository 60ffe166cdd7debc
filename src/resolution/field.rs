//! The study's field and its eye's place. The field (`field_deg`): the direction its charts
//! face, off the axis ([`Chart::at_field`], Fick's angles as the eye's gaze,
//! [`crate::optics::eye::gaze`]). Checked against the eye's range (at most 60 degrees) and the
//! chart's size (the whole chart within 85 degrees of the axis, where its tangents stay finite),
//! with a warning when the display's LCD, seen from the pupil centre, does not reach the whole
//! chart. The eye's place ([`EyePlacement`], issue #50's field and eye-box maps): `[eye] gaze_deg`
//! turns it about its centre of rotation (`centre_of_rotation_mm`), `[eye] position` moves its
//! pupil, as in an experiment; the chart goes with the eye ([`super::chart`]); PupilCenter renders
//! for the pupil `[display_render] pupil_tracking` says (as an experiment's,
//! [`crate::experiment::tracked_pupil`]).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::chart::{Chart, EyeFrame};
use super::study::Study;
use crate::error::{Error, Result};
use crate::optics::eye::settings::{pose_of, EyeModelSettings};
use crate::optics::eye::{CentreOfRotation, EyeModel, EyePose, Gaze};
use crate::optics::Display;
use crate::render::Method;

/// A study's `[display_render]`: what PupilCenter knows of the turned pupil, as an experiment's
/// fields of the same names.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyRenderSpec {
    /// `"ideal"` (the default: PupilCenter renders for the turned pupil) or `"none"` (for the
    /// pupil straight ahead, `eye.position`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pupil_tracking: Option<String>,
    /// The eye tracker's error, mm, with `pupil_tracking = "ideal"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracking_error_mm: Option<[f64; 3]>,
}

/// Where a study's eye is (module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EyePlacement {
    /// The gaze (straight ahead by default).
    pub gaze: Gaze,
    /// The pupil centre straight ahead, mm (the origin by default).
    pub position: DVec3,
    /// The eye turned about its centre of rotation; `None` straight ahead.
    pub pose: Option<EyePose>,
    /// The pupil centre PupilCenter renders for, mm.
    pub pupil_center: DVec3,
}

impl EyePlacement {
    /// The eye's frame in the display's; `None` for the eye at rest at the origin.
    pub fn frame(&self) -> Option<EyeFrame> {
        EyeFrame::of(self.position, self.pose.as_ref())
    }

    /// Resolves and checks `[eye] gaze_deg`, `centre_of_rotation_mm` and `position` of `eye` and
    /// `[display_render]` for an eye of `model` in front of `display`: a gaze beyond 60 degrees or
    /// whose line of sight misses the LCD, a centre of rotation in front of the cornea, a pupil at
    /// or beyond the lenslets, a pupil PupilCenter cannot render for (when `methods` has it) are
    /// refused naming the field and `source`.
    pub fn resolve(
        eye: &EyeModelSettings,
        render: Option<&StudyRenderSpec>,
        model: &EyeModel,
        (display, methods): (&Display, &[Method]),
        source: &str,
    ) -> Result<Self> {
        let gaze = eye.gaze_deg.map(Gaze::from).unwrap_or_default();
        gaze.validate(source, "eye.gaze_deg")?;
        let centre = eye
            .centre_of_rotation_mm
            .map_or_else(CentreOfRotation::default, |mm| CentreOfRotation { behind_cornea_mm: mm });
        centre.validate(source, "eye.centre_of_rotation_mm")?;
        let position = DVec3::from_array(eye.position.unwrap_or([0.0; 3]));
        if !position.is_finite() {
            return Err(Error::invalid(source, "eye.position", format!("must be finite mm, got {position}")));
        }
        for (i, v) in position.to_array().iter().enumerate() {
            crate::optics::limits::EYE_POSITION.check(source, &format!("eye.position[{i}]"), *v)?;
        }
        crate::optics::transfer::check_eye_in_front(display, position.z, source, "eye.position")?;
        let pose = pose_of(model, gaze, centre, position, source)?;
        if let Some(p) = &pose {
            display.check_gaze(p, source, "eye.gaze_deg")?;
        }
        let r = render.cloned().unwrap_or_default();
        let tracked = crate::experiment::tracked_pupil(
            r.pupil_tracking.as_deref(),
            r.tracking_error_mm,
            pose.as_ref(),
            position,
            source,
        )?;
        let pupil_center = tracked.unwrap_or(position);
        if tracked.is_some() {
            crate::optics::transfer::check_eye_in_front(
                display,
                pupil_center.z,
                source,
                "display_render.pupil_tracking",
            )?;
        }
        if let Some(i) = methods.iter().position(|m| *m == Method::PupilCenter) {
            crate::optics::transfer::check_pupil_center(display, pupil_center)
                .map_err(|e| Error::in_field(source, format!("methods[{i}] (PupilCenter) at eye.position"), e))?;
        }
        Ok(Self { gaze, position, pose, pupil_center })
    }
}

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
    if let Some(frame) = study.eye_place.frame() {
        return placed_warning(study, &frame);
    }
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

/// [`display_warning`] for an eye turned or moved to `frame`: the chart's corners, seen from the
/// pupil centre along the eye's turned directions, meet the LCD plane off the panel.
fn placed_warning(study: &Study, frame: &EyeFrame) -> Option<String> {
    let chart = Chart::of_study(study);
    let r = chart.eye_reach_tangent();
    let (half, lcd_z) = (0.5 * study.display.lcd.size, study.display.lcd_z());
    let corners = [r, -r, DVec2::new(r.x, -r.y), DVec2::new(-r.x, r.y)];
    let mut far = DVec2::ZERO;
    for c in corners {
        let d = frame.direction(DVec3::new(c.x, c.y, 1.0));
        let at = if d.z > 0.0 {
            frame.pupil.truncate() + d.truncate() * ((lcd_z - frame.pupil.z) / d.z)
        } else {
            DVec2::splat(f64::INFINITY)
        };
        far = far.max(at.abs());
    }
    (far.x > half.x || far.y > half.y).then(|| {
        let g = study.eye_place.gaze;
        format!(
            "{}: eye.gaze_deg / eye.position: the chart on the eye's line of sight (gaze [{}, {}], pupil at {}) \
             reaches the LCD plane up to ({:.2}, {:.2}) mm from its centre, beyond the {} x {} mm panel: the \
             methods show nothing there",
            study.source,
            g.horizontal_deg,
            g.vertical_deg,
            frame.pupil,
            far.x,
            far.y,
            study.display.lcd.size.x,
            study.display.lcd.size.y
        )
    })
}
