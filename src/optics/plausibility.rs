//! Plausibility of a near-eye display and an eye's settings: values that pass validation (they
//! are positive and finite) but lie far outside what a near-eye integral-imaging display or a
//! human eye can be, as a unit mistake gives them (a lenslet pitch in micrometres, a focal length
//! in metres, an LCD size in centimetres, `focus_mm = 1.5` meant as metres or diopters).
//!
//! Each check is a sensible range per quantity (see docs/CONFIGURATION.md, "Plausibility"); a
//! value outside it gets a warning naming the file, the field and, where one unit converts it
//! into the range, that unit. Warnings never stop a run: an unusual design may be deliberate.
//! The display's central depth plane is flagged when it is at infinity or real (the LCD at or
//! beyond the lenslets' focal plane), which the paper's eq. (1) geometry does not intend.

use super::Display;

/// A sensible range of one quantity, mm.
#[derive(Clone, Copy, Debug)]
pub struct Sensible {
    /// What the quantity is, for messages ("a lenslet pitch").
    pub what: &'static str,
    /// Smallest sensible value, mm.
    pub min: f64,
    /// Largest sensible value, mm (`f64::INFINITY`: no upper end).
    pub max: f64,
}

/// The lenslet pitch (cell size): microlens arrays of near-eye displays.
pub const LENSLET_PITCH: Sensible = Sensible { what: "a lenslet pitch", min: 0.05, max: 20.0 };
/// The elemental-image pitch on the LCD.
pub const ELEMENTAL_IMAGE_PITCH: Sensible = Sensible { what: "an elemental-image pitch", min: 0.05, max: 30.0 };
/// The lenslet focal length.
pub const FOCAL_LENGTH: Sensible = Sensible { what: "a lenslet focal length", min: 0.2, max: 200.0 };
/// v1, the eye relief.
pub const EYE_TO_LENSLETS: Sensible = Sensible { what: "a near-eye display's eye relief", min: 3.0, max: 300.0 };
/// v2, the lenslet-to-LCD gap.
pub const LENSLETS_TO_LCD: Sensible = Sensible { what: "a lenslet-to-LCD gap", min: 0.05, max: 200.0 };
/// The LCD's width or height (micro-displays upward).
pub const LCD_SIZE: Sensible = Sensible { what: "a near-eye LCD's width or height", min: 3.0, max: 1000.0 };
/// A focus distance from the pupil: no eye focuses nearer than about 5 cm (20 D).
pub const FOCUS_DISTANCE: Sensible = Sensible { what: "an eye's focus distance", min: 50.0, max: f64::INFINITY };
/// The pupil's diameter.
pub const PUPIL_DIAMETER: Sensible = Sensible { what: "a human pupil diameter", min: 1.0, max: 10.0 };

/// Units a millimetre value may have been typed in by mistake, with their size in mm.
const UNITS: [(&str, &str, f64); 4] =
    [("micrometres", "µm", 1e-3), ("centimetres", "cm", 10.0), ("metres", "m", 1000.0), ("inches", "in", 25.4)];

/// The warning for `value` (mm) of `field` in `source`, if it is outside `range`; it names the
/// unit that would bring it into the range, if one does.
pub fn check(source: &str, field: &str, value: f64, range: Sensible) -> Option<String> {
    if !value.is_finite() || (range.min..=range.max).contains(&value) {
        return None;
    }
    let span = if range.max.is_finite() {
        format!("{} to {} mm", range.min, range.max)
    } else {
        format!("at least {} mm", range.min)
    };
    let mut text = format!("{source}: {field} = {value} mm is outside the sensible range of {} ({span})", range.what);
    let fits: Vec<String> = UNITS
        .iter()
        .filter(|(_, _, mm)| (range.min..=range.max).contains(&(value * mm)))
        .map(|(name, symbol, mm)| format!("{name}? {value} {symbol} = {} mm", round(value * mm)))
        .collect();
    if !fits.is_empty() {
        text += &format!(": was it given in {}", fits.join(", or "));
    }
    Some(text)
}

