//! Times the element kernel and global assembly.
//!
//! `cargo run --release --example assembly_speed -- --kernel [ELEMENTS] [REPEATS]`:
//! microseconds per element per tangent and per residual (force + energy) of the 4-node
//! shell as the assembler calls it (`response_into`, one tangent matrix reused; with
//! `KERNEL_BOXED=1` `response_with`, which allocates a boxed tangent per call), on one thread (thread CPU time) and on a pool of two (wall time), for St. Venant–Kirchhoff, Ciarlet neo-Hookean and fabric laminae and the
//! three-ply fabric laminate section of the NBC suit (nine thickness levels), with
//! MITC4, SRI and both MITC4+ variants, on a patch of distorted, warped, strongly deformed elements (median
//! of REPEATS passes). Prints checksums of forces, energies and tangents, so that a change
//! of the kernel can be checked to leave the results unchanged. A second table times the
//! PSD projection of the projected Newton iterations (`plyshell::assembly::psd`) on the same
//! tangents, against nalgebra's `SymmetricEigen` and V|Λ|Vᵀ (the former projection), with
//! the share of tangents the Cholesky test passes, the mean number of eigenvalues mirrored
//! and the largest difference between the two. (The patch's strongly deformed tangents have
//! eight negative eigenvalues each; those of the projected iterations of a sheet dropped
//! onto a sphere 2.6, where the projection takes 6.6 µs against nalgebra's 12.3.)
//!
//! `cargo run --release --example assembly_speed -- SCENE.ron [REPEATS]`: seconds per
//! global assembly (element evaluation + scatter) of a scene's model in a deformed state,
//! with and without the tangent, on 1 and 2 threads (median of REPEATS; wall time and the
//! process's CPU time, which a shared machine does not inflate). With `ASSEMBLY_MIXED=1` the
//! tangents carry the mixed-stress records of a nonlinear static step (each assembly
//! extrapolates the last one's records and writes its own); with `ASSEMBLY_KEEP=1` they keep
//! every element's response (the time steps of a Dynamic step to rest); with `ASSEMBLY_FLUSH=1` the
//! caches are swept between assemblies. The Newton solver's own split is in `summary.json`.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Vector3;
use plyshell::assembly::psd::{project_psd_traced, Projection};
use plyshell::assembly::Assembler;
use plyshell::cpu_time::{process_seconds, thread_seconds};
use plyshell::element::{DirectorFrame, ElementGeometry, Section, SectionRule, ShearTreatment, ShellElement};
use plyshell::material::{twist_default, Fabric, FabricProperties, LaminaPly, Laminate, NeoHookean, ShellMaterial, StVenantKirchhoff};
use rayon::prelude::*;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn minimum(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// A patch of n×n distorted, slightly warped elements with non-parallel directors, and a
/// deformed state of each (stretch, shear, bending, director tilts of ~0.1–0.4 rad).
struct Patch {
    x0: Vec<[Vector3<f64>; 4]>,
    d0: Vec<[Vector3<f64>; 4]>,
    u: Vec<[Vector3<f64>; 4]>,
    frames: Vec<[DirectorFrame; 4]>,
}

fn patch(n: usize, size: f64) -> Patch {
    let node = |i: usize, j: usize| {
        let (x, y) = (i as f64, j as f64);
        let jig = 0.15 * ((1.7 * x + 0.3 * y).sin() + (0.9 * y - 1.1 * x).cos());
        Vector3::new(size * (x + 0.3 * jig), size * (y - 0.2 * jig), size * 0.05 * (0.7 * x).sin() * (0.5 * y).cos())
    };
    let normal = |i: usize, j: usize| Vector3::new(0.04 * (i as f64).sin(), -0.03 * (j as f64).cos(), 1.0).normalize();
    let mut p = Patch { x0: Vec::new(), d0: Vec::new(), u: Vec::new(), frames: Vec::new() };
    for j in 0..n {
        for i in 0..n {
            let ids = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let x0 = ids.map(|(a, b)| node(a, b));
            let d0 = ids.map(|(a, b)| normal(a, b));
            let u = std::array::from_fn(|a| {
                let x = x0[a];
                Vector3::new(0.05 * x.y + 0.01 * x.x, -0.03 * x.x, 0.1 * x.x * x.y / size)
            });
            let frames = std::array::from_fn(|a| {
                let (s, t) = (ids[a].0 as f64, ids[a].1 as f64);
                DirectorFrame::new(d0[a], Some(Vector3::x())).tilted([0.1 + 0.02 * s, -0.15 + 0.03 * t])
            });
            p.x0.push(x0);
            p.d0.push(d0);
            p.u.push(u);
            p.frames.push(frames);
        }
    }
    p
}

/// The three-ply laminate section of `garments/nbc_suit.ron` (`ply_model: Laminate`): the
/// ripstop outer shell, the carbon adsorbent layer and the knit liner, fabric plies of three
/// thickness points each (nine thickness levels).
fn suit_laminate() -> Result<Laminate, String> {
    let preset = |name: &str| FabricProperties::preset(name).ok_or(format!("preset {name}"));
    let mut carbon = preset("cotton_broadcloth")?;
    (carbon.warp_tensile, carbon.weft_tensile, carbon.shear, carbon.poisson) = (1500.0, 1200.0, 5.0, 0.2);
    (carbon.warp_bending, carbon.weft_bending, carbon.areal_density, carbon.thickness) = (2.0e-5, 1.6e-5, 0.25, 0.0015);
    carbon.twist_bending = twist_default(carbon.warp_bending, carbon.weft_bending, carbon.shear, carbon.thickness);
    carbon.transverse_shear = carbon.warp_tensile.max(carbon.weft_tensile);
    // Bottom (inside, ζ = −1) to top: liner, carbon layer, outer shell, as the garment stacks them.
    let plies = [("liner", preset("knit_liner")?, 0.0006), ("carbon", carbon, 0.0015), ("outer", preset("ripstop")?, 0.00035)];
    Laminate::new(
        plies
            .into_iter()
            .map(|(name, p, h)| LaminaPly { name: name.into(), material: Arc::new(Fabric::new(p)), thickness: h, areal_density: None })
            .collect(),
    )
}

fn kernel(n: usize, repeats: usize) -> Result<(), String> {
    let fabric = FabricProperties::preset("cotton_broadcloth").ok_or("preset")?;
    let h_fabric = fabric.thickness;
    let laminate = suit_laminate()?;
    let h_laminate = laminate.thickness();
    let materials: [(&str, Arc<dyn ShellMaterial>, f64, usize, f64); 4] = [
        ("SVK", Arc::new(StVenantKirchhoff::new(2.0e11, 0.3, 5.0 / 6.0)), 0.01, 2, 1.0),
        ("neo-Hookean", Arc::new(NeoHookean::new(4.0e5, 6.0e5)), 0.05, 2, 1.0),
        ("fabric", Arc::new(Fabric::new(fabric)), h_fabric, 3, 0.02),
        ("laminate", Arc::new(laminate), h_laminate, 2, 0.1),
    ];
    println!("kernel: {} elements, {repeats} passes: fastest pass (median) in µs per element; 1 thread: thread CPU time, 2 threads: wall time", n * n);
    println!("{:<12} {:<15} {:>16} {:>16} {:>16} {:>16}   checksums (Σ|f|, Σ energy, Σ|K|)", "material", "shear", "tangent 1t", "residual 1t", "tangent 2t", "residual 2t");
    // KERNEL_MATERIAL=SVK (or neo-Hookean, fabric, laminate) times one material only (for profiling).
    let only = std::env::var("KERNEL_MATERIAL").ok();
    let mut psd_rows = Vec::new();
    for (name, material, h, tp, size) in materials {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            let section = Section { thickness: h, shear, thickness_points: tp, material: material.clone() };
            let p = patch(n, size);
            let rule = SectionRule::new(&section).map_err(|e| e.to_string())?;
            let elements: Vec<ShellElement> = (0..n * n).map(|e| ShellElement { x0: p.x0[e], d0: p.d0[e], grain: None, section: &section }).collect();
            let geoms: Vec<ElementGeometry> = elements.iter().map(|el| el.geometry(&rule)).collect::<Result<_, _>>().map_err(|e| e.to_string())?;
            let mut times = [Vec::new(), Vec::new()];
            // The assembler's call: `response_into` with one tangent matrix reused element after
            // element (KERNEL_BOXED=1: `response_with`, which allocates a boxed tangent per call).
            let boxed = std::env::var_os("KERNEL_BOXED").is_some();
            let mut k = plyshell::element::ElemMat::zeros();
            for with_tangent in [true, false] {
                for pass in 0..repeats + 1 {
                    let t = thread_seconds();
                    let mut energy = 0.0;
                    for e in 0..n * n {
                        energy += if boxed {
                            elements[e].response_with(&rule, &geoms[e], &p.u[e], &p.frames[e], with_tangent).map_err(|e| e.to_string())?.energy
                        } else {
                            elements[e].response_into(&rule, &geoms[e], &p.u[e], &p.frames[e], with_tangent.then_some(&mut k)).map_err(|e| e.to_string())?.1
                        };
                    }
                    let us = (thread_seconds() - t) * 1e6 / (n * n) as f64;
                    if pass > 0 {
                        times[usize::from(!with_tangent)].push(us);
                    }
                    std::hint::black_box(energy);
                }
            }
            // Two threads: the patch split between a pool of two (wall time per element).
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().map_err(|e| e.to_string())?;
            let mut times2 = [Vec::new(), Vec::new()];
            for with_tangent in [true, false] {
                for pass in 0..repeats + 1 {
                    let t = Instant::now();
                    let energy: Result<f64, String> = pool.install(|| {
                        (0..n * n)
                            .into_par_iter()
                            .with_min_len(64)
                            .map_init(plyshell::element::ElemMat::zeros, |k, e| {
                                if boxed {
                                    elements[e].response_with(&rule, &geoms[e], &p.u[e], &p.frames[e], with_tangent).map(|o| o.energy)
                                } else {
                                    elements[e].response_into(&rule, &geoms[e], &p.u[e], &p.frames[e], with_tangent.then_some(k)).map(|o| o.1)
                                }
                                .map_err(|e| e.to_string())
                            })
                            .sum()
                    });
                    let us = t.elapsed().as_secs_f64() * 1e6 / (n * n) as f64;
                    if pass > 0 {
                        times2[usize::from(!with_tangent)].push(us);
                    }
                    std::hint::black_box(energy?);
                }
            }
            // Checksums (untimed); the residual-only path must give the same force and energy.
            let mut sums = (0.0, 0.0, 0.0);
            let mut tangents = Vec::with_capacity(n * n);
            for e in 0..n * n {
                let out = elements[e].response_with(&rule, &geoms[e], &p.u[e], &p.frames[e], true).map_err(|e| e.to_string())?;
                if let Some(k) = out.stiffness.as_deref() {
                    tangents.push(*k);
                }
                let res = elements[e].response_with(&rule, &geoms[e], &p.u[e], &p.frames[e], false).map_err(|e| e.to_string())?;
                if res.force != out.force || res.energy != out.energy {
                    println!("  element {e}: residual-only path differs from the tangent path");
                }
                sums.0 += out.force.abs().sum();
                sums.1 += out.energy;
                sums.2 += out.stiffness.as_ref().map_or(0.0, |k| k.abs().sum());
            }
            let cell = |t: &Vec<f64>| format!("{:.3} ({:.3})", minimum(t), median(t.clone()));
            println!(
                "{:<12} {:<15} {:>16} {:>16} {:>16} {:>16}   {:.15e} {:.15e} {:.15e}",
                name,
                format!("{shear:?}"),
                cell(&times[0]),
                cell(&times[1]),
                cell(&times2[0]),
                cell(&times2[1]),
                sums.0,
                sums.1,
                sums.2
            );
            psd_rows.push(format!("{name:<12} {:<15} {}", format!("{shear:?}"), psd_timing(&tangents, repeats)));
        }
    }
    println!("PSD projection of the same tangents, 1 thread (thread CPU time), fastest pass (median) in µs per element:");
    println!("{:<12} {:<15} {:>16} {:>16} {:>10} {:>10} {:>10} {:>12}", "material", "shear", "projection", "nalgebra", "Cholesky", "mirrored", "λ < −εm", "max diff");
    for row in psd_rows {
        println!("{row}");
    }
    Ok(())
}

