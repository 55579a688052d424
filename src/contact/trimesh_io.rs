//! Triangle meshes of rigid bodies: Wavefront OBJ and STL (ASCII and binary) readers, and
//! a check that repairs what can be repaired (degenerate and duplicate triangles,
//! inconsistent orientation, inward orientation) with warnings and rejects the rest
//! (non-manifold edges, empty meshes, non-finite coordinates) with an error naming the file.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::Vector3;

/// A raw triangle soup: vertices and 0-based triangles.
#[derive(Clone, Debug, Default)]
pub struct TriSoup {
    /// Vertex positions.
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles (vertex indices).
    pub triangles: Vec<[u32; 3]>,
}

/// Reads an OBJ or STL file (by extension; STL binary or ASCII detected from the content)
/// and checks/repairs it. Returns the mesh and the repair warnings.
pub fn read_trimesh(path: &Path) -> Result<(TriSoup, Vec<String>), String> {
    let name = path.display().to_string();
    // The bytes and the parsed triangles: a few times the file's size, within the budget.
    let len = std::fs::metadata(path).map_err(|e| format!("cannot read {name}: {e}"))?.len();
    crate::budget::check_alloc(&format!("reading the mesh file {name} ({len} bytes)"), len, 4)?;
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {name}: {e}"))?;
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let soup = match ext.as_str() {
        "obj" => parse_obj(&String::from_utf8_lossy(&bytes)).map_err(|e| format!("{name}: {e}"))?,
        "stl" => parse_stl(&bytes).map_err(|e| format!("{name}: {e}"))?,
        _ => return Err(format!("{name}: unknown triangle-mesh format \"{ext}\" (expected .obj or .stl)")),
    };
    repair(soup).map_err(|e| format!("{name}: {e}"))
}

/// Parses OBJ `v` and `f` records (polygons fan-triangulated; `v/vt/vn` and negative
/// indices accepted; other records ignored).
pub fn parse_obj(text: &str) -> Result<TriSoup, String> {
    let mut s = TriSoup::default();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|t| t.parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("line {}: bad vertex: {e}", ln + 1))?;
                if c.len() != 3 {
                    return Err(format!("line {}: a vertex needs three coordinates", ln + 1));
                }
                s.vertices.push(Vector3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let mut idx = Vec::new();
                for t in it {
                    let first = t.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| format!("line {}: bad face index \"{t}\"", ln + 1))?;
                    let n = s.vertices.len() as i64;
                    let k = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || k < 0 || k >= n {
                        return Err(format!("line {}: face index {i} out of range (1..={n})", ln + 1));
                    }
                    idx.push(k as u32);
                }
                if idx.len() < 3 {
                    return Err(format!("line {}: a face needs at least three vertices", ln + 1));
                }
                for k in 1..idx.len() - 1 {
                    s.triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(s)
}

/// Parses binary STL (80-byte header, u32 count, 50 bytes per facet) or ASCII STL
/// (`solid … facet … vertex x y z … endsolid`). Vertices are merged exactly.
pub fn parse_stl(bytes: &[u8]) -> Result<TriSoup, String> {
    let binary_len = |n: usize| 84 + 50 * n;
    let is_binary = bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        bytes.len() == binary_len(n)
    };
    let mut corners: Vec<[f64; 3]> = Vec::new();
    if is_binary {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        for f in 0..n {
            let base = 84 + 50 * f + 12;
            for v in 0..3 {
                let mut p = [0.0; 3];
                for (k, pk) in p.iter_mut().enumerate() {
                    let o = base + 12 * v + 4 * k;
                    *pk = f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64;
                }
                corners.push(p);
            }
        }
    } else {
        let text = std::str::from_utf8(bytes).map_err(|_| "neither a binary STL (size does not match the facet count) nor ASCII text".to_string())?;
        if !text.trim_start().starts_with("solid") {
            return Err("neither a binary STL (size does not match the facet count) nor an ASCII STL (no \"solid\")".into());
        }
        for (ln, line) in text.lines().enumerate() {
            let mut it = line.split_whitespace();
            if it.next() == Some("vertex") {
                let c: Vec<f64> = it.take(3).map(|t| t.parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("line {}: bad vertex: {e}", ln + 1))?;
                if c.len() != 3 {
                    return Err(format!("line {}: a vertex needs three coordinates", ln + 1));
                }
                corners.push([c[0], c[1], c[2]]);
            }
        }
        if !corners.len().is_multiple_of(3) {
            return Err(format!("{} vertices is not a whole number of facets", corners.len()));
        }
    }
    let mut s = TriSoup::default();
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut tri = [0u32; 3];
    for (i, c) in corners.iter().enumerate() {
        let key = c.map(f64::to_bits);
        let id = *index.entry(key).or_insert_with(|| {
            s.vertices.push(Vector3::new(c[0], c[1], c[2]));
            (s.vertices.len() - 1) as u32
        });
        tri[i % 3] = id;
        if i % 3 == 2 {
            s.triangles.push(tri);
        }
    }
    Ok(s)
}

