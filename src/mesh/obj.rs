//! Wavefront OBJ import and export of quad shell meshes.
//!
//! Only `v` (vertex) and `f` (face) records are used; `vt`, `vn`, `g`, `o`,
//! `s`, `usemtl`, `mtllib`, `l` and other records, comments (`#`) and blank
//! lines are ignored. Faces must be quads.

use super::{MeshError, ShellMesh, quad_normal};
use nalgebra::Vector3;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

fn parse_err(line: usize, message: impl Into<String>) -> MeshError {
    MeshError::Parse {
        line,
        message: message.into(),
    }
}

/// One `f` record after syntax checks: 0-based vertex indices (positive OBJ
/// indices not yet range-checked) and its line number.
struct Face {
    line: usize,
    v: [usize; 4],
}

/// Parses one face vertex token (`a`, `a/t`, `a//n`, `a/t/n`) into a 0-based
/// index. `seen` is the number of vertices defined before this line
/// (negative indices count back from it).
fn face_index(token: &str, seen: usize, line: usize) -> Result<usize, MeshError> {
    let head = token.split('/').next().unwrap_or("");
    let idx: i64 = head
        .parse()
        .map_err(|_| parse_err(line, format!("invalid vertex index \"{token}\" in face")))?;
    if idx > 0 {
        usize::try_from(idx - 1)
            .map_err(|_| parse_err(line, format!("vertex index {idx} is too large")))
    } else if idx < 0 {
        let back = idx.unsigned_abs();
        match usize::try_from(back).ok().and_then(|b| seen.checked_sub(b)) {
            Some(i) => Ok(i),
            None => Err(parse_err(
                line,
                format!(
                    "relative vertex index {idx} points before the first vertex ({seen} defined so far)"
                ),
            )),
        }
    } else {
        Err(parse_err(
            line,
            "vertex index 0 is invalid (OBJ indices start at 1)",
        ))
    }
}

/// Builds a shell mesh from Wavefront OBJ text with `v x y z` vertex lines
/// and quad `f a b c d` face lines (`a/t/n`, `a//n` forms and negative,
/// relative indices accepted).
///
/// Directors are the normalised average of the unit normals of the quads
/// around each node (quad normal = cross product of its diagonals, so the
/// faces' winding defines the positive side). The single edge
/// `"boundary"` holds, sorted ascending, all nodes on free edges (edges used
/// by one quad); it is empty for a closed surface.
///
/// Errors (with the 1-based line number where one applies): malformed
/// numbers, faces that are not quads (a triangle gives "face with 3
/// vertices: plyshell needs quads"), vertex indices out of range or zero,
/// repeated vertices in a face, vertices used by no face, edges shared by
/// more than two faces, neighbouring faces with opposite winding, no faces
/// at all, and any failure of [`ShellMesh::validate`].
pub fn from_obj(text: &str) -> Result<ShellMesh, MeshError> {
    let mut nodes: Vec<Vector3<f64>> = Vec::new();
    let mut vertex_lines: Vec<usize> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();

    for (ln0, raw) in text.lines().enumerate() {
        let line = ln0 + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut xyz = [0.0; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let tok = tokens.next().ok_or_else(|| {
                        parse_err(line, format!("vertex needs 3 coordinates, found {k}"))
                    })?;
                    let val: f64 = tok.parse().map_err(|_| {
                        parse_err(line, format!("invalid vertex coordinate \"{tok}\""))
                    })?;
                    if !val.is_finite() {
                        return Err(parse_err(
                            line,
                            format!("non-finite vertex coordinate \"{tok}\""),
                        ));
                    }
                    *c = val;
                }
                // an optional 4th (weight) component or colour values are ignored
                nodes.push(Vector3::new(xyz[0], xyz[1], xyz[2]));
                vertex_lines.push(line);
            }
            "f" => {
                let toks: Vec<&str> = tokens.collect();
                if toks.len() != 4 {
                    return Err(parse_err(
                        line,
                        format!("face with {} vertices: plyshell needs quads", toks.len()),
                    ));
                }
                let mut v = [0usize; 4];
                for (slot, tok) in v.iter_mut().zip(&toks) {
                    *slot = face_index(tok, nodes.len(), line)?;
                }
                faces.push(Face { line, v });
            }
            _ => {}
        }
    }

    if faces.is_empty() {
        return Err(MeshError::Invalid("OBJ text contains no quad faces".into()));
    }
    let n = nodes.len();
    let mut used = vec![false; n];
    for f in &faces {
        for (a, &i) in f.v.iter().enumerate() {
            if i >= n {
                return Err(parse_err(
                    f.line,
                    format!(
                        "vertex index {} out of range (the file has {n} vertices)",
                        i + 1
                    ),
                ));
            }
            if f.v[..a].contains(&i) {
                return Err(parse_err(
                    f.line,
                    format!("face uses vertex {} twice", i + 1),
                ));
            }
            used[i] = true;
        }
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(parse_err(
            vertex_lines[i],
            format!(
                "vertex {} is not used by any face (no director can be defined)",
                i + 1
            ),
        ));
    }

    // Edge topology: (lo, hi) -> faces using it, with direction lo -> hi?
    let mut edge_use: HashMap<(usize, usize), Vec<(usize, bool)>> = HashMap::new();
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (f.v[k], f.v[(k + 1) % 4]);
            let uses = edge_use.entry((a.min(b), a.max(b))).or_default();
            if uses.len() == 2 {
                return Err(parse_err(
                    f.line,
                    format!(
                        "edge {}-{} is shared by more than two faces (lines {}, {} and this one)",
                        a + 1,
                        b + 1,
                        faces[uses[0].0].line,
                        faces[uses[1].0].line
                    ),
                ));
            }
            if let Some(&(other, fwd)) = uses.first()
                && fwd == (a < b)
            {
                return Err(parse_err(
                    f.line,
                    format!(
                        "face is wound opposite to its neighbour on line {} (shared edge {}-{}); \
                             all faces must be counter-clockwise seen from the same side",
                        faces[other].line,
                        a + 1,
                        b + 1
                    ),
                ));
            }
            uses.push((fi, a < b));
        }
    }

    let mut sum = vec![Vector3::zeros(); n];
    for f in &faces {
        let x = [nodes[f.v[0]], nodes[f.v[1]], nodes[f.v[2]], nodes[f.v[3]]];
        let ne = quad_normal(&x);
        let len = ne.norm();
        if !(len > 0.0 && len.is_finite()) {
            return Err(parse_err(f.line, "degenerate face (zero area)"));
        }
        for &i in &f.v {
            sum[i] += ne / len;
        }
    }
    let mut directors = Vec::with_capacity(n);
    for (i, s) in sum.iter().enumerate() {
        let len = s.norm();
        if len <= 1e-12 {
            return Err(parse_err(
                vertex_lines[i],
                format!(
                    "the face normals around vertex {} cancel out: no director",
                    i + 1
                ),
            ));
        }
        directors.push(s / len);
    }

    let mut boundary: Vec<usize> = edge_use
        .iter()
        .filter(|(_, u)| u.len() == 1)
        .flat_map(|(&(a, b), _)| [a, b])
        .collect();
    boundary.sort_unstable();
    boundary.dedup();
    let mut edges = BTreeMap::new();
    edges.insert("boundary".to_string(), boundary);

    let mesh = ShellMesh {
        nodes,
        directors,
        quads: faces.iter().map(|f| f.v).collect(),
        edges,
    };
    mesh.validate()
        .map_err(|e| MeshError::Invalid(format!("OBJ mesh (quad k = k-th face record): {e}")))?;
    Ok(mesh)
}