/// A value with at most 6 significant digits, for messages.
fn round(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    let scale = 10f64.powi(5 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Every plausibility warning of `display`, read from `source` (field names as in the display
/// TOML).
pub fn display_warnings(display: &Display, source: &str) -> Vec<String> {
    let mut w = Vec::new();
    let lenslet = display.lenslets.cell_area().abs().sqrt();
    let ei = display.elemental_images.cell_area().abs().sqrt();
    w.extend(check(source, "lenslets.pitch", lenslet, LENSLET_PITCH));
    w.extend(check(source, "elemental_images.pitch", ei, ELEMENTAL_IMAGE_PITCH));
    w.extend(check(source, "lenslets.focal_length", display.focal_length, FOCAL_LENGTH));
    w.extend(check(source, "eye_to_lenslets", display.eye_to_lenslets, EYE_TO_LENSLETS));
    w.extend(check(source, "lenslets_to_lcd", display.lenslets_to_lcd, LENSLETS_TO_LCD));
    let size = display.lcd.size;
    // One warning for the size, with the smaller side (a centimetre size is small on both).
    let side = if LCD_SIZE.min <= size.x.min(size.y) { size.x.max(size.y) } else { size.x.min(size.y) };
    w.extend(check(source, "lcd.size", side, LCD_SIZE));
    let (v2, f) = (display.lenslets_to_lcd, display.focal_length);
    if display.thick_lenslet().is_some() {
        w.extend(channel_cdp_warning(display, source));
    } else if (v2 - f).abs() <= 1e-9 * f {
        w.push(format!(
            "{source}: the central depth plane is at infinity (lenslets_to_lcd = lenslets.focal_length = {f} mm): \
             content is sharpest at optical infinity, and the display has no finite central depth plane"
        ));
    } else if v2 > f {
        let image = 1.0 / (1.0 / f - 1.0 / v2);
        w.push(format!(
            "{source}: no virtual central depth plane: lenslets_to_lcd = {v2} mm is beyond the lenslets' focal length \
             {f} mm, so each lenslet forms a real image of the LCD {} mm in front of the lenslets (toward the eye), \
             not a virtual image behind them; near-eye displays put the LCD inside the focal length",
            round(image)
        ));
    }
    w
}

/// The warning for a real lenslet that images the LCD at no central depth plane in some colour
/// channel (at the channel's median wavelength, where the simulation refracts it): its dispersion
/// shortens the back focal distance toward blue, and an LCD beyond it is imaged at infinity or as
/// a real image on the eye's side, so that channel's content has no depth the eye can focus on.
fn channel_cdp_warning(display: &Display, source: &str) -> Option<String> {
    let t = display.thick_lenslet()?;
    let v2 = display.lenslets_to_lcd;
    let nm = display.channel_wavelengths();
    let names = ["red", "green", "blue"];
    let missing: Vec<usize> = (0..3).filter(|&c| t.lcd_image_distance(v2, nm[c]).is_none()).collect();
    if missing.is_empty() {
        return None;
    }
    let which: Vec<String> = missing
        .iter()
        .map(|&c| {
            let p = t.paraxial(nm[c]);
            format!("{} ({} nm: back focal distance {} mm)", names[c], round(nm[c]), round(p.bfd))
        })
        .collect();
    Some(format!(
        "{source}: the real lenslets image the LCD at no central depth plane in the {} channel: lenslets_to_lcd = \
         {v2} mm is at or beyond the lenslet's back focal distance there (its dispersion), so that channel's image \
         of the LCD is at infinity or real, on the eye's side; no accommodation focuses it as a plane behind the \
         lenslets (`inimtrace info --display` lists each channel's central depth plane)",
        which.join(", ")
    ))
}

/// The warning for an eye's focus distance `focus_mm` (mm from the pupil), stated as `field`;
/// `diopters` says whether the user gave it in diopters (then the distance is 1000 / D).
pub fn focus_warning(source: &str, field: &str, focus_mm: f64, diopters: bool) -> Option<String> {
    if diopters {
        let d = 1000.0 / focus_mm;
        if d > 1000.0 / FOCUS_DISTANCE.min {
            return Some(format!(
                "{source}: {field} = {} D is more than the {} D any eye accommodates (a focus {} mm from the pupil)",
                round(d),
                1000.0 / FOCUS_DISTANCE.min,
                round(focus_mm)
            ));
        }
        return None;
    }
    check(source, field, focus_mm, FOCUS_DISTANCE).map(|mut w| {
        if focus_mm > 0.0 && focus_mm <= 1000.0 / FOCUS_DISTANCE.min {
            w += &format!(", or meant as diopters (focus_diopters = {focus_mm}: {} mm)?", round(1000.0 / focus_mm));
        }
        w
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_display_and_eye_raise_nothing() {
        assert!(display_warnings(&Display::paper(), "paper").is_empty());
        for f in [300.0, 400.0, 600.0, 1e6] {
            assert_eq!(focus_warning("x", "focus_mm", f, false), None);
            assert_eq!(focus_warning("x", "focus_diopters", f, true), None);
        }
    }

    #[test]
    fn unit_mistakes_are_named() {
        let w = check("d.toml", "lenslets.pitch", 1200.0, LENSLET_PITCH).unwrap();
        assert!(
            w.contains("d.toml") && w.contains("lenslets.pitch") && w.contains("micrometres? 1200 µm = 1.2 mm"),
            "{w}"
        );
        let w = check("d.toml", "lenslets.focal_length", 0.006427, FOCAL_LENGTH).unwrap();
        assert!(w.contains("metres? 0.006427 m = 6.427 mm"), "{w}");
        let w = check("d.toml", "lcd.size", 2.16, LCD_SIZE).unwrap();
        assert!(w.contains("centimetres? 2.16 cm = 21.6 mm"), "{w}");
        let w = focus_warning("e.toml", "eye_cases[0].focus_mm", 1.5, false).unwrap();
        assert!(w.contains("metres? 1.5 m = 1500 mm") && w.contains("focus_diopters = 1.5"), "{w}");
        // Nothing to suggest: still a warning, without a unit.
        let w = check("d.toml", "lenslets.pitch", 1e9, LENSLET_PITCH).unwrap();
        assert!(!w.contains('?'), "{w}");
    }

    #[test]
    fn the_central_depth_plane_at_infinity_or_real_is_flagged() {
        let mut d = Display::paper();
        d.lenslets_to_lcd = d.focal_length;
        let w = display_warnings(&d, "d");
        assert!(w.len() == 1 && w[0].contains("infinity"), "{w:?}");
        d.lenslets_to_lcd = 2.0 * d.focal_length;
        let w = display_warnings(&d, "d");
        // 1/f - 1/(2f) = 1/(2f): the real image is 2f in front of the lenslets.
        assert!(w.len() == 1 && w[0].contains("real image") && w[0].contains("12.854 mm"), "{w:?}");
    }
}
