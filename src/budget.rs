//! Estimating a run's peak memory and work from its settings before allocating anything, so
//! that settings which would exhaust the machine are refused with one line naming the setting
//! responsible, and long runs are announced before they start.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The memory limit set with `--max-memory` in bytes; 0 means "not set".
static MEMORY_LIMIT: AtomicU64 = AtomicU64::new(0);

/// Bytes held by long-lived buffers that the system's own figures may not show yet (decoded
/// textures, see [`Held`]); they count against `--max-memory`.
static HELD: AtomicU64 = AtomicU64::new(0);

/// Bytes a mesh's triangle takes once loaded: its indices and its share of an acceleration
/// structure over it.
pub const MESH_BYTES_PER_TRIANGLE: u64 = 100;
/// Bytes a mesh's vertex takes once loaded: position, normal, texture coordinate and colour.
pub const MESH_BYTES_PER_VERTEX: u64 = 88;

/// The most worker threads `--threads` (and Python's `threads=`) accepts.
pub const MAX_THREADS: usize = 1024;

/// Checks a worker-thread count as `--threads` / `threads=` gives it: 1 to [`MAX_THREADS`].
/// `option` is how the caller spells it (`--threads`, `threads`).
pub fn check_threads(option: &str, n: usize) -> std::result::Result<usize, String> {
    if n == 0 || n > MAX_THREADS {
        return Err(format!("{option} must be between 1 and {MAX_THREADS}, got {n}"));
    }
    Ok(n)
}

/// Sets the memory limit every estimate and every file reader checks against (`--max-memory`).
/// The system's own limits still apply: the budget is the smallest of them ([`memory_budget`]).
pub fn set_memory_limit(bytes: u64) {
    MEMORY_LIMIT.store(bytes, Ordering::Relaxed);
}

/// The memory budget in bytes ([`memory_budget`]).
pub fn memory_limit() -> u64 {
    memory_budget().bytes
}

/// Which limit a [`Budget`] comes from, as a refusal names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Limit {
    /// `--max-memory` (or `set_memory_limit`).
    MaxMemory,
    /// `MemAvailable` of `/proc/meminfo`.
    MemAvailable,
    /// The soft `RLIMIT_AS`, less the address space already mapped (`VmSize`).
    AddressSpace,
    /// The soft `RLIMIT_DATA`, less the data already mapped (`VmData`).
    Data,
    /// A cgroup's limit file (`memory.max`, `memory.limit_in_bytes`), less this process's
    /// resident memory (`VmRSS`).
    Cgroup(PathBuf),
    /// None is known: a default of 8 GiB.
    Default,
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Limit::MaxMemory => write!(f, "set with --max-memory"),
            Limit::MemAvailable => write!(f, "the memory available on this machine, MemAvailable"),
            Limit::AddressSpace => {
                write!(f, "the process's address-space limit RLIMIT_AS (prlimit --as, ulimit -v) less what is mapped")
            }
            Limit::Data => {
                write!(f, "the process's data limit RLIMIT_DATA (prlimit --data, ulimit -d) less what is mapped")
            }
            Limit::Cgroup(file) => write!(f, "the cgroup limit {}", file.display()),
            Limit::Default => write!(f, "a default, as this machine's memory is not known"),
        }
    }
}

/// The memory a run may still use, and the limit that sets it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Budget {
    /// The bytes the run may still allocate.
    pub bytes: u64,
    /// Which limit sets them (named in refusals).
    pub limit: Limit,
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", Bytes(self.bytes), self.limit)
    }
}

/// The memory budget: the smallest of the limits that apply to this process, each as the
/// headroom it leaves now: `--max-memory` (less the decoded textures held), `MemAvailable`,
/// RLIMIT_AS less `VmSize`, RLIMIT_DATA less `VmData`, and the memory limit of the process's
/// cgroup and of every cgroup above it (v2 `memory.max`, v1 `memory.limit_in_bytes`) less
/// `VmRSS`. Read afresh at each call (a few small files of `/proc` and the cgroup mount).
pub fn memory_budget() -> Budget {
    let mut limits = Vec::new();
    match MEMORY_LIMIT.load(Ordering::Relaxed) {
        0 => {}
        set => limits.push(Budget { bytes: set.saturating_sub(HELD.load(Ordering::Relaxed)), limit: Limit::MaxMemory }),
    }
    limits.extend(system_limits(Path::new("/")));
    smallest(limits)
}

