//! The note a command prints before work that will take long (over a minute): every command
//! that traces rays (`assess`, `render-display`, `simulate`, `ground-truth`, `resolution`,
//! `sweep`) estimates its rays from its settings before it starts, and says how long that is
//! likely to take on this machine, even when stderr is not a terminal (the Sec. 4 measurements
//! at the paper's sizes take minutes to hours).

/// Rays per second per thread that the note assumes: a conservative figure for the generic
/// tracers (the fused planar kernel is faster).
pub const RAYS_PER_SECOND: f64 = 10e6;

/// The note for `rays` of work on `threads` threads, when it would take more than a minute.
pub fn note(rays: u64, threads: usize) -> Option<String> {
    let seconds = rays as f64 / (RAYS_PER_SECOND * threads.max(1) as f64);
    (seconds > 60.0).then(|| {
        format!(
            "note: this run traces about {:.2e} rays: roughly {} on this machine",
            rays as f64,
            if seconds < 3600.0 {
                match (seconds / 60.0).round() as u64 {
                    1 => "1 minute".to_string(),
                    m => format!("{m} minutes"),
                }
            } else {
                format!("{:.1} hours", seconds / 3600.0)
            }
        )
    })
}

/// Prints [`note`] for the current thread pool to stderr when the work is long.
pub fn announce(rays: u64) {
    if let Some(n) = note(rays, rayon::current_num_threads()) {
        eprintln!("{n}");
    }
}

/// The rays of an eye's retinal image: `n x n` pixels, `k x k` samples each, `pupil` pupil
/// samples per sample, `images` images (saturating).
pub fn retina_rays(n: usize, k: usize, pupil: usize, images: usize) -> u64 {
    [n, n, k, k, pupil, images].iter().fold(1u64, |acc, &x| acc.saturating_mul(x as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_note_appears_past_a_minute_of_work() {
        assert_eq!(note(599_000_000, 1), None);
        let n = note(601_000_000 * 2, 2).unwrap();
        assert_eq!(n, "note: this run traces about 1.20e9 rays: roughly 1 minute on this machine");
        assert!(note(2_000_000_000, 1).unwrap().ends_with("roughly 3 minutes on this machine"));
        assert!(note(1_000_000_000_000, 2).unwrap().contains("13.9 hours"));
        assert_eq!(retina_rays(512, 1, 52, 1), 512 * 512 * 52);
        assert_eq!(retina_rays(usize::MAX, 2, 2, 2), u64::MAX);
    }
}
