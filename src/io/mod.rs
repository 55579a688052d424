//! Output files: VTU/PVD for ParaView and meshio, SVG plots, atomic writes.

pub mod atomic;
pub mod export;
pub mod gltf;
pub mod inp;
pub mod modes;
pub mod obj;
pub mod plot;
pub mod png;
pub mod pvd;
pub mod raster;
pub mod surface;
pub mod vtu;
