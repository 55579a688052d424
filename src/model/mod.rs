//! The discrete model: nodes, elements, sections, degrees of freedom and loads.
//!
//! Global unknown numbering: node n owns DOFs 5n..5n+5 = (ux, uy, uz, α1, α2), the tilts
//! taken in the node's current director frame. Fixed and prescribed DOFs are removed from
//! the equation system; the rest are numbered 0..n_free.

use nalgebra::Vector3;

use crate::element::{DirectorFrame, Section, ShellElement, NODE_DOFS};

/// Marker for a DOF that has no equation (fixed or prescribed).
pub const FIXED: usize = usize::MAX;

/// One shell element of the model.
#[derive(Clone, Debug)]
pub struct ElementDef {
    /// Global node numbers, counter-clockwise about the director.
    pub nodes: [usize; 4],
    /// Index into [`Model::sections`].
    pub section: usize,
    /// Index into [`Model::parts`].
    pub part: usize,
    /// Material grain direction (lamina e1), if any.
    pub grain: Option<Vector3<f64>>,
}

/// Where a part's nodes and elements sit in the global numbering.
#[derive(Clone, Debug)]
pub struct PartInfo {
    /// Part name from the scene.
    pub name: String,
    /// First global node.
    pub first_node: usize,
    /// Number of nodes.
    pub n_nodes: usize,
    /// First global element.
    pub first_element: usize,
    /// Number of elements.
    pub n_elements: usize,
    /// Mass per reference area (0: massless), for lumped masses.
    pub areal_density: f64,
}

/// A named load pattern; its magnitude is scaled by the step's factor for this name.
#[derive(Clone, Debug)]
pub struct Load {
    /// Name used by the steps' scale tables.
    pub name: String,
    /// What the pattern applies at unit scale.
    pub kind: LoadKind,
}

/// Kinds of load pattern, all given at unit scale.
#[derive(Clone, Debug)]
pub enum LoadKind {
    /// Dead forces on node translations.
    Forces(Vec<(usize, Vector3<f64>)>),
    /// Moments on nodes about fixed global axes (virtual work m·δω, δω = d × δd).
    Moments(Vec<(usize, Vector3<f64>)>),
    /// Prescribed translations: (global DOF, value).
    Displacements(Vec<(usize, f64)>),
}

/// Numbering of the free DOFs.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Equation number of each global DOF, or [`FIXED`].
    pub eq: Vec<usize>,
    /// Number of equations.
    pub n_free: usize,
}

impl DofMap {
    /// Numbers every DOF not flagged in `fixed`.
    pub fn new(fixed: &[bool]) -> Self {
        let mut n_free = 0;
        let eq = fixed
            .iter()
            .map(|&f| {
                if f {
                    FIXED
                } else {
                    n_free += 1;
                    n_free - 1
                }
            })
            .collect();
        Self { eq, n_free }
    }
}

/// Current configuration: mid-surface displacements and director frames. Displacements,
/// not positions, are stored so that small strains are computed without cancellation.
#[derive(Clone, Debug)]
pub struct State {
    /// Node displacements from the reference positions.
    pub u: Vec<Vector3<f64>>,
    /// Current director frames.
    pub frames: Vec<DirectorFrame>,
}

/// The assembled finite-element model.
#[derive(Clone, Debug)]
pub struct Model {
    /// Reference node positions.
    pub x0: Vec<Vector3<f64>>,
    /// Reference director frames (tangent pairs aligned with any tilt constraints).
    pub frames0: Vec<DirectorFrame>,
    /// Elements.
    pub elements: Vec<ElementDef>,
    /// Sections.
    pub sections: Vec<Section>,
    /// Parts.
    pub parts: Vec<PartInfo>,
    /// Free-DOF numbering.
    pub dofs: DofMap,
    /// Load patterns.
    pub loads: Vec<Load>,
}

impl Model {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    /// The reference state.
    pub fn initial_state(&self) -> State {
        State { u: vec![Vector3::zeros(); self.x0.len()], frames: self.frames0.clone() }
    }

    /// Element `e` as a shell element view.
    pub fn element(&self, e: usize) -> ShellElement<'_> {
        let def = &self.elements[e];
        ShellElement {
            x0: def.nodes.map(|n| self.x0[n]),
            d0: def.nodes.map(|n| self.frames0[n].d),
            grain: def.grain,
            section: &self.sections[def.section],
        }
    }

    /// Index of a load pattern by name.
    pub fn load_index(&self, name: &str) -> Option<usize> {
        self.loads.iter().position(|l| l.name == name)
    }

    /// External generalised force (all DOFs) for load scales `scales` (one per pattern) in
    /// configuration `state` (moments map to tilt forces through the current frames).
    pub fn external_force(&self, state: &State, scales: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (load, &s) in self.loads.iter().zip(scales) {
            if s == 0.0 {
                continue;
            }
            match &load.kind {
                LoadKind::Forces(list) => {
                    for (n, f) in list {
                        for k in 0..3 {
                            out[NODE_DOFS * n + k] += s * f[k];
                        }
                    }
                }
                LoadKind::Moments(list) => {
                    for (n, m) in list {
                        let t = state.frames[*n].moment_to_tilt_forces(&(m * s));
                        out[NODE_DOFS * n + 3] += t[0];
                        out[NODE_DOFS * n + 4] += t[1];
                    }
                }
                LoadKind::Displacements(_) => {}
            }
        }
    }

    /// Sets prescribed translations to their values at load scales `scales`.
    pub fn apply_prescribed(&self, state: &mut State, scales: &[f64]) {
        for (load, &s) in self.loads.iter().zip(scales) {
            if let LoadKind::Displacements(list) = &load.kind {
                for &(dof, v) in list {
                    let (n, k) = (dof / NODE_DOFS, dof % NODE_DOFS);
                    state.u[n][k] = s * v;
                }
            }
        }
    }

    /// Adds `step` × the free-DOF increment `du` to `state` (translations added, tilts
    /// applied with the exponential map).
    pub fn update(&self, state: &mut State, du: &[f64], step: f64) {
        let eq = &self.dofs.eq;
        for n in 0..self.n_nodes() {
            let base = NODE_DOFS * n;
            for k in 0..3 {
                if eq[base + k] != FIXED {
                    state.u[n][k] += step * du[eq[base + k]];
                }
            }
            let a1 = if eq[base + 3] != FIXED { step * du[eq[base + 3]] } else { 0.0 };
            let a2 = if eq[base + 4] != FIXED { step * du[eq[base + 4]] } else { 0.0 };
            if a1 != 0.0 || a2 != 0.0 {
                state.frames[n] = state.frames[n].tilted([a1, a2]);
            }
        }
    }

    /// Displacement of node `n` in `state`.
    pub fn displacement(&self, state: &State, n: usize) -> Vector3<f64> {
        state.u[n]
    }

    /// Current position of node `n` in `state`.
    pub fn position(&self, state: &State, n: usize) -> Vector3<f64> {
        self.x0[n] + state.u[n]
    }
}
