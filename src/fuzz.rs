//! A seeded mutational fuzzer for scene files (and the OBJ/STL meshes they read): mutants of
//! the project's own scenes are run through `plyshell check` (and a sample through `plyshell
//! solve`) in subprocesses, each under a memory cap (`ulimit -v`), a `--max-memory` budget
//! and a timeout, and every outcome is classified: ok, a clean error (with or without
//! file:line:col), a panic, an abort (a signal, e.g. a failed allocation), a hang, or a
//! solve that wrote non-finite monitor values.
//!
//! Mutations (one to three per mutant): a number set to 0, −1, ±1e308, NaN, inf, 2⁶⁴−1,
//! 2³²+1, 2.5, 1e400, 1e-300, 99999, …; a `key: value` field deleted or duplicated; two
//! quoted names swapped; a name given a quote, backslash or control character; truncation;
//! byte flips and insertions; a line duplicated or deleted. A mesh file next to a scene is
//! mutated instead of the scene one time in five (numbers, truncation, byte flips).
//! Mutant k depends only on the seed and k, so a failure is reproduced by its seed and index.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Scenes small and quick enough for the sampled solves (each well under a second).
pub const SOLVE_SCENES: &[&str] = &["cantilever_end_moment.ron", "cantilever_end_shear.ron", "twisted_beam.ron", "clamped_plate.ron"];

/// SplitMix64: a small, seedable generator (no dependency).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// Values a mutated number takes.
const NUMBERS: &[&str] = &[
    "0", "0.0", "-1", "-1.0", "1e308", "-1e308", "NaN", "inf", "-inf", "18446744073709551615", "4294967297", "2.5", "1e400", "1e-300",
    "99999", "100000", "-0.0", "1e-9", "3", "1e6", "9223372036854775808",
];

/// Names a mutated quoted string takes.
const NAMES: &[&str] = &["", "a\\\"b", "a\\\\b", "a\\u{0}b", "x/y", "..", " pad ", "\\n", "ünï"];

/// Byte ranges of numeric literals in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        let after_ident = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !after_ident {
            let s = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'_') || (matches!(b[i], b'-' | b'+') && matches!(b[i - 1], b'e' | b'E'))) {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of quoted strings (with their quotes).
fn strings(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'"' {
            let s = i;
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            out.push((s, (i + 1).min(b.len())));
        }
        i += 1;
    }
    out
}

/// Byte ranges of `key: value` fields up to (and with) the comma that ends them at their
/// nesting level.
fn fields(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    for (i, _) in text.match_indices(':') {
        let mut s = i;
        while s > 0 && (b[s - 1].is_ascii_alphanumeric() || b[s - 1] == b'_') {
            s -= 1;
        }
        if s == i {
            continue;
        }
        let mut depth = 0i32;
        let mut e = i + 1;
        while e < b.len() {
            match b[e] {
                b'(' | b'[' | b'{' => depth += 1,
                b')' | b']' | b'}' => {
                    if depth == 0 {
                        break;
                    }
                    depth -= 1;
                }
                b',' if depth == 0 => {
                    e += 1;
                    break;
                }
                _ => {}
            }
            e += 1;
        }
        out.push((s, e.min(b.len())));
    }
    out
}

fn splice(bytes: &[u8], (s, e): (usize, usize), with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len() + with.len());
    out.extend_from_slice(&bytes[..s]);
    out.extend_from_slice(with);
    out.extend_from_slice(&bytes[e..]);
    out
}

