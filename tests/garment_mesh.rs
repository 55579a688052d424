//! Panel meshing (issue 5): quad meshes of simple polygons at a target size, with quality
//! reported, and node rows that match across a seam when possible.
//!
//! Reference: geometry. A seam row of a split (triangulated) panel facing a mapped-grid side
//! of n element edges gets n/2 boundary pieces, i.e. the same n + 1 nodes at the same
//! arc-length positions when n is even, so every slave node coincides with one master node
//! (weight 1); when n is odd the rows cannot match and the seam ties by interpolation.

use plyshell::scene;

fn garment(width: f64) -> String {
    format!(
        r#"Scene(
    name: "yoke",
    materials: {{"poplin": StVenantKirchhoff(young: 2.0e6, poisson: 0.3)}},
    parts: [],
    garment: Some((
        element_size: 0.05,
        plies: {{"shell": (material: "poplin", thickness: 0.0005)}},
        panels: [
            (name: "body", outline: [(0.0, 0.0), ({width}, 0.0), ({width}, 0.5), (0.0, 0.5)],
             edges: {{"hem": (from: 0, to: 1), "top": (from: 2, to: 3)}}, plies: ["shell"]),
            (name: "yoke", outline: [(0.0, 0.0), ({width}, 0.0), ({width}, 0.1), ({half}, 0.2), (0.0, 0.1)],
             edges: {{"bottom": (from: 0, to: 1)}}, plies: ["shell"],
             placement: Rigid(translation: (0.0, 0.5, 0.0))),
        ],
        seams: [(name: "yoke_seam", a: (panel: "body", edge: "top", reversed: true), b: (panel: "yoke", edge: "bottom"), kind: Welded)],
    )),
    node_sets: {{"hem": Edge(part: "body", edge: "hem")}},
    boundary: [Clamp(set: "hem")],
    steps: [(name: "none", increments: 1)],
)"#,
        half = 0.5 * width
    )
}

#[test]
fn seam_rows_match_a_mapped_partner_when_its_count_is_even() {
    for (width, matching) in [(0.4, true), (0.45, false)] {
        let text = garment(width);
        let sc = scene::parse("yoke.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let built = scene::build(&sc, "yoke.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let seam = &built.seams[0];
        let singles = seam.weights.iter().filter(|w| w.len() == 1).count();
        println!(
            "width {width}: master {} nodes, slave {} nodes, {singles} slave nodes on a master node; quality {:?}",
            seam.master.len(),
            seam.slave.len(),
            built.quality
        );
        let gap = seam.gaps(|n| built.model.x0[n]).into_iter().fold(0.0, f64::max);
        assert!(gap < 1e-12, "the placed spans coincide: {gap}");
        if matching {
            assert_eq!(seam.master.len(), seam.slave.len());
            assert_eq!(singles, seam.slave.len());
        } else {
            assert_ne!(seam.master.len(), seam.slave.len());
            assert!(singles < seam.slave.len());
        }
        for (name, q) in &built.quality {
            assert!(q.min_angle_deg > 20.0 && q.max_angle_deg < 160.0 && q.min_jacobian_ratio > 0.0, "{name}: {q:?}");
        }
    }
}
