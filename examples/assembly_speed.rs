//! Times global assembly (element evaluation + scatter) of a scene's model at its reference
//! state, with and without the tangent: `cargo run --release --example assembly_speed -- SCENE.ron [REPEATS]`.
//! Prints seconds per assembly; the Newton solver's own split is in `summary.json`.

use std::path::Path;
use std::time::Instant;

use plyshell::assembly::Assembler;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: assembly_speed SCENE.ron [REPEATS]")?;
    let repeats: usize = match args.get(2) {
        Some(r) => r.parse().map_err(|e| format!("REPEATS: {e}"))?,
        None => 5,
    };
    let (_, built) = plyshell::scene::load(Path::new(path)).map_err(|e| e.to_string())?;
    let model = &built.model;
    let t = Instant::now();
    let asm = Assembler::new(model);
    println!("elements {}, dofs {}, nnz {}, pattern {:.3} s", model.elements.len(), model.dofs.n_free, asm.nnz(), t.elapsed().as_secs_f64());
    // A deformed state: a smooth transverse bulge with tilted directors.
    let mut state = model.initial_state();
    let du: Vec<f64> = (0..model.dofs.n_free).map(|i| 1e-5 * ((i % 17) as f64 - 8.0)).collect();
    model.update(&mut state, &du, 1.0);
    let mut f = vec![0.0; 5 * model.n_nodes()];
    let mut vals = vec![0.0; asm.nnz()];
    for with_tangent in [false, true] {
        let mut best = f64::INFINITY;
        let mut total = 0.0;
        for _ in 0..repeats {
            let t = Instant::now();
            let values = if with_tangent { Some(vals.as_mut_slice()) } else { None };
            asm.assemble(model, &state, &mut f, values).map_err(|e| format!("element {}: {}", e.element, e.failure))?;
            let s = t.elapsed().as_secs_f64();
            best = best.min(s);
            total += s;
        }
        println!("tangent {with_tangent}: best {best:.4} s, mean {:.4} s per assembly", total / repeats as f64);
    }
    let norm: f64 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
    let ksum: f64 = vals.iter().map(|v| v.abs()).sum();
    println!("checks: |f| = {norm:.12e}, sum|K| = {ksum:.12e}");
    Ok(())
}
