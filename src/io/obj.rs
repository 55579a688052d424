//! Wavefront OBJ export of a textured quad surface: `v` positions, `vt` texture coordinates,
//! one `g` group per named group, `f` quads with `vertex/texture` indices (1-based), as in
//! the Wavefront "Object Files (.obj)" specification (Appendix B1 of the Advanced
//! Visualizer manual).

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::atomic::write_atomic;
use super::surface::TexturedMesh;

/// The OBJ text of `mesh`; `comment` lines head the file. Group names have whitespace
/// replaced by `_` (OBJ names end at whitespace).
pub fn obj_string(mesh: &TexturedMesh, comment: &[String]) -> Result<String, String> {
    if let Some(p) = mesh.problem() {
        return Err(p);
    }
    let mut t = String::with_capacity(64 * mesh.positions.len());
    for c in comment {
        for line in c.lines() {
            let _ = writeln!(t, "# {line}");
        }
    }
    for p in &mesh.positions {
        let _ = writeln!(t, "v {} {} {}", p[0], p[1], p[2]);
    }
    for uv in &mesh.uvs {
        let _ = writeln!(t, "vt {} {}", uv[0], uv[1]);
    }
    for (name, quads) in &mesh.groups {
        let name: String = name.chars().map(|c| if c.is_whitespace() { '_' } else { c }).collect();
        let _ = writeln!(t, "g {name}");
        for q in quads {
            let [a, b, c, d] = q.map(|n| n + 1);
            let _ = writeln!(t, "f {a}/{a} {b}/{b} {c}/{c} {d}/{d}");
        }
    }
    Ok(t)
}

/// Writes `mesh` as OBJ to `path`, whole or not at all.
pub fn write_obj(path: &Path, mesh: &TexturedMesh, comment: &[String]) -> io::Result<()> {
    let text = obj_string(mesh, comment).map_err(|m| io::Error::new(io::ErrorKind::InvalidInput, format!("cannot write '{}': {m}", path.display())))?;
    write_atomic(path, text.as_bytes())
}
