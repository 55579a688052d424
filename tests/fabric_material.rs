//! Fabric material on a single patch of shell elements: uniaxial tension along warp, weft
//! and bias and pure bending reproduce the input sheet stiffnesses for any in-plane grain
//! rotation.
//!
//! Reference values: the inputs themselves (warp/weft tensile stiffness, bending rigidity)
//! and, for loading at an angle θ to the warp, the orthotropic compliance transformation
//! (Jones, *Mechanics of Composite Materials*, 2nd ed., eq. 2.97):
//! 1/E_θ = c⁴/E₁ + s⁴/E₂ + (1/G₁₂ − 2ν₁₂/E₁) c²s², and for bending with a diagonal
//! rigidity matrix (no bending Poisson term) 1/B_θ = c⁴/B₁ + s⁴/B₂ + c²s²/B₆₆.

use nalgebra::{DMatrix, DVector, Vector3};
use plyshell::material::FabricProperties;
use plyshell::model::State;
use plyshell::scene;
use plyshell::solver::Solver;

const L: f64 = 0.1;

/// Builds and solves a 4×4 patch of `preset` fabric with the grain at `grain_deg` to x and
/// the given loads; returns the model's reference positions and the final state.
fn solve(grain_deg: f64, loads: &str, scales: &str) -> (Vec<Vector3<f64>>, State) {
    let g = grain_deg.to_radians();
    let text = format!(
        "Scene(name: \"fabric_patch\",
         materials: {{\"f\": Fabric((preset: Some(\"cotton_broadcloth\")))}},
         parts: [(name: \"p\", mesh: Rectangle(lx: {L}, ly: {L}, nx: 4, ny: 4), material: \"f\", thickness: 0.3e-3,
                  grain: Some(({:.17}, {:.17}, 0.0)))],
         node_sets: {{ \"a\": Nearest(point: (0.0, 0.0, 0.0)), \"b\": Nearest(point: ({L}, 0.0, 0.0)),
            \"c\": Nearest(point: (0.0, {L}, 0.0)),
            \"xmin\": Edge(part: \"p\", edge: \"xmin\"), \"xmax\": Edge(part: \"p\", edge: \"xmax\"),
            \"ymin\": Edge(part: \"p\", edge: \"ymin\"), \"ymax\": Edge(part: \"p\", edge: \"ymax\") }},
         boundary: [Fix(set: \"a\", dofs: [Ux, Uy, Uz]), Fix(set: \"b\", dofs: [Uy, Uz]), Fix(set: \"c\", dofs: [Uz])],
         loads: {{ {loads} }},
         steps: [(name: \"load\", increments: 1, scale: {{ {scales} }})],
         solver: (residual_tol: 1e-8))",
        g.cos(),
        g.sin()
    );
    let sc = scene::parse("fabric_patch.ron", &text).expect("parse");
    let built = scene::build(&sc, "fabric_patch.ron", &text).expect("build");
    let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
    let mut state = built.model.initial_state();
    solver.run(&built.steps, &mut state, &mut |_, _, _| {}, &mut |_| {}).expect("solve");
    (built.model.x0.clone(), state)
}

/// Edge loads of the uniform membrane stress N n⊗n (N/m) on the square's four edges.
fn membrane_loads(n: Vector3<f64>, nn: f64) -> (String, String) {
    let mut loads = String::new();
    for (edge, nu) in [("xmax", Vector3::x()), ("xmin", -Vector3::x()), ("ymax", Vector3::y()), ("ymin", -Vector3::y())] {
        let t = n * (nn * n.dot(&nu));
        loads += &format!("\"{edge}\": EdgeForce(set: \"{edge}\", force_per_length: ({:e}, {:e}, 0.0)), ", t.x, t.y);
    }
    (loads, "\"xmax\": 1.0, \"xmin\": 1.0, \"ymax\": 1.0, \"ymin\": 1.0".into())
}

/// Edge couples of the uniform bending moment M n⊗n (N·m/m): on an edge of outward normal
/// ν the couple per length is M (n·ν) ẑ × n.
fn bending_loads(n: Vector3<f64>, m: f64) -> (String, String) {
    let mut loads = String::new();
    for (edge, nu) in [("xmax", Vector3::x()), ("xmin", -Vector3::x()), ("ymax", Vector3::y()), ("ymin", -Vector3::y())] {
        let c = Vector3::z().cross(&n) * (m * n.dot(&nu));
        loads += &format!("\"{edge}\": EdgeMoment(set: \"{edge}\", moment_per_length: ({:e}, {:e}, 0.0)), ", c.x, c.y);
    }
    (loads, "\"xmax\": 1.0, \"xmin\": 1.0, \"ymax\": 1.0, \"ymin\": 1.0".into())
}

/// Least-squares fit of the in-plane displacement gradient ∇u (2×2) over all nodes.
fn displacement_gradient(x0: &[Vector3<f64>], st: &State) -> nalgebra::Matrix2<f64> {
    let n = x0.len();
    let mut a = DMatrix::zeros(n, 3);
    let (mut bx, mut by) = (DVector::zeros(n), DVector::zeros(n));
    for i in 0..n {
        a[(i, 0)] = 1.0;
        a[(i, 1)] = x0[i].x;
        a[(i, 2)] = x0[i].y;
        bx[i] = st.u[i].x;
        by[i] = st.u[i].y;
    }
    let svd = a.svd(true, true);
    let cx = svd.solve(&bx, 1e-14).expect("fit");
    let cy = svd.solve(&by, 1e-14).expect("fit");
    nalgebra::Matrix2::new(cx[1], cx[2], cy[1], cy[2])
}

/// Least-squares fit of w = c + ax + by + ½(k11 x² + 2 k12 xy + k22 y²); returns the
/// curvature tensor [[k11, k12], [k12, k22]].
fn curvature(x0: &[Vector3<f64>], st: &State) -> nalgebra::Matrix2<f64> {
    let n = x0.len();
    let mut a = DMatrix::zeros(n, 6);
    let mut b = DVector::zeros(n);
    for i in 0..n {
        let (x, y) = (x0[i].x, x0[i].y);
        for (k, v) in [1.0, x, y, 0.5 * x * x, x * y, 0.5 * y * y].into_iter().enumerate() {
            a[(i, k)] = v;
        }
        b[i] = st.u[i].z;
    }
    let c = a.svd(true, true).solve(&b, 1e-14).expect("fit");
    nalgebra::Matrix2::new(c[3], c[4], c[4], c[5])
}

/// Uniaxial warp, weft and bias (45°) tension on the patch with the grain at 0°, 30° and
/// 90° to the mesh: N/ε_nn equals E_θ within 1 %.
#[test]
fn uniaxial_tension_reproduces_warp_weft_bias_stiffness() {
    let p = FabricProperties::preset("cotton_broadcloth").expect("preset");
    let (e1, e2, g12, nu12) = (p.warp_tensile, p.weft_tensile, p.shear, p.poisson);
    let nn = 0.01; // N/m: strains ~1e-5, Green–Lagrange ≈ small strain to 1e-5
    for grain in [0.0f64, 30.0, 90.0] {
        for (label, theta) in [("warp", 0.0f64), ("weft", 90.0), ("bias", 45.0)] {
            let phi = (grain + theta).to_radians();
            let n = Vector3::new(phi.cos(), phi.sin(), 0.0);
            let (loads, scales) = membrane_loads(n, nn);
            let (x0, st) = solve(grain, &loads, &scales);
            let gu = displacement_gradient(&x0, &st);
            let n2 = nalgebra::Vector2::new(n.x, n.y);
            let eps = n2.dot(&(gu * n2));
            let measured = nn / eps;
            let (c, s) = (theta.to_radians().cos(), theta.to_radians().sin());
            let expected = 1.0 / (c.powi(4) / e1 + s.powi(4) / e2 + (1.0 / g12 - 2.0 * nu12 / e1) * c * c * s * s);
            let err = measured / expected - 1.0;
            println!("grain {grain:>4}° {label}: measured {measured:.6e} N/m, expected {expected:.6e}, error {:.2e}", err);
            assert!(err.abs() < 0.01, "grain {grain}° {label}: {measured} vs {expected}");
        }
    }
}

/// Pure bending along warp, weft and bias with the grain at 0°, 30° and 90°: M/κ_nn equals
/// B_θ within 1 %.
#[test]
fn pure_bending_reproduces_bending_rigidity() {
    let p = FabricProperties::preset("cotton_broadcloth").expect("preset");
    let (b1, b2, b66) = (p.warp_bending, p.weft_bending, p.twist_bending);
    for grain in [0.0f64, 30.0, 90.0] {
        for (label, theta) in [("warp", 0.0f64), ("weft", 90.0), ("bias", 45.0)] {
            let phi = (grain + theta).to_radians();
            let n = Vector3::new(phi.cos(), phi.sin(), 0.0);
            let (c, s) = (theta.to_radians().cos(), theta.to_radians().sin());
            let expected = 1.0 / (c.powi(4) / b1 + s.powi(4) / b2 + c * c * s * s / b66);
            // κL = 1e-5: the membrane energy of the non-developable (twisted) shape, of order
            // A κ⁴L⁶ against D κ²L², stays below 1e-3 of the bending energy even for the soft
            // twist (D ≈ 7e-8 N·m against A ≈ 3e3 N/m).
            let m = 1e-5 * expected / L;
            let (loads, scales) = bending_loads(n, m);
            let (x0, st) = solve(grain, &loads, &scales);
            let k = curvature(&x0, &st);
            let n2 = nalgebra::Vector2::new(n.x, n.y);
            let kappa = n2.dot(&(k * n2)).abs();
            let measured = m / kappa;
            let err = measured / expected - 1.0;
            println!("grain {grain:>4}° {label} bending: measured {measured:.6e} N·m, expected {expected:.6e}, error {:.2e}", err);
            assert!(err.abs() < 0.01, "grain {grain}° {label}: {measured} vs {expected}");
        }
    }
}
