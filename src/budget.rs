//! Estimating a run's peak memory and work from its settings before allocating anything, so
//! that settings which would exhaust the machine are refused with one line naming the setting
//! responsible, and long runs are announced before they start.

use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The process's memory limit in bytes; 0 means "not set" (then [`memory_limit`] uses the
/// memory available on the machine).
static MEMORY_LIMIT: AtomicU64 = AtomicU64::new(0);

/// Sets the memory limit every estimate and every file reader checks against (`--max-memory`).
pub fn set_memory_limit(bytes: u64) {
    MEMORY_LIMIT.store(bytes, Ordering::Relaxed);
}

/// The memory limit in bytes: the one set by [`set_memory_limit`], else the memory available
/// on this machine, else 8 GiB where that is unknown.
pub fn memory_limit() -> u64 {
    match MEMORY_LIMIT.load(Ordering::Relaxed) {
        0 => available_memory().unwrap_or(8 << 30),
        set => set,
    }
}

/// One part of an estimate: what it is for, the setting that sizes it, and its bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// What the memory is for.
    pub what: String,
    /// The setting(s) that make this part large, as a user would change them
    /// (e.g. `lcd.resolution = [30000, 30000]`).
    pub setting: String,
    /// Bytes it takes.
    pub bytes: u64,
}

/// A run's estimated peak memory (the sum of its parts that are alive at once) and its work in
/// rays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// The parts, each alive for the whole run.
    pub parts: Vec<Part>,
    /// Rays of work.
    pub rays: u64,
}

impl Estimate {
    /// Adds `count x bytes_each` bytes (saturating: an overflow is an estimate of "too much").
    pub fn add(&mut self, what: impl Into<String>, setting: impl Into<String>, count: u64, bytes_each: u64) {
        self.parts.push(Part { what: what.into(), setting: setting.into(), bytes: count.saturating_mul(bytes_each) });
    }

    /// Adds rays of work (saturating).
    pub fn add_rays(&mut self, rays: u64) {
        self.rays = self.rays.saturating_add(rays);
    }

    /// Estimated peak memory: the sum of the parts' bytes (saturating).
    pub fn bytes(&self) -> u64 {
        self.parts.iter().fold(0u64, |a, p| a.saturating_add(p.bytes))
    }

    /// The largest part.
    pub fn largest(&self) -> Option<&Part> {
        self.parts.iter().max_by_key(|p| p.bytes)
    }

    /// Refuses the run when its estimated peak memory exceeds `limit` bytes, naming the largest
    /// part and the setting behind it.
    pub fn check_memory(&self, limit: u64, source: &str) -> Result<()> {
        let total = self.bytes();
        if total <= limit {
            return Ok(());
        }
        let (field, detail) = match self.largest() {
            Some(p) => (p.setting.clone(), format!("; the largest part is {} ({})", p.what, Bytes(p.bytes))),
            None => ("settings".to_string(), String::new()),
        };
        Err(Error::invalid(
            source,
            field,
            format!(
                "the run would need about {} of memory, more than the limit of {} (set with --max-memory){detail}",
                Bytes(total),
                Bytes(limit)
            ),
        ))
    }

    /// Seconds the run's rays take at `rays_per_second`.
    pub fn seconds(&self, rays_per_second: f64) -> f64 {
        self.rays as f64 / rays_per_second
    }
}

/// Byte counts as people read them (binary units).
#[derive(Clone, Copy, Debug)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
        let mut v = self.0 as f64;
        let mut u = 0;
        while v >= 1024.0 && u + 1 < UNITS.len() {
            v /= 1024.0;
            u += 1;
        }
        if u == 0 {
            write!(f, "{} B", self.0)
        } else {
            write!(f, "{v:.1} {}", UNITS[u])
        }
    }
}

/// Memory available to a new process on this machine (`MemAvailable` of `/proc/meminfo`),
/// or `None` where that is not known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Parses a memory size as users write it: `512M`, `2G`, `1.5GiB`, `300MB`, or plain bytes.
pub fn parse_bytes(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.trim().parse().map_err(|_| format!("`{text}` is not a size (e.g. 512M, 2G)"))?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0f64.powi(4),
        _ => return Err(format!("`{text}`: unknown unit (use K, M, G or T)")),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes > 0.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{text}` must be a positive size"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_saturate_and_name_the_largest_setting() {
        let mut e = Estimate::default();
        e.add("display images", "lcd.resolution = [30000, 30000]", 30000 * 30000 * 3, 12);
        e.add("retinal images", "retina_resolution = 512", 512 * 512, 12);
        e.add("overflow", "sphere-grid count", u64::MAX, 2);
        assert_eq!(e.bytes(), u64::MAX);
        let err = e.check_memory(1 << 30, "exp.toml").unwrap_err().to_string();
        assert!(err.contains("exp.toml") && err.contains("sphere-grid count") && err.contains("--max-memory"), "{err}");
        let mut small = Estimate::default();
        small.add("retinal images", "retina_resolution = 512", 512 * 512, 12);
        small.check_memory(1 << 30, "exp.toml").unwrap();
    }

    #[test]
    fn sizes_parse_as_written() {
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("2G").unwrap(), 2 << 30);
        assert_eq!(parse_bytes("1.5GiB").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("100").unwrap(), 100);
        assert!(parse_bytes("-1G").is_err() && parse_bytes("lots").is_err() && parse_bytes("2X").is_err());
        assert_eq!(format!("{}", Bytes(3 << 29)), "1.5 GiB");
        assert_eq!(parse_meminfo("MemTotal: 10 kB\nMemAvailable:   2048 kB\n"), Some(2 << 20));
    }
}
