//! VTK XML `UnstructuredGrid` (`.vtu`) writer for shell meshes.
//!
//! Writes bilinear quadrilaterals (VTK cell type 9) followed by line
//! segments (VTK cell type 3, e.g. seams or beams) in one grid, with
//! `Float64` point/cell data and `Int32` cell data (part id, ply id, ...).
//!
//! Two encodings are supported:
//! * ASCII (`format="ascii"`), human readable; non-finite floats are rejected
//!   because VTK's ASCII parser cannot read them;
//! * inline binary (`format="binary"`): per array, base64 of an 8-byte
//!   little-endian `UInt64` byte count followed by the little-endian raw
//!   data, encoded as one stream (`header_type="UInt64"`, no compression).
//!   NaN and infinities are preserved.
//!
//! Point coordinates and float data are `Float64`, connectivity and offsets
//! `Int64`, cell types `UInt8`.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;

use super::atomic::write_atomic;

/// Kind of cell written to a VTU file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CellKind {
    /// Four-node quadrilateral, `VTK_QUAD` (9).
    Quad,
    /// Two-node line segment, `VTK_LINE` (3).
    Line,
}

impl CellKind {
    /// The VTK cell type id (`VTK_QUAD` = 9, `VTK_LINE` = 3).
    pub fn vtk_type(self) -> u8 {
        match self {
            CellKind::Quad => 9,
            CellKind::Line => 3,
        }
    }

    /// Number of nodes of the cell.
    pub fn num_nodes(self) -> usize {
        match self {
            CellKind::Quad => 4,
            CellKind::Line => 2,
        }
    }
}

/// A named `Float64` data array with `components` values per tuple.
///
/// `values` is stored tuple-major: `values.len()` must equal
/// `n * components`, where `n` is the number of points (point data) or the
/// number of cells, quads first then lines (cell data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataArray<'a> {
    /// Array name shown in ParaView (unique within point or cell data).
    pub name: &'a str,
    /// Number of components per tuple (1 = scalar, 3 = vector, ...).
    pub components: usize,
    /// Flat values, `n * components` of them.
    pub values: &'a [f64],
}

/// A mesh of quads and lines with attached data, borrowed from the caller.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtuMesh<'a> {
    /// Point coordinates.
    pub points: &'a [[f64; 3]],
    /// Quadrilateral connectivity (0-based point indices, VTK node order).
    pub quads: &'a [[usize; 4]],
    /// Line connectivity; may be empty. Written after the quads.
    pub lines: &'a [[usize; 2]],
    /// Point data, one tuple per point.
    pub point_data: Vec<DataArray<'a>>,
    /// Cell data, one tuple per cell: quads first, then lines.
    pub cell_data: Vec<DataArray<'a>>,
    /// `Int32` cell data (e.g. part id, ply id), one value per cell:
    /// quads first, then lines.
    pub int_cell_data: Vec<(&'a str, Vec<i32>)>,
    /// Field data of the whole grid (VTK `FieldData`, any number of tuples), e.g. the
    /// name and thickness of each ply id.
    pub field_data: Vec<(&'a str, FieldValues)>,
}

/// Values of one field-data array.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldValues {
    /// `Float64` scalars.
    Float(Vec<f64>),
    /// `UInt8` bytes, e.g. names as UTF-8, each ended by a NUL byte (VTK's own `String`
    /// arrays are not read by meshio, so names are written as bytes).
    Bytes(Vec<u8>),
}

impl FieldValues {
    /// The strings `names` as UTF-8 bytes, each followed by a NUL byte.
    pub fn names<S: AsRef<str>>(names: &[S]) -> Self {
        FieldValues::Bytes(names.iter().flat_map(|n| n.as_ref().bytes().chain([0])).collect())
    }
}

impl VtuMesh<'_> {
    /// Total number of cells (quads + lines).
    pub fn num_cells(&self) -> usize {
        self.quads.len() + self.lines.len()
    }
}

