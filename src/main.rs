//! Command line: `plyshell solve`, `plyshell demo`, `plyshell check`, `plyshell import`, `plyshell export`,
//! `plyshell bench`, `plyshell study`, `plyshell body`, `plyshell compare`.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use plyshell::analysis::{self, RunError, RunOptions};
use plyshell::scene::{self, Scene};
use plyshell::solver::Progress;
use plyshell::{bench, scene::BuiltScene};

/// The bundled default scene solved by `plyshell demo`: the coarse NBC coverall sewn shut
/// round the mannequin and draped to rest.
const DEMO_SCENE: &str = include_str!("../garments/nbc_suit.ron");
/// The name the bundled demo scene's messages carry; its mannequin files (measurements and
/// pose, relative to the scene) are read from the source tree's `garments/`.
const DEMO_NAME: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_suit.ron");
/// The demo writes a VTU every this many time steps (and the last).
const DEMO_OUTPUT_EVERY: usize = 10;

#[derive(Parser)]
#[command(name = "plyshell", version, about = "Nonlinear shell finite elements for layered protective garments")]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Memory budget for the model, tangent and factor (e.g. 8G, 512M); default 60 % of the
    /// available memory. Scenes estimated to need more are refused before allocating.
    #[arg(long, global = true, value_parser = plyshell::budget::parse_size)]
    max_memory: Option<u64>,
}

