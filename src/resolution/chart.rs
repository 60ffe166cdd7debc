//! The study's test chart (gratings and a slanted edge on paper Sec. 4.1's kind of planar content): one plane at the
//! content depth holding a grating patch per frequency and a slanted-edge patch, on a grey of
//! the gratings' mean, all laid out in tangent coordinates seen from the pupil centre (so a
//! patch covers the same angles, and a frequency in cycles per degree means the same, at every
//! depth). Degrees here are tangent units of `pi / 180`, the unit the retina's pixels use.
//!
//! Each patch is its measured window plus a guard band on every side in which the pattern goes
//! on: blur narrower than the guard brings nothing but the patch's own pattern into its window,
//! and the grey between patches adds no signal at any frequency. Every grating holds a whole
//! number of periods over its window, so the windowed Fourier coefficients of different
//! frequencies are orthogonal.
//!
//! **Orientations.** The study measures the gratings at other orientations on the same chart
//! turned as a whole about the visual axis ([`Chart::turned`]): a turned chart shows every
//! grating turned by `a` (degrees counter-clockwise; its modulation along `(cos a, sin a)`) at the
//! 0-degree grating's place turned by `a`, and its windows' retina pixels are cut in the turned
//! frame. In its own frame every grating is still vertical bars over a whole number of periods,
//! measured by the same analysis; the retina pixel's own box response along the modulation, and
//! the eccentricity of each grating, are the same at every orientation: only the display (and an
//! eye that is not rotationally symmetric) differ. On a display that is symmetric under a quarter
//! turn (the paper's square one) 90 degrees shows the same as 0.
//!
//! **Field.** A study may measure off axis ([`Chart::at_field`]): the whole chart, turned or not,
//! faces the direction of a field `[horizontal, vertical]` in Fick's angles (the eye's gaze
//! convention, [`crate::optics::eye::gaze`]), carried there by that direction's Listing rotation
//! about the pupil centre. Its tangent coordinates are then the gnomonic ones about the field
//! direction, so a degree still means a degree of visual angle at the chart's centre, and its
//! plane stays the content plane `z = depth`: each point of that plane shows the chart's value
//! in the direction from the pupil centre. Retina pixels of its windows are cut in the chart's
//! own frame and carried to the eye's tangents the same way.
//!
//! **The eye's frame.** Everything above is the eye's own frame: its pupil centre at the origin,
//! its line of sight along +z. A study whose eye is turned (`[eye] gaze_deg`, about its centre
//! of rotation, [`crate::optics::eye::EyePose`]) or moved (`[eye] position`) carries the chart
//! with it ([`Chart::seen_by`]): the chart, its plane and its windows stay on the eye's line of
//! sight at the content distance, while the display stays where it is. A turned eye therefore
//! measures a chart on its line of sight exactly as the eye at rest measures it on the axis; only
//! what the display shows it differs.
//!
//! [`ChartField`] is the chart as a [`RadianceField`] (the plane's radiance along any ray), the
//! one field that renders the display images and the ground truth alike.

use std::f64::consts::{PI, TAU};

use glam::{DMat3, DVec2, DVec3};

use super::study::Study;
use crate::optics::eye::Gaze;
use crate::ray::Ray;
use crate::render::RadianceField;

/// What a patch shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pattern {
    /// Vertical bars: `mean (1 + contrast cos(2 pi f (x - x_centre)))`, `f` in cycles per degree.
    Grating {
        /// Frequency, cycles per degree.
        frequency_cpd: f64,
    },
    /// A straight edge through the patch centre, `angle_deg` from vertical: dark on the left,
    /// light on the right.
    Edge {
        /// Angle from vertical, degrees.
        angle_deg: f64,
    },
}

/// A patch: its pattern, its measured window and the guard around it (degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// What the patch shows.
    pub pattern: Pattern,
    /// Window centre, degrees (x right, y up).
    pub center_deg: DVec2,
    /// Window size in retina pixels (columns along x, rows along y).
    pub cols: usize,
    /// Window rows (along y), retina pixels.
    pub rows: usize,
    /// Half-size of the patch (window plus guard), degrees.
    pub half_deg: DVec2,
    /// The edge's normal `(cos a, sin a)` (the light side is along it); zero for gratings.
    pub edge_normal: DVec2,
}