/// Reads and parses an OBJ file with [`from_obj`]; read failures are
/// [`MeshError::Io`] naming the path.
pub fn read_obj(path: &Path) -> Result<ShellMesh, MeshError> {
    // The text and its parsed mesh: about four times the file's size, within the budget.
    let len = std::fs::metadata(path).map_err(|e| MeshError::Io(format!("cannot read {}: {e}", path.display())))?.len();
    crate::budget::check_alloc(&format!("reading the OBJ file {} ({len} bytes)", path.display()), len, 4).map_err(MeshError::Io)?;
    let text = std::fs::read_to_string(path)
        .map_err(|e| MeshError::Io(format!("cannot read {}: {e}", path.display())))?;
    from_obj(&text)
}

impl ShellMesh {
    /// The mesh as Wavefront OBJ text: one `v` line per node (shortest
    /// round-trip float formatting) and one `f` line per quad (1-based).
    /// Directors and edge names are not written; [`from_obj`] recomputes
    /// directors from the faces.
    pub fn to_obj(&self) -> String {
        let mut s = String::from("# plyshell quad shell mesh\n");
        for p in &self.nodes {
            s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for q in &self.quads {
            s.push_str(&format!(
                "f {} {} {} {}\n",
                q[0] + 1,
                q[1] + 1,
                q[2] + 1,
                q[3] + 1
            ));
        }
        s
    }

    /// Writes [`ShellMesh::to_obj`] to `path`; failures are [`MeshError::Io`].
    pub fn write_obj(&self, path: &Path) -> Result<(), MeshError> {
        std::fs::write(path, self.to_obj())
            .map_err(|e| MeshError::Io(format!("cannot write {}: {e}", path.display())))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{cylindrical_panel, rectangle};
    use super::*;

    const SQUARE_2X1: &str = "# two quads
o plate
v 0 0 0
v 1 0 0
v 2 0 0
v 0 1 0
v 1 1 0
v 2 1 0
vn 0 0 1
vt 0 0
s off
f 1/1/1 2/1/1 5/1/1 4/1/1
f -5//1 -4//1 -1//1 -2//1
";

    #[test]
    fn parses_slash_forms_and_negative_indices() {
        let m = from_obj(SQUARE_2X1).unwrap();
        assert_eq!(m.nodes.len(), 6);
        assert_eq!(m.quads, vec![[0, 1, 4, 3], [1, 2, 5, 4]]);
        assert!(
            m.directors
                .iter()
                .all(|d| (d - Vector3::z()).norm() < 1e-15)
        );
        assert_eq!(m.edges["boundary"], vec![0, 1, 2, 3, 4, 5]);
        m.validate().unwrap();
    }

    #[test]
    fn round_trip_rectangle_and_curved_panel() {
        let m = rectangle(3.0, 1.5, 3, 2).unwrap();
        let back = from_obj(&m.to_obj()).unwrap();
        assert_eq!(back.nodes, m.nodes);
        assert_eq!(back.quads, m.quads);
        for (a, b) in back.directors.iter().zip(&m.directors) {
            assert!((a - b).norm() < 1e-14);
        }
        // interior nodes of a 3x2 grid: 5 and 6 (0-based); all others on the boundary
        let expect: Vec<usize> = (0..12).filter(|&i| i != 5 && i != 6).collect();
        assert_eq!(back.edges["boundary"], expect);

        let c = cylindrical_panel(2.0, 1.0, -0.4, 0.4, 2, 8).unwrap();
        let back = from_obj(&c.to_obj()).unwrap();
        assert_eq!(back.nodes, c.nodes);
        assert_eq!(back.quads, c.quads);
        for (a, b) in back.directors.iter().zip(&c.directors) {
            // averaged facet normals differ from the exact radial by the chord angle
            assert!(a.dot(b) > 0.99);
        }
    }

    #[test]
    fn closed_tube_has_empty_boundary_only_at_ends() {
        let t = cylindrical_panel(1.0, 1.0, 0.0, std::f64::consts::TAU, 2, 8).unwrap();
        let back = from_obj(&t.to_obj()).unwrap();
        let mut ends = [t.edges["x0"].clone(), t.edges["x1"].clone()].concat();
        ends.sort_unstable();
        assert_eq!(back.edges["boundary"], ends);
    }

    #[test]
    fn file_round_trip() {
        let m = rectangle(1.0, 1.0, 1, 1).unwrap();
        let dir = std::env::temp_dir().join(format!("plyshell_mesh_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.obj");
        m.write_obj(&p).unwrap();
        assert_eq!(read_obj(&p).unwrap().nodes, m.nodes);
        std::fs::remove_dir_all(&dir).unwrap();
        let e = read_obj(&dir.join("missing.obj")).unwrap_err();
        assert!(matches!(e, MeshError::Io(_)), "{e}");
    }

    fn err_line(text: &str) -> (usize, String) {
        match from_obj(text) {
            Err(MeshError::Parse { line, message }) => (line, message),
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn triangle_is_rejected_with_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\n";
        let (line, msg) = err_line(text);
        assert_eq!(line, 5);
        assert_eq!(msg, "face with 3 vertices: plyshell needs quads");
        let e = from_obj(text).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("needs quads"), "{e}");
    }

    #[test]
    fn bad_indices_are_rejected_with_line() {
        let base = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
        let (line, msg) = err_line(&format!("{base}f 1 2 3 9\n"));
        assert_eq!(line, 5);
        assert!(msg.contains("9") && msg.contains("out of range"), "{msg}");
        let (line, msg) = err_line(&format!("{base}f 0 1 2 3\n"));
        assert_eq!(line, 5);
        assert!(msg.contains("index 0"), "{msg}");
        let (line, msg) = err_line(&format!("{base}f -1 -2 -3 -5\n"));
        assert_eq!(line, 5);
        assert!(msg.contains("-5"), "{msg}");
        let (line, msg) = err_line(&format!("{base}\nf 1 2 x 4\n"));
        assert_eq!(line, 6);
        assert!(msg.contains("\"x\""), "{msg}");
        let (line, msg) = err_line(&format!("{base}f 1 2 2 4\n"));
        assert_eq!(line, 5);
        assert!(msg.contains("twice"), "{msg}");
    }

    #[test]
    fn other_errors() {
        let (line, msg) = err_line("v 0 0\n");
        assert_eq!(line, 1);
        assert!(msg.contains("3 coordinates"), "{msg}");
        let (line, _) = err_line("v 0 0 nan\n");
        assert_eq!(line, 1);
        let (line, msg) = err_line("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4 1\n");
        assert_eq!(line, 5);
        assert!(msg.contains("face with 5 vertices"), "{msg}");
        // stray vertex
        let (line, msg) = err_line("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nf 1 2 3 4\n");
        assert_eq!(line, 5);
        assert!(msg.contains("not used"), "{msg}");
        // opposite winding of neighbours
        let mut text = String::from("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n");
        text.push_str("f 1 2 5 4\nf 2 5 6 3\n");
        let (line, msg) = err_line(&text);
        assert_eq!(line, 8);
        assert!(msg.contains("line 7"), "{msg}");
        // no faces
        assert!(matches!(from_obj("v 0 0 0\n"), Err(MeshError::Invalid(_))));
        assert!(matches!(from_obj(""), Err(MeshError::Invalid(_))));
        // non-convex (dart) quad fails validation
        let e = from_obj("v 0 0 0\nv 1 0 0\nv 0.2 0.2 0\nv 0 1 0\nf 1 2 3 4\n").unwrap_err();
        assert!(e.to_string().contains("non-convex"), "{e}");
    }
}