/// Prints a line to stdout; a closed pipe (`plyshell check S | head -1`) is not an error.
macro_rules! say {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// Prints a line to stderr, ignoring a closed stream.
macro_rules! warn {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

#[derive(Subcommand)]
enum Command {
    /// Solve a scene file and write VTU/PVD, summary.json and plots into DIR.
    Solve {
        /// Scene file (RON).
        scene: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Solve the bundled default scene: a three-ply NBC sleeve (outer shell, carbon layer,
    /// liner) with an underarm seam and quilting lines, hung under its own weight.
    Demo {
        /// Output directory.
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
    },
    /// Parse and build a scene without solving; print its sizes, mesh quality, each seam's
    /// initial gap and every part starting on, inside or near a contact body.
    Check {
        /// Scene file (RON).
        scene: PathBuf,
        /// Also write the seam and body report as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Mutational fuzzing of the scene files (developer tool): mutants of every .ron under
    /// CORPUS run through `check` (and a sample through `solve`) in capped subprocesses.
    #[command(hide = true)]
    Fuzz {
        /// Directory of scene files to mutate.
        #[arg(long, default_value = "garments")]
        corpus: PathBuf,
        /// Seed of the first mutant.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Number of check mutants.
        #[arg(long, default_value_t = 2000)]
        count: usize,
        /// Solve every N-th mutant of a small scene (0: never).
        #[arg(long, default_value_t = 50)]
        solve_every: usize,
        /// Parallel subprocesses.
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Scratch directory (failing mutants are kept in its failures/).
        #[arg(long, default_value = "target/fuzz-work")]
        work: PathBuf,
        /// Seconds before a check counts as a hang.
        #[arg(long, default_value_t = 10.0)]
        check_timeout: f64,
        /// Seconds a sampled solve may run.
        #[arg(long, default_value_t = 20.0)]
        solve_timeout: f64,
    },
    /// Export the assembled model of a scene: `--inp` writes a CalculiX / Abaqus input deck.
    Export {
        /// Scene file (RON).
        scene: PathBuf,
        /// CalculiX / Abaqus input deck to write (.inp).
        #[arg(long)]
        inp: PathBuf,
    },
    /// Import a pattern (DXF, AAMA / ASTM D6673 layers) as a scene file: one panel per piece
    /// with its outline, notch edge spans (N1-N2, …) and grain.
    Import {
        /// Pattern file (.dxf).
        pattern: PathBuf,
        /// Scene file to write (RON).
        #[arg(long)]
        out: PathBuf,
        /// Size to take from a graded file.
        #[arg(long)]
        size: Option<String>,
        /// Drawing units (mm, cm, m, in), overriding the header's $INSUNITS.
        #[arg(long, value_parser = parse_unit)]
        units: Option<plyshell::garment::LengthUnit>,
    },
    /// Generate the parametric mannequin from body measurements and write it posed as OBJ
    /// (one object per segment): the zero-angle pose, a pose file, or every pose of a motion.
    Body {
        /// Measurements file (RON, ISO 8559-1 names, metres); default: the default size.
        measurements: Option<PathBuf>,
        /// Pose file (RON): joint angles in degrees.
        #[arg(long, conflicts_with = "motion")]
        pose: Option<PathBuf>,
        /// Motion file (RON): timed pose files; one OBJ per pose.
        #[arg(long)]
        motion: Option<PathBuf>,
        /// Mesh refinement (1–8), overriding the measurements file's `resolution`.
        #[arg(long)]
        resolution: Option<u32>,
        /// Output directory.
        #[arg(long, default_value = "out/body")]
        out: PathBuf,
    },
    /// Solve a garment scene at increasing fidelity (mesh levels × laminate / Auto / discrete plies)
    /// and report each run's time and error against the finest discrete model: table, JSON
    /// and error-vs-time plot. A scene without a garment: its sized parts (SizedAnnulus,
    /// SizedRectangle) at the mesh levels.
    Study {
        /// Scene file (RON) with a garment or sized parts.
        scene: PathBuf,
        /// Output directory (study.md, study.json, study.svg; study_drape.svg where the
        /// scene measures a drape coefficient).
        #[arg(long, default_value = "out/study")]
        out: PathBuf,
        /// Element size multipliers (comma-separated); the smallest is the reference mesh.
        #[arg(long, value_delimiter = ',', default_value = "4,2,1")]
        sizes: Vec<f64>,
        /// Extra runs with `element_size: Auto((tolerance: T))` (comma-separated tolerances).
        #[arg(long, value_delimiter = ',')]
        tolerances: Vec<f64>,
        /// Only the discrete ply model (no laminate or Auto runs).
        #[arg(long)]
        discrete_only: bool,
        /// Ply models to run (comma-separated from laminate, auto, discrete; default all
        /// three); the discrete reference is always run.
        #[arg(long, value_delimiter = ',')]
        ply_models: Vec<String>,
        /// A-posteriori refinement (comma-separated tolerances T): per T and per mesh level
        /// coarser than the reference, a discrete run refined once at T (`refine`).
        #[arg(long, value_delimiter = ',')]
        refine: Vec<f64>,
        /// Also write every run's VTU/PVD and summary.json into OUT/<run>/.
        #[arg(long)]
        vtu: bool,
    },
    /// Solve several garment variants (scene files with the same movement protocol) and
    /// write a side-by-side report: per pose and seam the seam measures, per pose the strain,
    /// clearance and body pressure, force-along-seam plots, pose pictures and each variant's
    /// VTU/PVD series (compare.md, compare.json, plots/, VARIANT/).
    Compare {
        /// Scene files (RON), each with a `protocol`.
        #[arg(required = true, num_args = 2..)]
        scenes: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = "out/compare")]
        out: PathBuf,
        /// No progress lines.
        #[arg(long)]
        quiet: bool,
    },
    /// Run the verification benchmarks at several mesh sizes: table, JSON and error-vs-time plot.
    Bench {
        /// Write the records as JSON here (the plot goes beside it as .svg).
        #[arg(long, default_value = "bench.json")]
        json: PathBuf,
        /// Only the smallest meshes (a quick look).
        #[arg(long)]
        quick: bool,
        /// The solve-driving cases instead (sheet dropped onto a sphere, sagging plate): time
        /// steps, Newton iterations, line-search cuts, projected iterations, time split.
        #[arg(long)]
        drive: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    plyshell::budget::set_limit(cli.max_memory);
    let result = match cli.command {
        Command::Solve { scene, out, quiet } => scene::load(&scene).map_err(|e| e.to_string()).and_then(|(s, b)| {
            // `ply_model: Auto` rebuilds the scene for its second pass: it needs the text.
            let text = if plyshell::analysis_auto::is_auto(&s) { std::fs::read_to_string(&scene).map_err(|e| format!("{}: {e}", scene.display()))? } else { String::new() };
            solve(&s, &b, (&scene.display().to_string(), scene::strip_bom(&text)), &out, quiet)
        }),
        Command::Demo { out } => scene::parse(DEMO_NAME, DEMO_SCENE)
            // Every tenth time step of the ~160 to rest is enough to watch the sewing.
            .map(|s| Scene { output: scene::OutputSpec { every: s.output.every.max(DEMO_OUTPUT_EVERY), ..s.output.clone() }, ..s })
            .and_then(|s| scene::build(&s, DEMO_NAME, DEMO_SCENE).map(|b| (s, b)))
            .map_err(|e| e.to_string())
            .and_then(|(s, b)| solve(&s, &b, (DEMO_NAME, DEMO_SCENE), &out, false)),
        Command::Check { scene, .. } if let Some(r) = plyshell::mannequin::check_file(&scene) => r.map(|d| say!("{}: {d}", scene.display())).map_err(|e| e.to_string()),
        Command::Check { scene, json } => scene::load(&scene).map_err(|e| e.to_string()).and_then(|(s, b)| check(&scene, &s, &b, json.as_deref())),
        Command::Export { scene, inp } => scene::load(&scene).map_err(|e| e.to_string()).and_then(|(s, b)| export_inp(&s, &b, &inp)),
        Command::Import { pattern, out, size, units } => import(&pattern, &out, size.as_deref(), units),
        Command::Compare { scenes, out, quiet } => compare(&scenes, &out, quiet),
        Command::Bench { json, quick, drive } => if drive { bench::drive::run_drive(&json, quick) } else { bench::run_all(&json, quick) }.map_err(|e| e.to_string()),
        Command::Study { scene, out, sizes, tolerances, discrete_only, ply_models, refine, vtu } => (|| {
            use plyshell::garment::PlyModel;
            let named = ply_models
                .iter()
                .map(|m| match m.to_ascii_lowercase().as_str() {
                    "laminate" => Ok(PlyModel::Laminate),
                    "auto" => Ok(PlyModel::Auto),
                    "discrete" => Ok(PlyModel::Discrete),
                    other => Err(format!("--ply-models: unknown ply model \"{other}\" (expected laminate, auto or discrete)")),
                })
                .collect::<Result<Vec<_>, _>>()?;
            let ply_models = if discrete_only { vec![PlyModel::Discrete] } else if named.is_empty() { vec![PlyModel::Laminate, PlyModel::Auto, PlyModel::Discrete] } else { named };
            let options = plyshell::study::StudyOptions { sizes, tolerances, ply_models, refine, out: out.clone(), vtu };
            plyshell::study::run_study(&scene, &options, &mut |m| warn!("{m}")).map(|rows| {
                say!("{}", plyshell::study::markdown(&scene.display().to_string(), &rows));
                say!("wrote {}", ["study.md", "study.json", "study.svg"].map(|f| out.join(f).display().to_string()).join(", "));
            })
        })(),
        Command::Body { measurements, pose, motion, resolution, out } => body(measurements.as_deref(), pose.as_deref(), motion.as_deref(), resolution, &out),
        Command::Fuzz { corpus, seed, count, solve_every, jobs, work, check_timeout, solve_timeout } => {
            fuzz(corpus, seed, count, solve_every, jobs, work, check_timeout, solve_timeout)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            warn!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn fuzz(corpus: PathBuf, seed: u64, count: usize, solve_every: usize, jobs: usize, work: PathBuf, check_timeout: f64, solve_timeout: f64) -> Result<(), String> {
    use plyshell::fuzz::{self, FuzzConfig};
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let secs = |s: f64| std::time::Duration::from_secs_f64(if s.is_finite() && s > 0.0 { s.min(86_400.0) } else { 10.0 });
    let cfg = FuzzConfig {
        exe,
        corpus: fuzz::corpus(&corpus),
        seed,
        count,
        solve_every,
        solve_scenes: fuzz::SOLVE_SCENES.iter().map(|s| s.to_string()).collect(),
        check_timeout: secs(check_timeout),
        solve_timeout: secs(solve_timeout),
        memory_cap: 4 << 30,
        budget: 1 << 30,
        jobs,
        work,
    };
    if cfg.corpus.is_empty() {
        return Err(format!("no .ron files under {}", corpus.display()));
    }
    let report = fuzz::run(&cfg).map_err(|e| e.to_string())?;
    say!("{report}");
    if report.failures.is_empty() { Ok(()) } else { Err(format!("{} failing mutants", report.failures.len())) }
}

/// `plyshell body`: generates the mannequin, prints its segments and measurements (requested
/// and measured on the surfaces), and writes one OBJ per pose into `out`.
fn body(measurements: Option<&Path>, pose: Option<&Path>, motion: Option<&Path>, resolution: Option<u32>, out: &Path) -> Result<(), String> {
    use plyshell::mannequin::{self, Joint, Mannequin, Measurements, Pose, Segment};
    let mut m = match measurements {
        Some(p) => mannequin::load_measurements(p).map_err(|e| e.to_string())?,
        None => Measurements::default_size().fill(),
    };
    if let Some(r) = resolution {
        if !(1..=8).contains(&r) {
            return Err(format!("--resolution {r}: must be 1 to 8"));
        }
        m.resolution = r;
    }
    let poses: Vec<(String, Pose)> = match (pose, motion) {
        (Some(p), _) => vec![(p.file_stem().map_or("pose".into(), |s| s.to_string_lossy().into_owned()), mannequin::load_pose(p).map_err(|e| e.to_string())?)],
        (None, Some(mp)) => {
            let mo = mannequin::load_motion(mp).map_err(|e| e.to_string())?;
            mo.frames.into_iter().enumerate().map(|(k, (t, name, p))| (format!("{k:02}_{name}_t{t}"), p)).collect()
        }
        (None, None) => vec![("zero_pose".into(), Pose::default())],
    };
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {}: exists and is not a directory; name a directory for the OBJ files", out.display()));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    let body = Mannequin::new(&m);
    say!("mannequin: stature {:.3} m, {} segments, {} triangles (resolution {})", m.stature, body.segments.len(), body.n_triangles(), m.resolution);
    say!("  {:<12} {:>8} {:>9} {:>10}", "segment", "vertices", "triangles", "volume l");
    for s in &body.segments {
        say!("  {:<12} {:>8} {:>9} {:>10.3}", s.segment.name(), s.surface.vertices.len(), s.surface.triangles.len(), 1e3 * s.surface.volume());
    }
    say!("  {:<12} {:<16} {:>10} {:>10} {:>9}", "segment", "measurement", "requested", "measured", "error");
    let row = |seg: &str, name: &str, want: f64, got: f64| say!("  {seg:<12} {name:<16} {want:>10.4} {got:>10.4} {:>8.3}%", 100.0 * (got - want) / want);
    for (seg, g, measured) in body.girth_report() {
        row(seg.name(), g.name, g.requested, measured);
    }
    let rest = body.placements(&Pose::default());
    let rest = &rest;
    let zs = |s: Segment| body.segments[s.index()].surface.vertices.iter().map(move |v| (rest[s.index()] * v).z);
    let top = zs(Segment::Head).fold(f64::MIN, f64::max);
    let floor = zs(Segment::FootL).chain(zs(Segment::FootR)).fold(f64::MAX, f64::min);
    row("body", "stature", m.stature, top - floor);
    row("pelvis", "inseam", m.inseam, zs(Segment::Pelvis).fold(f64::MAX, f64::min) - floor);
    let sk = &body.skeleton;
    row("arm_l", "arm_length", m.arm_length, (sk.centre(Joint::ElbowL) - sk.centre(Joint::ShoulderL)).norm() + (sk.centre(Joint::WristL) - sk.centre(Joint::ElbowL)).norm());
    for (name, p) in &poses {
        let path = out.join(format!("{name}.obj"));
        mannequin::obj::write_obj(&path, &body, &body.placements(p), name)?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// `plyshell compare`: loads every variant first (a bad file stops before any solve), then
/// solves each and writes the report (`plyshell::compare`).
fn compare(scenes: &[PathBuf], out: &Path, quiet: bool) -> Result<(), String> {
    let variants = plyshell::compare::load_variants(scenes)?;
    let started = std::time::Instant::now();
    let mut last: Option<(String, usize, f64)> = None;
    let mut progress = |variant: &str, p: &Progress| {
        if quiet {
            return;
        }
        let now = started.elapsed().as_secs_f64();
        if last.as_ref().is_none_or(|(v, step, at)| v != variant || *step != p.step || now - at >= 10.0) {
            last = Some((variant.to_string(), p.step, now));
            let clock = p.dynamic.map(|(t, k)| format!(" time step {k} t = {t:.4} s")).unwrap_or_default();
            warn!("[{now:8.1} s] {variant}: step {} iter {} residual {:.2e}{clock}", p.step + 1, p.iteration, p.residual);
        }
    };
    let report = plyshell::compare::run(&variants, out, &mut progress)?;
    for v in &variants {
        say!("variant {}: {} → {}", v.name, v.file.display(), out.join(&v.name).display());
    }
    say!("report in {}: {}", out.display(), report.files.iter().filter(|f| !f.starts_with("plots/")).cloned().collect::<Vec<_>>().join(", "));
    say!("{} seam plots in {}", report.files.iter().filter(|f| f.starts_with("plots/")).count(), out.join("plots").display());
    Ok(())
}

/// A length unit from its symbol.
fn parse_unit(s: &str) -> Result<plyshell::garment::LengthUnit, String> {
    use plyshell::garment::LengthUnit;
    match s {
        "mm" => Ok(LengthUnit::Mm),
        "cm" => Ok(LengthUnit::Cm),
        "m" => Ok(LengthUnit::M),
        "in" => Ok(LengthUnit::In),
        _ => Err(format!("unknown unit \"{}\"; expected mm, cm, m or in", s.escape_debug())),
    }
}

fn import(pattern: &Path, out: &Path, size: Option<&str>, units: Option<plyshell::garment::LengthUnit>) -> Result<(), String> {
    let pieces = plyshell::pattern::dxf::read_dxf(pattern, size, units).map_err(|e| e.to_string())?;
    let name = pattern.file_stem().map_or("pattern".into(), |s| s.to_string_lossy().into_owned());
    let text = plyshell::pattern::scene_ron(&name, &pattern.display().to_string(), &pieces);
    plyshell::io::atomic::write_atomic(out, text.as_bytes()).map_err(|e| format!("{}: {e}", out.display()))?;
    for p in &pieces {
        say!("piece \"{}\"{}: {} outline vertices, {} notches, {} internal lines", p.name, p.size.as_ref().map(|s| format!(" (size {s})")).unwrap_or_default(), p.outline.len(), p.notches.len(), p.internal_lines.len());
    }
    say!("wrote {}", out.display());
    Ok(())
}

fn export_inp(scene: &Scene, built: &BuiltScene, path: &Path) -> Result<(), String> {
    let deck = analysis::inp_deck(scene, built);
    let r = plyshell::io::inp::write_inp(path, &deck).map_err(|e| e.to_string())?;
    say!("wrote {}: {} nodes, {} S4 elements, {} sections, {} equations, {} steps", path.display(), built.model.n_nodes(), built.model.elements.len(), built.model.sections.len(), r.equations, built.steps.len());
    if r.offsets_dropped > 0 {
        warn!("warning: {} tied DOFs close a gap (sewing) in plyshell; the deck ties the reference gap", r.offsets_dropped);
    }
    if r.links_dropped > 0 {
        warn!("warning: {} through-thickness rigid links (ply stacks, stitch lines) are not in the deck", r.links_dropped);
    }
    if r.single_tilts_free > 0 {
        warn!("warning: {} nodes with a single fixed director tilt have free rotations in the deck", r.single_tilts_free);
    }
    if r.materials_approximated > 0 {
        warn!("warning: {} sections of non-isotropic materials are written with their small-strain isotropic E and nu", r.materials_approximated);
    }
    Ok(())
}

/// `plyshell check`: the sizes and mesh quality ([`summary`]), then the seam gaps and the
/// parts near contact bodies ([`plyshell::check`]) as a table and, with `json`, as JSON. A part
/// starting inside a body under barrier contact is an error (the solve would refuse it).
fn check(scene_path: &Path, scene: &Scene, built: &BuiltScene, json: Option<&Path>) -> Result<(), String> {
    summary(scene, built);
    let report = plyshell::check::report(&scene.name, built);
    // Diagnostics point at the seam or panel in the file when its text can be read again.
    let file = scene_path.display().to_string();
    let text = std::fs::read(scene_path).ok().map(|b| String::from_utf8_lossy(&b).into_owned()).unwrap_or_default();
    let loc = scene::Locator::new(&file, &text);
    let locate = |anchor: &str, field: &str, message: &str| loc.at_name(anchor, field, message).to_string();
    let (table, diagnostics) = plyshell::check::table(&report, &locate);
    for l in &table {
        say!("{l}");
    }
    for l in &diagnostics {
        warn!("{l}");
    }
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        plyshell::io::atomic::write_atomic(path, text.as_bytes()).map_err(|e| format!("--json {}: {e}", path.display()))?;
        say!("wrote {}", path.display());
    }
    match report.errors() {
        0 => Ok(()),
        n => Err(format!("{n} part(s) start on or inside a contact body (listed above); barrier contact needs a gap")),
    }
}

/// Prints the scene's sizes, mesh quality per part and the build warnings.
fn summary(scene: &Scene, built: &BuiltScene) {
    let m = &built.model;
    say!("scene '{}': {} parts, {} nodes, {} elements, {} free DOFs", scene.name, m.parts.len(), m.n_nodes(), m.elements.len(), m.dofs.n_free);
    for (name, q) in &built.quality {
        say!(
            "  part {name}: angles {:.1}°..{:.1}°, max aspect {:.2}, min Jacobian ratio {:.3}",
            q.min_angle_deg, q.max_angle_deg, q.max_aspect_ratio, q.min_jacobian_ratio
        );
    }
    for (name, report) in &built.sized_parts {
        say!("  part {name}: {report}");
    }
    if !built.seams.is_empty() {
        say!("  {} seams, {} tied DOFs", built.seams.len(), m.dofs.ties.len());
    }
    for w in &built.warnings {
        warn!("{w}");
    }
    for w in built.contact.iter().flat_map(|c| &c.warnings) {
        warn!("warning: {w}");
    }
}

fn solve(scene: &Scene, built: &BuiltScene, source: (&str, &str), out: &Path, quiet: bool) -> Result<(), String> {
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {}: exists and is not a directory; name a directory for the results", out.display()));
    }
    summary(scene, built);
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(1000) };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {percent:>3}% {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let names: Vec<String> = built.steps.iter().map(|s| s.name.clone()).collect();
    // Without a terminal (a log file, CI) the bar is hidden: print a progress line at every
    // new step and at most every PROGRESS_EVERY seconds instead.
    const PROGRESS_EVERY: f64 = 10.0;
    let lines = !quiet && !std::io::stderr().is_terminal();
    let started = std::time::Instant::now();
    let mut last_line: Option<(usize, f64)> = None;
    let mut progress = |p: &Progress| {
        let mut msg = format!("step {} '{}' iter {} residual {:.2e}", p.step + 1, names.get(p.step).map(String::as_str).unwrap_or(""), p.iteration, p.residual);
        if let Some((t, k)) = p.dynamic {
            msg.push_str(&format!(" time step {k} t = {t:.4} s"));
        }
        if lines {
            let now = started.elapsed().as_secs_f64();
            if last_line.is_none_or(|(step, at)| step != p.step || now - at >= PROGRESS_EVERY) {
                last_line = Some((p.step, now));
                eprintln!("[{now:8.1} s] {:5.1} % {msg}", 100.0 * p.fraction);
            }
        }
        bar.set_position((p.fraction * 1000.0) as u64);
        bar.set_message(msg);
    };
    let options = RunOptions { out_dir: Some(out.to_path_buf()) };
    let result = if plyshell::analysis_auto::is_auto(scene) {
        plyshell::analysis_auto::run(scene, source.0, source.1, &options, &mut progress).map(|r| {
            for line in plyshell::analysis_auto::describe(&r) {
                say!("{line}");
            }
            r.summary
        })
    } else {
        analysis::run(scene, built, &options, &mut progress)
    };
    bar.finish_and_clear();
    match result {
        Ok(s) => {
            say!(
                "solved in {:.2} s ({} increments, {} Newton iterations; assembly {:.2} s, factorization {:.2} s, solve {:.2} s)",
                s.wall_s,
                s.increments.len(),
                s.newton_iterations,
                s.timings.assembly,
                s.timings.factorization,
                s.timings.solve
            );
            if let Some(passes) = s.extra.get("refinement").and_then(|r| r["passes"].as_array()) {
                for p in passes.iter().skip(1) {
                    say!(
                        "  refinement pass {}: {} → {} elements ({} marked, {} coarsened), grids {}, mapped static residual {:.2e}, {} time steps, {} Newton iterations",
                        p["pass"], p["elements_before"], p["elements"], p["marked"], p["coarsened"], p["grids"], p["static_residual"].as_f64().unwrap_or(f64::NAN), p["time_steps"], p["newton_iterations"]
                    );
                }
            }
            for h in &s.monitors {
                if let Some(last) = h.values.last() {
                    let vals: Vec<String> = h.quantities.iter().zip(last).map(|(q, v)| format!("{q} = {v:.6e}")).collect();
                    say!("  {} (node {}): {}", h.name, h.node, vals.join(", "));
                }
            }
            // A long series is summarised: its first and last files and the collections.
            let files = if s.files.len() > 12 {
                let series: Vec<&String> = s.files.iter().filter(|f| !f.ends_with(".vtu")).collect();
                let vtu: Vec<&String> = s.files.iter().filter(|f| f.ends_with(".vtu")).collect();
                format!(
                    "{} VTU files ({} … {}), {}",
                    vtu.len(),
                    vtu.first().map_or("", |f| f.as_str()),
                    vtu.last().map_or("", |f| f.as_str()),
                    series.iter().map(|f| f.as_str()).collect::<Vec<_>>().join(", ")
                )
            } else {
                s.files.join(", ")
            };
            say!("results in {}: {files}", out.display());
            Ok(())
        }
        Err(RunError::Solve { error, summary }) => {
            let last = summary.files.iter().find(|f| f.ends_with("_last_converged.vtu")).map_or("(not written)", String::as_str);
            Err(format!("{error}\nthe last converged state is {}; summary.json and the time series ({} files) are in {}", out.join(last).display(), summary.files.len(), out.display()))
        }
        Err(e) => Err(e.to_string()),
    }
}