impl Patch {
    fn contains(&self, p: DVec2) -> bool {
        let d = (p - self.center_deg).abs();
        d.x <= self.half_deg.x && d.y <= self.half_deg.y
    }
}

/// The chart: patches, luminances, and the retina pixel pitch the windows are cut in.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    /// Every patch.
    pub patches: Vec<Patch>,
    /// Mean luminance of every pattern (linear, in [0, 1]).
    pub mean: f64,
    /// Michelson contrast of every pattern.
    pub contrast: f64,
    /// Retina pixels per degree the windows are cut in.
    pub pixels_per_degree: f64,
    /// Half-extent of all patches, degrees.
    pub half_extent_deg: DVec2,
    /// Column layout: left edge and width of each column of patches, degrees.
    columns: Vec<(f64, f64, Vec<usize>)>,
    /// The turn of the whole chart about the axis, degrees counter-clockwise (0: as laid out).
    pub orientation_deg: f64,
    /// `(cos a, sin a)` of the turn (exact at multiples of 90 degrees); `None` at 0.
    turn: Option<DVec2>,
    /// The field the chart faces (straight ahead by default).
    pub field: Gaze,
    /// The rotation from the chart's own frame to the eye's; `None` on the axis.
    facing: Option<DMat3>,
    /// The eye's frame in the display's, when the eye is turned or moved; `None`: the eye at rest
    /// at the origin.
    pub eye: Option<EyeFrame>,
}

/// Where the eye is: its frame (pupil centre at the origin, line of sight along +z) in the
/// display's, `x_display = R x_eye + pupil`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeFrame {
    /// The eye's rotation `R` (its gaze); `None`: looking straight ahead.
    pub rotation: Option<DMat3>,
    /// The pupil centre, mm (for a turned eye, where its turn has moved it).
    pub pupil: DVec3,
}

impl EyeFrame {
    /// The frame of an eye whose pupil centre is at `position` when it looks straight ahead,
    /// turned by `pose` (`None`: straight ahead); `None` for the eye at rest at the origin.
    pub fn of(position: DVec3, pose: Option<&crate::optics::eye::EyePose>) -> Option<Self> {
        match pose {
            Some(p) => Some(Self { rotation: Some(DMat3::from_quat(p.rotation)), pupil: p.pupil_centre }),
            None if position == DVec3::ZERO => None,
            None => Some(Self { rotation: None, pupil: position }),
        }
    }

    /// A ray of the display's frame in the eye's.
    #[inline]
    pub fn to_eye(&self, ray: &Ray) -> Ray {
        let o = ray.origin - self.pupil;
        match self.rotation {
            None => Ray { origin: o, dir: ray.dir },
            Some(m) => Ray { origin: m.transpose() * o, dir: m.transpose() * ray.dir },
        }
    }

    /// A direction of the eye's frame in the display's.
    #[inline]
    pub fn direction(&self, d: DVec3) -> DVec3 {
        self.rotation.map_or(d, |m| m * d)
    }
}

impl Chart {
    /// The study's chart: one grating per frequency, then the edge, in columns about the axis,
    /// facing the study's field.
    pub fn of_study(study: &Study) -> Self {
        let r = &study.retina;
        let ppd = r.pixels_per_degree;
        let g = r.guard_deg;
        let mut items: Vec<(Pattern, DVec2)> = study
            .frequencies_cpd
            .iter()
            .map(|&f| (Pattern::Grating { frequency_cpd: f }, DVec2::from(r.window_deg)))
            .collect();
        items.push((Pattern::Edge { angle_deg: r.edge_angle_deg }, DVec2::from(r.edge_window_deg)));
        Self::layout(&items, g, ppd, study.target.mean, study.target.contrast)
            .at_field(study.field_deg)
            .seen_by(study.eye_place.frame())
    }