/// One random mutation of scene bytes.
pub fn mutate_scene(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let pick = |v: &[(usize, usize)], rng: &mut Rng| if v.is_empty() { None } else { Some(v[rng.below(v.len())]) };
    match rng.below(12) {
        0..=3 => match pick(&numbers(&text), rng) {
            Some(r) => splice(text.as_bytes(), r, NUMBERS[rng.below(NUMBERS.len())].as_bytes()),
            None => bytes.to_vec(),
        },
        4 => match pick(&fields(&text), rng) {
            Some(r) => splice(text.as_bytes(), r, b""),
            None => bytes.to_vec(),
        },
        5 => match pick(&fields(&text), rng) {
            Some((s, e)) => {
                let mut f = text.as_bytes()[s..e].to_vec();
                if !f.ends_with(b",") {
                    f.push(b',');
                }
                splice(text.as_bytes(), (s, s), &f)
            }
            None => bytes.to_vec(),
        },
        6 => {
            let st = strings(&text);
            match (pick(&st, rng), pick(&st, rng)) {
                (Some(a), Some(b)) if a != b => {
                    let (a, b) = if a.0 < b.0 { (a, b) } else { (b, a) };
                    if a.1 > b.0 {
                        return bytes.to_vec();
                    }
                    let t = text.as_bytes();
                    let mut out = t[..a.0].to_vec();
                    out.extend_from_slice(&t[b.0..b.1]);
                    out.extend_from_slice(&t[a.1..b.0]);
                    out.extend_from_slice(&t[a.0..a.1]);
                    out.extend_from_slice(&t[b.1..]);
                    out
                }
                _ => bytes.to_vec(),
            }
        }
        7 => match pick(&strings(&text), rng) {
            Some(r) => splice(text.as_bytes(), r, format!("\"{}\"", NAMES[rng.below(NAMES.len())]).as_bytes()),
            None => bytes.to_vec(),
        },
        8 => bytes[..rng.below(bytes.len() + 1)].to_vec(),
        9 => {
            let mut out = bytes.to_vec();
            for _ in 0..1 + rng.below(4) {
                if !out.is_empty() {
                    let i = rng.below(out.len());
                    out[i] = (rng.next_u64() & 0xff) as u8;
                }
            }
            out
        }
        10 => {
            let lines: Vec<&str> = text.split_inclusive('\n').collect();
            let k = rng.below(lines.len());
            let mut out = String::new();
            let dup = rng.below(2) == 0;
            for (i, l) in lines.iter().enumerate() {
                if i != k || dup {
                    out.push_str(l);
                }
                if i == k && dup {
                    out.push_str(l);
                }
            }
            out.into_bytes()
        }
        _ => {
            const BITS: &[&str] = &["(", ")", "[", "]", "{", "}", ",", ":", "\"", "\u{feff}", "\0", "Some(", "r#\"", "/*", "//", "-", "e9"];
            let i = rng.below(bytes.len() + 1);
            splice(bytes, (i, i), BITS[rng.below(BITS.len())].as_bytes())
        }
    }
}

/// One random mutation of a mesh file (OBJ text or STL).
pub fn mutate_mesh(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    match rng.below(4) {
        0 | 1 => {
            let nums = numbers(&text);
            if nums.is_empty() {
                return bytes.to_vec();
            }
            let r = nums[rng.below(nums.len())];
            splice(text.as_bytes(), r, NUMBERS[rng.below(NUMBERS.len())].as_bytes())
        }
        2 => bytes[..rng.below(bytes.len() + 1)].to_vec(),
        _ => {
            let mut out = bytes.to_vec();
            for _ in 0..1 + rng.below(8) {
                if !out.is_empty() {
                    let i = rng.below(out.len());
                    out[i] = (rng.next_u64() & 0xff) as u8;
                }
            }
            out
        }
    }
}

/// How one run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Outcome {
    /// Exit 0.
    Ok,
    /// A clean error naming file:line:col.
    ErrorLocated,
    /// A clean error without a position (e.g. a mesh file's line, a solver failure).
    Error,
    /// A Rust panic (exit 101 or "panicked" on stderr).
    Panic,
    /// Killed by a signal other than the timeout (abort on allocation failure, segfault).
    Abort,
    /// Still running at the timeout.
    Hang,
    /// A solve that finished but wrote non-finite monitor values.
    NonFinite,
    /// A sampled solve still running (making progress) at its time limit: not a failure.
    SolveTimeout,
}

impl Outcome {
    /// Whether the outcome fails the fuzz run.
    pub fn is_failure(self) -> bool {
        matches!(self, Outcome::Panic | Outcome::Abort | Outcome::Hang | Outcome::NonFinite)
    }
}

/// Fuzz run settings.
#[derive(Clone, Debug)]
pub struct FuzzConfig {
    /// The plyshell executable.
    pub exe: PathBuf,
    /// Scene files to mutate.
    pub corpus: Vec<PathBuf>,
    /// Seed of mutant 0 (mutant k uses seed + k).
    pub seed: u64,
    /// Number of `check` mutants.
    pub count: usize,
    /// Solve every `solve_every`-th mutant of a scene in `solve_scenes` (0: never).
    pub solve_every: usize,
    /// Scenes (file names) small enough to solve.
    pub solve_scenes: Vec<String>,
    /// Timeout of a check.
    pub check_timeout: Duration,
    /// Time limit of a sampled solve.
    pub solve_timeout: Duration,
    /// Address-space cap of each subprocess (bytes, `ulimit -v`).
    pub memory_cap: u64,
    /// `--max-memory` passed to each subprocess (bytes).
    pub budget: u64,
    /// Parallel subprocesses.
    pub jobs: usize,
    /// Scratch directory (mutants, outputs; failing mutants are kept in `failures/`).
    pub work: PathBuf,
}

