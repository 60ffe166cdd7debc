//! Fuzzing through the command line: the shipped experiment, display, scene, eye, study and sweep
//! files, randomly mutated (bytes flipped, lines dropped or repeated, numbers replaced by NaN,
//! infinities, huge, negative or sub-normal values, values swapped for other types), each run
//! through the binary with `--check` (every input loaded and validated, the memory estimate made,
//! nothing traced) or `info`. Every run must end by itself within its time limit with exit status
//! 0, 1 or 2, never a signal; a failure (1, or 2 for a usage error) is one line on stderr
//! starting `error:` (warnings and notes may precede it), never a panic. `tests/fuzz.rs` fuzzes the readers in-process; this
//! goes through `main`, the settings, the overrides and the error reporting too.
//!
//! The cases are drawn from a fixed seed, so a failure names a case that reproduces:
//! `INIMTRACE_CLI_FUZZ_CASES` (default 2,000) and `INIMTRACE_CLI_FUZZ_SEED` change them. Cases
//! run on as many workers as the machine has cores.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

fn bin() -> String {
    std::env::var("INIMTRACE_TEST_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_inimtrace").to_string())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The most a case may take (loading a mesh scene is the slowest check, well under a second).
const CASE_LIMIT: Duration = Duration::from_secs(30);

/// A small, fast, reproducible generator (xorshift64*, Vigna 2016).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values a mutation writes in place of a number or a token.
const VALUES: [&str; 24] = [
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "0.0",
    "1e400",
    "-1e20",
    "1e308",
    "1e-310",
    "5e-324",
    "18446744073709551616",
    "4294967297",
    "2.5",
    "true",
    "\"\"",
    "\"x\"",
    "[]",
    "[1, 2]",
    "{}",
    "[[1, 0], [0, 1]]",
    "-0.0",
    "1e9",
    "100000",
];

/// Replaces the `k`-th number of `text` (the digits with their sign, point and exponent).
fn replace_number(text: &str, k: usize, with: &str) -> String {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start_of_number =
            b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'_');
        if start_of_number {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'_')) {
                j += 1;
            }
            let s = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            spans.push((s, j));
            i = j;
        } else {
            i += 1;
        }
    }
    if spans.is_empty() {
        return text.to_string();
    }
    let (s, e) = spans[k % spans.len()];
    format!("{}{with}{}", &text[..s], &text[e..])
}

/// One to three random mutations of `text`.
fn mutate(text: &str, rng: &mut Rng) -> Vec<u8> {
    let mut out = text.to_string();
    for _ in 0..1 + rng.below(3) {
        let lines: Vec<&str> = out.lines().collect();
        out = match rng.below(8) {
            0..=2 => replace_number(&out, rng.below(10_000), VALUES[rng.below(VALUES.len())]),
            3 if !lines.is_empty() => {
                let k = rng.below(lines.len());
                let mut v = lines.clone();
                v.remove(k);
                v.join("\n")
            }
            4 if !lines.is_empty() => {
                let k = rng.below(lines.len());
                let mut v = lines.clone();
                v.insert(k, lines[k]);
                v.join("\n")
            }
            5 if !lines.is_empty() => {
                // A value swapped for another type (`key = VALUE`).
                let k = rng.below(lines.len());
                let mut v: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
                if let Some(eq) = v[k].find(" = ") {
                    v[k] = format!("{} = {}", &v[k][..eq], VALUES[rng.below(VALUES.len())]);
                }
                v.join("\n")
            }
            6 => {
                let mut bytes = out.into_bytes();
                if !bytes.is_empty() {
                    let k = rng.below(bytes.len());
                    bytes[k] ^= 1 << rng.below(7);
                }
                String::from_utf8_lossy(&bytes).into_owned()
            }
            _ => {
                let cut = rng.below(out.len() + 1);
                let cut = (0..=cut).rev().find(|&c| out.is_char_boundary(c)).unwrap_or(0);
                out[..cut].to_string()
            }
        };
    }
    out.into_bytes()
}

/// A family of input files and how a mutated one is run.
struct Family {
    /// The shipped files mutated, relative to the repository (copied into the case's tree).
    seeds: Vec<PathBuf>,
    /// The folder of the tree the mutated file goes in (its relative references resolve there).
    folder: &'static str,
    /// The command's words before the mutated file's path.
    args: &'static [&'static str],
}

fn files(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .map(|p| p.strip_prefix(root()).unwrap().to_path_buf())
        .collect();
    v.sort();
    v
}

fn families() -> Vec<Family> {
    vec![
        Family { seeds: files("experiments", "toml"), folder: "experiments", args: &["assess", "--check"] },
        Family {
            seeds: [files("displays", "toml"), vec![PathBuf::from("data/lensletdisplay.yaml")]].concat(),
            folder: "displays",
            args: &["info", "--display"],
        },
        Family { seeds: files("scenes", "toml"), folder: "scenes", args: &["info", "--scene"] },
        Family {
            // The user eye: its surface table as the `[eye.user]` of an experiment.
            seeds: vec![PathBuf::from("tests/data/eyes/navarro-like.toml")],
            folder: "experiments",
            args: &["assess", "--check"],
        },
        Family {
            // studies/navarro.toml fits a schematic eye's ray map for each of its 19 focuses (2 s a
            // check): its eye is fuzzed through experiments/navarro.toml and the user eye instead.
            seeds: files("studies", "toml").into_iter().filter(|p| !p.ends_with("navarro.toml")).collect(),
            folder: "studies",
            args: &["resolution", "--check"],
        },
        Family { seeds: files("sweeps", "toml"), folder: "sweeps", args: &["sweep", "--check"] },
    ]
}

