//! Scene files: format, parsing with located errors, and building the model.

mod build;
mod fabric_spec;
mod names;
mod path;
pub mod protocol;
pub mod sequence;
mod spec;
mod sizing;
mod steps;

pub use build::{build, build_sized, BuiltScene};
pub use crate::results::Monitor;
pub use crate::input::{decode, strip_bom, Locator, SceneError, MAX_SCENE_BYTES};
pub use spec::*;

use std::path::Path;

/// Parses scene text; `file` names it in errors. A leading UTF-8 byte-order mark is
/// skipped (columns count from after it).
pub fn parse(file: &str, text: &str) -> Result<Scene, SceneError> {
    let text = strip_bom(text);
    let loc = Locator::new(file, text);
    let scene = ron::Options::default().from_str::<Scene>(text).map_err(|e| loc.from_ron(&e))?;
    names::check(&scene, &loc)?;
    Ok(scene)
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
