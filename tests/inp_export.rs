//! CalculiX / Abaqus deck export (issue 19): the deck of the two-panel seam example runs in
//! CalculiX (Debian's `calculix-ccx`, which `.ci/run` installs) and its linear displacements
//! match plyshell's within 2 % of the largest displacement, node by node — in tension through
//! a plain seam (`*EQUATION`s), and in bending through a welded seam (merged coincident
//! nodes). Plus the deck of a three-ply garment has one section per ply and sets per panel,
//! ply and seam.
//!
//! CalculiX expands S4 shells into C3D8I bricks; plyshell uses MITC4 degenerated shells, so
//! the two agree to discretization error, not round-off.

use std::path::{Path, PathBuf};
use std::process::Command;

use plyshell::{analysis, io::inp, scene};

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("output directory");
    d
}

/// Nodal displacements (node id from 1 → [ux, uy, uz]) of the last `displacements` block of
/// a CalculiX `.dat` file.
fn ccx_displacements(dat: &str) -> Vec<(usize, [f64; 3])> {
    let mut out = Vec::new();
    for line in dat.lines() {
        if line.contains("displacements") {
            out.clear();
            continue;
        }
        let p: Vec<&str> = line.split_whitespace().collect();
        if let [n, x, y, z] = p.as_slice()
            && let (Ok(n), Ok(x), Ok(y), Ok(z)) = (n.parse::<usize>(), x.parse::<f64>(), y.parse::<f64>(), z.parse::<f64>())
        {
            out.push((n, [x, y, z]));
        }
    }
    out
}

