//! glTF 2.0 binary (`.glb`) export of a textured quad surface, written by hand after the
//! Khronos glTF 2.0 specification: a 12-byte header, a JSON chunk and a BIN chunk (§4.4);
//! one node and mesh per named group (quads split into two triangles, one double-sided
//! material, `TEXCOORD_0` with v
//! flipped as glTF's origin is the image's top left, §3.7.2.1), and a pose series as morph
//! targets (§3.7.2.2) with a STEP animation of the morph weights showing one pose per second.

use std::io;
use std::path::Path;

use serde_json::{json, Value};

use super::atomic::write_atomic;
use super::surface::TexturedMesh;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Builds the BIN chunk and its buffer views and accessors.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends `values` (`width` floats per element: 1 SCALAR, 2 VEC2, 3 VEC3) as a view and
    /// an accessor with min and max; returns the accessor index.
    fn floats(&mut self, values: &[f32], width: usize, target: Option<u32>) -> usize {
        let kind = ["SCALAR", "VEC2", "VEC3"][width - 1];
        let mut lo = vec![f32::INFINITY; width];
        let mut hi = vec![f32::NEG_INFINITY; width];
        for chunk in values.chunks(width) {
            for k in 0..width {
                lo[k] = lo[k].min(chunk[k]);
                hi[k] = hi[k].max(chunk[k]);
            }
        }
        let view = self.view(values.iter().flat_map(|v| v.to_le_bytes()).collect(), target);
        self.accessors.push(json!({"bufferView": view, "componentType": FLOAT, "count": values.len() / width, "type": kind, "min": lo, "max": hi}));
        self.accessors.len() - 1
    }

    /// Appends triangle indices; returns the accessor index.
    fn indices(&mut self, values: &[u32]) -> usize {
        let view = self.view(values.iter().flat_map(|v| v.to_le_bytes()).collect(), Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": values.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    fn view(&mut self, data: Vec<u8>, target: Option<u32>) -> usize {
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(&data);
        while self.bytes.len() % 4 != 0 {
            self.bytes.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }
}

/// The GLB bytes of `mesh` (its positions are the default pose). With `frames` (positions of
/// every vertex per pose, at `times`), each group's mesh gets one morph target per pose
/// (pose − default) and the file an animation `poses` whose morph weights select pose k at
/// t = k s (STEP); the poses' own times are listed in the scene's `extras.pose_times`.
pub fn glb_bytes(mesh: &TexturedMesh, frames: &[Vec<[f64; 3]>], times: &[f64], generator: &str) -> Result<Vec<u8>, String> {
    if let Some(p) = mesh.problem() {
        return Err(p);
    }
    if frames.len() != times.len() {
        return Err(format!("{} poses but {} times", frames.len(), times.len()));
    }
    if let Some(k) = frames.iter().position(|f| f.len() != mesh.positions.len() || f.iter().flatten().any(|c| !c.is_finite())) {
        return Err(format!("pose {k}: expected {} finite positions", mesh.positions.len()));
    }
    let mut bin = Bin::default();
    let (mut meshes, mut nodes) = (Vec::new(), Vec::new());
    for (name, quads) in &mesh.groups {
        // The group's own vertices, in first-use order.
        let mut local = std::collections::HashMap::new();
        let mut verts: Vec<usize> = Vec::new();
        let mut tri: Vec<u32> = Vec::with_capacity(6 * quads.len());
        for q in quads {
            let l = q.map(|n| *local.entry(n).or_insert_with(|| {
                verts.push(n);
                verts.len() - 1
            }) as u32);
            tri.extend_from_slice(&[l[0], l[1], l[2], l[0], l[2], l[3]]);
        }
        let pos: Vec<f32> = verts.iter().flat_map(|&n| mesh.positions[n].map(|c| c as f32)).collect();
        let uv: Vec<f32> = verts.iter().flat_map(|&n| [mesh.uvs[n][0] as f32, (1.0 - mesh.uvs[n][1]) as f32]).collect();
        let mut primitive = json!({
            "attributes": {"POSITION": bin.floats(&pos, 3, Some(ARRAY_BUFFER)), "TEXCOORD_0": bin.floats(&uv, 2, Some(ARRAY_BUFFER))},
            "indices": bin.indices(&tri),
            "material": 0,
            "mode": 4,
        });
        let mut m = json!({"name": name});
        if !frames.is_empty() {
            let targets: Vec<Value> = frames
                .iter()
                .map(|f| {
                    let d: Vec<f32> = verts.iter().flat_map(|&n| [0, 1, 2].map(|k| (f[n][k] - mesh.positions[n][k]) as f32)).collect();
                    json!({"POSITION": bin.floats(&d, 3, Some(ARRAY_BUFFER))})
                })
                .collect();
            primitive["targets"] = json!(targets);
            m["weights"] = json!(vec![0.0; frames.len()]);
        }
        m["primitives"] = json!([primitive]);
        meshes.push(m);
        nodes.push(json!({"name": name, "mesh": meshes.len() - 1}));
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": generator},
        "scene": 0,
        "scenes": [{"name": "garment", "nodes": (0..nodes.len()).collect::<Vec<_>>(), "extras": {"pose_times": times}}],
        "nodes": nodes,
        "meshes": meshes,
        // One double-sided matte material (cloth is seen from both sides; a renderer sets its
        // base colour texture to the fabric print, mapped by TEXCOORD_0).
        "materials": [{"name": "fabric", "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
    });
    if !frames.is_empty() && !mesh.groups.is_empty() {
        let n = frames.len();
        let input: Vec<f32> = (0..n).map(|k| k as f32).collect();
        let output: Vec<f32> = (0..n).flat_map(|k| (0..n).map(move |j| if j == k { 1.0 } else { 0.0 })).collect();
        let (i, o) = (bin.floats(&input, 1, None), bin.floats(&output, 1, None));
        let channels: Vec<Value> = (0..mesh.groups.len()).map(|g| json!({"sampler": 0, "target": {"node": g, "path": "weights"}})).collect();
        doc["animations"] = json!([{"name": "poses", "samplers": [{"input": i, "output": o, "interpolation": "STEP"}], "channels": channels}]);
    }
    doc["bufferViews"] = json!(bin.views);
    doc["accessors"] = json!(bin.accessors);
    doc["buffers"] = json!([{"byteLength": bin.bytes.len()}]);
    let mut text = serde_json::to_vec(&doc).map_err(|e| e.to_string())?;
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.bytes.len();
    let total32 = u32::try_from(total).map_err(|_| format!("the file would have {total} bytes; GLB files are limited to 4 GiB"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin.bytes);
    Ok(out)
}

/// Writes [`glb_bytes`] to `path`, whole or not at all.
pub fn write_glb(path: &Path, mesh: &TexturedMesh, frames: &[Vec<[f64; 3]>], times: &[f64], generator: &str) -> io::Result<()> {
    let bytes = glb_bytes(mesh, frames, times, generator).map_err(|m| io::Error::new(io::ErrorKind::InvalidInput, format!("cannot write '{}': {m}", path.display())))?;
    write_atomic(path, &bytes)
}