/// Renders `mesh` as a VTU document.
///
/// `binary` selects inline base64 binary data (`format="binary"`,
/// `header_type="UInt64"`); otherwise ASCII is written.
///
/// # Errors
/// Returns a message naming the offending array or cell if an array length
/// does not match the point/cell count, a component count is zero, a name is
/// empty or duplicated, a cell references a missing point, or (ASCII only) a
/// coordinate or value is NaN or infinite.
pub fn vtu_string(mesh: &VtuMesh, binary: bool) -> Result<String, String> {
    validate(mesh, binary)?;

    let n_points = mesh.points.len();
    let n_cells = mesh.num_cells();
    let mut w = XmlOut {
        out: String::new(),
        binary,
    };

    w.out.push_str("<?xml version=\"1.0\"?>\n");
    w.out.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    w.out.push_str("  <UnstructuredGrid>\n");
    if !mesh.field_data.is_empty() {
        w.out.push_str("    <FieldData>\n");
        for (name, values) in &mesh.field_data {
            match values {
                FieldValues::Float(v) => w.array_tuples(Some(name), 1, v, Some(v.len())),
                FieldValues::Bytes(v) => w.array_tuples(Some(name), 1, v, Some(v.len())),
            }
        }
        w.out.push_str("    </FieldData>\n");
    }
    let _ = writeln!(
        w.out,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );

    // Points.
    w.out.push_str("      <Points>\n");
    let coords: Vec<f64> = mesh.points.iter().flatten().copied().collect();
    w.array(None, 3, &coords);
    w.out.push_str("      </Points>\n");

    // Cells.
    w.out.push_str("      <Cells>\n");
    let mut connectivity: Vec<i64> =
        Vec::with_capacity(4 * mesh.quads.len() + 2 * mesh.lines.len());
    let mut offsets: Vec<i64> = Vec::with_capacity(n_cells);
    let mut types: Vec<u8> = Vec::with_capacity(n_cells);
    for q in mesh.quads {
        connectivity.extend(q.iter().map(|&i| i as i64));
        offsets.push(connectivity.len() as i64);
        types.push(CellKind::Quad.vtk_type());
    }
    for l in mesh.lines {
        connectivity.extend(l.iter().map(|&i| i as i64));
        offsets.push(connectivity.len() as i64);
        types.push(CellKind::Line.vtk_type());
    }
    w.array(Some("connectivity"), 1, &connectivity);
    w.array(Some("offsets"), 1, &offsets);
    w.array(Some("types"), 1, &types);
    w.out.push_str("      </Cells>\n");

    // Point data.
    if !mesh.point_data.is_empty() {
        w.out.push_str("      <PointData>\n");
        for a in &mesh.point_data {
            w.array(Some(a.name), a.components, a.values);
        }
        w.out.push_str("      </PointData>\n");
    }

    // Cell data.
    if !mesh.cell_data.is_empty() || !mesh.int_cell_data.is_empty() {
        w.out.push_str("      <CellData>\n");
        for a in &mesh.cell_data {
            w.array(Some(a.name), a.components, a.values);
        }
        for (name, values) in &mesh.int_cell_data {
            w.array(Some(name), 1, values);
        }
        w.out.push_str("      </CellData>\n");
    }

    w.out.push_str("    </Piece>\n");
    w.out.push_str("  </UnstructuredGrid>\n");
    w.out.push_str("</VTKFile>\n");
    Ok(w.out)
}

/// Writes `mesh` to `path` as a VTU file, atomically (see
/// [`write_atomic`]).
///
/// # Errors
/// Validation failures of [`vtu_string`] are returned as
/// [`io::ErrorKind::InvalidInput`]; I/O failures are passed through.
pub fn write_vtu(path: &Path, mesh: &VtuMesh, binary: bool) -> io::Result<()> {
    let text = vtu_string(mesh, binary).map_err(|msg| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write '{}': {msg}", path.display()),
        )
    })?;
    write_atomic(path, text.as_bytes())
}

// ---------------------------------------------------------------------------
// Validation

fn validate(mesh: &VtuMesh, binary: bool) -> Result<(), String> {
    let n_points = mesh.points.len();
    let n_cells = mesh.num_cells();

    if !binary
        && let Some((i, p)) = mesh
            .points
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
    {
        return Err(format!(
            "point {i} has a non-finite coordinate {p:?}; ASCII VTU cannot store it \
             (use binary output)"
        ));
    }

    for (c, q) in mesh.quads.iter().enumerate() {
        if let Some(&bad) = q.iter().find(|&&i| i >= n_points) {
            return Err(format!(
                "quad {c} references point {bad}, but the mesh has only {n_points} points"
            ));
        }
    }
    for (c, l) in mesh.lines.iter().enumerate() {
        if let Some(&bad) = l.iter().find(|&&i| i >= n_points) {
            return Err(format!(
                "line {c} references point {bad}, but the mesh has only {n_points} points"
            ));
        }
    }

    let mut names = HashSet::new();
    for a in &mesh.point_data {
        check_float_array("point data", a, n_points, "points", binary, &mut names)?;
    }

    let cells_desc = format!(
        "cells ({} quads + {} lines)",
        mesh.quads.len(),
        mesh.lines.len()
    );
    let mut names = HashSet::new();
    for a in &mesh.cell_data {
        check_float_array("cell data", a, n_cells, &cells_desc, binary, &mut names)?;
    }
    let mut field_names = HashSet::new();
    for (name, values) in &mesh.field_data {
        check_name("field data", name, &mut field_names)?;
        if let FieldValues::Float(v) = values
            && !binary
            && let Some(x) = v.iter().find(|x| !x.is_finite())
        {
            return Err(format!("field data array '{name}' has a non-finite value {x}; ASCII VTU cannot store it (use binary output)"));
        }
    }
    for (name, values) in &mesh.int_cell_data {
        check_name("integer cell data", name, &mut names)?;
        if values.len() != n_cells {
            return Err(format!(
                "integer cell data array '{name}' has {} values, expected {n_cells} \
                 (one per cell: {cells_desc})",
                values.len()
            ));
        }
    }
    Ok(())
}

