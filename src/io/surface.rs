//! A textured quad surface for exchange formats (OBJ, glTF): positions, texture coordinates
//! and named groups of quads.

/// Quads in named groups over shared vertices, each vertex with a texture coordinate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TexturedMesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Texture coordinate of each vertex (u, v), v upwards.
    pub uvs: Vec<[f64; 2]>,
    /// Named groups of quads (vertex indices, counter-clockwise seen from the front).
    pub groups: Vec<(String, Vec<[usize; 4]>)>,
}

impl TexturedMesh {
    /// What is inconsistent, if anything: a UV count that differs from the vertex count, an
    /// index beyond the vertices, a non-finite coordinate, an empty or duplicated group name.
    pub fn problem(&self) -> Option<String> {
        if self.uvs.len() != self.positions.len() {
            return Some(format!("{} texture coordinates for {} vertices", self.uvs.len(), self.positions.len()));
        }
        if let Some(i) = self.positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Some(format!("vertex {i} has a non-finite coordinate {:?}", self.positions[i]));
        }
        if let Some(i) = self.uvs.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Some(format!("vertex {i} has a non-finite texture coordinate {:?}", self.uvs[i]));
        }
        for (k, (name, quads)) in self.groups.iter().enumerate() {
            if name.is_empty() || self.groups[..k].iter().any(|g| &g.0 == name) {
                return Some(format!("group {k}: names must be non-empty and unique, found {name:?}"));
            }
            if let Some(q) = quads.iter().find(|q| q.iter().any(|&n| n >= self.positions.len())) {
                return Some(format!("group \"{name}\": quad {q:?} refers to a vertex beyond the {} vertices", self.positions.len()));
            }
        }
        None
    }
}
