//! Pattern files in: pieces read from pattern CAD exchange files (DXF in the AAMA / ASTM
//! D6673 convention, [`dxf`]) become garment panels — outline, grain, notched edge spans and
//! internal lines — either filled into a garment file's panels ([`resolve`]) or written out
//! as a new scene file ([`scene_ron`], `plyshell import`).

pub mod dxf;

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use crate::garment::spec::{EdgeSpan, GarmentSpec, PatternSource, StitchLineSpec};

/// A pattern piece, in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Piece name (the `Piece Name:` text, else the block name).
    pub name: String,
    /// Size (the `Size:` text), if any.
    pub size: Option<String>,
    /// Cut line, counter-clockwise, starting at the file's first boundary vertex, with every
    /// notch as a vertex.
    pub outline: Vec<[f64; 2]>,
    /// Notches `N1`, `N2`, … numbered counter-clockwise from the first boundary vertex, each
    /// with its outline vertex.
    pub notches: Vec<(String, usize)>,
    /// Unit grain (warp) direction.
    pub grain: [f64; 2],
    /// Internal lines (polylines).
    pub internal_lines: Vec<Vec<[f64; 2]>>,
    /// Handle of the piece's INSERT entity (for messages).
    pub handle: u64,
}

impl Piece {
    /// Named edge spans between consecutive notches, counter-clockwise: `N1-N2`, `N2-N3`, …,
    /// the last one closing back to `N1` (none with fewer than two notches).
    pub fn edges(&self) -> BTreeMap<String, EdgeSpan> {
        let n = self.notches.len();
        if n < 2 {
            return BTreeMap::new();
        }
        (0..n)
            .map(|k| {
                let (a, b) = (&self.notches[k], &self.notches[(k + 1) % n]);
                (format!("{}-{}", a.0, b.0), EdgeSpan { from: a.1, to: b.1 })
            })
            .collect()
    }
}

/// An error in a pattern file: the file, the DXF handle and layer of the entity at fault
/// (where one is), and what was expected.
#[derive(Clone, Debug, PartialEq)]
pub struct PatternError {
    /// File name.
    pub file: String,
    /// Handle of the entity at fault.
    pub handle: Option<u64>,
    /// Its layer.
    pub layer: Option<String>,
    /// What is wrong and what was expected.
    pub message: String,
}


