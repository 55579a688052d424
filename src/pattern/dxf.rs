//! Pattern pieces from a DXF file in the AAMA / ASTM D6673 layer convention ("Standard
//! Practice for Sewn Products Pattern Data Interchange — Data Format", ASTM D6673-10, itself
//! the AAMA DXF convention on AutoCAD DXF R13/R14).
//!
//! One pattern style per file. Each piece is a block inserted (INSERT) in the ENTITIES
//! section; inside the block, the layer names are AAMA layer numbers:
//!
//! | layer | meaning | read as |
//! |---|---|---|
//! | 1 | boundary (cut) line, and the piece's TEXT or MTEXT (`Piece Name:`, `Size:`, …; read on any layer) | closed POLYLINE / LWPOLYLINE → outline |
//! | 4 | notches (also 80–83: T, castle, check and U notches) | LINE (the end nearer the boundary) or POINT → outline vertices |
//! | 7 | grain line | LINE or 2-vertex polyline → `grain` (first → second point) |
//! | 8 | internal lines | LINE / polylines → stitch lines |
//! | 14 | sew lines | checked, not used (the cut line is the panel outline) |
//! | 2, 3, 5, 6, 9–13, 15, 84–87 | turn / curve points, grade reference, mirror, stripe, plaid, cut-outs, drill holes, annotation, quality curves | ignored |
//!
//! Any other layer inside a piece block is an error naming the entity's handle and layer.
//! Units come from the header's `$INSUNITS` (1 in, 2 ft, 4 mm, 5 cm, 6 m); a unitless file
//! needs the units given by the caller. Polyline bulges (circular arcs) are sampled at most
//! 5° per chord. Graded files hold one block per piece and size (`Size:` text): the caller
//! chooses the size.

use std::collections::BTreeMap;
use std::path::Path;

use dxf::entities::{Entity, EntityType};
use dxf::enums::Units;
use dxf::Drawing;

use super::{PatternError, Piece};
use crate::garment::spec::LengthUnit;

/// Largest DXF file read (256 MiB).
pub const MAX_DXF_BYTES: u64 = 256 << 20;

/// AAMA layers that carry nothing the import uses.
const IGNORED_LAYERS: [&str; 14] = ["2", "3", "5", "6", "9", "10", "11", "12", "13", "15", "84", "85", "86", "87"];

/// Reads the pattern pieces of the DXF file `path` (see the module documentation for the
/// layer convention). `size` chooses the size of a graded file (required when pieces come in
/// more than one size); `units` overrides the header's `$INSUNITS` (required when that is
/// unitless).
///
/// # Errors
/// A [`PatternError`] naming the file and, where one is at fault, the entity's handle and
/// layer: unreadable, truncated or non-DXF files, no pieces, open or degenerate boundaries,
/// a piece without or with two grain lines, notches off the boundary, unknown layers,
/// duplicated piece names, a size not in the file.
pub fn read_dxf(path: &Path, size: Option<&str>, units: Option<LengthUnit>) -> Result<Vec<Piece>, PatternError> {
    let file = path.display().to_string();
    let err = |message: String| PatternError { file: file.clone(), handle: None, layer: None, message };
    let meta = std::fs::metadata(path).map_err(|e| err(format!("cannot read the pattern file: {e}")))?;
    if !meta.is_file() {
        return Err(err("cannot read the pattern file: not a regular file".into()));
    }
    if meta.len() > MAX_DXF_BYTES {
        return Err(err(format!("the file has {} bytes; pattern files are limited to {MAX_DXF_BYTES} bytes", meta.len())));
    }
    let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read the pattern file: {e}")))?;
    read_dxf_bytes(&file, &bytes, size, units)
}

