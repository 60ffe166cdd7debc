//! The files of a resolution study: `mtf.csv`,
//! `mtf50.csv`, `accommodation.csv`, `display.md`, `display.json` and `study.json` (every resolved
//! setting, the chart's layout, the stage timings), built from [`StudyResults`] as rows and text.

use std::fmt::Write as _;

use serde::Serialize;

use super::accommodation::{area_rule, area_under, frequency_rule, peak_half_width, GridEdge};
use super::chart::Pattern;
use super::limits::DisplayLimits;
use super::run::{StudyResults, Timing};
use super::study::Study;
use crate::io::output::OutputFile;
use crate::provenance::Provenance;

/// One row of `accommodation.csv`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccommodationRow {
    /// "ground_truth" or a method's short name.
    pub source: String,
    /// The content depth, dioptres.
    pub target_diopters: f64,
    /// `contrast_at_frequency` or `mtf_area`.
    pub rule: &'static str,
    /// The frequency rule's frequency, or the area rule's upper limit.
    pub frequency_cpd: f64,
    /// The eye focus the rule predicts, dioptres.
    pub predicted_focus_diopters: f64,
    /// Half-width of its 95% interval: the contrasts' half-widths carried through the parabola
    /// that places the peak (`resolution::accommodation::peak_half_width`); NaN on a grid edge.
    pub predicted_focus_ci95: f64,
    /// Whether the prediction is the focus grid's floor or ceiling (the response may lie beyond).
    pub grid_edge: GridEdge,
    /// The frequency rule: the contrast at the peak; the area rule: the mean contrast over the
    /// band (the area over its width) at the peak.
    pub contrast_at_peak: f64,
    /// Half-width of the 95% interval of the contrast at the focus sample nearest the peak: the
    /// frequency rule's measured contrast there; for the area rule, the band's mean of the
    /// half-widths (an upper bound of the band mean's, whatever their correlation).
    pub contrast_at_peak_ci95: f64,
}

/// The measurement's precision beside every table row: samples per retina pixel over all
/// replicates (as `results.csv` counts them) and the replicates. The study samples a fixed
/// number (`[measurement]`), so there is no precision target to meet.
pub fn samples_per_pixel(study: &Study) -> u64 {
    u64::from(study.measurement.samples_per_pixel) * study.measurement.replicates as u64
}

/// The index of the focus nearest `at` (the first of equals; `None` for NaN).
fn nearest(focus: &[f64], at: f64) -> Option<usize> {
    (!at.is_nan()).then(|| {
        (0..focus.len()).fold(0, |best, j| if (focus[j] - at).abs() < (focus[best] - at).abs() { j } else { best })
    })
}