/// The smallest budget (the first of equals), else the 8 GiB default.
fn smallest(limits: Vec<Budget>) -> Budget {
    let mut best: Option<Budget> = None;
    for b in limits {
        if best.as_ref().is_none_or(|x| b.bytes < x.bytes) {
            best = Some(b);
        }
    }
    best.unwrap_or(Budget { bytes: 8 << 30, limit: Limit::Default })
}

/// The system's limits on this process as seen under `root` (`/`, or a fixture tree laid out
/// like it: `proc/meminfo`, `proc/self/{limits,status,cgroup,mountinfo}` and the cgroup mounts
/// the mountinfo names, below `root`). Files that are missing or unreadable add no limit.
pub fn system_limits(root: &Path) -> Vec<Budget> {
    let read = |rel: &str| std::fs::read_to_string(root.join(rel)).ok();
    let mut out = Vec::new();
    if let Some(bytes) = read("proc/meminfo").as_deref().and_then(parse_meminfo) {
        out.push(Budget { bytes, limit: Limit::MemAvailable });
    }
    let status = read("proc/self/status").unwrap_or_default();
    let used = |key: &str| status_kib(&status, key).unwrap_or(0);
    if let Some(limits) = read("proc/self/limits") {
        for (name, key, limit) in
            [("Max address space", "VmSize:", Limit::AddressSpace), ("Max data size", "VmData:", Limit::Data)]
        {
            if let Some(soft) = soft_limit(&limits, name) {
                out.push(Budget { bytes: soft.saturating_sub(used(key)), limit });
            }
        }
    }
    if let (Some(cgroup), Some(mountinfo)) = (read("proc/self/cgroup"), read("proc/self/mountinfo")) {
        let rss = used("VmRSS:");
        for (file, bytes) in cgroup_limits(root, &cgroup, &mountinfo) {
            out.push(Budget { bytes: bytes.saturating_sub(rss), limit: Limit::Cgroup(file) });
        }
    }
    out
}

/// A `VmSize:`-style line of `/proc/self/status`, in bytes.
fn status_kib(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse::<u64>().ok()?.checked_mul(1024)
}

/// The soft limit of the `/proc/self/limits` line `name` (e.g. `Max address space`), in bytes;
/// `None` when unlimited.
fn soft_limit(limits: &str, name: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with(name))?;
    line[name.len()..].split_whitespace().next()?.parse().ok()
}

/// Limits at or above this are "no limit" (cgroup v1 writes 2^63 rounded down to a page).
const UNLIMITED: u64 = 1 << 60;

/// The memory limits of the process's cgroups: for each memory hierarchy the process is in
/// (cgroup v2's `0::/path`, cgroup v1's `N:...memory...:/path` of `/proc/self/cgroup`), the
/// limit file of its cgroup and of each cgroup above it up to the mount's root, as found through
/// `/proc/self/mountinfo`; the smallest of each hierarchy, with the file that sets it. A
/// parent's limit caps all its children, so the walk up matters where the process sits in an
/// unlimited child of a limited job (Slurm's `job_N/step_M/task_K`).
pub fn cgroup_limits(root: &Path, cgroup: &str, mountinfo: &str) -> Vec<(PathBuf, u64)> {
    let mut out = Vec::new();
    for line in cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next()) else { continue };
        let (v2, file) = if id == "0" && controllers.is_empty() {
            (true, "memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            (false, "memory.limit_in_bytes")
        } else {
            continue;
        };
        let Some((mount_root, mount_point)) = cgroup_mount(mountinfo, v2) else { continue };
        // The cgroup's directory: its path relative to the mount's root, under the mount point
        // (a path outside the mount's root, as a cgroup namespace may show, is the mount point).
        let relative = path.strip_prefix(mount_root.as_str()).unwrap_or("").trim_start_matches('/');
        let top = root.join(mount_point.trim_start_matches('/'));
        let mut dir = top.join(relative);
        let mut best: Option<(PathBuf, u64)> = None;
        loop {
            let f = dir.join(file);
            if let Some(bytes) = std::fs::read_to_string(&f).ok().and_then(|t| parse_cgroup_limit(&t)) {
                if best.as_ref().is_none_or(|(_, b)| bytes < *b) {
                    best = Some((f, bytes));
                }
            }
            if dir == top || !dir.pop() || !dir.starts_with(&top) {
                break;
            }
        }
        out.extend(best);
    }
    out
}