/// [`read_dxf`] on the bytes of a file named `file` in messages.
pub fn read_dxf_bytes(file: &str, bytes: &[u8], size: Option<&str>, units: Option<LengthUnit>) -> Result<Vec<Piece>, PatternError> {
    let err = |message: String| PatternError { file: file.to_string(), handle: None, layer: None, message };
    if bytes.iter().take(4096).all(|b| b.is_ascii_whitespace()) {
        return Err(err("the file is empty; expected a DXF drawing (ASTM D6673)".into()));
    }
    // The reader sees only the header variables used here ($ACADVER, $INSUNITS): it panics on
    // out-of-range date variables (dxf 0.6.2 through chrono). Any other panic inside the
    // third-party reader on hostile input still becomes an error.
    let trimmed = minimal_header(bytes);
    let loaded = std::panic::catch_unwind(|| Drawing::load(&mut std::io::Cursor::new(&trimmed)));
    let drawing = match loaded {
        Ok(Ok(d)) => d,
        Ok(Err(e)) => return Err(err(format!("not a readable DXF drawing: {e}"))),
        Err(_) => return Err(err("not a readable DXF drawing (the DXF reader failed on it)".into())),
    };
    let scale = match units {
        Some(u) => u.metres(),
        None => header_scale(&drawing).ok_or_else(|| {
            err(format!(
                "the header's $INSUNITS is {:?}; expected inches (1), feet (2), millimetres (4), centimetres (5) or metres (6), or give the units explicitly",
                drawing.header.default_drawing_units
            ))
        })?,
    };
    let inserts: Vec<&Entity> = drawing.entities().filter(|e| matches!(e.specific, EntityType::Insert(_))).collect();
    if inserts.is_empty() {
        return Err(err("no pattern pieces: expected one block per piece, inserted (INSERT) in the ENTITIES section (ASTM D6673)".into()));
    }
    let handles = block_entity_handles(bytes);
    let mut pieces: Vec<Piece> = Vec::new();
    for ins in inserts {
        let EntityType::Insert(i) = &ins.specific else { continue };
        let Some(block) = drawing.blocks().find(|b| b.name == i.name) else {
            return Err(at_entity(file, Some(ins.common.handle.0), ins, format!("INSERT of block \"{}\", which the BLOCKS section does not define (a truncated file?)", i.name)));
        };
        // The scan's entities must be the reader's, one for one; else no handles are named.
        let own = handles.get(&block.name).filter(|h| h.len() == block.entities.len()).map_or(&[][..], Vec::as_slice);
        let piece = read_piece(file, &block.name, ins, &block.entities, own, [block.base_point.x, block.base_point.y], scale)?;
        pieces.push(piece);
    }
    choose_size(file, pieces, size)
}

/// `bytes` with the HEADER section (if any) reduced to `$ACADVER` (when it reads `AC` and
/// four digits) and `$INSUNITS` (when an integer), everything else byte for byte.
fn minimal_header(bytes: &[u8]) -> Vec<u8> {
    // Line start offsets.
    let mut starts = vec![0];
    starts.extend(bytes.iter().enumerate().filter(|&(_, &b)| b == b'\n').map(|(i, _)| i + 1));
    let line = |k: usize| -> &[u8] {
        let (a, b) = (starts[k], starts.get(k + 1).map_or(bytes.len(), |&e| e - 1));
        bytes.get(a..b.max(a)).unwrap_or(&[]).trim_ascii()
    };
    let n = starts.len();
    let Some(begin) = (0..n.saturating_sub(3)).step_by(2).find(|&k| line(k) == b"0" && line(k + 1) == b"SECTION" && line(k + 2) == b"2" && line(k + 3) == b"HEADER") else {
        return bytes.to_vec();
    };
    let Some(end) = (begin + 4..n.saturating_sub(1)).step_by(2).find(|&k| line(k) == b"0" && line(k + 1) == b"ENDSEC") else {
        return bytes.to_vec();
    };
    let (mut version, mut units) = (None, None);
    for k in (begin + 4..end).step_by(2) {
        let next = |code: &[u8]| (k + 3 < end && line(k + 2) == code).then(|| String::from_utf8_lossy(line(k + 3)).into_owned());
        if line(k) == b"9" && line(k + 1) == b"$ACADVER" {
            version = next(b"1").filter(|v| v.len() == 6 && v.starts_with("AC") && v[2..].bytes().all(|c| c.is_ascii_digit()));
        } else if line(k) == b"9" && line(k + 1) == b"$INSUNITS" {
            units = next(b"70").and_then(|v| v.parse::<i16>().ok());
        }
    }
    let mut header = String::from("0\nSECTION\n2\nHEADER\n");
    if let Some(v) = version {
        header += &format!("9\n$ACADVER\n1\n{v}\n");
    }
    if let Some(u) = units {
        header += &format!("9\n$INSUNITS\n70\n{u}\n");
    }
    header += "0\nENDSEC\n";
    let after = starts.get(end + 2).copied().unwrap_or(bytes.len());
    let mut out = bytes[..starts[begin]].to_vec();
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(&bytes[after..]);
    out
}

