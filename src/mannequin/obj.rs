//! Wavefront OBJ export of a posed mannequin: one object (`o`) per segment, each a whole
//! closed surface with its triangles counter-clockwise seen from outside (OBJ's convention
//! for front faces), so viewers derive outward normals.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Isometry3;

use super::Mannequin;

/// OBJ text of `m` placed by `placements` (one per segment, local → world).
pub fn obj_text(m: &Mannequin, placements: &[Isometry3<f64>], title: &str) -> String {
    let mut s = String::with_capacity(64 * m.n_triangles());
    let _ = writeln!(s, "# plyshell mannequin: {title}\n# z up, y forward, x to the body's right; metres");
    let mut base = 1usize;
    for (seg, iso) in m.segments.iter().zip(placements) {
        let _ = writeln!(s, "o {}", seg.segment.name());
        for v in &seg.surface.vertices {
            let p = iso * v;
            let _ = writeln!(s, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
        }
        for t in &seg.surface.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] as usize + base, t[1] as usize + base, t[2] as usize + base);
        }
        base += seg.surface.vertices.len();
    }
    s
}

/// Writes `m` placed by `placements` to `path` (atomically).
pub fn write_obj(path: &Path, m: &Mannequin, placements: &[Isometry3<f64>], title: &str) -> Result<(), String> {
    crate::io::atomic::write_atomic(path, obj_text(m, placements, title).as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}