/// Times `project_psd` and the former projection (nalgebra `SymmetricEigen`, V|Λ|Vᵀ) on
/// `tangents`; the table cells: both timings, the share of tangents passing the Cholesky
/// test and mirrored, the mean number of eigenvalues below −ε·max(diag) (the ones mirrored;
/// the cost of the projection grows with it), and the largest entry of the difference over
/// the largest entry.
fn psd_timing(tangents: &[plyshell::element::ElemMat], repeats: usize) -> String {
    let reference = |k: &plyshell::element::ElemMat| {
        let e = nalgebra::SymmetricEigen::new((k + k.transpose()) * 0.5);
        &e.eigenvectors * nalgebra::Matrix::from_diagonal(&e.eigenvalues.map(f64::abs)) * e.eigenvectors.transpose()
    };
    let mut times = [Vec::new(), Vec::new()];
    for pass in 0..repeats + 1 {
        for (which, t) in times.iter_mut().enumerate() {
            let start = thread_seconds();
            for k in tangents {
                if which == 0 {
                    std::hint::black_box(project_psd_traced(k));
                } else {
                    std::hint::black_box(reference(k));
                }
            }
            if pass > 0 {
                t.push((thread_seconds() - start) * 1e6 / tangents.len().max(1) as f64);
            }
        }
    }
    let mut ways = [0usize; 3];
    let mut diff: f64 = 0.0;
    let mut negative = 0;
    for k in tangents {
        let (p, way) = project_psd_traced(k);
        ways[way as usize] += 1;
        let sym = (k + k.transpose()) * 0.5;
        let m = sym.diagonal().max();
        negative += nalgebra::SymmetricEigen::new(sym).eigenvalues.iter().filter(|&&l| l < -plyshell::assembly::psd::PSD_TOLERANCE * m).count();
        let r = reference(k);
        diff = diff.max((p - r).abs().max() / r.abs().max());
    }
    let share = |w: Projection| format!("{:.1} %", 100.0 * ways[w as usize] as f64 / tangents.len().max(1) as f64);
    let cell = |t: &Vec<f64>| format!("{:.3} ({:.3})", minimum(t), median(t.clone()));
    let fallback = if ways[2] > 0 { format!("  ({} fell back to nalgebra)", ways[2]) } else { String::new() };
    let per = negative as f64 / tangents.len().max(1) as f64;
    format!("{:>16} {:>16} {:>10} {:>10} {:>10.1} {:>12.2e}{fallback}", cell(&times[0]), cell(&times[1]), share(Projection::Definite), share(Projection::Mirrored), per, diff)
}

