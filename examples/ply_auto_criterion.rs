//! The `ply_model: Auto` criterion alone (`garment::ply_auto`): solves the laminated first
//! pass of an Auto scene (or reads its state from STATE.json, written on the first call) and
//! prints the slip and peel demand per panel and interface as JSON, without the discrete
//! second solve.
//!
//! `cargo run --release --example ply_auto_criterion -- SCENE.ron STATE.json`
//! (gravity (0, 0, −9.81), the garment's inter-ply friction).

type NodeState = ([f64; 3], [f64; 3], [f64; 3], [f64; 3]);

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(file), Some(state_file)) = (args.get(1), args.get(2)) else { return Err("usage: ply_auto_criterion SCENE.ron STATE.json".into()) };
    let text = std::fs::read_to_string(file).map_err(|e| format!("{file}: {e}"))?;
    let sc = plyshell::scene::parse(file, &text).map_err(|e| e.to_string())?;
    let g = sc.garment.as_ref().ok_or("the scene has no garment")?;
    let friction = if g.interply.enabled { g.interply.friction } else { 0.0 };
    let (spec, _) = plyshell::garment::laminate::resolve_auto(g, &[]);
    let mut first = sc.clone();
    first.garment = Some(spec.clone());
    let built = plyshell::scene::build(&first, file, &text).map_err(|e| e.to_string())?;
    let mut state = built.model.initial_state();
    match std::fs::read_to_string(state_file) {
        Ok(s) => {
            let v: Vec<NodeState> = serde_json::from_str(&s).map_err(|e| e.to_string())?;
            for (n, (u, d, t1, t2)) in v.into_iter().enumerate() {
                state.u[n] = u.into();
                state.frames[n].d = d.into();
                state.frames[n].t1 = t1.into();
                state.frames[n].t2 = t2.into();
            }
        }
        Err(_) => {
            let t = std::time::Instant::now();
            let s = plyshell::analysis::run(&first, &built, &Default::default(), &mut |_| {}).map_err(|e| e.to_string())?;
            eprintln!("laminated first pass: {} Newton iterations, {:.1} s", s.newton_iterations, t.elapsed().as_secs_f64());
            state = s.final_state.ok_or("no final state")?;
            let v: Vec<NodeState> = (0..state.u.len()).map(|n| (state.u[n].into(), state.frames[n].d.into(), state.frames[n].t1.into(), state.frames[n].t2.into())).collect();
            std::fs::write(state_file, serde_json::to_string(&v).map_err(|e| e.to_string())?).map_err(|e| e.to_string())?;
        }
    }
    let layout = built.garment.as_ref().ok_or("no garment layout")?;
    let d = plyshell::garment::ply_auto::evaluate(&spec, &built.model, &state, layout, &built.seams, nalgebra::Vector3::new(0.0, 0.0, -9.81), friction)?;
    println!("{}", serde_json::to_string_pretty(&d).map_err(|e| e.to_string())?);
    Ok(())
}