/// Counts by outcome and the failing mutants.
#[derive(Clone, Debug, Default)]
pub struct FuzzReport {
    /// `check` runs by outcome.
    pub check: std::collections::BTreeMap<Outcome, usize>,
    /// Sampled `solve` runs by outcome.
    pub solve: std::collections::BTreeMap<Outcome, usize>,
    /// (mutant index, command, outcome, first stderr line, saved mutant path).
    pub failures: Vec<(usize, String, Outcome, String, PathBuf)>,
    /// Wall time (s).
    pub seconds: f64,
    /// The first few distinct error lines without file:line:col, for review.
    pub unlocated: Vec<String>,
}

impl std::fmt::Display for FuzzReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let total: usize = self.check.values().sum();
        writeln!(f, "{total} check mutants, {} solves in {:.1} s", self.solve.values().sum::<usize>(), self.seconds)?;
        writeln!(f, "  check: {:?}", self.check)?;
        writeln!(f, "  solve: {:?}", self.solve)?;
        for m in &self.unlocated {
            writeln!(f, "  unlocated: {m}")?;
        }
        for (k, cmd, o, msg, path) in &self.failures {
            writeln!(f, "  FAIL mutant {k} ({cmd}): {o:?}: {msg} [{}]", path.display())?;
        }
        Ok(())
    }
}

/// Runs `args` of the executable under the memory cap; returns the outcome and stderr.
fn run_capped(cfg: &FuzzConfig, dir: &Path, args: &[&str], timeout: Duration, solve: bool) -> (Outcome, String) {
    let kb = (cfg.memory_cap / 1024).max(1);
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg(format!("ulimit -v {kb} && exec \"$0\" \"$@\"")).arg(&cfg.exe).args(args);
    cmd.arg("--max-memory").arg(cfg.budget.to_string());
    cmd.current_dir(dir).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped()).env("RUST_BACKTRACE", "0");
    // Few threads and malloc arenas, so the address-space cap measures the model, not the
    // machine's core count (64 threads × 64 MiB arenas would approach 4 GiB by themselves).
    cmd.env("RAYON_NUM_THREADS", "2").env("MALLOC_ARENA_MAX", "2");
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => return (Outcome::Abort, format!("cannot start: {e}")),
    };
    // Read stderr on a thread so a chatty child cannot block on a full pipe.
    let mut pipe = child.stderr.take();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(p) = pipe.as_mut() {
            let _ = std::io::Read::read_to_string(p, &mut s);
        }
        s
    });
    let t0 = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) if t0.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(2)),
            Err(_) => break None,
        }
    };
    let err = reader.join().unwrap_or_default();
    let outcome = match status {
        None => {
            if solve {
                Outcome::SolveTimeout
            } else {
                Outcome::Hang
            }
        }
        Some(s) if err.contains("panicked") || s.code() == Some(101) => Outcome::Panic,
        Some(s) if s.code().is_none() || err.contains("memory allocation of") => Outcome::Abort,
        Some(s) if s.success() => Outcome::Ok,
        Some(_) if err.lines().any(|l| l.starts_with("error:") && located(l)) => Outcome::ErrorLocated,
        Some(_) if err.contains("error:") => Outcome::Error,
        Some(_) => Outcome::Panic,
    };
    (outcome, err)
}

/// Whether an error line carries `file:line:col:` with line and column > 0.
fn located(line: &str) -> bool {
    let l = line.trim_start_matches("error: ");
    let mut parts = l.split(':');
    let _file = parts.next();
    let (Some(a), Some(b)) = (parts.next(), parts.next()) else { return false };
    a.trim().parse::<usize>().is_ok_and(|x| x > 0) && b.trim().parse::<usize>().is_ok_and(|x| x > 0)
}

/// Whether every monitor value of a summary.json is a finite number (serde writes NaN and
/// infinities as null).
fn finite_summary(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else { return true };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else { return false };
    let monitors = v.get("monitors").and_then(|m| m.as_array()).cloned().unwrap_or_default();
    monitors.iter().all(|m| {
        m.get("values").and_then(|x| x.as_array()).is_none_or(|rows| rows.iter().all(|r| r.as_array().is_none_or(|r| r.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)))))
    })
}