fn scene(path: &str, repeats: usize) -> Result<(), String> {
    let (_, built) = plyshell::scene::load(Path::new(path)).map_err(|e| e.to_string())?;
    let model = &built.model;
    let t = Instant::now();
    let mut asm = Assembler::new(model);
    // ASSEMBLY_MIXED=1: tangents with mixed-stress records, as a nonlinear static step
    // assembles them (each extrapolates the last assembly's records and writes its own).
    asm.mixed = std::env::var_os("ASSEMBLY_MIXED").is_some();
    // ASSEMBLY_KEEP=1: tangent assemblies keep every element's response, as the time steps
    // of a Dynamic step to rest do (for a projected re-assembly of the same state).
    asm.keep_responses = std::env::var_os("ASSEMBLY_KEEP").is_some();
    let n_el = model.elements.len();
    println!(
        "elements {n_el} ({} with tied DOFs, scattered serially), dofs {}, nnz {}, pattern {:.3} s{}",
        asm.n_serial(),
        model.dofs.n_free,
        asm.nnz(),
        t.elapsed().as_secs_f64(),
        match (asm.mixed, asm.keep_responses) {
            (true, true) => ", mixed-stress records, kept responses",
            (true, false) => ", mixed-stress records",
            (false, true) => ", kept responses",
            (false, false) => "",
        }
    );
    // A deformed state: a small smooth perturbation of every free DOF; and a second one
    // 1 % further, so that successive assemblies alternate between two states (as Newton's
    // do: kept responses are not reused, mixed-stress records are extrapolated).
    let mut states = [model.initial_state(), model.initial_state()];
    let du: Vec<f64> = (0..model.dofs.n_free).map(|i| 1e-5 * ((i % 17) as f64 - 8.0)).collect();
    model.update(&mut states[0], &du, 1.0);
    model.update(&mut states[1], &du, 1.01);
    let mut f = vec![0.0; 5 * model.n_nodes()];
    let mut vals = vec![0.0; asm.nnz()];
    // ASSEMBLY_FLUSH=1: sweep 256 MB between assemblies (cold caches, as inside Newton).
    let flush = std::env::var_os("ASSEMBLY_FLUSH").is_some();
    let mut sweep = if flush { vec![0.0f64; 32 << 20] } else { Vec::new() };
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
        for with_tangent in [true, false] {
            let mut times = Vec::new();
            let mut cpu = Vec::new();
            for repeat in 0..repeats {
                let state = &states[repeat % 2];
                if flush {
                    // Evict the caches as a factorization between two assemblies does.
                    sweep.iter_mut().for_each(|v| *v += 1.0);
                    std::hint::black_box(&sweep);
                }
                let t = Instant::now();
                let c = process_seconds();
                let values = if with_tangent { Some(vals.as_mut_slice()) } else { None };
                pool.install(|| asm.assemble(model, state, &mut f, values)).map_err(|e| format!("element {}: {}", e.element, e.failure))?;
                times.push(t.elapsed().as_secs_f64());
                cpu.push(process_seconds() - c);
            }
            let (fast, s) = (minimum(&times), median(times));
            println!(
                "threads {threads}, {}: fastest {fast:.4} s, median {s:.4} s per assembly; {:.3} ({:.3}) µs per element; CPU (all threads) {:.3} ({:.3}) µs per element",
                if with_tangent { "tangent " } else { "residual" },
                fast * 1e6 / n_el as f64,
                s * 1e6 / n_el as f64,
                minimum(&cpu) * 1e6 / n_el as f64,
                median(cpu) * 1e6 / n_el as f64
            );
        }
    }
    let norm: f64 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
    let ksum: f64 = vals.iter().map(|v| v.abs()).sum();
    println!("checks: |f| = {norm:.15e}, sum|K| = {ksum:.15e}");
    Ok(())
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: assembly_speed --kernel [ELEMENTS] [REPEATS] | assembly_speed SCENE.ron [REPEATS]";
    let first = args.get(1).ok_or(usage)?;
    let number = |i: usize, default: usize| -> Result<usize, String> {
        args.get(i).map_or(Ok(default), |r| r.parse().map_err(|e| format!("argument {i}: {e}")))
    };
    if first == "--kernel" {
        let n = (number(2, 1024)? as f64).sqrt().ceil().max(1.0) as usize;
        kernel(n, number(3, 7)?)
    } else {
        scene(first, number(2, 5)?)
    }
}
