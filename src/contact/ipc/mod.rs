//! Incremental-potential contact between shell surfaces: primitive distances and their
//! closed-form derivatives, broad phase and the barrier/friction term.

mod blocks;
pub mod broad_phase;
pub mod distance;
mod friction;
mod potential;
pub mod primitives;
mod report;
mod settings;
pub mod surface;

pub(crate) use potential::FxMap;
pub use surface::{attach, SurfaceContact, SurfaceIncrement, SurfaceSettings, SurfaceSetup, SurfaceTimings};