/// Both rules for every source and content depth.
pub fn accommodation_rows(r: &StudyResults) -> Vec<AccommodationRow> {
    let s = &r.study;
    let qf = s.frequency_index(s.accommodation.frequency_cpd).expect("validated");
    let mut rows = Vec::new();
    for (k, source) in r.sources.iter().enumerate() {
        for (di, d) in s.depths.iter().enumerate() {
            let at_f: Vec<f64> = r.grating[k][di].iter().map(|q| q[qf].value).collect();
            let nan = super::accommodation::Peak { at: f64::NAN, value: f64::NAN };
            let p = frequency_rule(&s.focus_diopters, &at_f).unwrap_or(nan);
            let ci95 = nearest(&s.focus_diopters, p.at).map_or(f64::NAN, |j| r.grating[k][di][j][qf].ci95);
            let hs: Vec<f64> = r.grating[k][di].iter().map(|q| q[qf].ci95).collect();
            let focus_ci95 = peak_half_width(&s.focus_diopters, &at_f, &hs).unwrap_or(f64::NAN);
            rows.push(AccommodationRow {
                source: source.clone(),
                target_diopters: d.diopters,
                rule: "contrast_at_frequency",
                frequency_cpd: s.accommodation.frequency_cpd,
                predicted_focus_diopters: p.at,
                predicted_focus_ci95: focus_ci95,
                grid_edge: GridEdge::of(&s.focus_diopters, p.at),
                contrast_at_peak: p.value,
                contrast_at_peak_ci95: ci95,
            });
            let mtf: Vec<Vec<f64>> = r.grating[k][di].iter().map(|q| q.iter().map(|v| v.value).collect()).collect();
            let p =
                area_rule(&s.focus_diopters, &s.frequencies_cpd, &mtf, s.accommodation.area_limit_cpd).unwrap_or(nan);
            let limit = s.accommodation.area_limit_cpd;
            // The band mean of the half-widths at each focus (an upper bound of the band mean's).
            let band_ci95: Vec<f64> = r.grating[k][di]
                .iter()
                .map(|q| {
                    let h: Vec<f64> = q.iter().map(|v| v.ci95).collect();
                    area_under(&s.frequencies_cpd, &h, limit) / (limit - s.frequencies_cpd[0])
                })
                .collect();
            let ci95 = nearest(&s.focus_diopters, p.at).map_or(f64::NAN, |j| band_ci95[j]);
            let areas: Vec<f64> = mtf.iter().map(|m| area_under(&s.frequencies_cpd, m, limit)).collect();
            let width = limit - s.frequencies_cpd[0];
            let means: Vec<f64> = areas.iter().map(|a| a / width).collect();
            let focus_ci95 = peak_half_width(&s.focus_diopters, &means, &band_ci95).unwrap_or(f64::NAN);
            rows.push(AccommodationRow {
                source: source.clone(),
                target_diopters: d.diopters,
                rule: "mtf_area",
                frequency_cpd: s.accommodation.area_limit_cpd,
                predicted_focus_diopters: p.at,
                predicted_focus_ci95: focus_ci95,
                grid_edge: GridEdge::of(&s.focus_diopters, p.at),
                contrast_at_peak: p.value,
                contrast_at_peak_ci95: ci95,
            });
        }
    }
    rows
}

/// Numbers in CSV: shortest round-trip form, empty for NaN.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `mtf.csv`: source, target_diopters, focus_diopters, frequency_cpd, orientation_deg, measure,
/// contrast, contrast_ci95, samples_per_pixel, replicates. For each source, depth and focus: the gratings at 0 degrees (vertical
/// bars), the edge (its angle from vertical), then the gratings at each other orientation (only
/// with the eye on the content unless `orientations_through_focus`), at every study frequency.
pub fn mtf_csv(r: &StudyResults) -> String {
    let s = &r.study;
    let mut out = String::from(
        "source,target_diopters,focus_diopters,frequency_cpd,orientation_deg,measure,contrast,contrast_ci95,\
         samples_per_pixel,replicates\n",
    );
    let (spp, replicates) = (samples_per_pixel(s), s.measurement.replicates);
    let edge_angle = r
        .chart
        .patches
        .iter()
        .find_map(|p| match p.pattern {
            Pattern::Edge { angle_deg } => Some(angle_deg),
            _ => None,
        })
        .unwrap_or(f64::NAN);
    for (k, source) in r.sources.iter().enumerate() {
        for (di, d) in s.depths.iter().enumerate() {
            for (fi, f) in s.focus_diopters.iter().enumerate() {
                // Other orientations: with the eye on the content only, unless measured through focus.
                let measured = s.orientations_through_focus || s.focus_index(d.diopters) == Some(fi);
                let turned = r
                    .oriented
                    .iter()
                    .filter(|_| measured)
                    .map(|o| ("grating", &o.grating[k][di][fi], o.orientation_deg));
                for (measure, values, angle) in
                    [("grating", &r.grating[k][di][fi], 0.0), ("edge", &r.edge[k][di][fi], edge_angle)]
                        .into_iter()
                        .chain(turned)
                {
                    for (q, v) in s.frequencies_cpd.iter().zip(values) {
                        let _ = writeln!(
                            out,
                            "{source},{},{},{},{},{measure},{},{},{spp},{replicates}",
                            num(d.diopters),
                            num(*f),
                            num(*q),
                            num(angle),
                            num(v.value),
                            num(v.ci95)
                        );
                    }
                }
            }
        }
    }
    out
}

