//! ParaView Data collection (`.pvd`) writer for time series of VTU files.

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::atomic::write_atomic;
use super::vtu::{push_f64, xml_escape};

/// Renders a ParaView collection listing `(timestep, file)` entries.
///
/// File names are written as given; ParaView resolves relative names
/// against the directory of the `.pvd` file. Entries are written in the
/// given order (ParaView sorts by timestep itself).
///
/// # Errors
/// Returns a message if a timestep is NaN or infinite or a file name is
/// empty.
pub fn pvd_string(entries: &[(f64, String)]) -> Result<String, String> {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <Collection>\n");
    for (i, (t, file)) in entries.iter().enumerate() {
        if !t.is_finite() {
            return Err(format!(
                "PVD entry {i} ('{file}') has a non-finite timestep {t}"
            ));
        }
        if file.trim().is_empty() {
            return Err(format!(
                "PVD entry {i} (timestep {t}) has an empty file name"
            ));
        }
        out.push_str("    <DataSet timestep=\"");
        push_f64(&mut out, *t);
        let _ = writeln!(
            out,
            "\" group=\"\" part=\"0\" file=\"{}\"/>",
            xml_escape(file)
        );
    }
    out.push_str("  </Collection>\n");
    out.push_str("</VTKFile>\n");
    Ok(out)
}

/// Writes a ParaView collection file to `path`, atomically (see
/// [`write_atomic`]). `entries` are `(timestep, file name relative to the
/// .pvd file)`.
///
/// # Errors
/// Invalid entries (see [`pvd_string`]) give
/// [`io::ErrorKind::InvalidInput`]; I/O failures are passed through.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> io::Result<()> {
    let text = pvd_string(entries).map_err(|msg| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write '{}': {msg}", path.display()),
        )
    })?;
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collection_layout() {
        let entries = vec![
            (0.0, "step_0000.vtu".to_string()),
            (0.25, "step_0001.vtu".to_string()),
            (1e-9, "a&b.vtu".to_string()),
        ];
        let s = pvd_string(&entries).expect("valid");
        assert!(s.contains("type=\"Collection\""));
        assert!(
            s.contains("<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"step_0000.vtu\"/>")
        );
        assert!(s.contains("timestep=\"0.25\""));
        assert!(s.contains("timestep=\"1e-9\" group=\"\" part=\"0\" file=\"a&amp;b.vtu\""));
        assert_eq!(s.matches("<DataSet").count(), 3);
    }

    #[test]
    fn empty_collection_is_valid() {
        let s = pvd_string(&[]).expect("valid");
        assert!(s.contains("<Collection>\n  </Collection>"));
    }

    #[test]
    fn rejects_bad_entries() {
        assert!(pvd_string(&[(f64::NAN, "x.vtu".into())]).is_err());
        assert!(pvd_string(&[(1.0, " ".into())]).is_err());
        let p = std::env::temp_dir().join(format!("plyshell_pvd_bad_{}.pvd", std::process::id()));
        let err = write_pvd(&p, &[(f64::INFINITY, "x.vtu".into())]).expect_err("invalid");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(!p.exists());
    }
}