/// The user eye's table inside an experiment with pinhole eyes (the user eye has no
/// accommodation), at small sizes.
fn eye_experiment(table: &str) -> String {
    let mut t = String::from(
        "name = \"user-eye\"\nscene = \"../scenes/paper.toml\"\ndisplay = \"../displays/paper.toml\"\n\
         [eye]\nmodel = \"user\"\nretina_resolution = 64\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n",
    );
    t.push_str("[eye.user]\n");
    // The table's own sub-tables and arrays of tables move under `eye.user`.
    for line in table.lines() {
        t.push_str(&line.replace("[[surfaces]]", "[[eye.user.surfaces]]"));
        t.push('\n');
    }
    t
}

/// Copies the shipped input folders into `tree` (the references between them stay relative).
fn copy_tree(tree: &Path) {
    for dir in ["experiments", "displays", "scenes", "studies", "sweeps", "data"] {
        std::fs::create_dir_all(tree.join(dir)).unwrap();
        for e in std::fs::read_dir(root().join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.is_file() {
                std::fs::copy(&p, tree.join(dir).join(p.file_name().unwrap())).unwrap();
            }
        }
    }
}

/// Runs one case: its exit status, or what was wrong.
fn run_case(tree: &Path, case: usize, fam: &Family, seed: &Path, rng: &mut Rng) -> Result<i32, String> {
    let text = std::fs::read_to_string(root().join(seed)).unwrap();
    let mut bytes = mutate(&text, rng);
    if seed.ends_with("navarro-like.toml") {
        bytes = eye_experiment(&String::from_utf8_lossy(&bytes)).into_bytes();
    }
    let ext = seed.extension().unwrap().to_str().unwrap();
    let name = format!("fuzz-{case}.{ext}");
    let path = tree.join(fam.folder).join(&name);
    std::fs::write(&path, &bytes).unwrap();
    let rel = format!("{}/{name}", fam.folder);
    let mut args = vec!["--quiet".to_string(), "--threads".into(), "1".into(), "--max-memory".into(), "2G".into()];
    args.extend(fam.args.iter().map(|a| a.to_string()));
    args.push(rel);
    let mut child = Command::new(bin())
        .args(&args)
        .current_dir(tree)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > CASE_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("hung (killed after {CASE_LIMIT:?}): inimtrace {}", args.join(" ")));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let mut stderr = String::new();
    use std::io::Read;
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    let what = || format!("inimtrace {} ({} bytes)\n{stderr}", args.join(" "), bytes.len());
    let code = status.code().ok_or_else(|| format!("killed by a signal: {}", what()))?;
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        return Err(format!("panic: {}", what()));
    }
    match code {
        0 => {}
        1 | 2 => {
            let lines: Vec<&str> = stderr.lines().collect();
            let errors = lines.iter().filter(|l| l.starts_with("error:")).count();
            let others = lines.iter().filter(|l| !l.starts_with("warning: ") && !l.starts_with("note: ")).count();
            if errors != 1 || others != 1 || !lines.last().is_some_and(|l| l.starts_with("error:")) {
                return Err(format!("a failure is not one error line: {}", what()));
            }
        }
        other => return Err(format!("exit status {other}: {}", what())),
    }
    std::fs::remove_file(&path).unwrap();
    Ok(code)
}

#[test]
fn mutated_input_files_end_cleanly_through_the_command_line() {
    let cases: usize = std::env::var("INIMTRACE_CLI_FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let seed: u64 = std::env::var("INIMTRACE_CLI_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(52);
    let dir = tempfile::tempdir().unwrap();
    copy_tree(dir.path());
    let families = families();
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    // Cases by exit status 0, 1, 2: both outcomes must occur, or the mutations test nothing.
    let outcomes = [AtomicUsize::new(0), AtomicUsize::new(0), AtomicUsize::new(0)];
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get());
    let start = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let case = next.fetch_add(1, Ordering::Relaxed);
                if case >= cases {
                    break;
                }
                // Each case has its own generator: the same case whatever the worker.
                let mut rng =
                    Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15)
                        ^ (case as u64 + 1).wrapping_mul(0xbf58_476d_1ce4_e5b9));
                rng.next();
                let fam = &families[case % families.len()];
                let file = &fam.seeds[rng.below(fam.seeds.len())];
                match run_case(dir.path(), case, fam, file, &mut rng) {
                    Ok(code) => {
                        outcomes[code as usize].fetch_add(1, Ordering::Relaxed);
                    }
                    Err(e) => {
                        failures.lock().unwrap().push(format!("case {case} (seed {seed}, {}): {e}", file.display()))
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    let [ok, refused, usage] = outcomes.map(|c| c.into_inner());
    eprintln!(
        "{cases} cases in {:.1} s on {workers} workers: {ok} valid, {refused} refused, {usage} usage errors",
        start.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{} of {cases} cases failed:\n{}", failures.len(), failures.join("\n\n"));
    assert!(ok >= cases / 20 && refused >= cases / 20, "{ok} valid and {refused} refused: the mutations test little");
}
