//! The unit of a settings key, for the axis labels of a sweep's plots: the settings files state
//! lengths in millimetres, vergences in diopters, angles in degrees, times in seconds (see
//! docs/CONFIGURATION.md), and this table names the unit of every numeric field by its last
//! path segment. A key it does not know gets no unit (a count or a ratio).

/// The unit of `key` (a dotted settings path such as `eye.pupil_diameter` or
/// `eye_cases[0].focus_diopters`), if it has one.
pub fn unit_of(key: &str) -> Option<&'static str> {
    let last = key.rsplit('.').next().unwrap_or(key);
    // An index at the end (`position[0]`) names a component of the field.
    let field = last.split('[').next().unwrap_or(last);
    if field.ends_with("_mm") {
        return Some("mm");
    }
    if field.ends_with("_diopters") || field.ends_with("_d") {
        return Some("D");
    }
    if field.ends_with("_db") {
        return Some("dB");
    }
    if field.ends_with("_deg") || field.ends_with("_degrees") {
        return Some("deg");
    }
    if field.ends_with("_nm") {
        return Some("nm");
    }
    match field {
        "pupil_diameter" | "pitch" | "focal_length" | "eye_to_lenslets" | "lenslets_to_lcd" | "size" | "position"
        | "retina_distance" | "reference_plane_z" | "eye_position" | "center" | "width" | "height" | "distance"
        | "depth" | "thickness" | "radius" => Some("mm"),
        "max_seconds" => Some("s"),
        "stiles_crawford_rho" => Some("1/mm²"),
        "resolution" | "retina_resolution" => Some("px"),
        _ => None,
    }
}

/// `key (unit)`, or the key alone when it has no unit.
pub fn label(key: &str) -> String {
    match unit_of(key) {
        Some(u) => format!("{key} ({u})"),
        None => key.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_get_their_units() {
        assert_eq!(label("eye.pupil_diameter"), "eye.pupil_diameter (mm)");
        assert_eq!(label("eye_cases[0].focus_diopters"), "eye_cases[0].focus_diopters (D)");
        assert_eq!(label("eye_cases[1].focus_mm"), "eye_cases[1].focus_mm (mm)");
        assert_eq!(label("display.lenslets.pitch"), "display.lenslets.pitch (mm)");
        assert_eq!(label("eye.position[0]"), "eye.position[0] (mm)");
        assert_eq!(label("measurement.max_seconds"), "measurement.max_seconds (s)");
        assert_eq!(label("display_render.la_grid"), "display_render.la_grid");
        assert_eq!(label("measurement.replicates"), "measurement.replicates");
    }
}