/// `mtf50.csv`: source, target_diopters, focus_diopters, mtf50_cpd, mtf50_ci95 (slanted edge;
/// empty when the MTF stays above 0.5 up to the retina's Nyquist frequency), samples_per_pixel,
/// replicates.
pub fn mtf50_csv(r: &StudyResults) -> String {
    let s = &r.study;
    let mut out =
        String::from("source,target_diopters,focus_diopters,mtf50_cpd,mtf50_ci95,samples_per_pixel,replicates\n");
    let (spp, replicates) = (samples_per_pixel(s), s.measurement.replicates);
    for (k, source) in r.sources.iter().enumerate() {
        for (di, d) in s.depths.iter().enumerate() {
            for (fi, f) in s.focus_diopters.iter().enumerate() {
                let v = r.mtf50[k][di][fi];
                let _ = writeln!(
                    out,
                    "{source},{},{},{},{},{spp},{replicates}",
                    num(d.diopters),
                    num(*f),
                    num(v.value),
                    num(v.ci95)
                );
            }
        }
    }
    out
}

/// `accommodation.csv`: the rows, each with its precision (`contrast_at_peak_ci95`, and the
/// study's samples per pixel and replicates).
pub fn accommodation_csv(rows: &[AccommodationRow], study: &Study) -> String {
    let mut out = String::from(
        "source,target_diopters,rule,frequency_cpd,predicted_focus_diopters,predicted_focus_ci95,grid_edge,\
         contrast_at_peak,contrast_at_peak_ci95,samples_per_pixel,replicates\n",
    );
    let (spp, replicates) = (samples_per_pixel(study), study.measurement.replicates);
    for a in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{spp},{replicates}",
            a.source,
            num(a.target_diopters),
            a.rule,
            num(a.frequency_cpd),
            num(a.predicted_focus_diopters),
            num(a.predicted_focus_ci95),
            a.grid_edge.name(),
            num(a.contrast_at_peak),
            num(a.contrast_at_peak_ci95)
        );
    }
    out
}

/// A chart patch as `study.json` records it.
#[derive(Serialize)]
struct PatchRecord {
    pattern: &'static str,
    frequency_cpd: Option<f64>,
    edge_angle_deg: Option<f64>,
    window_center_deg: [f64; 2],
    window_pixels: [usize; 2],
    patch_size_deg: [f64; 2],
}

/// `study.json`: every resolved setting, the chart, the LCD crop, the stage timings.
#[derive(Serialize)]
struct StudyRecord<'a> {
    inimtrace_version: String,
    study: &'a Study,
    central_depth_plane_mm: Option<f64>,
    central_depth_plane_diopters: Option<f64>,
    sources: &'a [String],
    chart: Vec<PatchRecord>,
    chart_half_extent_deg: [f64; 2],
    lcd_crop_pixels: [usize; 2],
    eye_rays: u64,
    timings: &'a [Timing],
    total_seconds: f64,
    /// Every other file of the run, with its size and CRC-32.
    files: &'a [OutputFile],
    /// What the run read (with SHA-256) and how it was asked (`inimtrace info --provenance`).
    provenance: &'a Provenance,
}