/// Checks and repairs a triangle soup:
/// - non-finite coordinates, no triangles, or an edge shared by more than two triangles
///   (non-manifold) → error;
/// - triangles with repeated vertices or zero area (relative 1e-12 of the bounding box),
///   and duplicate triangles → removed, with a warning;
/// - inconsistent orientation between neighbours → fixed by propagating the orientation of
///   one triangle per connected component across shared edges, with a warning;
/// - a closed component with negative signed volume (normals inward) → flipped, with a
///   warning; open surfaces are kept (signed distance is then meaningful only near the
///   surface on its front side) with a warning.
pub fn repair(mut s: TriSoup) -> Result<(TriSoup, Vec<String>), String> {
    let mut warnings = Vec::new();
    if s.vertices.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
        return Err("a vertex coordinate is NaN or infinite".into());
    }
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for v in &s.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let diag = (hi - lo).norm();
    let before = s.triangles.len();
    let mut seen = std::collections::HashSet::new();
    s.triangles.retain(|t| {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return false;
        }
        let [a, b, c] = t.map(|i| s.vertices[i as usize]);
        if (b - a).cross(&(c - a)).norm() <= 1e-12 * diag * diag {
            return false;
        }
        let mut k = *t;
        k.sort_unstable();
        seen.insert(k)
    });
    if s.triangles.len() < before {
        warnings.push(format!("removed {} degenerate or duplicate triangle(s) of {before}", before - s.triangles.len()));
    }
    if s.triangles.is_empty() {
        return Err("no valid triangle (all missing or degenerate)".into());
    }
    // Edge → incident (triangle, whether the triangle traverses it as (min, max)).
    let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
    for (ti, t) in s.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push((ti, a < b));
        }
    }
    if let Some(((a, b), inc)) = edges.iter().find(|(_, v)| v.len() > 2) {
        return Err(format!("non-manifold edge between vertices {} and {} shared by {} triangles (cannot orient)", a + 1, b + 1, inc.len()));
    }
    let open = edges.values().filter(|v| v.len() == 1).count();
    // Orientation propagation (breadth-first per component).
    let nt = s.triangles.len();
    let mut flip = vec![false; nt];
    let mut visited = vec![false; nt];
    let mut component = vec![usize::MAX; nt];
    let mut n_comp = 0;
    let mut flipped = 0;
    let mut conflicts = 0;
    let tri_edges = |t: &[u32; 3]| -> [(u32, u32); 3] { std::array::from_fn(|k| (t[k], t[(k + 1) % 3])) };
    for seed in 0..nt {
        if visited[seed] {
            continue;
        }
        visited[seed] = true;
        component[seed] = n_comp;
        let mut queue = std::collections::VecDeque::from([seed]);
        while let Some(ti) = queue.pop_front() {
            for (a, b) in tri_edges(&s.triangles[ti]) {
                let dir_i = (a < b) != flip[ti];
                for &(tj, dir) in &edges[&(a.min(b), a.max(b))] {
                    if tj == ti {
                        continue;
                    }
                    // Consistent neighbours traverse the shared edge in opposite directions.
                    let want_flip = dir == dir_i;
                    if !visited[tj] {
                        visited[tj] = true;
                        component[tj] = n_comp;
                        flip[tj] = want_flip;
                        flipped += usize::from(want_flip);
                        queue.push_back(tj);
                    } else if (dir != flip[tj]) == dir_i {
                        conflicts += 1;
                    }
                }
            }
        }
        n_comp += 1;
    }
    if conflicts > 0 {
        return Err(format!("the surface is not orientable ({conflicts} edge conflicts after propagating the orientation, e.g. a Möbius band)"));
    }
    if flipped > 0 {
        warnings.push(format!("inconsistent triangle orientation: flipped {flipped} triangle(s) to agree with their neighbours"));
    }
    for (t, f) in s.triangles.iter_mut().zip(&flip) {
        if *f {
            t.swap(1, 2);
        }
    }
    // Outward orientation of closed components from the signed volume.
    let mut volume = vec![0.0; n_comp];
    let mut closed = vec![true; n_comp];
    for (ti, t) in s.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| s.vertices[i as usize] - lo);
        volume[component[ti]] += a.dot(&b.cross(&c)) / 6.0;
    }
    for inc in edges.values().filter(|v| v.len() == 1) {
        closed[component[inc[0].0]] = false;
    }
    let inward: Vec<bool> = (0..n_comp).map(|c| closed[c] && volume[c] < 0.0).collect();
    if inward.iter().any(|&b| b) {
        for (ti, t) in s.triangles.iter_mut().enumerate() {
            if inward[component[ti]] {
                t.swap(1, 2);
            }
        }
        warnings.push(format!("{} closed component(s) had inward normals (negative volume): flipped", inward.iter().filter(|&&b| b).count()));
    }
    if open > 0 {
        warnings.push(format!("the surface is open ({open} boundary edges): inside/outside is decided by the nearest triangle's orientation"));
    }
    Ok((s, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> TriSoup {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                    f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
        parse_obj(text).expect("obj")
    }

    #[test]
    fn consistent_cube_needs_no_repair() {
        let (s, w) = repair(cube()).expect("repair");
        assert_eq!(s.triangles.len(), 12);
        assert!(w.is_empty(), "{w:?}");
    }

    #[test]
    fn flipped_and_degenerate_triangles_are_repaired() {
        let mut c = cube();
        c.triangles[3].swap(1, 2);
        c.triangles.push([0, 0, 1]);
        c.triangles.push([0, 1, 1]);
        let (s, w) = repair(c).expect("repair");
        assert_eq!(s.triangles.len(), 12);
        assert_eq!(w.len(), 2, "{w:?}");
        // Inverted cube is flipped outward.
        let mut c = cube();
        c.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let (_, w) = repair(c).expect("repair");
        assert!(w.iter().any(|m| m.contains("inward")), "{w:?}");
    }

    #[test]
    fn stl_ascii_and_binary_agree() {
        let (c, _) = repair(cube()).expect("repair");
        let mut ascii = String::from("solid c\n");
        let mut bin = vec![0u8; 80];
        bin.extend_from_slice(&(c.triangles.len() as u32).to_le_bytes());
        for t in &c.triangles {
            ascii += " facet normal 0 0 0\n  outer loop\n";
            bin.extend_from_slice(&[0u8; 12]);
            for &i in t {
                let v = c.vertices[i as usize];
                ascii += &format!("   vertex {} {} {}\n", v.x, v.y, v.z);
                for k in 0..3 {
                    bin.extend_from_slice(&(v[k] as f32).to_le_bytes());
                }
            }
            ascii += "  endloop\n endfacet\n";
            bin.extend_from_slice(&[0u8; 2]);
        }
        ascii += "endsolid c\n";
        let a = parse_stl(ascii.as_bytes()).expect("ascii");
        let b = parse_stl(&bin).expect("binary");
        assert_eq!((a.vertices.len(), a.triangles.len()), (8, 12));
        assert_eq!((b.vertices.len(), b.triangles.len()), (8, 12));
        assert_eq!(a.triangles, b.triangles);
    }
}
