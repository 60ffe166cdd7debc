//! The eye box's light (docs/FIELD.md): for a display and an eye (eq. (1)'s thin lens focused at
//! `FOCUS_MM`, pupil `PUPIL_MM`, or a pinhole for 0), moved over a 5 x 5 grid of pupil positions
//! from -2 to 2 mm, the shares of a uniformly white display's perceived light that come from the
//! crossed lenslet's own elemental image, from a neighbour's (crosstalk) and from off the panel
//! (the relative illumination's loss), over the paper experiment's retina (+-0.3 in tangent).
//!
//! ```text
//! cargo run --release --example eyebox_light [-- DISPLAY [PUPIL_MM [FOCUS_MM]]]
//!                                            # default: displays/paper.toml 5 400
//! ```

use std::path::Path;

use glam::DVec3;
use inimtrace::optics::crosstalk::light_shares;
use inimtrace::optics::{Aperture, Eye, Focus, Retina};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args.first().map_or_else(|| root.join("displays/paper.toml"), |a| a.into());
    let number = |i: usize, default: f64| args.get(i).map_or(Ok(default), |a| a.parse::<f64>());
    let (pupil, focus) = (number(1, 5.0)?, number(2, 400.0)?);
    let display = inimtrace::settings::load_display_part(Some(&file), &[])?;
    let aperture = if pupil > 0.0 {
        Aperture::ThinLens { pupil_diameter: pupil, focus: Focus::Millimetres(focus) }
    } else {
        Aperture::Pinhole
    };
    let retina = Retina { resolution: 128, half_tangent: 0.3, samples_per_pixel: 1 };
    let steps = [-2.0, -1.0, 0.0, 1.0, 2.0];
    println!("{}: pupil {pupil} mm focused at {focus} mm (0: pinhole); own / neighbour / off panel, %", display.name);
    println!("| y \\ x | {} |", steps.map(|x| format!("{x}")).join(" | "));
    println!("|---|{}", "---|".repeat(steps.len()));
    for y in steps.iter().rev() {
        let mut row = Vec::new();
        for x in steps {
            let eye = Eye {
                retina_distance: 17.0,
                aperture,
                pupil_grid: 24,
                position: DVec3::new(x, *y, 0.0),
                optics: None,
                pose: None,
            };
            eye.validate("eye")?;
            let s = light_shares(&display, &eye, &retina, "eye")?;
            row.push(format!("{:.1} / {:.1} / {:.1}", 100.0 * s.own, 100.0 * s.neighbour, 100.0 * s.off_panel));
        }
        println!("| {y:+} | {} |", row.join(" | "));
    }
    Ok(())
}