/// The text of `study.json`: the resolved study, its results, stage timings and output files.
pub fn study_json(r: &StudyResults, timings: &[Timing], files: &[OutputFile], provenance: &Provenance) -> String {
    let cdp = r.study.display.central_depth_plane();
    let rec = StudyRecord {
        inimtrace_version: crate::version::software(),
        study: &r.study,
        central_depth_plane_mm: cdp,
        central_depth_plane_diopters: cdp.map(|z| 1000.0 / z),
        sources: &r.sources,
        chart: r
            .chart
            .patches
            .iter()
            .map(|p| PatchRecord {
                pattern: match p.pattern {
                    Pattern::Grating { .. } => "grating",
                    Pattern::Edge { .. } => "edge",
                },
                frequency_cpd: match p.pattern {
                    Pattern::Grating { frequency_cpd } => Some(frequency_cpd),
                    _ => None,
                },
                edge_angle_deg: match p.pattern {
                    Pattern::Edge { angle_deg } => Some(angle_deg),
                    _ => None,
                },
                window_center_deg: p.center_deg.to_array(),
                window_pixels: [p.cols, p.rows],
                patch_size_deg: (2.0 * p.half_deg).to_array(),
            })
            .collect(),
        chart_half_extent_deg: r.chart.half_extent_deg.to_array(),
        lcd_crop_pixels: r.lcd_crop,
        eye_rays: r.eye_rays,
        timings,
        total_seconds: timings.iter().map(|t| t.seconds).sum(),
        files,
        provenance,
    };
    serde_json::to_string_pretty(&rec).unwrap_or_default() + "\n"
}

/// `display.json`.
pub fn display_json(l: &DisplayLimits) -> String {
    serde_json::to_string_pretty(l).unwrap_or_default() + "\n"
}

/// Where the study's eye is, when it is not at rest at the origin: its gaze (and centre of
/// rotation) and its pupil's position; empty at rest, as before the eye could move.
fn eye_place_text(study: &Study) -> String {
    let place = &study.eye_place;
    let mut t = String::new();
    if let Some(pose) = &place.pose {
        let c = pose.centre;
        let _ = write!(
            t,
            ", gaze [{}, {}] degrees about the centre of rotation ({}, {}, {}) mm",
            place.gaze.horizontal_deg, place.gaze.vertical_deg, c.x, c.y, c.z
        );
    }
    if place.position != glam::DVec3::ZERO {
        let p = place.position;
        let _ = write!(t, ", pupil at ({}, {}, {}) mm", p.x, p.y, p.z);
    }
    t
}

