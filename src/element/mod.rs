//! The 4-node degenerated shell element and its pieces: kinematic vectors and director
//! chain (`kinematics`), integration rule and reference geometry (`rule`), tangent
//! assembly (`tangent`), MITC4+ assumed membrane strains (`membrane`), the director
//! orientation barrier (`orientation`), and the element itself (`shell4`).

pub mod director;
mod kinematics;
mod membrane;
pub mod mixed;
pub mod orientation;
pub mod quadrature;
mod rule;
pub mod shell4;
mod tangent;

pub use director::DirectorFrame;
pub use shell4::{ElemMat, ElemVec, ElementFailure, ElementGeometry, ElementOutput, Section, SectionRule, ShearTreatment, ShellElement};

/// Unknowns per node: three translations and the two director tilts (α1, α2).
pub const NODE_DOFS: usize = 5;
/// Unknowns per element.
pub const ELEMENT_DOFS: usize = 4 * NODE_DOFS;
