//! Scene files: format, parsing with located errors, and building the model.

mod build;
mod error;
mod fabric_spec;
mod path;
mod spec;

pub use build::{build, BuiltScene, Monitor};
pub use error::{Locator, SceneError};
pub use spec::*;

use std::path::Path;

/// Parses scene text; `file` names it in errors.
pub fn parse(file: &str, text: &str) -> Result<Scene, SceneError> {
    let loc = Locator::new(file, text);
    ron::Options::default().from_str::<Scene>(text).map_err(|e| loc.from_ron(&e))
}

/// Reads, parses and builds the scene at `path`.
pub fn load(path: &Path) -> Result<(Scene, BuiltScene), SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        line: 0,
        column: 0,
        field: "file".into(),
        message: format!("cannot read the scene file: {e}"),
    })?;
    let scene = parse(&file, &text)?;
    let built = build(&scene, &file, &text)?;
    Ok((scene, built))
}
