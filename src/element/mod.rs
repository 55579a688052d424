//! The 4-node degenerated shell element and its pieces.

pub mod director;
pub mod quadrature;
pub mod shell4;

pub use director::DirectorFrame;
pub use shell4::{ElemMat, ElementFailure, ElementGeometry, ElementOutput, Section, SectionRule, ShearTreatment, ShellElement};

/// Unknowns per node: three translations and the two director tilts (α1, α2).
pub const NODE_DOFS: usize = 5;
/// Unknowns per element.
pub const ELEMENT_DOFS: usize = 4 * NODE_DOFS;