fn check_name<'a>(kind: &str, name: &'a str, seen: &mut HashSet<&'a str>) -> Result<(), String> {
    if name.trim().is_empty() {
        return Err(format!("{kind} array has an empty name"));
    }
    if !seen.insert(name) {
        return Err(format!("{kind} array name '{name}' is used more than once"));
    }
    Ok(())
}

fn check_float_array<'a>(
    kind: &str,
    a: &DataArray<'a>,
    n: usize,
    what: &str,
    binary: bool,
    seen: &mut HashSet<&'a str>,
) -> Result<(), String> {
    check_name(kind, a.name, seen)?;
    if a.components == 0 {
        return Err(format!("{kind} array '{}' has 0 components", a.name));
    }
    let expected = n
        .checked_mul(a.components)
        .ok_or_else(|| format!("{kind} array '{}': size overflow", a.name))?;
    if a.values.len() != expected {
        return Err(format!(
            "{kind} array '{}' has {} values, expected {expected} ({n} {what} x {} components)",
            a.name,
            a.values.len(),
            a.components
        ));
    }
    if !binary && let Some((i, v)) = a.values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(format!(
            "{kind} array '{}' has a non-finite value {v} at tuple {}, component {}; \
             ASCII VTU cannot store it (use binary output)",
            a.name,
            i / a.components,
            i % a.components
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Encoding helpers

/// Scalar types that can be written as a VTK `DataArray`.
trait VtkScalar: Copy {
    const VTK_TYPE: &'static str;
    fn push_le(self, buf: &mut Vec<u8>);
    fn push_ascii(self, out: &mut String);
}

impl VtkScalar for f64 {
    const VTK_TYPE: &'static str = "Float64";
    fn push_le(self, buf: &mut Vec<u8>) {
        buf.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        push_f64(out, self);
    }
}

impl VtkScalar for i64 {
    const VTK_TYPE: &'static str = "Int64";
    fn push_le(self, buf: &mut Vec<u8>) {
        buf.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

impl VtkScalar for i32 {
    const VTK_TYPE: &'static str = "Int32";
    fn push_le(self, buf: &mut Vec<u8>) {
        buf.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

impl VtkScalar for u8 {
    const VTK_TYPE: &'static str = "UInt8";
    fn push_le(self, buf: &mut Vec<u8>) {
        buf.push(self);
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

/// Formats a float so that it round-trips exactly and stays short:
/// plain notation for moderate magnitudes, exponent notation otherwise.
pub(super) fn push_f64(out: &mut String, v: f64) {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e15).contains(&a) {
        let _ = write!(out, "{v}");
    } else {
        let _ = write!(out, "{v:e}");
    }
}

/// Escapes a string for use inside a double-quoted XML attribute.
pub(super) fn xml_escape(s: &str) -> String {
    let mut r = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => r.push_str("&amp;"),
            '<' => r.push_str("&lt;"),
            '>' => r.push_str("&gt;"),
            '"' => r.push_str("&quot;"),
            '\'' => r.push_str("&apos;"),
            '\n' => r.push_str("&#10;"),
            '\r' => r.push_str("&#13;"),
            '\t' => r.push_str("&#9;"),
            _ => r.push(ch),
        }
    }
    r
}

struct XmlOut {
    out: String,
    binary: bool,
}

impl XmlOut {
    /// Writes one `<DataArray>` element (8-space indent, data at 10 spaces).
    fn array<T: VtkScalar>(&mut self, name: Option<&str>, components: usize, values: &[T]) {
        self.array_tuples(name, components, values, None);
    }

    /// [`Self::array`] with a `NumberOfTuples` attribute (required for field data).
    fn array_tuples<T: VtkScalar>(&mut self, name: Option<&str>, components: usize, values: &[T], tuples: Option<usize>) {
        let out = &mut self.out;
        let _ = write!(out, "        <DataArray type=\"{}\"", T::VTK_TYPE);
        if let Some(n) = name {
            let _ = write!(out, " Name=\"{}\"", xml_escape(n));
        }
        if let Some(t) = tuples {
            let _ = write!(out, " NumberOfTuples=\"{t}\"");
        }
        if components != 1 {
            let _ = write!(out, " NumberOfComponents=\"{components}\"");
        }
        let format = if self.binary { "binary" } else { "ascii" };
        let _ = writeln!(out, " format=\"{format}\">");

        if self.binary {
            let nbytes = std::mem::size_of_val(values);
            let mut buf = Vec::with_capacity(8 + nbytes);
            buf.extend_from_slice(&(nbytes as u64).to_le_bytes());
            for &v in values {
                v.push_le(&mut buf);
            }
            out.push_str("          ");
            STANDARD.encode_string(&buf, out);
            out.push('\n');
        } else if !values.is_empty() {
            // One tuple per line for vectors, six scalars per line otherwise.
            let per_line = if components > 1 { components } else { 6 };
            for chunk in values.chunks(per_line) {
                out.push_str("          ");
                for (k, &v) in chunk.iter().enumerate() {
                    if k > 0 {
                        out.push(' ');
                    }
                    v.push_ascii(out);
                }
                out.push('\n');
            }
        }
        out.push_str("        </DataArray>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const POINTS: [[f64; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.1],
        [2.0, 1.0, 0.0],
    ];
    const QUADS: [[usize; 4]; 2] = [[0, 1, 4, 3], [1, 2, 5, 4]];
    const LINES: [[usize; 2]; 1] = [[3, 4]];

    fn disp() -> Vec<f64> {
        (0..18).map(|i| i as f64 * 0.5 - 1.0).collect()
    }

    fn mesh<'a>(d: &'a [f64], e: &'a [f64]) -> VtuMesh<'a> {
        VtuMesh {
            points: &POINTS,
            quads: &QUADS,
            lines: &LINES,
            point_data: vec![DataArray {
                name: "displacement",
                components: 3,
                values: d,
            }],
            field_data: vec![],
            cell_data: vec![DataArray {
                name: "energy_density",
                components: 1,
                values: e,
            }],
            int_cell_data: vec![("part", vec![1, 2, 7])],
        }
    }

    /// Extracts the text content of the DataArray with the given attribute
    /// snippet (e.g. `Name="offsets"`).
    fn array_text<'s>(doc: &'s str, key: &str) -> &'s str {
        let start = doc.find(key).expect("array present");
        let body = &doc[start..];
        let open_end = body.find('>').expect("tag end") + 1;
        let close = body.find("</DataArray>").expect("close tag");
        body[open_end..close].trim()
    }

    fn decode(text: &str) -> Vec<u8> {
        let raw = STANDARD.decode(text).expect("valid base64");
        let n = u64::from_le_bytes(raw[..8].try_into().expect("8 bytes")) as usize;
        assert_eq!(raw.len(), 8 + n, "header byte count matches payload");
        raw[8..].to_vec()
    }

    #[test]
    fn ascii_layout() {
        let d = disp();
        let e = [1.5, 2.5e-7, 3.0];
        let s = vtu_string(&mesh(&d, &e), false).expect("valid");
        assert!(s.contains("NumberOfPoints=\"6\" NumberOfCells=\"3\""));
        assert_eq!(
            array_text(&s, "Name=\"connectivity\""),
            "0 1 4 3 1 2\n          5 4 3 4"
        );
        assert_eq!(array_text(&s, "Name=\"offsets\""), "4 8 10");
        assert_eq!(array_text(&s, "Name=\"types\""), "9 9 3");
        assert_eq!(array_text(&s, "Name=\"energy_density\""), "1.5 2.5e-7 3");
        assert_eq!(array_text(&s, "Name=\"part\""), "1 2 7");
        assert!(s.contains("<DataArray type=\"Int32\" Name=\"part\" format=\"ascii\">"));
        assert!(s.contains(
            "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">"
        ));
        // Values round-trip.
        let parsed: Vec<f64> = array_text(&s, "Name=\"displacement\"")
            .split_whitespace()
            .map(|t| t.parse().expect("float"))
            .collect();
        assert_eq!(parsed, d);
    }

    #[test]
    fn binary_layout() {
        let d = disp();
        let e = [1.5, f64::NAN, -3.0];
        let s = vtu_string(&mesh(&d, &e), true).expect("valid");
        assert!(s.contains("header_type=\"UInt64\""));
        assert!(!s.contains("format=\"ascii\""));
        let conn = decode(array_text(&s, "Name=\"connectivity\""));
        let conn: Vec<i64> = conn
            .chunks(8)
            .map(|c| i64::from_le_bytes(c.try_into().expect("8")))
            .collect();
        assert_eq!(conn, vec![0, 1, 4, 3, 1, 2, 5, 4, 3, 4]);
        assert_eq!(decode(array_text(&s, "Name=\"types\"")), vec![9, 9, 3]);
        let ed: Vec<f64> = decode(array_text(&s, "Name=\"energy_density\""))
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8")))
            .collect();
        assert_eq!(ed[0], 1.5);
        assert!(ed[1].is_nan());
        assert_eq!(ed[2], -3.0);
        let part: Vec<i32> = decode(array_text(&s, "Name=\"part\""))
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().expect("4")))
            .collect();
        assert_eq!(part, vec![1, 2, 7]);
    }

    #[test]
    fn float_format_round_trips() {
        for v in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1e-4,
            9.99e-5,
            1e15,
            123456.789,
            -2.5e-300,
            f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            let mut s = String::new();
            push_f64(&mut s, v);
            assert!(s.len() < 30, "{s}");
            assert_eq!(s.parse::<f64>().expect("parse"), v, "{s}");
        }
    }

    #[test]
    fn validation_messages_name_the_array() {
        let d = disp();
        let e = [1.0, 2.0, 3.0];

        let short = &d[..17];
        let err = vtu_string(&mesh(short, &e), true).expect_err("short point data");
        assert!(
            err.contains("'displacement'") && err.contains("expected 18"),
            "{err}"
        );

        let err = vtu_string(&mesh(&d, &e[..2]), true).expect_err("short cell data");
        assert!(
            err.contains("'energy_density'") && err.contains("expected 3"),
            "{err}"
        );

        let mut m = mesh(&d, &e);
        m.int_cell_data[0].1.pop();
        let err = vtu_string(&m, false).expect_err("short int data");
        assert!(err.contains("'part'"), "{err}");

        let mut m = mesh(&d, &e);
        m.cell_data.push(DataArray {
            name: "part",
            components: 1,
            values: &e,
        });
        let err = vtu_string(&m, false).expect_err("duplicate");
        assert!(
            err.contains("'part'") && err.contains("more than once"),
            "{err}"
        );

        let mut m = mesh(&d, &e);
        m.point_data[0].components = 0;
        assert!(
            vtu_string(&m, false)
                .expect_err("0 comps")
                .contains("0 components")
        );

        let bad_quads = [[0, 1, 4, 6]];
        let mut m = mesh(&d, &e);
        m.quads = &bad_quads;
        let err = vtu_string(&m, false).expect_err("bad index");
        assert!(err.contains("quad 0") && err.contains("point 6"), "{err}");

        let e_nan = [1.0, f64::INFINITY, 3.0];
        let err = vtu_string(&mesh(&d, &e_nan), false).expect_err("nan in ascii");
        assert!(
            err.contains("'energy_density'") && err.contains("tuple 1"),
            "{err}"
        );
        assert!(vtu_string(&mesh(&d, &e_nan), true).is_ok());
    }

    #[test]
    fn empty_mesh_and_escaping() {
        let e: [f64; 0] = [];
        let m = VtuMesh {
            point_data: vec![DataArray {
                name: "a<&\"b\">",
                components: 2,
                values: &e,
            }],
            ..Default::default()
        };
        for binary in [false, true] {
            let s = vtu_string(&m, binary).expect("valid");
            assert!(s.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""));
            assert!(s.contains("Name=\"a&lt;&amp;&quot;b&quot;&gt;\""));
            assert!(!s.contains("<CellData>"));
        }
    }

    #[test]
    fn write_vtu_reports_invalid_input() {
        let d = disp();
        let e = [1.0];
        let p = std::env::temp_dir().join(format!("plyshell_vtu_bad_{}.vtu", std::process::id()));
        let err = write_vtu(&p, &mesh(&d, &e), true).expect_err("invalid");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(!p.exists());
    }
}
