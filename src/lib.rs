//! plyshell: nonlinear shell finite elements for layered protective garments.

pub mod element;
pub mod mesh;
pub mod material;
pub mod assembly;
pub mod model;
pub mod solver;
pub mod scene;
pub mod analysis;
pub mod io;
pub mod results;
pub mod bench;
