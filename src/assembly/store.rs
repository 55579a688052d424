//! Per-element storage of an assembly that outlives it: the element responses kept for a
//! re-assembly of the same state, and the mixed-integration-point stress records
//! (`element::mixed`).

use nalgebra::Vector3;

use crate::element::mixed::PointRecord;
use crate::element::{DirectorFrame, ElemMat, ElemVec};
use crate::model::State;

/// Largest model whose element responses [`Assembler::keep_responses`] keeps (about 3.4 KB
/// per element: 56 MB).
pub const CACHE_ELEMENTS: usize = 16_384;

/// One element's force, energy and unprojected tangent.
pub(super) type Response = (ElemVec, f64, ElemMat);

/// Element responses of the last tangent assembly and a copy of its state.
#[derive(Debug, Default)]
pub(super) struct ResponseCache {
    /// Whether `items` holds the responses of every element at `u`, `frames`.
    pub(super) valid: bool,
    pub(super) u: Vec<nalgebra::Vector3<f64>>,
    pub(super) frames: Vec<crate::element::DirectorFrame>,
    pub(super) items: Vec<Response>,
}

impl ResponseCache {
    /// Whether `state` is bit for bit the state of the kept responses.
    pub(super) fn holds(&self, state: &State) -> bool {
        let same = |a: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>| a.iter().zip(b.iter()).all(|(x, y)| x.to_bits() == y.to_bits());
        self.valid
            && self.u.len() == state.u.len()
            && self.frames.len() == state.frames.len()
            && self.u.iter().zip(&state.u).all(|(a, b)| same(a, b))
            && self.frames.iter().zip(&state.frames).all(|(a, b)| same(&a.d, &b.d) && same(&a.t1, &b.t1) && same(&a.t2, &b.t2))
    }
}

/// A pointer to the kept responses, written by the tasks of an assembly at disjoint elements.
#[derive(Clone, Copy)]
pub(super) struct ResponsePtr(pub(super) *mut Response);

// SAFETY: each element's entry is read or written by the one task that evaluates the element.
unsafe impl Send for ResponsePtr {}
// SAFETY: as above.
unsafe impl Sync for ResponsePtr {}

impl ResponsePtr {
    /// Pointer to element e's entry (dereferenced only for e below the cache's length).
    pub(super) fn entry(self, e: usize) -> *mut Response {
        self.0.wrapping_add(e)
    }
}

/// Largest number of integration points per element for which mixed stresses are kept.
pub(super) const MAX_MIXED_POINTS: usize = 64;

/// Configuration of an element's nodes (displacements and director frames).
pub(super) type ElementConfiguration = ([Vector3<f64>; 4], [DirectorFrame; 4]);

/// Mixed-integration-point stress records of every element.
#[derive(Debug, Default)]
pub(super) struct MixedStore {
    /// First record of each element in `records` (n_el + 1 entries).
    pub(super) offsets: Vec<usize>,
    /// Per integration point, the last tangent evaluation's [`PointRecord`].
    pub(super) records: Vec<PointRecord>,
    /// The configuration of each element at its record (None: no valid record).
    pub(super) at: Vec<Option<ElementConfiguration>>,
}

/// Raw access to the [`MixedStore`] of one assembly, shared by the threads of a colour
/// (each element touches only its own records).
#[derive(Clone, Copy)]
pub(super) struct MixedAccess<'a> {
    pub(super) offsets: &'a [usize],
    pub(super) records: *mut PointRecord,
    pub(super) at: *mut Option<ElementConfiguration>,
}

// SAFETY: the pointers come from a store locked for the whole assembly, and every element
// touches only its own records and configuration (disjoint ranges).
unsafe impl Send for MixedAccess<'_> {}
// SAFETY: as for Send.
unsafe impl Sync for MixedAccess<'_> {}
