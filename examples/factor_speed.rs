//! Times the sparse Cholesky of `plyshell::solver::linear::SparseCholesky` on 5-DOF quad-grid
//! patterns: the monolithic factorization (one thread: AMD, faer supernodal LLᵀ) against the
//! split one (two threads: one level of nested dissection, the two halves on two cores and a
//! dense Schur complement, `src/solver/split_cholesky.rs`).
//!
//! `cargo run --release --example factor_speed -- [M ... | SCENE.ron ...] [--repeats R]`
//! (default M = 32 64 100 200; a trailing `x2` on M, e.g. `64x2`, takes two disconnected M×M
//! grids; a scene file takes its model's initial tangent pattern, without contact couplings,
//! with diagonally dominant values). Per size:
//! equations, factor entries, separator size, symbolic analysis (process CPU seconds), numeric
//! LLᵀ (median of R repeats: CPU seconds of the one thread, and wall), the split's halves and
//! Schur part (CPU seconds of each on its thread, the last of the fastest repeat), its critical
//! path max(halves) + Schur and wall time, the speed-ups by CPU path and by wall, the solve
//! (median wall) and the relative residual ‖Ax − b‖/‖b‖ of both. The grid matrix is the graph
//! Laplacian ⊗ K₅ + 10⁻⁴ I (K₅ couples three stiff and two soft DOFs, condition ≈ 10⁸).
//! On a machine shared with other jobs, wall times are inflated whenever a core is busy
//! elsewhere; the CPU critical path is what two free cores would give (less the join's
//! wake-up, tens of microseconds).

use std::time::Instant;

use plyshell::assembly::Pattern;
use plyshell::cpu_time::{process_seconds, thread_seconds};
use plyshell::solver::linear::SparseCholesky;



/// The scene's initial tangent pattern with diagonally dominant values (each diagonal entry
/// one more than its row's off-diagonal magnitudes).
fn scene_pattern(path: &str) -> Result<(Pattern, Vec<f64>), String> {
    let (_, built) = plyshell::scene::load(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    let p = plyshell::assembly::Assembler::new(&built.model).pattern.clone();
    let mut values = vec![0.0; p.row_idx.len()];
    let mut row_sum = vec![1.0; p.n];
    for c in 0..p.n {
        for s in p.col_ptr[c]..p.col_ptr[c + 1] {
            let r = p.row_idx[s];
            if r != c {
                values[s] = -1.0 / (1.0 + ((r * 7 + c) % 5) as f64);
                row_sum[r] -= values[s];
                row_sum[c] -= values[s];
            }
        }
    }
    for c in 0..p.n {
        for s in p.col_ptr[c]..p.col_ptr[c + 1] {
            if p.row_idx[s] == c {
                values[s] = row_sum[c];
            }
        }
    }
    Ok((p, values))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Run {
    symbolic: f64,
    numeric: f64,
    /// CPU seconds of the calling thread during the numeric factorization (the whole
    /// monolithic factorization; the split's halves run on the pool's threads).
    numeric_cpu: f64,
    solve: f64,
    residual: f64,
    nnz: usize,
    separator: Option<usize>,
    profile: Option<[f64; 3]>,
}

fn run(p: &Pattern, v: &[f64], threads: usize, repeats: usize) -> Result<Run, String> {
    let c = process_seconds();
    let mut chol = SparseCholesky::analyse(p, threads).map_err(|e| e.to_string())?;
    let symbolic = process_seconds() - c;
    let b: Vec<f64> = (0..p.n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
    let (mut numeric, mut numeric_cpu, mut solve, mut halves) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut x = b.clone();
    for r in 0..repeats {
        // A fresh matrix each time (the factorization of an unchanged one is kept).
        let vr: Vec<f64> = v.iter().map(|a| a * (1.0 + 1e-12 * r as f64)).collect();
        let (t, c) = (Instant::now(), thread_seconds());
        chol.factorize(&vr).map_err(|e| e.to_string())?;
        numeric.push(t.elapsed().as_secs_f64());
        numeric_cpu.push(thread_seconds() - c);
        halves.push(chol.split_profile());
        x.copy_from_slice(&b);
        let t = Instant::now();
        chol.solve(&mut x);
        solve.push(t.elapsed().as_secs_f64());
    }
    let vr: Vec<f64> = v.iter().map(|a| a * (1.0 + 1e-12 * (repeats - 1) as f64)).collect();
    let mut ax = vec![0.0; p.n];
    chol.multiply(&vr, &x, &mut ax);
    let res = ax.iter().zip(&b).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt() / b.iter().map(|a| a * a).sum::<f64>().sqrt();
    let profile = halves.iter().flatten().copied().min_by(|a, b| (a[0].max(a[1]) + a[2]).total_cmp(&(b[0].max(b[1]) + b[2])));
    Ok(Run { symbolic, numeric: median(numeric), numeric_cpu: median(numeric_cpu), solve: median(solve), residual: res, nnz: chol.factor_nnz(), separator: chol.separator_len(), profile })
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeats = 7;
    let mut sizes = Vec::new();
    let mut scenes = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--repeats" {
            repeats = it.next().and_then(|s| s.parse().ok()).ok_or("--repeats takes a number")?;
        } else if a.ends_with(".ron") {
            sizes.push((0, 0));
            scenes.push(a.clone());
        } else {
            let (m, copies) = a.split_once('x').map_or((a.as_str(), "1"), |(m, c)| (m, c));
            sizes.push((m.parse::<usize>().map_err(|e| format!("{a}: {e}"))?, copies.parse::<usize>().map_err(|e| format!("{a}: {e}"))?));
        }
    }
    if sizes.is_empty() {
        sizes = vec![(32, 1), (64, 1), (100, 1), (200, 1)];
    }
    rayon::ThreadPoolBuilder::new().num_threads(2).build_global().map_err(|e| e.to_string())?;
    println!("grid      equations  factor 1t   factor 2t   |Σ|  symbolic 1t  2t  | numeric 1t (CPU  wall) | 2t halves (CPU)  Schur  path   wall | speed-up path  wall | solve 1t   2t | residual 1t / 2t");
    let mut scenes = scenes.into_iter();
    for (m, copies) in sizes {
        let (p, v) = if copies == 0 { scene_pattern(&scenes.next().unwrap_or_default())? } else { plyshell::solver::split_cholesky::grid_plies(m, copies, 0, 1e-4) };
        let mono = run(&p, &v, 1, repeats)?;
        let split = run(&p, &v, 2, repeats)?;
        let [h1, h2, s] = split.profile.unwrap_or([f64::NAN; 3]);
        let path = h1.max(h2) + s;
        let name = if copies == 0 { "scene".to_string() } else { format!("{m:>4}²×{copies}") };
        println!(
            "{name:>7} {:>9} {:>10} {:>10} {:>5}  {:>6.3} {:>6.3}  | {:>8.4} {:>8.4} | {:>7.4} {:>7.4} {:>6.4} {:>6.4} {:>6.4} | {:>8.2}× {:>5.2}× | {:>6.4} {:>6.4} | {:.1e} / {:.1e}",
            p.n,
            mono.nnz,
            split.nnz,
            split.separator.map_or("-".to_string(), |s| s.to_string()),
            mono.symbolic,
            split.symbolic,
            mono.numeric_cpu,
            mono.numeric,
            h1,
            h2,
            s,
            path,
            split.numeric,
            mono.numeric_cpu / path,
            mono.numeric / split.numeric,
            mono.solve,
            split.solve,
            mono.residual,
            split.residual
        );
    }
    Ok(())
}
