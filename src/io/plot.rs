//! What the plots of `bench`, `sweep` and `resolution` share (plotters): the one legend style
//! (white, slightly transparent box with a black border), plotters errors as text, and the one
//! font. Text is rasterised by plotters' `ab_glyph` renderer with DejaVu Sans (Debian's
//! `fonts-dejavu-core`, found by path or by fontconfig's `fc-match`), registered once per process
//! as `sans-serif` ([`register_font`]); plotters' `ttf` renderer clips the part of a glyph left of
//! its origin, which erased `j` ("ob ective").

use std::sync::OnceLock;

use plotters::chart::{ChartContext, SeriesLabelPosition};
use plotters::coord::CoordTranslate;
use plotters::prelude::*;

/// Where Debian puts DejaVu Sans.
const DEJAVU_SANS: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Registers the plots' font (module comment) once per process; every plot calls this before it
/// draws text. The error says which font was looked for and how to install it.
pub fn register_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let path = if std::path::Path::new(DEJAVU_SANS).is_file() {
                DEJAVU_SANS.to_string()
            } else {
                let out = std::process::Command::new("fc-match").args(["-f", "%{file}", "DejaVu Sans"]).output();
                out.ok().filter(|o| o.status.success()).map(|o| String::from_utf8_lossy(&o.stdout).into_owned()).unwrap_or_default()
            };
            let missing = || format!("the plots' font DejaVu Sans was not found ({DEJAVU_SANS}, or fontconfig's fc-match): install Debian's fonts-dejavu-core");
            let bytes = std::fs::read(&path).map_err(|_| missing())?;
            // One font for the process's lifetime: plotters keeps a 'static reference to it.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| format!("{path} is not a font plotters can read: install Debian's fonts-dejavu-core"))
        })
        .clone()
}

/// A plotters error as text.
pub fn e2s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Draws `chart`'s series legend at `position`, labels in sans-serif of `font_size` (`None`:
/// plotters' default).
pub fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: Option<u32>,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    let mut labels = chart.configure_series_labels();
    labels.position(position).background_style(WHITE.mix(0.85)).border_style(BLACK);
    if let Some(size) = font_size {
        labels.label_font(("sans-serif", size));
    }
    labels.draw().map_err(e2s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_ascii_letter_and_digit_leaves_ink() {
        register_font().unwrap();
        let (w, h) = (48u32, 48u32);
        for c in ('a'..='z').chain('A'..='Z').chain('0'..='9') {
            let mut buf = vec![255u8; (w * h * 3) as usize];
            {
                let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                let style = ("sans-serif", 28).into_font().color(&BLACK);
                area.draw_text(&c.to_string(), &style, (12, 8)).unwrap();
                area.present().unwrap();
            }
            let ink = buf.iter().filter(|&&v| v < 128).count();
            assert!(ink >= 6, "`{c}` leaves {ink} dark subpixels");
        }
    }
}
