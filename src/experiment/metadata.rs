//! What every image of the pipeline (Fig. 2: display image, ground truth, perceived image)
//! records about how it was made, as typed EXR header attributes. `assess` and the single-stage
//! commands (`render-display`, `ground-truth`, `simulate`) build their headers here, so the same
//! image carries the same metadata whichever command wrote it.
//!
//! Numbers are `double` (lengths in mm, diopters, tangents) or `int` (counts); names and notes
//! are `string`. Every file also carries `inimtrace:version` and `inimtrace:git_revision`
//! (added by [`crate::io::exr::write_rgb_with`]).

use super::assess::Z_CHANNEL_NOTE;
use crate::io::exr::{AttrValue, Attributes};
use crate::optics::eye::model::EyeModel;
use crate::optics::lenslet::LensletOptics;
use crate::optics::{Aperture, Display, Eye, Lattice, Retina};
use crate::render::{DisplayRenderSettings, Method};

/// What all images share: `kind` ("display image", "ground truth retinal image", "simulated
/// retinal image"), the experiment's name when there is one, and the units.
pub fn common(kind: &str, experiment: Option<&str>) -> Attributes {
    let mut a = Attributes::new();
    a.set("inimtrace:kind", kind);
    if let Some(name) = experiment {
        a.set("inimtrace:experiment", name);
    }
    a.set("inimtrace:units", "linear radiance (albedo units); lengths in mm");
    a
}

fn lattice(a: &mut Attributes, prefix: &str, l: &Lattice) {
    let [m00, m01, m10, m11] = l.row_major();
    a.set(format!("inimtrace:{prefix}_shift_x_mm"), l.shift.x);
    a.set(format!("inimtrace:{prefix}_shift_y_mm"), l.shift.y);
    for (k, v) in [("m00", m00), ("m01", m01), ("m10", m10), ("m11", m11)] {
        a.set(format!("inimtrace:{prefix}_pitch_{k}_mm"), v);
    }
}

/// The display: its name, v1, v2, f, both lattices (shift and row-major pitch matrix), the LCD
/// and the central depth plane (absent when at infinity or real).
pub fn display(d: &Display) -> Attributes {
    let mut a = Attributes::new();
    a.set("inimtrace:display", d.name.as_str());
    a.set("inimtrace:display_v1_mm", d.eye_to_lenslets);
    a.set("inimtrace:display_v2_mm", d.lenslets_to_lcd);
    a.set("inimtrace:display_focal_length_mm", d.focal_length);
    lattice(&mut a, "lenslets", &d.lenslets);
    lattice(&mut a, "elemental_images", &d.elemental_images);
    a.set("inimtrace:lcd_width_mm", d.lcd.size.x);
    a.set("inimtrace:lcd_height_mm", d.lcd.size.y);
    a.set("inimtrace:lcd_columns", AttrValue::count(d.lcd.columns()));
    a.set("inimtrace:lcd_rows", AttrValue::count(d.lcd.rows()));
    if let Some(z) = d.central_depth_plane() {
        a.set("inimtrace:central_depth_plane_mm", z);
        a.set("inimtrace:central_depth_plane_diopters", 1000.0 / z);
    }
    // A real lenslet is named with its surfaces (the thin lens of the paper is the default and
    // adds nothing, so its files keep their headers).
    if let LensletOptics::Thick(t) = &d.lenslet {
        a.set("inimtrace:lenslet", "thick lenslet");
        a.set("inimtrace:lenslet_material", t.material.name.as_str());
        a.set("inimtrace:lenslet_front_radius_mm", t.front.radius);
        a.set("inimtrace:lenslet_front_conic", t.front.conic);
        a.set("inimtrace:lenslet_back_radius_mm", t.back.radius);
        a.set("inimtrace:lenslet_back_conic", t.back.conic);
        a.set("inimtrace:lenslet_thickness_mm", t.thickness);
    }
    a
}