impl fmt::Display for PatternError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(h) = self.handle {
            write!(f, ": entity {h:X}")?;
        }
        if let Some(l) = &self.layer {
            write!(f, " (layer \"{}\")", l.escape_debug())?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for PatternError {}

/// Reads the pieces of `source`, its file taken relative to `base_dir`.
pub fn read(source: &PatternSource, base_dir: &Path) -> Result<Vec<Piece>, PatternError> {
    match source {
        PatternSource::Dxf { file, size, units } => dxf::read_dxf(&base_dir.join(file), size.as_deref(), *units),
    }
}

/// `spec` with its pattern file's pieces filled in: every panel without an outline takes the
/// outline, grain and notch edge spans (`N1-N2`, …; the panel's own `edges` are added and
/// win) of the piece of the same name, and a multi-ply panel's internal lines become stitch
/// lines `PANEL/line1`, `PANEL/line2`, …. Without a pattern, `spec` is returned unchanged.
///
/// # Errors
/// `(field, message)`: the pattern file's own error, or a panel without outline that names no
/// piece of the file.
pub fn resolve(spec: &GarmentSpec, base_dir: &Path) -> Result<GarmentSpec, (String, String)> {
    let Some(source) = &spec.pattern else { return Ok(spec.clone()) };
    let pieces = read(source, base_dir).map_err(|e| ("garment.pattern".to_string(), e.to_string()))?;
    let mut out = spec.clone();
    for panel in out.panels.iter_mut().filter(|p| p.outline.is_empty()) {
        let Some(piece) = pieces.iter().find(|q| q.name == panel.name) else {
            let names: Vec<&str> = pieces.iter().map(|q| q.name.as_str()).collect();
            return Err((format!("garment.panels[{}].outline", panel.name), format!(
                "panel \"{}\" has no outline and the pattern file has no piece of that name; its pieces: {}",
                panel.name,
                names.join(", ")
            )));
        };
        panel.outline = piece.outline.clone();
        panel.grain = piece.grain;
        let own = std::mem::take(&mut panel.edges);
        panel.edges = piece.edges();
        panel.edges.extend(own);
        if panel.plies.len() > 1 {
            for (k, line) in piece.internal_lines.iter().enumerate() {
                out.stitch_lines.push(StitchLineSpec { name: format!("{}/line{}", panel.name, k + 1), panel: panel.name.clone(), points: line.clone() });
            }
        }
    }
    Ok(out)
}

/// A scene file (RON) for `pieces`, read from `source_name`: one single-ply panel per piece
/// with its outline, notch edge spans and grain, laid side by side in the plane z = 0, a
/// placeholder material and ply, no seams, supports or loads, and one unloaded step (the comments list
/// each piece's notches and internal lines). `plyshell check` accepts it as written.
pub fn scene_ron(name: &str, source_name: &str, pieces: &[Piece]) -> String {
    use std::fmt::Write as _;
    let q = |s: &str| format!("\"{}\"", s.escape_debug());
    let mut t = String::new();
    let _ = writeln!(t, "// Imported from {} by `plyshell import`: {} pattern pieces (lengths in metres).", source_name.escape_debug(), pieces.len());
    let _ = writeln!(t, "// The material and ply are placeholders; declare seams between notch spans (edges \"N1-N2\", …),");
    let _ = writeln!(t, "// supports, loads and steps, and place the panels in 3D.");
    let _ = writeln!(t, "Scene(\n    name: {},\n    materials: {{\n        \"fabric\": StVenantKirchhoff(young: 2.0e6, poisson: 0.3),\n    }},\n    parts: [],", q(name));
    let h = pieces.iter().map(|p| extent(&p.outline)).map(|(lo, hi)| (hi[0] - lo[0]).max(hi[1] - lo[1])).fold(0.0, f64::max);
    let _ = writeln!(t, "    garment: Some((\n        element_size: {:?},\n        plies: {{\"shell\": (material: \"fabric\", thickness: 0.0005)}},\n        panels: [", round_sig(h / 20.0));
    let mut x = 0.0;
    for p in pieces {
        let (lo, hi) = extent(&p.outline);
        let _ = writeln!(t, "            (");
        let _ = writeln!(t, "                name: {},", q(&p.name));
        if let Some(s) = &p.size {
            let _ = writeln!(t, "                // size {}", s.escape_debug());
        }
        let pts: Vec<String> = p.outline.iter().map(|v| format!("({:?}, {:?})", v[0], v[1])).collect();
        let _ = writeln!(t, "                outline: [{}],", pts.join(", "));
        let _ = writeln!(t, "                edges: {{");
        for (e, span) in p.edges() {
            let _ = writeln!(t, "                    {}: (from: {}, to: {}),", q(&e), span.from, span.to);
        }
        let _ = writeln!(t, "                }},");
        let notes: Vec<String> = p.notches.iter().map(|(n, v)| format!("{n} at vertex {v}")).collect();
        if !notes.is_empty() {
            let _ = writeln!(t, "                // notches: {}", notes.join(", "));
        }
        for (k, l) in p.internal_lines.iter().enumerate() {
            let pts: Vec<String> = l.iter().map(|v| format!("({:?}, {:?})", v[0], v[1])).collect();
            let _ = writeln!(t, "                // internal line {}: [{}]", k + 1, pts.join(", "));
        }
        let _ = writeln!(t, "                grain: ({:?}, {:?}),", p.grain[0], p.grain[1]);
        let _ = writeln!(t, "                plies: [\"shell\"],");
        let _ = writeln!(t, "                placement: Rigid(translation: ({:?}, {:?}, 0.0)),", x - lo[0] + 0.0, -lo[1] + 0.0);
        let _ = writeln!(t, "            ),");
        x += hi[0] - lo[0] + 0.1 * h;
    }
    let _ = writeln!(t, "        ],\n    )),\n    steps: [(name: \"unloaded\", increments: 1, scale: {{}})],\n)");
    t
}

/// Bounding box of a point set.
fn extent(p: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    p.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), v| ([lo[0].min(v[0]), lo[1].min(v[1])], [hi[0].max(v[0]), hi[1].max(v[1])]))
}

/// `x` rounded to two significant digits (a tidy element size).
fn round_sig(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 0.01;
    }
    let e = 10f64.powf(x.log10().floor() - 1.0);
    (x / e).round() * e
}
