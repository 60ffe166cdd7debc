//! What the plots of `bench`, `sweep` and `resolution` share (plotters): the one legend style
//! (white, slightly transparent box with a black border) and plotters errors as text.

use plotters::chart::{ChartContext, SeriesLabelPosition};
use plotters::coord::CoordTranslate;
use plotters::prelude::*;

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