/// A display image: the method (and LA's grid), the sampling, the reference plane, the pupil
/// centre PupilCenter aims at, the backend and, with a depth plane, what `Z` holds; then the
/// display.
pub fn display_image(
    method: Method,
    d: &Display,
    render: &DisplayRenderSettings,
    backend: &str,
    has_depth: bool,
) -> Attributes {
    let mut a = Attributes::new();
    a.set("inimtrace:method", method.to_string());
    if let Method::LensletAverage { grid } = method {
        a.set("inimtrace:la_grid", AttrValue::count(grid));
    }
    a.set("inimtrace:samples_per_pixel", AttrValue::count(render.samples_per_pixel.pow(2)));
    a.set("inimtrace:reference_plane_z_mm", render.reference_plane_z);
    a.set("inimtrace:pc_eye_x_mm", render.eye_position.x);
    a.set("inimtrace:pc_eye_y_mm", render.eye_position.y);
    a.set("inimtrace:pc_eye_z_mm", render.eye_position.z);
    a.set("inimtrace:backend", backend);
    if has_depth {
        a.set("inimtrace:Z", Z_CHANNEL_NOTE);
    }
    a.extend(display(d));
    a
}

/// A retinal image's eye: the eye case's name when there is one, the aperture (and for a thin
/// lens the focus in mm and diopters and the pupil diameter), the pupil grid and samples, the
/// retina distance, the pupil centre, and the retina's resolution, field and samples.
pub fn eye(case: Option<&str>, eye: &Eye, retina: &Retina) -> Attributes {
    let mut a = Attributes::new();
    if let Some(name) = case {
        a.set("inimtrace:eye_case", name);
    }
    // A schematic eye is no thin lens: its kind says so, and the thin lens's own field (its
    // pupil-to-retina distance) is left out.
    let schematic = eye.optics.as_ref().is_some_and(|o| o.model != EyeModel::ThinLens);
    match eye.aperture {
        Aperture::Pinhole => {
            a.set("inimtrace:eye", "pinhole");
        }
        Aperture::ThinLens { pupil_diameter, focus } => {
            a.set("inimtrace:eye", if schematic { "schematic eye" } else { "thin lens" });
            a.set("inimtrace:focus_mm", focus.distance_mm());
            a.set("inimtrace:focus_diopters", focus.diopters());
            a.set("inimtrace:pupil_diameter_mm", pupil_diameter);
            a.set("inimtrace:pupil_grid", AttrValue::count(eye.pupil_grid));
        }
    }
    if let Some(o) = &eye.optics {
        a.set("inimtrace:eye_model", o.model.name());
        a.set("inimtrace:eye_model_citation", o.model.citation());
        if let Some(acc) = o.accommodation {
            a.set("inimtrace:accommodation_diopters", acc);
            a.set("inimtrace:focus_criterion", crate::optics::eye::rays::criterion_name(o.criterion));
        }
        a.set("inimtrace:reference_wavelength_nm", o.reference_nm);
        a.set("inimtrace:iris_diameter_mm", o.iris_diameter);
        a.set("inimtrace:spectrum", if o.is_single_wavelength() { "single" } else { "primaries" });
        a.set("inimtrace:diffraction", o.diffraction.name());
        if let Some(sc) = &o.stiles_crawford {
            a.set("inimtrace:stiles_crawford_rho", sc.rho);
            a.set("inimtrace:stiles_crawford_peak_x_mm", sc.peak.x);
            a.set("inimtrace:stiles_crawford_peak_y_mm", sc.peak.y);
        }
    }
    a.set("inimtrace:pupil_samples", AttrValue::count(eye.pupil_samples().len()));
    if !schematic {
        a.set("inimtrace:retina_distance_mm", eye.retina_distance);
    }
    a.set("inimtrace:eye_x_mm", eye.position.x);
    a.set("inimtrace:eye_y_mm", eye.position.y);
    a.set("inimtrace:eye_z_mm", eye.position.z);
    // A turned eye (absent: straight ahead, as before gaze existed).
    if let Some(pose) = &eye.pose {
        a.set("inimtrace:gaze_horizontal_deg", pose.gaze.horizontal_deg);
        a.set("inimtrace:gaze_vertical_deg", pose.gaze.vertical_deg);
        a.set("inimtrace:centre_of_rotation_x_mm", pose.centre.x);
        a.set("inimtrace:centre_of_rotation_y_mm", pose.centre.y);
        a.set("inimtrace:centre_of_rotation_z_mm", pose.centre.z);
    }
    a.set("inimtrace:retina_resolution", AttrValue::count(retina.resolution));
    a.set("inimtrace:retina_half_tangent", retina.half_tangent);
    a.set("inimtrace:retina_samples_per_pixel", AttrValue::count(retina.samples_per_pixel.pow(2)));
    a
}