    /// Lays `items` (pattern, window size in degrees) out in columns, choosing the column
    /// count that makes the chart most nearly square; centred on the axis.
    pub fn layout(items: &[(Pattern, DVec2)], guard_deg: f64, ppd: f64, mean: f64, contrast: f64) -> Self {
        let sizes: Vec<DVec2> = items.iter().map(|(_, w)| *w + DVec2::splat(2.0 * guard_deg)).collect();
        let col_w = sizes.iter().map(|s| s.x).fold(0.0, f64::max);
        let split = |c: usize| -> Vec<Vec<usize>> {
            let per = items.len().div_ceil(c);
            (0..items.len()).collect::<Vec<_>>().chunks(per).map(|ch| ch.to_vec()).collect()
        };
        let height =
            |cols: &[Vec<usize>]| cols.iter().map(|c| c.iter().map(|&i| sizes[i].y).sum::<f64>()).fold(0.0, f64::max);
        let best = (1..=items.len().max(1))
            .map(split)
            .min_by(|a, b| {
                let ea = (a.len() as f64 * col_w).max(height(a));
                let eb = (b.len() as f64 * col_w).max(height(b));
                ea.total_cmp(&eb)
            })
            .unwrap_or_default();
        let total_w = best.len() as f64 * col_w;
        let total_h = height(&best);
        let mut patches = vec![None; items.len()];
        let mut columns = Vec::new();
        for (ci, col) in best.iter().enumerate() {
            let x0 = -0.5 * total_w + ci as f64 * col_w;
            let mut y = 0.5 * total_h;
            for &i in col {
                let (pattern, window) = items[i];
                let cy = y - 0.5 * sizes[i].y;
                y -= sizes[i].y;
                patches[i] = Some(Patch {
                    pattern,
                    center_deg: DVec2::new(x0 + 0.5 * col_w, cy),
                    cols: (window.x * ppd).round() as usize,
                    rows: (window.y * ppd).round() as usize,
                    half_deg: 0.5 * sizes[i],
                    edge_normal: match pattern {
                        Pattern::Edge { angle_deg } => {
                            let (s, c) = angle_deg.to_radians().sin_cos();
                            DVec2::new(c, s)
                        }
                        Pattern::Grating { .. } => DVec2::ZERO,
                    },
                });
            }
            columns.push((x0, col_w, col.clone()));
        }
        Chart {
            patches: patches.into_iter().map(|p| p.expect("every patch placed")).collect(),
            mean,
            contrast,
            pixels_per_degree: ppd,
            half_extent_deg: DVec2::new(0.5 * total_w, 0.5 * total_h),
            columns,
            orientation_deg: 0.0,
            turn: None,
            field: Gaze::AHEAD,
            facing: None,
            eye: None,
        }
    }

    /// This chart carried with the eye of `frame` (module documentation); `None` leaves it as it
    /// is.
    pub fn seen_by(self, frame: Option<EyeFrame>) -> Chart {
        Chart { eye: frame, ..self }
    }

    /// This chart facing `field` (module documentation); straight ahead leaves it on the axis.
    pub fn at_field(self, field: Gaze) -> Chart {
        Chart { field, facing: (!field.is_ahead()).then(|| field.matrix()), ..self }
    }

    /// The eye's tangent of the chart-frame tangent `t` (after any turn).
    #[inline]
    pub fn eye_tangent(&self, t: DVec2) -> DVec2 {
        match self.facing {
            None => t,
            Some(m) => {
                let d = m * DVec3::new(t.x, t.y, 1.0);
                DVec2::new(d.x, d.y) / d.z
            }
        }
    }

    /// The chart-frame tangent of the eye's tangent `t`; `None` for a direction at or beyond 90
    /// degrees from the chart's centre.
    #[inline]
    pub fn chart_tangent(&self, t: DVec2) -> Option<DVec2> {
        match self.facing {
            None => Some(t),
            Some(m) => {
                let d = m.transpose() * DVec3::new(t.x, t.y, 1.0);
                (d.z > 0.0).then(|| DVec2::new(d.x, d.y) / d.z)
            }
        }
    }

    /// Half-extent per axis of the eye's tangents the chart covers: [`Chart::reach_tangent`] on
    /// the axis; off axis, of the images of the reach's corners (the gnomonic map keeps straight
    /// lines straight, so they bound the image).
    pub fn eye_reach_tangent(&self) -> DVec2 {
        let r = self.reach_tangent();
        if self.facing.is_none() {
            return r;
        }
        [r, DVec2::new(r.x, -r.y), -r, DVec2::new(-r.x, r.y)]
            .iter()
            .map(|&c| self.eye_tangent(c).abs())
            .fold(DVec2::ZERO, DVec2::max)
    }