/// An error at the entity `e` with file handle `handle`.
fn at_entity(file: &str, handle: Option<u64>, e: &Entity, message: String) -> PatternError {
    PatternError { file: file.to_string(), handle, layer: Some(e.common.layer.clone()), message }
}

/// The handles (group code 5) of each block's entities as written in the file, in order, by
/// block name: the DXF reader assigns new handles to block entities, so messages take the
/// file's own from this scan of the BLOCKS section's group-code pairs (ASCII DXF; VERTEX,
/// SEQEND and ATTRIB belong to the entity before them).
fn block_entity_handles(bytes: &[u8]) -> BTreeMap<String, Vec<Option<u64>>> {
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines();
    let mut out: BTreeMap<String, Vec<Option<u64>>> = BTreeMap::new();
    let (mut in_blocks, mut block, mut in_header, mut sub) = (false, None::<String>, false, false);
    let mut current: Vec<Option<u64>> = Vec::new();
    while let (Some(code), Some(value)) = (lines.next(), lines.next()) {
        let (code, value) = (code.trim(), value.trim());
        match (code, value) {
            ("2", "BLOCKS") => in_blocks = true,
            ("0", "ENDSEC") => in_blocks = false,
            ("0", "BLOCK") if in_blocks => {
                (block, in_header, sub) = (None, true, false);
                current.clear();
            }
            ("2", name) if in_blocks && in_header && block.is_none() => block = Some(name.to_string()),
            ("0", "ENDBLK") if in_blocks => {
                if let Some(b) = block.take() {
                    out.insert(b, std::mem::take(&mut current));
                }
                in_header = false;
            }
            ("0", "VERTEX" | "SEQEND" | "ATTRIB") if in_blocks => sub = true,
            ("0", _) if in_blocks && block.is_some() => {
                (in_header, sub) = (false, false);
                current.push(None);
            }
            ("5", h) if in_blocks && !in_header && !sub => {
                if let Some(last) = current.last_mut() {
                    *last = u64::from_str_radix(h, 16).ok();
                }
            }
            _ => {}
        }
    }
    out
}

/// Metres per drawing unit from `$INSUNITS`, if it names a length unit used for patterns.
fn header_scale(d: &Drawing) -> Option<f64> {
    match d.header.default_drawing_units {
        Units::Inches => Some(LengthUnit::In.metres()),
        Units::Feet => Some(0.3048),
        Units::Millimeters => Some(LengthUnit::Mm.metres()),
        Units::Centimeters => Some(LengthUnit::Cm.metres()),
        Units::Meters => Some(LengthUnit::M.metres()),
        _ => None,
    }
}

/// Keeps the pieces of one size: all of them when the file is not graded (one size, or no
/// `Size:` text); else those of `size`. Duplicated (name, size) pairs are errors.
fn choose_size(file: &str, pieces: Vec<Piece>, size: Option<&str>) -> Result<Vec<Piece>, PatternError> {
    let err = |handle: Option<u64>, message: String| PatternError { file: file.to_string(), handle, layer: None, message };
    let mut seen: BTreeMap<(&str, Option<&str>), u64> = BTreeMap::new();
    for p in &pieces {
        if let Some(h) = seen.insert((&p.name, p.size.as_deref()), p.handle) {
            return Err(err(Some(p.handle), format!(
                "duplicated piece name \"{}\"{} (also the INSERT with handle {h:X}); piece names must be unique within a size",
                p.name,
                p.size.as_ref().map(|s| format!(" in size \"{s}\"")).unwrap_or_default()
            )));
        }
    }
    let mut sizes: Vec<&str> = pieces.iter().filter_map(|p| p.size.as_deref()).collect();
    sizes.sort();
    sizes.dedup();
    let wanted = match (size, sizes.len()) {
        (Some(s), _) => {
            if !sizes.contains(&s) {
                return Err(err(None, format!("no pieces in size \"{s}\"; the file's sizes: {}", if sizes.is_empty() { "none (not graded)".into() } else { sizes.join(", ") })));
            }
            Some(s.to_string())
        }
        (None, 0 | 1) => None,
        (None, _) => return Err(err(None, format!("the file is graded into sizes {}; choose one (`size`)", sizes.join(", ")))),
    };
    Ok(pieces.into_iter().filter(|p| wanted.is_none() || p.size.is_none() || p.size == wanted).collect())
}

