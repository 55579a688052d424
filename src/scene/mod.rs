//! Scene files: format, parsing with located errors, and building the model.

mod build;
mod error;
mod fabric_spec;
mod names;
mod path;
pub mod protocol;
mod spec;

pub use build::{build, BuiltScene, Monitor};
pub use error::{Locator, SceneError};
pub use spec::*;

use std::path::Path;

/// Largest scene file read (64 MiB): scenes are hand-written text.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;

/// Parses scene text; `file` names it in errors. A leading UTF-8 byte-order mark is
/// skipped (columns count from after it).
pub fn parse(file: &str, text: &str) -> Result<Scene, SceneError> {
    let text = strip_bom(text);
    let loc = Locator::new(file, text);
    let scene = ron::Options::default().from_str::<Scene>(text).map_err(|e| loc.from_ron(&e))?;
    names::check(&scene, &loc)?;
    Ok(scene)
}

/// `text` without a leading UTF-8 byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Scene text from the bytes of `file`: UTF-8 (a byte-order mark allowed), else an error at
/// the line, column and byte offset of the first invalid byte.
pub fn decode(file: &str, bytes: Vec<u8>) -> Result<String, SceneError> {
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let before = &bytes[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        let column = String::from_utf8_lossy(&before[line_start..]).chars().count() + 1;
        SceneError {
            file: file.to_string(),
            line,
            column,
            field: "encoding".into(),
            message: format!("invalid UTF-8 at byte offset {at} (byte 0x{:02x}); scene files must be UTF-8 text", bytes[at]),
        }
    })
}

/// Reads, parses and builds the scene at `path`.
pub fn load(path: &Path) -> Result<(Scene, BuiltScene), SceneError> {
    let file = path.display().to_string();
    let unreadable = |message: String| SceneError { file: file.clone(), line: 0, column: 0, field: "file".into(), message };
    let meta = std::fs::metadata(path).map_err(|e| unreadable(format!("cannot read the scene file: {e}")))?;
    if !meta.is_file() {
        return Err(unreadable("cannot read the scene file: not a regular file".into()));
    }
    if meta.len() > MAX_SCENE_BYTES {
        return Err(unreadable(format!("the scene file has {} bytes; scene files are limited to {MAX_SCENE_BYTES} bytes", meta.len())));
    }
    let bytes = std::fs::read(path).map_err(|e| unreadable(format!("cannot read the scene file: {e}")))?;
    let text = decode(&file, bytes)?;
    let text = strip_bom(&text);
    let scene = parse(&file, text)?;
    let built = build(&scene, &file, text)?;
    Ok((scene, built))
}
