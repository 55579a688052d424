//! Output files: VTU/PVD for ParaView and meshio, SVG plots, atomic writes.

pub mod atomic;
pub mod export;
pub mod modes;
pub mod plot;
pub mod pvd;
pub mod vtu;