/// Runs the fuzzer.
pub fn run(cfg: &FuzzConfig) -> std::io::Result<FuzzReport> {
    let t0 = Instant::now();
    std::fs::create_dir_all(cfg.work.join("failures"))?;
    let sources: Vec<(PathBuf, Vec<u8>, Vec<(String, Vec<u8>)>)> = cfg
        .corpus
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p)?;
            // Mesh and pattern files beside the scene (read by OBJ parts, TriMesh bodies and
            // garment patterns).
            let mut meshes = Vec::new();
            if let Some(dir) = p.parent() {
                for e in std::fs::read_dir(dir)?.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if name.ends_with(".obj") || name.ends_with(".stl") || name.ends_with(".dxf") {
                        meshes.push((name, std::fs::read(e.path())?));
                    }
                }
            }
            meshes.sort();
            Ok((p.clone(), bytes, meshes))
        })
        .collect::<std::io::Result<_>>()?;
    let jobs = cfg.jobs.max(1);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let report = std::sync::Mutex::new(FuzzReport::default());
    std::thread::scope(|scope| {
        for w in 0..jobs {
            let (next, report, sources) = (&next, &report, &sources);
            scope.spawn(move || {
                let dir = cfg.work.join(format!("worker{w}"));
                let _ = std::fs::create_dir_all(&dir);
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    if k >= cfg.count {
                        break;
                    }
                    let mut rng = Rng::new(cfg.seed.wrapping_add(k as u64));
                    let (path, bytes, meshes) = &sources[rng.below(sources.len())];
                    let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                    // Fresh copies of the mesh files; one of them mutated one time in five.
                    let mutate_mesh_file = !meshes.is_empty() && rng.below(5) == 0;
                    let which = rng.below(meshes.len().max(1));
                    for (i, (name, m)) in meshes.iter().enumerate() {
                        let data = if mutate_mesh_file && i == which { mutate_mesh(m, &mut rng) } else { m.clone() };
                        let _ = std::fs::write(dir.join(name), data);
                    }
                    let mut mutant = bytes.clone();
                    if !mutate_mesh_file {
                        for _ in 0..1 + rng.below(3) {
                            mutant = mutate_scene(&mutant, &mut rng);
                        }
                    }
                    let scene = dir.join("mutant.ron");
                    if std::fs::write(&scene, &mutant).is_err() {
                        continue;
                    }
                    let (o, err) = run_capped(cfg, &dir, &["check", "mutant.ron"], cfg.check_timeout, false);
                    let mut results = vec![("check", o, err)];
                    let solve = cfg.solve_every > 0 && k % cfg.solve_every == 0 && o == Outcome::Ok && cfg.solve_scenes.contains(&file_name);
                    if solve {
                        let out = dir.join("out");
                        let _ = std::fs::remove_dir_all(&out);
                        let (mut o, err) = run_capped(cfg, &dir, &["solve", "mutant.ron", "--quiet", "--out", "out"], cfg.solve_timeout, true);
                        if matches!(o, Outcome::Ok | Outcome::Error | Outcome::ErrorLocated) && !finite_summary(&out.join("summary.json")) {
                            o = Outcome::NonFinite;
                        }
                        results.push(("solve", o, err));
                    }
                    let mut r = report.lock().unwrap_or_else(|e| e.into_inner());
                    for (cmd, o, err) in results {
                        if o == Outcome::Error && r.unlocated.len() < 30 {
                            let line: String = err.lines().find(|l| l.starts_with("error:")).unwrap_or("").chars().take(200).collect();
                            let key: String = line.chars().take(60).collect();
                            if !r.unlocated.iter().any(|u| u.starts_with(&key)) {
                                r.unlocated.push(line);
                            }
                        }
                        *(if cmd == "check" { &mut r.check } else { &mut r.solve }).entry(o).or_default() += 1;
                        if o.is_failure() {
                            let keep = cfg.work.join("failures").join(format!("mutant_{k}_{file_name}"));
                            let _ = std::fs::write(&keep, &mutant);
                            let msg = err.lines().find(|l| !l.trim().is_empty()).unwrap_or("").chars().take(300).collect();
                            r.failures.push((k, format!("{cmd} of a mutant of {}", path.display()), o, msg, keep));
                        }
                    }
                }
            });
        }
    });
    let mut r = report.into_inner().unwrap_or_else(|e| e.into_inner());
    r.failures.sort_by_key(|f| f.0);
    r.seconds = t0.elapsed().as_secs_f64();
    Ok(r)
}

/// Every `.ron` file under `dir`, sorted.
pub fn corpus(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "ron") && std::fs::read_to_string(&p).is_ok_and(|t| t.contains("Scene(")) {
                // Scenes only: the mannequin's measurement, pose and motion files are not scenes.
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutants_are_reproducible_and_differ() {
        let text = b"Scene(name: \"a\", parts: [(n: 1.5, m: [1, 2])], x: -3e2)";
        let a: Vec<Vec<u8>> = (0..50).map(|k| mutate_scene(text, &mut Rng::new(k))).collect();
        let b: Vec<Vec<u8>> = (0..50).map(|k| mutate_scene(text, &mut Rng::new(k))).collect();
        assert_eq!(a, b);
        assert!(a.iter().filter(|m| m.as_slice() != text).count() > 40);
        assert_eq!(numbers("x: -3e2, y: 1.5, z2: 4").len(), 3);
        assert!(located("error: a.ron:3:7: steps: x") && !located("error: a.ron: file: x"));
    }
}