/// The points of a LINE, LWPOLYLINE or POLYLINE (bulges sampled), its closed flag; None for
/// other entity types.
fn polyline(e: &Entity) -> Option<(Vec<[f64; 2]>, bool)> {
    match &e.specific {
        EntityType::Line(l) => Some((vec![[l.p1.x, l.p1.y], [l.p2.x, l.p2.y]], false)),
        EntityType::LwPolyline(p) => {
            let v: Vec<([f64; 2], f64)> = p.vertices.iter().map(|v| ([v.x, v.y], v.bulge)).collect();
            Some((with_bulges(&v, p.is_closed()), p.is_closed()))
        }
        EntityType::Polyline(p) => {
            let v: Vec<([f64; 2], f64)> = p.vertices().map(|v| ([v.location.x, v.location.y], v.bulge)).collect();
            Some((with_bulges(&v, p.is_closed()), p.is_closed()))
        }
        _ => None,
    }
}

/// Vertices with each bulged segment (bulge = tan(θ/4), θ the arc's included angle,
/// positive counter-clockwise; DXF reference, LWPOLYLINE group 42) sampled at ≤ 5° chords.
fn with_bulges(v: &[([f64; 2], f64)], closed: bool) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(v.len());
    let n = v.len();
    for k in 0..n {
        let (a, bulge) = v[k];
        out.push(a);
        if k + 1 == n && !closed {
            break;
        }
        let b = v[(k + 1) % n].0;
        if bulge.is_finite() && bulge.abs() > 1e-12 {
            let theta = 4.0 * bulge.atan();
            let steps = ((theta.abs().to_degrees() / 5.0).ceil() as usize).clamp(1, 72);
            // Chord midpoint, then the centre on the chord's normal at distance d.
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let c = dx.hypot(dy);
            if c == 0.0 {
                continue;
            }
            let r = c / (2.0 * (theta / 2.0).sin());
            let d = r * (theta / 2.0).cos();
            let centre = [0.5 * (a[0] + b[0]) - d * dy / c, 0.5 * (a[1] + b[1]) + d * dx / c];
            let phi0 = (a[1] - centre[1]).atan2(a[0] - centre[0]);
            let rr = (a[0] - centre[0]).hypot(a[1] - centre[1]);
            for s in 1..steps {
                let phi = phi0 + theta * s as f64 / steps as f64;
                out.push([centre[0] + rr * phi.cos(), centre[1] + rr * phi.sin()]);
            }
        }
    }
    out
}

/// Twice the signed area of a closed polygon (positive: counter-clockwise).
fn signed_area2(p: &[[f64; 2]]) -> f64 {
    (0..p.len()).map(|i| {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        a[0] * b[1] - b[0] * a[1]
    }).sum()
}