    /// This chart's gratings (the edge left out) turned by `deg` about the axis (module
    /// documentation); `deg = 0` gives the gratings unturned.
    pub fn turned(&self, deg: f64) -> Chart {
        let keep: Vec<usize> =
            (0..self.patches.len()).filter(|&i| matches!(self.patches[i].pattern, Pattern::Grating { .. })).collect();
        let renumber = |i: &usize| keep.iter().position(|k| k == i);
        Chart {
            patches: keep.iter().map(|&i| self.patches[i]).collect(),
            columns: self
                .columns
                .iter()
                .map(|(x0, w, idx)| (*x0, *w, idx.iter().filter_map(renumber).collect()))
                .collect(),
            orientation_deg: deg,
            turn: (deg != 0.0).then(|| unit_at(deg)),
            ..self.clone()
        }
    }

    /// A point of the unturned layout, turned with the chart (tangent or degree units alike).
    #[inline]
    pub fn turn(&self, p: DVec2) -> DVec2 {
        match self.turn {
            None => p,
            Some(u) => DVec2::new(u.x * p.x - u.y * p.y, u.y * p.x + u.x * p.y),
        }
    }

    /// Half-extent of the area the chart covers, degrees: its layout's, or the bounding box of
    /// the turned layout.
    pub fn reach_deg(&self) -> DVec2 {
        match self.turn {
            None => self.half_extent_deg,
            Some(u) => {
                let (c, s, h) = (u.x.abs(), u.y.abs(), self.half_extent_deg);
                DVec2::new(c * h.x + s * h.y, s * h.x + c * h.y)
            }
        }
    }

    /// Luminance at direction `deg` (degrees of tangent from the pupil centre).
    #[inline]
    pub fn luminance(&self, deg: DVec2) -> f64 {
        // A turned chart: the point in the layout's own frame (turned back).
        let deg = match self.turn {
            None => deg,
            Some(u) => DVec2::new(u.x * deg.x + u.y * deg.y, u.x * deg.y - u.y * deg.x),
        };
        for (x0, w, idx) in &self.columns {
            if deg.x < *x0 || deg.x > x0 + w {
                continue;
            }
            for &i in idx {
                let p = &self.patches[i];
                if p.contains(deg) {
                    let d = deg - p.center_deg;
                    return match p.pattern {
                        Pattern::Grating { frequency_cpd } => {
                            self.mean * (1.0 + self.contrast * (TAU * frequency_cpd * d.x).cos())
                        }
                        Pattern::Edge { .. } => {
                            let side = d.dot(p.edge_normal);
                            self.mean * (1.0 + if side > 0.0 { self.contrast } else { -self.contrast })
                        }
                    };
                }
            }
        }
        self.mean
    }

    /// One retina pixel's pitch in tangent units.
    pub fn pixel_tangent(&self) -> f64 {
        PI / 180.0 / self.pixels_per_degree
    }

    /// Half-extent of the chart in tangent units.
    pub fn half_extent_tangent(&self) -> DVec2 {
        self.half_extent_deg * (PI / 180.0)
    }

    /// [`Chart::reach_deg`] in tangent units.
    pub fn reach_tangent(&self) -> DVec2 {
        self.reach_deg() * (PI / 180.0)
    }
}

/// `(cos a, sin a)` for `a` in degrees, exact at multiples of 90 degrees.
pub fn unit_at(deg: f64) -> DVec2 {
    match deg.rem_euclid(360.0) {
        0.0 => DVec2::X,
        90.0 => DVec2::Y,
        180.0 => -DVec2::X,
        270.0 => -DVec2::Y,
        _ => {
            let (s, c) = deg.to_radians().sin_cos();
            DVec2::new(c, s)
        }
    }
}

/// The chart on the plane `z = depth` (mm from the pupil) of the eye's frame, as a radiance
/// field: rays that meet the plane in front of them see the chart at `(x, y) / depth`; others see
/// the grey mean.
pub struct ChartField<'a> {
    /// The chart.
    pub chart: &'a Chart,
    /// Its plane's distance from the pupil, mm.
    pub depth: f64,
}

