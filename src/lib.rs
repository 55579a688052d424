//! plyshell: nonlinear shell finite elements for layered protective garments.

pub mod element;
pub mod material;