/// `display.md`: the limits as a short report.
pub fn display_md(l: &DisplayLimits, study: &Study) -> String {
    let opt2 = |v: Option<[f64; 2]>, d: usize| match v {
        Some([a, b]) => format!("{a:.d$} x {b:.d$}"),
        None => "none".into(),
    };
    let mut s = String::new();
    let _ = writeln!(s, "# Display limits: {}\n", l.display.name);
    let _ = writeln!(s, "Study `{}`, pupil {} mm{}.\n", study.name, l.pupil_diameter_mm, eye_place_text(study));
    let _ = writeln!(s, "| quantity | value |\n|---|---|");
    let _ = writeln!(
        s,
        "| central depth plane (CDP) | {} |",
        match (l.central_depth_plane_mm, l.central_depth_plane_diopters) {
            (Some(z), Some(d)) => format!("{z:.1} mm ({d:.3} D)"),
            _ => "at infinity or real".into(),
        }
    );
    let _ = writeln!(s, "| angular pixel pitch at the CDP | {} arcmin |", opt2(l.angular_pixel_pitch_arcmin, 2));
    let _ = writeln!(s, "| pixels per degree at the CDP | {} |", opt2(l.pixels_per_degree, 2));
    let _ = writeln!(s, "| Nyquist frequency at the CDP | {} cpd |", opt2(l.nyquist_cpd, 2));
    let _ = writeln!(s, "| lenslet angular pitch | {} degrees |", opt2(Some(l.lenslet_angular_pitch_deg), 2));
    let _ = writeln!(
        s,
        "| views through the pupil (a point at the CDP) | {} across; {} in the pupil disk |",
        opt2(l.views_across_pupil, 2),
        l.views_in_pupil.map_or("none".into(), |n| n.to_string())
    );
    let _ = writeln!(s, "| eye box at the eye relief ({} mm) | {} mm |", l.eye_relief_mm, opt2(l.eye_box_mm, 2));
    let _ = writeln!(s, "| field of view | {} degrees |", opt2(Some(l.field_of_view_deg), 1));
    if let Some(z) = l.lc_cdp_first_zero_cpd {
        let _ = writeln!(s, "| LC at the CDP: first zero of the MTF (analytic) | {z:.2} cpd |");
    }
    let _ = writeln!(
        s,
        "\nContent depths where each source keeps a grating contrast above {} with the eye focused on the \
         content (measured depths: {} D):\n",
        study.limits.contrast,
        study.depths.iter().map(|d| format!("{:.3}", d.diopters)).collect::<Vec<_>>().join(", ")
    );
    let _ = writeln!(
        s,
        "| source | frequency (cpd) | longest run of passing depths | every passing depth (D) |\n|---|---:|---|---|"
    );
    for r in &l.depth_ranges {
        let run = match (r.range_diopters, r.range_mm) {
            (Some([a, b]), Some([za, zb])) => format!("{a:.3} to {b:.3} D ({za:.0} to {zb:.0} mm)"),
            _ => "none".into(),
        };
        let all = r.passing_diopters.iter().map(|d| format!("{d:.3}")).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            s,
            "| {} | {} | {run} | {} |",
            r.source,
            r.frequency_cpd,
            if all.is_empty() { "none".into() } else { all }
        );
    }
    s
}

/// The part of `display.md` on orientations: for each source, the grating contrast at every
/// study orientation at the `[limits]` frequencies, for the content depth nearest the CDP and the
/// farthest one, the eye focused on the content; and the largest spread between orientations.
pub fn orientations_md(r: &StudyResults) -> String {
    let s = &r.study;
    let mut out = String::new();
    if s.orientations_deg.len() < 2 {
        return out;
    }
    let cdp = s.display.central_depth_plane().map_or(0.0, |z| 1000.0 / z);
    let near_cdp = (0..s.depths.len())
        .min_by(|&a, &b| (s.depths[a].diopters - cdp).abs().total_cmp(&(s.depths[b].diopters - cdp).abs()))
        .unwrap_or(0);
    let mut depths = vec![near_cdp];
    if near_cdp != 0 {
        depths.push(0);
    }
    let _ = writeln!(
        out,
        "
Grating contrast by orientation (degrees counter-clockwise from vertical bars), the eye focused on the \
         content, +- the 95% half-width:\n"
    );
    let heads: Vec<String> = s.orientations_deg.iter().map(|o| format!("{o} deg")).collect();
    let _ = writeln!(
        out,
        "| source | content (D) | frequency (cpd) | {} | spread |\n|---|---:|---:|{}---:|",
        heads.join(" | "),
        "---:|".repeat(heads.len())
    );
    for (k, source) in r.sources.iter().enumerate() {
        for &di in &depths {
            let d = s.depths[di];
            let Some(fi) = s.focus_index(d.diopters) else { continue };
            for f in &s.limits.frequencies_cpd {
                let Some(qi) = s.frequency_index(*f) else { continue };
                let vals: Vec<super::run::Value> =
                    (0..s.orientations_deg.len()).map(|oi| r.grating_at(oi)[k][di][fi][qi]).collect();
                let cells: Vec<String> = vals.iter().map(|v| format!("{:.3} +- {:.3}", v.value, v.ci95)).collect();
                let (lo, hi) =
                    vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v.value), b.max(v.value)));
                let _ =
                    writeln!(out, "| {source} | {:.3} | {f} | {} | {:.3} |", d.diopters, cells.join(" | "), hi - lo);
            }
        }
    }
    out
}