impl RadianceField for ChartField<'_> {
    #[inline]
    fn radiance(&self, ray: &Ray) -> DVec3 {
        let seen;
        let ray = match &self.chart.eye {
            None => ray,
            Some(frame) => {
                seen = frame.to_eye(ray);
                &seen
            }
        };
        let l = if ray.dir.z > 0.0 {
            let t = (self.depth - ray.origin.z) / ray.dir.z;
            if t > 0.0 {
                let p = ray.origin + t * ray.dir;
                if self.chart.facing.is_none() {
                    self.chart.luminance(DVec2::new(p.x, p.y) * (180.0 / PI / self.depth))
                } else {
                    match self.chart.chart_tangent(DVec2::new(p.x, p.y) / self.depth) {
                        Some(c) => self.chart.luminance(c * (180.0 / PI)),
                        None => self.chart.mean,
                    }
                }
            } else {
                self.chart.mean
            }
        } else {
            self.chart.mean
        };
        DVec3::splat(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> Chart {
        let items: Vec<_> = [0.5, 1.0, 2.0, 4.0]
            .iter()
            .map(|&f| (Pattern::Grating { frequency_cpd: f }, DVec2::new(2.0, 0.25)))
            .chain([(Pattern::Edge { angle_deg: 5.0 }, DVec2::new(2.0, 1.0))])
            .collect();
        Chart::layout(&items, 0.5, 64.0, 0.5, 0.8)
    }

    #[test]
    fn patches_do_not_overlap_and_windows_are_whole_pixels() {
        let c = chart();
        assert_eq!(c.patches.len(), 5);
        for (i, a) in c.patches.iter().enumerate() {
            for b in &c.patches[i + 1..] {
                let d = (a.center_deg - b.center_deg).abs();
                assert!(d.x >= a.half_deg.x + b.half_deg.x - 1e-9 || d.y >= a.half_deg.y + b.half_deg.y - 1e-9);
            }
            assert!(a.center_deg.abs().cmple(c.half_extent_deg - a.half_deg + 1e-9).all());
        }
        assert_eq!((c.patches[0].cols, c.patches[0].rows), (128, 16));
        assert_eq!((c.patches[4].cols, c.patches[4].rows), (128, 64));
        assert!((c.patches[4].edge_normal.x - 5f64.to_radians().cos()).abs() < 1e-15);
    }

    #[test]
    fn a_turned_chart_shows_each_grating_turned_at_its_turned_place() {
        let c = chart();
        for deg in [90.0, 45.0, 135.0, 30.0] {
            let t = c.turned(deg);
            assert_eq!(t.patches.len(), 4);
            let u = unit_at(deg);
            for p in &t.patches {
                let Pattern::Grating { frequency_cpd: f } = p.pattern else { panic!() };
                // Along the turned modulation: a peak, a trough half a period on; across it: flat.
                let centre = t.turn(p.center_deg);
                let across = DVec2::new(-u.y, u.x);
                for (offset, want) in [(0.0, 0.9), (0.5 / f, 0.1), (1.0 / f, 0.9)] {
                    let q = centre + offset * u + 0.1 * across;
                    assert!((t.luminance(q) - want).abs() < 1e-9, "{deg} deg, {f} cpd at {offset}: {}", t.luminance(q));
                }
            }
            let r = t.reach_deg();
            assert!(r.x >= c.half_extent_deg.x.min(c.half_extent_deg.y) - 1e-12);
        }
        // A quarter turn is exact: the layout's corners map onto each other.
        let t = c.turned(90.0);
        assert_eq!(t.turn(DVec2::new(1.5, -0.25)), DVec2::new(0.25, 1.5));
        assert_eq!(t.reach_deg(), DVec2::new(c.half_extent_deg.y, c.half_extent_deg.x));
        // Unturned, the gratings are where they were (the edge is not part of a turned chart).
        let q = c.patches[2].center_deg + DVec2::new(0.1, 0.05);
        assert_eq!(c.turned(0.0).luminance(q), c.luminance(q));
    }

    #[test]
    fn a_chart_off_axis_faces_its_field_and_keeps_its_degrees() {
        let g = Gaze::new(20.0, -10.0);
        let c = chart().at_field(g);
        // Its centre is the field's line of sight; the two maps are each other's inverse.
        let los = g.line_of_sight();
        assert!((c.eye_tangent(DVec2::ZERO) - DVec2::new(los.x, los.y) / los.z).length() < 1e-15);
        for t in [DVec2::new(0.01, -0.02), DVec2::new(-0.05, 0.03)] {
            assert!((c.chart_tangent(c.eye_tangent(t)).unwrap() - t).length() < 1e-14);
        }
        // A small step in the chart's frame at its centre is the same angle of view, any way.
        let dir = |t: DVec2| {
            let e = c.eye_tangent(t);
            DVec3::new(e.x, e.y, 1.0).normalize()
        };
        for u in [DVec2::X, DVec2::Y, DVec2::new(0.6, 0.8)] {
            let angle = dir(DVec2::ZERO).angle_between(dir(1e-4 * u));
            assert!((angle - 1e-4).abs() < 1e-12, "{u}: {angle}");
        }
        // The field: the 2 cpd grating's peak and trough along the eye's rays from the pupil.
        let p = c.patches[2];
        let f = ChartField { chart: &c, depth: 500.0 };
        for (offset, want) in [(0.0, 0.9), (0.25, 0.1), (0.5, 0.9)] {
            let e = c.eye_tangent((p.center_deg + DVec2::new(offset, 0.05)) * (PI / 180.0));
            let l = f.radiance(&Ray { origin: DVec3::ZERO, dir: DVec3::new(e.x, e.y, 1.0) }).x;
            assert!((l - want).abs() < 1e-9, "{offset}: {l}");
        }
        // Its reach holds every corner's image; straight ahead leaves the chart as it was.
        let r = c.eye_reach_tangent();
        let h = c.half_extent_tangent();
        for corner in [h, -h, DVec2::new(h.x, -h.y), DVec2::new(-h.x, h.y)] {
            assert!(c.eye_tangent(corner).abs().cmple(r + 1e-15).all());
        }
        assert_eq!(chart().at_field(Gaze::AHEAD), chart());
    }

    #[test]
    fn the_field_shows_each_grating_at_its_frequency_at_any_depth() {
        let c = chart();
        let p = c.patches[2]; // 2 cpd
        for depth in [300.0, 2000.0] {
            let f = ChartField { chart: &c, depth };
            let at = |deg: DVec2| {
                let t = deg * (PI / 180.0);
                f.radiance(&Ray { origin: DVec3::ZERO, dir: DVec3::new(t.x, t.y, 1.0) }).x
            };
            // A peak at the centre, a trough half a period (0.25 degree) away, a peak a period away.
            assert!((at(p.center_deg) - 0.9).abs() < 1e-12);
            assert!((at(p.center_deg + DVec2::new(0.25, 0.0)) - 0.1).abs() < 1e-9);
            assert!((at(p.center_deg + DVec2::new(0.5, 0.1)) - 0.9).abs() < 1e-9);
            // Outside every patch: the mean.
            assert_eq!(at(c.half_extent_deg + 1.0), 0.5);
        }
        let e = c.patches[4];
        let f = ChartField { chart: &c, depth: 500.0 };
        let at = |deg: DVec2| {
            let t = deg * (PI / 180.0);
            f.radiance(&Ray { origin: DVec3::ZERO, dir: DVec3::new(t.x, t.y, 1.0) }).x
        };
        assert!((at(e.center_deg + DVec2::new(0.1, 0.0)) - 0.9).abs() < 1e-12);
        assert!((at(e.center_deg - DVec2::new(0.1, 0.0)) - 0.1).abs() < 1e-12);
        // 5 degrees off vertical: at 0.4 degree up, the edge is 0.035 degree left of the centre line.
        assert!((at(e.center_deg + DVec2::new(-0.02, 0.4)) - 0.9).abs() < 1e-12);
        assert!((at(e.center_deg + DVec2::new(-0.05, 0.4)) - 0.1).abs() < 1e-12);
    }
}