/// `memory.max` / `memory.limit_in_bytes`: bytes, or `max` (v2) / a huge value (v1) for none.
fn parse_cgroup_limit(text: &str) -> Option<u64> {
    let bytes: u64 = text.trim().parse().ok()?;
    (bytes < UNLIMITED).then_some(bytes)
}

/// The root and mount point of the cgroup v2 (`cgroup2`) or v1 memory (`cgroup` with the
/// `memory` option) mount in `/proc/self/mountinfo` (fields: id, parent, major:minor, root,
/// mount point, options, optional fields, `-`, type, source, super options).
fn cgroup_mount(mountinfo: &str, v2: bool) -> Option<(String, String)> {
    mountinfo.lines().find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let dash = fields.iter().position(|f| *f == "-")?;
        let (kind, options) = (*fields.get(dash + 1)?, fields.get(dash + 3).copied().unwrap_or(""));
        let wanted = if v2 { kind == "cgroup2" } else { kind == "cgroup" && options.split(',').any(|o| o == "memory") };
        (wanted && dash >= 5).then(|| (unescape(fields[3]), unescape(fields[4])))
    })
}

/// mountinfo's octal escapes (`\040` for a space).
fn unescape(field: &str) -> String {
    let mut out = String::new();
    let mut rest = field;
    while let Some(i) = rest.find('\\') {
        out.push_str(&rest[..i]);
        let code = rest.get(i + 1..i + 4).and_then(|c| u8::from_str_radix(c, 8).ok());
        match code {
            Some(c) => {
                out.push(c as char);
                rest = &rest[i + 4..];
            }
            None => {
                out.push('\\');
                rest = &rest[i + 1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// Counts `bytes` of a long-lived buffer (a decoded texture) against `--max-memory` while it
/// lives; cloning counts the copy.
#[derive(Debug)]
pub struct Held(u64);

impl Held {
    /// Counts `bytes` as held until the guard is dropped.
    pub fn new(bytes: u64) -> Self {
        HELD.fetch_add(bytes, Ordering::Relaxed);
        Held(bytes)
    }
}

impl Clone for Held {
    fn clone(&self) -> Self {
        Held::new(self.0)
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        HELD.fetch_sub(self.0, Ordering::Relaxed);
    }
}

/// A vector of `len` copies of `value`, allocated fallibly: an allocation the system refuses is
/// an error naming `what` and its size, not an abort.
pub fn try_vec<T: Clone>(len: usize, value: T, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| {
        Error::Alloc(format!(
            "cannot allocate {} for {what}: the system refused the memory",
            Bytes((len as u64).saturating_mul(std::mem::size_of::<T>() as u64))
        ))
    })?;
    v.resize(len, value);
    Ok(v)
}

/// Refuses an image (or buffer) of `count x bytes_each` bytes that would not fit in the memory
/// budget, naming the setting, before anything is allocated: the check the CLI and the Python
/// module make before a render.
pub fn check_buffer(what: &str, setting: &str, count: usize, bytes_each: u64, source: &str) -> Result<()> {
    let mut e = Estimate::default();
    e.add(what, setting, count as u64, bytes_each);
    e.check_memory(&memory_budget(), source)
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

    /// Refuses the run when its estimated peak memory exceeds the budget, naming the largest
    /// part and the setting behind it, and the limit that applied.
    pub fn check_memory(&self, budget: &Budget, source: &str) -> Result<()> {
        let total = self.bytes();
        if total <= budget.bytes {
            return Ok(());
        }
        let (field, detail) = match self.largest() {
            Some(p) => (p.setting.clone(), format!("; the largest part is {} ({})", p.what, Bytes(p.bytes))),
            None => ("settings".to_string(), String::new()),
        };
        Err(Error::Memory {
            source_name: source.to_string(),
            field,
            message: format!(
                "the run would need about {} of memory, more than the limit of {budget}{detail}",
                Bytes(total)
            ),
        })
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
        let budget = Budget { bytes: 1 << 30, limit: Limit::MaxMemory };
        let err = e.check_memory(&budget, "exp.toml").unwrap_err().to_string();
        assert!(err.contains("exp.toml") && err.contains("sphere-grid count") && err.contains("--max-memory"), "{err}");
        let mut small = Estimate::default();
        small.add("retinal images", "retina_resolution = 512", 512 * 512, 12);
        small.check_memory(&budget, "exp.toml").unwrap();
        // The refusal names the limit that applied.
        let cgroup = Budget { bytes: 2 << 30, limit: Limit::Cgroup("/sys/fs/cgroup/job_7/memory.max".into()) };
        let err = e.check_memory(&cgroup, "exp.toml").unwrap_err().to_string();
        assert!(err.contains("2.0 GiB (the cgroup limit /sys/fs/cgroup/job_7/memory.max)"), "{err}");
        let rlimit = Budget { bytes: 2 << 30, limit: Limit::AddressSpace };
        assert!(e.check_memory(&rlimit, "x").unwrap_err().to_string().contains("RLIMIT_AS"));
    }

    #[test]
    fn a_refused_allocation_is_an_error_not_an_abort() {
        let e = try_vec(1usize << 60, 0u64, "the test buffer").unwrap_err().to_string();
        assert_eq!(e, "cannot allocate 8388608.0 TiB for the test buffer: the system refused the memory");
        assert_eq!(try_vec(3, 7u8, "x").unwrap(), vec![7, 7, 7]);
    }

    #[test]
    fn thread_counts_are_checked_in_one_place() {
        assert_eq!(check_threads("--threads", 1), Ok(1));
        assert_eq!(check_threads("--threads", MAX_THREADS), Ok(MAX_THREADS));
        let e = check_threads("threads", 0).unwrap_err();
        assert_eq!(e, "threads must be between 1 and 1024, got 0");
        assert!(check_threads("--threads", MAX_THREADS + 1).is_err());
    }

    /// Writes `files` (path below the root, content) into a fresh fixture tree.
    fn tree(files: &[(&str, &str)]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for (path, text) in files {
            let p = dir.path().join(path);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, text).unwrap();
        }
        dir
    }

    const LIMITS: &str = "Limit                     Soft Limit           Hard Limit           Units     \n\
        Max cpu time              unlimited            unlimited            seconds   \n\
        Max data size             unlimited            unlimited            bytes     \n\
        Max stack size            8388608              unlimited            bytes     \n\
        Max address space         8589934592           unlimited            bytes     \n";
    const STATUS: &str =
        "Name:\tinimtrace\nVmPeak:\t  300000 kB\nVmSize:\t  262144 kB\nVmRSS:\t   1024 kB\nVmData:\t  100 kB\n";

    #[test]
    fn rlimits_are_read_from_proc_self_limits_less_what_is_mapped() {
        let dir = tree(&[
            ("proc/meminfo", "MemTotal: 100000000 kB\nMemAvailable: 90000000 kB\n"),
            ("proc/self/limits", LIMITS),
            ("proc/self/status", STATUS),
        ]);
        let limits = system_limits(dir.path());
        assert_eq!(limits.len(), 2, "{limits:?}"); // MemAvailable and RLIMIT_AS; RLIMIT_DATA unlimited
        let b = smallest(limits);
        assert_eq!(b, Budget { bytes: (8 << 30) - (256 << 20), limit: Limit::AddressSpace });
        // RLIMIT_DATA less VmData, when it is the smaller.
        let data = LIMITS.replace("Max data size             unlimited", "Max data size             1048576  ");
        let dir = tree(&[("proc/self/limits", &data), ("proc/self/status", STATUS)]);
        assert_eq!(smallest(system_limits(dir.path())), Budget { bytes: (1 << 20) - 100 * 1024, limit: Limit::Data });
        // Nothing readable: the default.
        let empty = tree(&[]);
        assert_eq!(smallest(system_limits(empty.path())).limit, Limit::Default);
    }

    #[test]
    fn cgroup_v2_limits_walk_up_to_the_mount_and_max_is_no_limit() {
        let mountinfo = "24 1 0:22 / /proc rw - proc proc rw\n\
            30 24 0:26 / /sys/fs/cgroup rw,nosuid shared:4 - cgroup2 cgroup2 rw,nsdelegate\n";
        let job = "sys/fs/cgroup/system.slice/slurmstepd.scope/job_7";
        let dir = tree(&[
            ("proc/self/cgroup", "0::/system.slice/slurmstepd.scope/job_7/step_0/user/task_0\n"),
            ("proc/self/mountinfo", mountinfo),
            ("proc/self/status", STATUS),
            ("sys/fs/cgroup/system.slice/memory.max", "max\n"),
            (&format!("{job}/memory.max"), "2147483648\n"),
            (&format!("{job}/step_0/memory.max"), "max\n"),
            (&format!("{job}/step_0/user/task_0/memory.max"), "max\n"),
        ]);
        let found = cgroup_limits(
            dir.path(),
            &std::fs::read_to_string(dir.path().join("proc/self/cgroup")).unwrap(),
            mountinfo,
        );
        assert_eq!(found, vec![(dir.path().join(job).join("memory.max"), 2 << 30)]);
        // In the budget: less VmRSS, named by its file.
        let b = smallest(system_limits(dir.path()));
        assert_eq!(b.bytes, (2 << 30) - (1 << 20));
        assert!(
            b.to_string().contains(&format!("the cgroup limit {}", dir.path().join(job).join("memory.max").display())),
            "{b}"
        );
        // A smaller limit on the process's own cgroup wins over its parent's.
        std::fs::write(dir.path().join(job).join("step_0/user/task_0/memory.max"), "1073741824\n").unwrap();
        let found =
            cgroup_limits(dir.path(), "0::/system.slice/slurmstepd.scope/job_7/step_0/user/task_0\n", mountinfo);
        assert_eq!(found[0].1, 1 << 30);
        // All "max": no limit.
        let dir = tree(&[("sys/fs/cgroup/a/memory.max", "max\n")]);
        assert!(cgroup_limits(dir.path(), "0::/a\n", mountinfo).is_empty());
    }

    #[test]
    fn cgroup_v1_limits_use_the_memory_hierarchy_and_its_mount_root() {
        // Hybrid layout: v1 controllers and a v2 tree without a memory controller; the memory
        // mount's root is the container's cgroup, as inside Docker.
        let mountinfo = "31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755\n\
            32 31 0:29 / /sys/fs/cgroup/cpu rw,relatime - cgroup cgroup rw,cpu\n\
            35 31 0:32 /docker/abc /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n\
            41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw\n";
        let cgroup = "9:name=systemd:/\n4:memory:/docker/abc/ci\n1:cpu:/\n0::/\n";
        let dir = tree(&[
            ("sys/fs/cgroup/memory/memory.limit_in_bytes", "3221225472\n"),
            ("sys/fs/cgroup/memory/ci/memory.limit_in_bytes", "9223372036854771712\n"),
            ("sys/fs/cgroup/cpu/memory.limit_in_bytes", "1\n"),
        ]);
        let found = cgroup_limits(dir.path(), cgroup, mountinfo);
        assert_eq!(found, vec![(dir.path().join("sys/fs/cgroup/memory/memory.limit_in_bytes"), 3 << 30)]);
        // An unlimited v1 hierarchy: nothing.
        std::fs::write(dir.path().join("sys/fs/cgroup/memory/memory.limit_in_bytes"), "9223372036854771712\n").unwrap();
        assert!(cgroup_limits(dir.path(), cgroup, mountinfo).is_empty());
        assert_eq!(unescape("/a\\040b"), "/a b");
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