/// A ground-truth retinal image: common, eye, backend.
pub fn ground_truth(
    experiment: Option<&str>,
    case: Option<&str>,
    e: &Eye,
    retina: &Retina,
    backend: &str,
) -> Attributes {
    let mut a = common("ground truth retinal image", experiment);
    a.extend(eye(case, e, retina));
    a.set("inimtrace:backend", backend);
    a
}

/// A perceived (simulated) retinal image: common, the method when known, eye, display, and the
/// display image it came from when it was read from a file.
pub fn perceived(
    experiment: Option<&str>,
    method: Option<Method>,
    case: Option<&str>,
    e: &Eye,
    retina: &Retina,
    d: &Display,
    source: Option<&str>,
) -> Attributes {
    let mut a = common("simulated retinal image", experiment);
    if let Some(m) = method {
        a.set("inimtrace:method", m.to_string());
    }
    if let Some(s) = source {
        a.set("inimtrace:source", s);
    }
    a.extend(eye(case, e, retina));
    a.extend(display(d));
    a
}

/// A seed as a number: an `int` when it fits one (every seed below 2^31), else a `double` when it
/// is exact as one (below 2^53), else its decimal text.
pub fn seed_value(seed: u64) -> AttrValue {
    if let Ok(v) = i32::try_from(seed) {
        AttrValue::I32(v)
    } else if seed < (1u64 << 53) {
        AttrValue::F64(seed as f64)
    } else {
        AttrValue::Text(seed.to_string())
    }
}

/// Where an image comes from (see [`crate::provenance`]): the scene's name and path as given,
/// its file's SHA-256, every input file with its SHA-256 (one `SHA256  PATH` line each, as
/// `sha256sum` writes them) and the `--set` overrides (one per line). Nothing for an
/// experiment built in code.
pub fn provenance(p: &crate::provenance::Provenance) -> Attributes {
    let mut a = Attributes::new();
    if p.scene_name.is_empty() {
        return a;
    }
    a.set("inimtrace:scene", latin1(&p.scene_name));
    a.set("inimtrace:scene_path", latin1(&p.scene_path));
    if let Some(h) = p.scene_sha256() {
        a.set("inimtrace:scene_sha256", h);
    }
    if let Some(e) = &p.experiment_path {
        a.set("inimtrace:experiment_path", latin1(e));
    }
    let files: Vec<String> = p.files.iter().map(|f| format!("{}  {}", f.sha256, latin1(&f.path))).collect();
    a.set("inimtrace:input_files_sha256", files.join("\n"));
    a.set("inimtrace:set", latin1(&p.set.join("\n")));
    a
}

/// Text OpenEXR can hold (Latin-1): other characters as `\u{...}` escapes (results.json has the
/// text as it is).
fn latin1(s: &str) -> String {
    s.chars().map(|c| if (c as u32) < 256 { c.to_string() } else { c.escape_unicode().to_string() }).collect()
}