/// Nearest point of the closed outline `p` to `q`: (segment index, parameter in [0, 1],
/// distance).
fn project(p: &[[f64; 2]], q: [f64; 2]) -> (usize, f64, f64) {
    let mut best = (0, 0.0, f64::INFINITY);
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        let ab = [b[0] - a[0], b[1] - a[1]];
        let l2 = ab[0] * ab[0] + ab[1] * ab[1];
        let t = if l2 > 0.0 { (((q[0] - a[0]) * ab[0] + (q[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
        let d = (a[0] + t * ab[0] - q[0]).hypot(a[1] + t * ab[1] - q[1]);
        if d < best.2 {
            best = (i, t, d);
        }
    }
    best
}

/// One piece from the entities of its block (coordinates relative to the block's base point,
/// scaled to metres by `scale`).
fn read_piece(file: &str, block: &str, insert: &Entity, entities: &[Entity], handles: &[Option<u64>], base: [f64; 2], scale: f64) -> Result<Piece, PatternError> {
    // The file's handle of a block entity (the DXF reader renumbers them).
    let handle_of = |e: &Entity| entities.iter().position(|x| std::ptr::eq(x, e)).and_then(|k| handles.get(k).copied().flatten());
    let at = |e: &Entity, m: String| at_entity(file, handle_of(e), e, format!("block \"{block}\": {m}"));
    let to_m = |p: [f64; 2]| [(p[0] - base[0]) * scale, (p[1] - base[1]) * scale];
    let mut boundary: Option<(&Entity, Vec<[f64; 2]>)> = None;
    let mut grain: Option<[f64; 2]> = None;
    let mut notches: Vec<(&Entity, Vec<[f64; 2]>)> = Vec::new();
    let mut internal = Vec::new();
    let (mut name, mut size) = (None, None);
    for e in entities {
        let layer = e.common.layer.trim();
        let finite = match &e.specific {
            EntityType::ModelPoint(p) => to_m([p.location.x, p.location.y]).iter().all(|c| c.is_finite()),
            _ => polyline(e).is_none_or(|(pts, _)| pts.into_iter().map(to_m).flatten().all(f64::is_finite)),
        };
        if !finite {
            return Err(at(e, "a coordinate is not a finite number (in metres)".into()));
        }
        let text = match &e.specific {
            EntityType::Text(t) => Some(t.value.as_str()),
            EntityType::MText(t) => Some(t.text.as_str()),
            _ => None,
        };
        if let Some(text) = text {
            if let Some((key, value)) = text.split_once(':') {
                let value = value.trim();
                match key.trim().to_ascii_lowercase().as_str() {
                    "piece name" => name = Some(value.to_string()),
                    "size" if !value.is_empty() => size = Some(value.to_string()),
                    _ => {}
                }
            }
            continue;
        }
        match layer {
            "1" => {
                let Some((pts, closed)) = polyline(e) else {
                    return Err(at(e, "expected the boundary as a closed POLYLINE or LWPOLYLINE".into()));
                };
                if boundary.is_some() {
                    return Err(at(e, "a second boundary polyline on layer 1; a piece has one cut line".into()));
                }
                let mut pts: Vec<[f64; 2]> = pts.into_iter().map(to_m).collect();
                pts.dedup_by(|b, a| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9);
                let (Some(first), Some(last)) = (pts.first().copied(), pts.last().copied()) else {
                    return Err(at(e, "the boundary has no vertices".into()));
                };
                let gap = (first[0] - last[0]).hypot(first[1] - last[1]);
                let tol = 1e-6;
                if pts.len() > 1 && gap < tol {
                    pts.pop();
                } else if !closed {
                    return Err(at(e, format!(
                        "the boundary is open: its ends are {:.3} mm apart and it is not flagged closed; expected a closed cut line",
                        gap * 1e3
                    )));
                }
                if pts.len() < 3 || signed_area2(&pts).abs() < 1e-12 {
                    return Err(at(e, format!("the boundary is degenerate ({} distinct vertices, no area)", pts.len())));
                }
                boundary = Some((e, pts));
            }
            "7" => {
                let Some((pts, _)) = polyline(e).filter(|(p, _)| p.len() == 2) else {
                    return Err(at(e, "expected the grain line as a LINE (or a two-vertex polyline)".into()));
                };
                if grain.is_some() {
                    return Err(at(e, "a second grain line; a piece has one".into()));
                }
                let (a, b) = (to_m(pts[0]), to_m(pts[1]));
                let d = [b[0] - a[0], b[1] - a[1]];
                let l = d[0].hypot(d[1]);
                if !(l > 0.0 && l.is_finite()) {
                    return Err(at(e, "the grain line has zero length".into()));
                }
                grain = Some([d[0] / l, d[1] / l]);
            }
            "4" | "80" | "81" | "82" | "83" => {
                let pts = match &e.specific {
                    EntityType::ModelPoint(p) => vec![[p.location.x, p.location.y]],
                    _ => match polyline(e) {
                        Some((p, _)) if p.len() == 2 => p,
                        _ => return Err(at(e, "expected a notch as a LINE or a POINT".into())),
                    },
                };
                notches.push((e, pts.into_iter().map(to_m).collect()));
            }
            "8" => match polyline(e) {
                Some((p, _)) if p.len() >= 2 => internal.push(p.into_iter().map(to_m).collect::<Vec<_>>()),
                _ => return Err(at(e, "expected an internal line as a LINE or polyline".into())),
            },
            "14" => {
                if polyline(e).is_none() {
                    return Err(at(e, "expected a sew line as a LINE or polyline".into()));
                }
            }
            l if IGNORED_LAYERS.contains(&l) => {}
            _ => {
                return Err(at(e, format!(
                    "unknown layer \"{}\"; pattern pieces use the AAMA / ASTM D6673 layers 1 (boundary), 2, 3, 4 (notches), 5, 6, 7 (grain), 8 (internal lines), 9–15 and 80–87",
                    e.common.layer
                )));
            }
        }
    }
    let ins_err = |m: String| at_entity(file, Some(insert.common.handle.0), insert, format!("block \"{block}\": {m}"));
    let Some((b_entity, mut outline)) = boundary else {
        return Err(ins_err("no boundary: expected a closed polyline on layer 1".into()));
    };
    let grain = grain.ok_or_else(|| ins_err("no grain line: expected a LINE on layer 7".into()))?;
    let name = name.unwrap_or_else(|| block.to_string());
    if name.is_empty() || name.chars().any(|c| c.is_control() || c == '"') {
        return Err(ins_err(format!("piece name {name:?}: expected a non-empty name without quotes or control characters")));
    }
    // Counter-clockwise, keeping the first vertex first.
    if signed_area2(&outline) < 0.0 {
        outline[1..].reverse();
    }
    // Notch tolerance: a thousandth of the piece's larger bounding-box side (1 mm on 1 m).
    let (lo, hi) = outline.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])]));
    let tol = 1e-3 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    // Notch positions on the boundary: the notch point nearest to it.
    let mut marks: Vec<(usize, f64, &Entity)> = Vec::new();
    for (e, pts) in &notches {
        let (seg, t, d) = pts.iter().map(|&q| project(&outline, q)).fold((0, 0.0, f64::INFINITY), |b, x| if x.2 < b.2 { x } else { b });
        if d > tol {
            return Err(at(e, format!("the notch lies {:.3} mm from the boundary (of handle {}); expected it on the cut line", d * 1e3, handle_of(b_entity).map_or("unknown".into(), |h| format!("{h:X}")))));
        }
        marks.push((seg, t, e));
    }
    marks.sort_by(|a, b| (a.0, a.1).partial_cmp(&(b.0, b.1)).unwrap_or(std::cmp::Ordering::Equal));
    // Notch points become outline vertices (unless within the tolerance of one).
    let point = |&(seg, t, _): &(usize, f64, &Entity)| {
        let (a, b) = (outline[seg], outline[(seg + 1) % outline.len()]);
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
    };
    let near = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) < tol;
    let mut with_notches: Vec<[f64; 2]> = Vec::new();
    for (i, &v) in outline.iter().enumerate() {
        with_notches.push(v);
        let w = outline[(i + 1) % outline.len()];
        for mark in marks.iter().filter(|m| m.0 == i) {
            let q = point(mark);
            if !near(q, v) && !near(q, w) && !with_notches.last().is_some_and(|&l| near(q, l)) {
                with_notches.push(q);
            }
        }
    }
    let notch_vertex: Vec<usize> = marks
        .iter()
        .map(|mark| {
            let q = point(mark);
            let d = |k: usize| (with_notches[k][0] - q[0]).hypot(with_notches[k][1] - q[1]);
            (0..with_notches.len()).min_by(|&x, &y| d(x).total_cmp(&d(y))).unwrap_or(0)
        })
        .collect();
    let mut sorted = notch_vertex.clone();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() != notch_vertex.len() {
        return Err(ins_err(format!("two notches at the same point of the boundary (within {:.3} mm)", tol * 1e3)));
    }
    let notches: Vec<(String, usize)> = sorted.iter().enumerate().map(|(k, &v)| (format!("N{}", k + 1), v)).collect();
    let handle = insert.common.handle.0;
    Ok(Piece { name, size, outline: with_notches, notches, grain, internal_lines: internal, handle })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bulge_of_a_half_circle() {
        // bulge 1 = half circle from (1, 0) to (-1, 0) counter-clockwise through (0, 1).
        let pts = with_bulges(&[([1.0, 0.0], 1.0), ([-1.0, 0.0], 0.0)], false);
        assert_eq!(pts.len(), 37);
        for p in &pts {
            assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-12, "{p:?}");
        }
        assert!((pts[18][1] - 1.0).abs() < 1e-12, "{:?}", pts[18]);
    }
}