/// Solves `text` with plyshell (one linear step), runs CalculiX on its deck, and returns the
/// largest nodal displacement difference over the largest plyshell displacement, and the
/// plyshell and CalculiX displacements of node `probe` (0-based).
fn compare(text: &str, name: &str, probe: usize) -> (f64, [f64; 3], [f64; 3]) {
    let ccx = which_ccx();
    let dir = out_dir(name);
    let sc = scene::parse(&format!("{name}.ron"), text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, &format!("{name}.ron"), text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    let mut solver = plyshell::solver::Solver::new(model, sc.solver.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut state = model.initial_state();
    solver.run(&built.steps, &mut state, &mut |_, _, _| {}, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let deck = analysis::inp_deck(&sc, &built);
    let report = inp::write_inp(&dir.join(format!("{name}.inp")), &deck).unwrap_or_else(|e| panic!("{e}"));
    println!("{name}: {report:?}");
    let t = std::time::Instant::now();
    let o = Command::new(&ccx).arg("-i").arg(name).current_dir(&dir).output().expect("ccx");
    let log = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && !log.contains("*ERROR"), "ccx failed:\n{log}\n{}", String::from_utf8_lossy(&o.stderr));
    println!("{name}: CalculiX ran in {:.2} s", t.elapsed().as_secs_f64());
    let dat = std::fs::read_to_string(dir.join(format!("{name}.dat"))).expect("ccx .dat");
    let u = ccx_displacements(&dat);
    assert_eq!(u.len(), model.n_nodes(), "CalculiX printed every node");
    let umax = state.u.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for &(n, c) in &u {
        // Merged slave nodes (welded seams) belong to no element in the deck: skip them.
        if c == [0.0; 3] && state.u[n - 1].norm() > 0.0 && deck_merged(&dir.join(format!("{name}.inp")), n) {
            continue;
        }
        let d = (nalgebra::Vector3::from(c) - state.u[n - 1]).norm();
        worst = worst.max(d / umax);
    }
    let p = state.u[probe];
    let c = u.iter().find(|x| x.0 == probe + 1).map_or([f64::NAN; 3], |x| x.1);
    (worst, [p.x, p.y, p.z], c)
}

/// Whether node `n` (1-based) appears in no element of the deck.
fn deck_merged(deck: &Path, n: usize) -> bool {
    let text = std::fs::read_to_string(deck).unwrap_or_default();
    let mut in_el = false;
    for line in text.lines() {
        if line.starts_with('*') {
            in_el = line.starts_with("*ELEMENT");
            continue;
        }
        if in_el && line.split(',').skip(1).any(|x| x.trim().parse::<usize>().ok() == Some(n)) {
            return false;
        }
    }
    true
}

fn which_ccx() -> PathBuf {
    let found = std::env::var_os("PATH").and_then(|p| std::env::split_paths(&p).map(|d| d.join("ccx")).find(|c| c.is_file()));
    found.unwrap_or_else(|| panic!("CalculiX (`ccx`) is not on PATH: install Debian's calculix-ccx (`.ci/run` does); this comparison is not skipped"))
}

fn example() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/examples/two_panel_seam.ron")).expect("two_panel_seam.ron")
}

/// Tension through a plain seam: the tip moves F L / (E A) = 1.0e-2 m (less the clamp's
/// restraint of the lateral contraction); CalculiX and plyshell agree within 2 % everywhere.
#[test]
fn plain_seam_in_tension_matches_calculix() {
    let (worst, p, c) = compare(&example(), "two_panel_seam", 87);
    println!("tension: worst |u_ccx − u| / max|u| = {worst:.3e}; tip node ux plyshell {:.6e}, CalculiX {:.6e}", p[0], c[0]);
    assert!((p[0] / 1.0e-2 - 1.0).abs() < 0.01, "tip {p:?} vs F L / (E A) = 1e-2");
    assert!(worst < 0.02, "{worst}");
}

/// Bending through a welded seam: a tip line load of 1 N/m on the 1 m cantilever (beam
/// theory P L³ / 3 E I = 0.400 m at ν = 0, 0.364 m as a plate strip at ν = 0.3); CalculiX
/// and plyshell agree within 2 % everywhere.
#[test]
fn welded_seam_in_bending_matches_calculix() {
    let text = example()
        .replace("kind: Plain", "kind: Welded")
        .replace("boundary: [Clamp(set: \"root\"), Fix(set: \"tip\", dofs: [Uz])]", "boundary: [Clamp(set: \"root\")]")
        .replace("force_per_length: (1000.0, 0.0, 0.0)", "force_per_length: (0.0, 0.0, 1.0)");
    let (worst, p, c) = compare(&text, "two_panel_seam_bending", 87);
    println!("bending: worst |u_ccx − u| / max|u| = {worst:.3e}; tip node uz plyshell {:.6e}, CalculiX {:.6e}", p[2], c[2]);
    assert!(p[2] > 0.364 && p[2] < 0.400, "{p:?}");
    assert!(worst < 0.02, "{worst}");
}

/// The NBC sleeve's deck: one shell section per ply (3), element sets per panel, node sets
/// per seam side and ply part; the stitch lines' through-thickness links are reported as not
/// exported.
#[test]
fn a_three_ply_garment_deck_has_a_section_per_ply_and_sets() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/nbc_sleeve.ron");
    let (sc, built) = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let deck = analysis::inp_deck(&sc, &built);
    let (text, report) = inp::inp_string(&deck).unwrap_or_else(|e| panic!("{e}"));
    let count = |s: &str| text.lines().filter(|l| l.starts_with(s)).count();
    assert_eq!(count("*SHELL SECTION"), 3);
    assert_eq!(count("*ELEMENT, TYPE=S4"), 3);
    assert_eq!(count("*STEP"), built.steps.len());
    for set in ["ELSET=P_sleeve_outer", "ELSET=P_sleeve_liner", "ELSET=PANEL_sleeve", "NSET=SEAM_underarm_outer_A", "NSET=SEAM_underarm_outer_B"] {
        assert!(text.contains(set), "{set} in the deck");
    }
    let elements: usize = text.split("*ELEMENT").skip(1).map(|b| b.lines().skip(1).take_while(|l| !l.starts_with('*')).count()).sum();
    assert_eq!(elements, built.model.elements.len());
    println!("{report:?}");
    assert!(report.links_dropped > 0, "the stitch lines' rigid links cannot be written as equations and are reported");
}

/// `plyshell export SCENE --inp DECK` writes the deck and says what it holds.
#[test]
fn the_export_command_writes_the_deck() {
    let dir = out_dir("inp_cli");
    let deck = dir.join("two_panel_seam.inp");
    let o = Command::new(env!("CARGO_BIN_EXE_plyshell"))
        .arg("export")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/examples/two_panel_seam.ron"))
        .arg("--inp")
        .arg(&deck)
        .output()
        .expect("plyshell export");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("110 nodes, 80 S4 elements, 2 sections, 15 equations, 1 steps"), "{said}");
    let text = std::fs::read_to_string(&deck).expect("deck written");
    assert!(text.starts_with("*HEADING") && text.trim_end().ends_with("*END STEP"));
}
