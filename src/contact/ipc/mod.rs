//! Incremental-potential contact between shell surfaces: primitive distances (derived with
//! `crate::autodiff`), broad phase and the barrier/friction term.

pub mod broad_phase;
mod friction;
mod potential;
pub mod primitives;
mod report;
mod settings;
pub mod surface;

pub use surface::{attach, SurfaceContact, SurfaceIncrement, SurfaceSettings, SurfaceSetup, SurfaceTimings};
