//! Geometrically nonlinear 4-node degenerated shell (total Lagrangian).
//!
//! Geometry (Ahmad, Irons & Zienkiewicz 1970; Hughes 2000 ch. 6; the seed note):
//! x(ξ,η,ζ) = Σ N_a(ξ,η) [x̄_a + ζ h/2 d_a], X likewise with the reference directors D_a.
//! Fibres stay straight and unstretched (Mindlin–Reissner); the stress normal to the lamina
//! vanishes (plane stress, handled by the material). Strains are Green–Lagrange,
//! E_ij = ½(g_i·g_j − G_i·G_j) in the convected basis, transformed to the local Cartesian
//! lamina basis (e1, e2 in the lamina ζ = const, e3 normal to it) of the reference state.
//!
//! Transverse shear: either MITC4 assumed covariant shear strains (Dvorkin & Bathe 1984),
//! E_ξζ = ½(1−η) E_ξζ(0,−1) + ½(1+η) E_ξζ(0,1), E_ηζ = ½(1−ξ) E_ηζ(−1,0) + ½(1+ξ) E_ηζ(1,0),
//! or selective reduced integration (SRI, the seed note): the covariant shear strains are
//! taken at the element centre, which for a parallelogram equals one-point integration of
//! the shear energy.
//!
//! In-plane shear: the lamina's in-plane shear strain 2E12 is sampled at the element centre
//! (ξ = η = 0, same ζ) and used at its four in-plane points, while E11, E22 and the
//! transverse shears stay at the points — selective reduced integration of the in-plane
//! shear (Hughes 2000, ch. 4, selective reduced integration; MacNeal 1994, Finite Elements:
//! Their Design and Performance, on parasitic shear). It removes
//! the parasitic in-plane shear of the bilinear membrane in in-plane bending (a 12×2 strip:
//! 0.74 → 0.98 of beam theory), without spurious modes (E11, E22 at 2×2 points still
//! resist the two hourglass modes). All points of an element share one lamina direction e1
//! (the grain, or ∂X/∂ξ at the centre, projected into each lamina), so a uniform strain
//! field has the same components everywhere and the membrane patch test still holds.
//!
//! Membrane strains: displacement-based (`Mitc4`, `Sri`), or the MITC4+ assumed membrane
//! strains of Ko, Lee & Bathe (2017) tied at the edge midpoints and the centre (`Mitc4Plus`,
//! `Mitc4PlusCentre`; see `membrane`), which free curved and distorted elements from
//! membrane locking. `Mitc4Plus` takes the in-plane shear from the assumed field at each
//! point, as the paper; `Mitc4PlusCentre` samples it at the centre as above.
//!
//! Director gradients (geodesic interpolation): along each element edge the director field
//! is taken as the great-circle (SLERP) arc between the two unit nodal directors; its
//! derivative at the edge midpoint is E = θ v/|v| = φ v with v = d_b − d_a, θ the angle
//! between the directors and φ = asin(|v|/2)/(|v|/2). The in-plane director gradients
//! d,ξ = ¼(1−η) E_ξ⁻ + ¼(1+η) E_ξ⁺ and d,η likewise blend these edge-midpoint values as the
//! bilinear interpolation blends its edge differences d_b − d_a (which it recovers when
//! φ = 1). With linearly interpolated directors an element bent by Δθ measures a curvature
//! proportional to 2 sin(Δθ/2) and its moment to sin Δθ, so nodal rotations come out
//! (1 + Δθ²/6) too large; the geodesic gradient measures Δθ exactly for uniform bending
//! (the constant curvature of a two-node geometrically exact beam element built on relative
//! rotations, Crisfield & Jelenić 1999, Proc. R. Soc. A 455, 1125), is objective (E
//! rotates with a rigid rotation of the directors) and reduces to the bilinear form at
//! equal directors, so flat-element stiffness, patch tests and zero-energy modes are those of
//! the standard element.
//!
//! Every strain component is a sum of terms ½(p·q − P·Q) with p, q linear in twelve
//! kinematic vectors (positions x̄_a, directors d_a, edge gradients E_k), so the residual and
//! the consistent tangent BᵀDB + Σ S ∂²E (material + geometric part, with ∂²d = −(δα·Δα) d
//! from the exponential director map and the second derivative of E(v)) follow exactly from
//! one small set of coefficients.

use std::sync::Arc;

use nalgebra::{SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};

use super::director::DirectorFrame;
use super::kinematics::{Kinematics, NV};
use super::membrane::MembraneState;
use super::mixed::{point_count, Mixed};
use super::quadrature::{bilinear, gauss_legendre};
use super::rule::{Comp, RulePoint, MAX_FORMS, MAX_PAIRS};
pub use super::rule::{ElementGeometry, SectionRule};
use super::tangent::{add_geometric_tangent, add_pair_forces, add_resultant_forces, add_upper_btc, mirror_into, symmetric_part, Row, Upper};
use super::ELEMENT_DOFS;
use crate::material::{MaterialFailure, ShellMaterial, Voigt5};

/// Element residual vector (20).
pub type ElemVec = SVector<f64, ELEMENT_DOFS>;
/// Element tangent matrix (20×20).
pub type ElemMat = SMatrix<f64, ELEMENT_DOFS, ELEMENT_DOFS>;


/// Element formulation against locking: the transverse shear treatment and, for
/// `Mitc4Plus` and `Mitc4PlusCentre`, assumed membrane strains.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ShearTreatment {
    /// MITC4 assumed natural shear strains (Dvorkin & Bathe 1984). No spurious modes.
    #[default]
    Mitc4,
    /// Selective reduced integration: shear strains sampled at the element centre.
    Sri,
    /// MITC4+ (Ko, Lee & Bathe 2017): MITC4 transverse shear plus assumed membrane strains
    /// tied at the edge midpoints and the centre, against membrane locking of curved and
    /// distorted elements (see `membrane`). The lamina's in-plane shear comes from the
    /// assumed field at each point, as in the paper.
    Mitc4Plus,
    /// `Mitc4Plus` with the lamina's in-plane shear sampled at the element centre, as `Mitc4`
    /// does: the assumed membrane strains of MITC4+ without the parasitic in-plane shear of
    /// the bilinear membrane in in-plane bending (on rectangles it equals `Mitc4` in linear
    /// analysis). Not the default: run as the default through the whole test suite it
    /// failed three cases that `Mitc4` passes — the strip twisted through 720° (80×4; strain
    /// energy at 90° +3.8 % against the 2 % tolerance, +13.5 % at 720°: the Wagner stretch
    /// E_xx = ½κ²y² varies quadratically across each element, and the tied ê_ξξ, linear
    /// between the edge midpoints, is its chord; the axial force it gives, ∝ ∫E_xx dy, is
    /// +12.7 % at 90°, the chord's +12.5 % at four elements across, and +3.3 % and +1.0 % at
    /// eight and sixteen, where `Mitc4` is within 0.2 %), the
    /// perfect 16×16 plate under compression (linearized buckling at 0.996 N_cr, below the
    /// analytic value, where `Mitc4` gives 1.002 and the test expects no negative pivot up
    /// to N_cr), and the free 16×16 SVK sheet dropped on a sphere with barrier contact (not
    /// at rest after 5000 time steps; it rests since the director orientation barrier,
    /// `orientation`, merged after that run).
    Mitc4PlusCentre,
}

impl ShearTreatment {
    /// Whether the formulation uses the MITC4+ assumed membrane strains.
    pub fn assumed_membrane(self) -> bool {
        matches!(self, ShearTreatment::Mitc4Plus | ShearTreatment::Mitc4PlusCentre)
    }
}

/// Shell section: thickness, integration and material of a set of elements.
#[derive(Clone, Debug)]
pub struct Section {
    /// Shell thickness h.
    pub thickness: f64,
    /// Transverse shear treatment.
    pub shear: ShearTreatment,
    /// Gauss points through the thickness (1–5).
    pub thickness_points: usize,
    /// Lamina material.
    pub material: Arc<dyn ShellMaterial>,
}

/// Why an element could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum ElementFailure {
    /// The reference geometry is degenerate at an integration point (det J ≤ 0).
    Geometry { det_j: f64 },
    /// The material failed at an integration point.
    Material(MaterialFailure),
    /// The section asks for an unsupported number of thickness points.
    ThicknessRule(usize),
    /// Two directors of one element are (nearly) opposite: |d_b − d_a| = `chord` ≥ 2, so the
    /// geodesic between them is undefined.
    DirectorSpread { chord: f64 },
    /// A nodal director has reached the tangent plane of an element corner: its cosine with
    /// the corner normal (signed by the reference) is `cosine` ≤ 0 (see `orientation`).
    DirectorThroughSurface { cosine: f64 },
}

impl std::fmt::Display for ElementFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementFailure::Geometry { det_j } => write!(f, "degenerate reference geometry (det J = {det_j:.3e})"),
            ElementFailure::Material(m) => write!(f, "{m}"),
            ElementFailure::ThicknessRule(n) => write!(f, "{n} thickness points (1 to 5 supported)"),
            ElementFailure::DirectorSpread { chord } => write!(f, "directors of neighbouring nodes nearly opposite (|d_b − d_a| = {chord:.6})"),
            ElementFailure::DirectorThroughSurface { cosine } => write!(f, "a director reached the element's tangent plane (cosine with the corner normal {cosine:.3e})"),
        }
    }
}

/// Residual, tangent and energy of one element.
#[derive(Clone, Debug)]
pub struct ElementOutput {
    /// Internal force vector (per node: force, then tilt generalised forces).
    pub force: ElemVec,
    /// Consistent tangent (material + geometric), when requested.
    pub stiffness: Option<Box<ElemMat>>,
    /// Stored strain energy.
    pub energy: f64,
}

/// Number of kinematic vectors of an element state: 4 mid-surface positions x̄_a, 4 unit
/// The 4-node shell element: reference geometry and section.
#[derive(Clone, Debug)]
pub struct ShellElement<'a> {
    /// Reference mid-surface node positions.
    pub x0: [Vector3<f64>; 4],
    /// Reference unit directors.
    pub d0: [Vector3<f64>; 4],
    /// In-plane reference direction of the lamina basis e1 (material grain); None = ∂X/∂ξ.
    pub grain: Option<Vector3<f64>>,
    /// Section.
    pub section: &'a Section,
}

/// Natural strain components [E_ξξ, E_ηη, E_ξη, E_ξζ, E_ηζ] of a point from the pair strains
/// `e` of its level.
#[inline(always)]
pub(super) fn natural_strain(comps: &[Comp; 5], e: &[f64; MAX_PAIRS]) -> Voigt5 {
    let mut nat = Voigt5::zeros();
    for (c, comp) in comps.iter().enumerate() {
        for (t, w) in comp.terms() {
            nat[c] += w * e[t];
        }
    }
    nat
}

/// Natural strain–DOF rows (5×20) of a point from the DOF-space rows of its level's pairs.
#[inline(always)]
fn natural_rows(comps: &[Comp; 5], rows: &[Row; MAX_PAIRS]) -> [Row; 5] {
    let mut bn = [[0.0; ELEMENT_DOFS]; 5];
    for (b, comp) in bn.iter_mut().zip(comps) {
        for (t, w) in comp.terms() {
            for (bj, rj) in b.iter_mut().zip(&rows[t]) {
                *bj += w * rj;
            }
        }
    }
    bn
}

/// Adds the stresses `sn` conjugate to the natural components of a point to the stress
/// weights σ of its level's pairs.
#[inline(always)]
fn add_pair_stress(comps: &[Comp; 5], sn: &Voigt5, sigma: &mut [f64; MAX_PAIRS]) {
    for (c, comp) in comps.iter().enumerate() {
        for (t, w) in comp.terms() {
            sigma[t] += sn[c] * w;
        }
    }
}

impl<'a> ShellElement<'a> {
    /// Internal force, tangent (if `with_tangent`) and energy in the configuration given by
    /// nodal displacements `u` and current director frames `frames`. Builds the section rule
    /// and the element's reference geometry on every call; the assembler caches both and
    /// calls `response_with` or `response_into`.
    pub fn response(
        &self,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        with_tangent: bool,
    ) -> Result<ElementOutput, ElementFailure> {
        let rule = SectionRule::new(self.section)?;
        let geom = self.geometry(&rule)?;
        self.response_with(&rule, &geom, u, frames, with_tangent)
    }

    /// `response` with a precomputed section rule (`SectionRule::new(self.section)`) and
    /// reference geometry (`self.geometry(rule)`).
    pub fn response_with(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        with_tangent: bool,
    ) -> Result<ElementOutput, ElementFailure> {
        let mut k = if with_tangent { Some(Box::new(ElemMat::zeros())) } else { None };
        let (force, energy) = self.response_into(rule, geom, u, frames, k.as_deref_mut())?;
        Ok(ElementOutput { force, stiffness: k, energy })
    }

    /// Internal force and energy, and the consistent tangent written into `k` when given
    /// (overwritten), with a precomputed section rule and reference geometry; without `k`
    /// only stresses and energies are evaluated (the residual-only path).
    ///
    /// Every natural strain component is a weighted sum of pair strains ½(p·q − P·Q) of the
    /// level (see `rule`); each pair is evaluated once per level as ½(P·Δq + Δp·Q + Δp·Δq)
    /// with Δp = p − P built from the changes of the kinematic vectors, so small strains carry
    /// no cancellation error (½(p·q − P·Q) would lose about |X|²/|E| of precision and leave a
    /// residual floor on stiff, thin shells). The stresses conjugate to the natural
    /// components are gathered per pair into weights σ, so a pair's gradient
    /// ∂(½ p·q)/∂V_i = ½(c^p_i q + c^q_i p) and second derivative enter once per level.
    ///
    /// Tangent = Σ BᵀDB (material, upper triangle) + Aᵀ(S⊗I)A (S_ij = Σ ½ σ (c^p_i c^q_j +
    /// c^q_i c^p_j), A = ∂V/∂DOF) + f·∂²V (second derivatives of the kinematic vectors:
    /// ∂²d_a = −(δα·Δα) d_a from the exponential map, and ∂²E_k = J_k ∂²v_k + ∂²F[δv_k, Δv_k]).
    ///
    /// On x86-64 CPUs with AVX2 the same code runs compiled for AVX2 (wider vectors for the
    /// 20-wide row operations; no fused multiply–adds, so the results are bit-identical).
    pub fn response_into(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        k: Option<&mut ElemMat>,
    ) -> Result<(ElemVec, f64), ElementFailure> {
        self.response_mixed(rule, geom, u, frames, k, None)
    }

    /// [`ShellElement::response_into`] with mixed-integration-point stresses
    /// ([`super::mixed`]): with a tangent and `mixed` given, the per-point stress and D·B rows
    /// are recorded into `mixed.record`, and the geometric stiffness is built from the
    /// extrapolated stresses `mixed.geo` when present (the force and energy always come from
    /// the current strains). Ignored by MITC4+ elements (their assumed membrane stresses are
    /// tied across points) and without a tangent.
    pub fn response_mixed(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        k: Option<&mut ElemMat>,
        mixed: Option<Mixed<'_>>,
    ) -> Result<(ElemVec, f64), ElementFailure> {
        // Compiled apart with and without the tangent (`TANGENT`), so that the residual-only
        // path carries none of the tangent's scratch (about 12 KB zeroed per element).
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, the only requirement of `response_avx2`.
            return unsafe {
                match k {
                    Some(k) => self.response_avx2::<true>(rule, geom, u, frames, Some(k), mixed),
                    None => self.response_avx2::<false>(rule, geom, u, frames, None, mixed),
                }
            };
        }
        match k {
            Some(k) => self.response_kernel::<true>(rule, geom, u, frames, Some(k), mixed),
            None => self.response_kernel::<false>(rule, geom, u, frames, None, mixed),
        }
    }

    /// `response_kernel` compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn response_avx2<const TANGENT: bool>(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        k: Option<&mut ElemMat>,
        mixed: Option<Mixed<'_>>,
    ) -> Result<(ElemVec, f64), ElementFailure> {
        self.response_kernel::<TANGENT>(rule, geom, u, frames, k, mixed)
    }

    /// The body of `response_into`; `TANGENT` is whether `k` is given (the tangent is written
    /// into `k` only with `TANGENT`).
    #[inline(always)]
    fn response_kernel<const TANGENT: bool>(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        mut k: Option<&mut ElemMat>,
        mixed: Option<Mixed<'_>>,
    ) -> Result<(ElemVec, f64), ElementFailure> {
        if !rule.fits() {
            return Err(ElementFailure::ThicknessRule(rule.levels.len()));
        }
        let kin = Kinematics::new(&geom.r, &geom.phi0, u, frames)?;
        let material = &*self.section.material;
        let with_tangent = TANGENT;
        // Changes Δp of the rule's forms.
        // (Stack scratch, or heap scratch for the long rules of many-ply laminates.)
        let mut df_stack = [Vector3::zeros(); MAX_FORMS];
        let mut df_heap = Vec::new();
        let df: &mut [Vector3<f64>] = if rule.forms.len() <= MAX_FORMS {
            &mut df_stack
        } else {
            df_heap.resize(rule.forms.len(), Vector3::zeros());
            &mut df_heap
        };
        for (d, f) in df.iter_mut().zip(rule.forms.iter()) {
            *d = f.eval(&kin.dv);
        }
        // MITC4+: the membrane pairs, evaluated once for all levels.
        let tying = rule.membrane.as_ref();
        let mut mstate = tying.map(|m| MembraneState::new(m, &geom.tying, &rule.forms, &geom.forms, df, &kin, with_tangent));
        // Mixed-integration-point stresses (`mixed`): the record, and the extrapolated
        // stresses that replace the current ones in the geometric stiffness.
        let (mut record, geo) = match mixed {
            Some(m) if with_tangent && tying.is_none() && m.record.len() == point_count(geom) => {
                let geo = m.geo.filter(|g| g.len() == point_count(geom));
                (Some(m.record), geo)
            }
            _ => (None, None),
        };
        let mut fv_geo = [Vector3::zeros(); NV];
        let mut upper: Upper = [[0.0; ELEMENT_DOFS]; ELEMENT_DOFS];
        let mut energy = 0.0;
        // Generalised forces on the kinematic vectors and the second-derivative matrix
        // S = X + Xᵀ over them.
        let mut fv = [Vector3::zeros(); NV];
        let mut x = [[0.0; NV]; NV];
        let mut first_point = 0;
        // Through-thickness resultants [Σσ, Σσζ, Σσζ²] of the level pairs' stress weights
        // (current and, with mixed stresses, extrapolated), when the rule has them.
        let resultants = rule.resultants.as_deref();
        let mut s_res = [[0.0; 3]; MAX_PAIRS];
        let mut s_res_geo = [[0.0; 3]; MAX_PAIRS];
        // Scratch of the tangent, reused level after level: the pairs' DOF-space rows and the
        // stacked rows of B and DB (per point E11, E22, 2E13, 2E23 and the level's 2E12 row
        // last with centre-sampled in-plane shear; all five rows per point without).
        const STACK: usize = 21;
        let mut rows: [Row; MAX_PAIRS] = [[0.0; ELEMENT_DOFS]; MAX_PAIRS];
        let mut b_stack: [Row; STACK] = [[0.0; ELEMENT_DOFS]; STACK];
        let mut db_stack: [Row; STACK] = [[0.0; ELEMENT_DOFS]; STACK];
        for (level, centre_geom) in rule.levels.iter().zip(geom.centres.iter()) {
            let pairs = &level.pairs;
            let current = |f: usize| geom.forms[f] + df[f];
            let mut e = [0.0; MAX_PAIRS];
            for (et, &(p, q)) in e.iter_mut().zip(pairs) {
                let (pr, dp, qr, dq) = (geom.forms[p], df[p], geom.forms[q], df[q]);
                *et = 0.5 * (pr.dot(&dq) + dp.dot(&qr) + dp.dot(&dq));
            }
            // DOF-space rows of the pairs: ∂(½ p·q)/∂DOF.
            if with_tangent {
                for (row, &(p, q)) in rows.iter_mut().zip(pairs) {
                    *row = [0.0; ELEMENT_DOFS];
                    if p == q {
                        kin.chain_form(&rule.forms[p], &current(p), row);
                    } else {
                        kin.chain_form(&rule.forms[p], &(current(q) * 0.5), row);
                        kin.chain_form(&rule.forms[q], &(current(p) * 0.5), row);
                    }
                }
            }
            // The lamina's centre strains (in-plane shear sampling), shared by its points.
            let mut nat_c = Voigt5::zeros();
            let n_pts = level.points.len();
            if rule.centre_shear {
                nat_c = natural_strain(&level.centre.comps, &e);
                if let Some(ms) = &mstate {
                    ms.correct(n_pts, &mut nat_c.as_mut_slice()[..3]);
                }
            }
            let points = &geom.points[first_point..first_point + level.points.len()];
            first_point += level.points.len();
            // Row 2E12 of the level (the centre's), common to its points.
            let mut b_shear: Row = [0.0; ELEMENT_DOFS];
            if with_tangent && rule.centre_shear {
                let mut bn_c = natural_rows(&level.centre.comps, &rows);
                if let Some(ms) = &mstate {
                    ms.add_correction_rows(n_pts, &mut bn_c);
                }
                for (c, bc) in bn_c.iter().enumerate() {
                    let m = centre_geom.m[(2, c)];
                    b_shear.iter_mut().zip(bc).for_each(|(b, r)| *b += m * r);
                }
            }
            let mut sigma = [0.0; MAX_PAIRS];
            let mut sn_c = Voigt5::zeros();
            let mut sigma_geo = [0.0; MAX_PAIRS];
            let mut sn_c_geo = Voigt5::zeros();
            let base = first_point - n_pts;
            // Σ BᵀDB over the level's points: the 2E12 row is the level's, common to its
            // points, so it enters once with Σ (DB)₂ (the last stacked row).
            let mut db_shear: Row = [0.0; ELEMENT_DOFS];
            let mut n_rows = 0;
            for (i, (rp, pg)) in level.points.iter().zip(points).enumerate() {
                let mut nat = natural_strain(&rp.comps, &e);
                if let Some(ms) = &mstate {
                    ms.correct(i, &mut nat.as_mut_slice()[..3]);
                }
                let mut eps = pg.m * nat;
                eps[2] += (pg.mc * nat_c)[0];
                let (stress, density, tangent) = if with_tangent {
                    let res = material.response_at(&eps, level.zeta).map_err(ElementFailure::Material)?;
                    (res.stress, res.energy, Some(res.tangent))
                } else {
                    let (stress, density) = material.stress_at(&eps, level.zeta).map_err(ElementFailure::Material)?;
                    (stress, density, None)
                };
                energy += pg.wdet * density;
                let sw = stress * pg.wdet;
                let sn = pg.m.transpose() * sw;
                sn_c += pg.mc.transpose() * sw[2];
                add_pair_stress(&rp.comps, &sn, &mut sigma);
                if let (Some(m), Some(ms)) = (tying, mstate.as_mut()) {
                    ms.add_stress(&m.points[i], &geom.tying[i], sn.as_slice());
                }
                if let Some(g) = geo {
                    let sw_geo = g[base + i];
                    sn_c_geo += pg.mc.transpose() * sw_geo[2];
                    add_pair_stress(&rp.comps, &(pg.m.transpose() * sw_geo), &mut sigma_geo);
                }
                if let Some(rec) = record.as_deref_mut() {
                    rec[base + i].sw = sw;
                }
                if let (Some(d), true) = (tangent, n_rows + 5 <= STACK) {
                    // B = M Bn (row 2E12 from the centre when sampled there), DB with D
                    // weighted by w det J.
                    let mut bn = natural_rows(&rp.comps, &rows);
                    if let Some(ms) = &mstate {
                        ms.add_correction_rows(i, &mut bn);
                    }
                    let mut b: [Row; 5] = [[0.0; ELEMENT_DOFS]; 5];
                    for (r, br) in b.iter_mut().enumerate() {
                        if r == 2 && rule.centre_shear {
                            *br = b_shear;
                            continue;
                        }
                        for (c, bc) in bn.iter().enumerate() {
                            let m = pg.m[(r, c)];
                            br.iter_mut().zip(bc).for_each(|(x, y)| *x += m * y);
                        }
                    }
                    let d = d * pg.wdet;
                    if let Some(rec) = record.as_deref_mut() {
                        rec[base + i].dw = d;
                    }
                    let mut slot = n_rows;
                    for r in 0..5 {
                        let mut dbr: Row = [0.0; ELEMENT_DOFS];
                        for (q, bq) in b.iter().enumerate() {
                            let dq = d[(r, q)];
                            if dq != 0.0 {
                                dbr.iter_mut().zip(bq).for_each(|(x, y)| *x += dq * y);
                            }
                        }
                        if r == 2 && rule.centre_shear {
                            db_shear.iter_mut().zip(&dbr).for_each(|(x, y)| *x += y);
                        } else {
                            b_stack[slot] = b[r];
                            db_stack[slot] = dbr;
                            slot += 1;
                        }
                    }
                    n_rows = slot;
                }
            }
            if rule.centre_shear {
                add_pair_stress(&level.centre.comps, &sn_c, &mut sigma);
                if geo.is_some() {
                    add_pair_stress(&level.centre.comps, &sn_c_geo, &mut sigma_geo);
                }
                if let (Some(m), Some(ms)) = (tying, mstate.as_mut()) {
                    ms.add_stress(&m.points[n_pts], &geom.tying[n_pts], sn_c.as_slice());
                }
                if with_tangent {
                    b_stack[n_rows] = b_shear;
                    db_stack[n_rows] = db_shear;
                    n_rows += 1;
                }
            }
            if with_tangent {
                add_upper_btc(&mut upper, &b_stack[..n_rows], &db_stack[..n_rows]);
            }
            if resultants.is_some() {
                let z = level.zeta;
                let zn = [1.0, z, z * z];
                for (s, &sg) in s_res.iter_mut().zip(&sigma[..pairs.len()]) {
                    s.iter_mut().zip(&zn).for_each(|(a, b)| *a += sg * b);
                }
                if geo.is_some() {
                    for (s, &sg) in s_res_geo.iter_mut().zip(&sigma_geo[..pairs.len()]) {
                        s.iter_mut().zip(&zn).for_each(|(a, b)| *a += sg * b);
                    }
                }
            } else if geo.is_some() {
                add_pair_forces(&sigma, pairs, &rule.forms, current, &mut fv, None);
                add_pair_forces(&sigma_geo, pairs, &rule.forms, current, &mut fv_geo, Some(&mut x));
            } else {
                add_pair_forces(&sigma, pairs, &rule.forms, current, &mut fv, with_tangent.then_some(&mut x));
            }
        }
        if let Some(split) = resultants {
            if geo.is_some() {
                add_resultant_forces(&s_res, split, &rule.forms, &geom.forms, df, &mut fv, None);
                add_resultant_forces(&s_res_geo, split, &rule.forms, &geom.forms, df, &mut fv_geo, Some(&mut x));
            } else {
                add_resultant_forces(&s_res, split, &rule.forms, &geom.forms, df, &mut fv, with_tangent.then_some(&mut x));
            }
        }
        if let (Some(m), Some(ms)) = (tying, &mstate) {
            let current = |f: usize| geom.forms[f] + df[f];
            add_pair_forces(&ms.sigma, &m.pairs, &rule.forms, current, &mut fv, with_tangent.then_some(&mut x));
        }
        let feff = kin.director_chain(&fv);
        let mut force = ElemVec::zeros();
        for a in 0..4 {
            for i in 0..3 {
                force[5 * a + i] = fv[a][i];
            }
            force[5 * a + 3] = feff[a].dot(&frames[a].t1);
            force[5 * a + 4] = feff[a].dot(&frames[a].t2);
        }
        if let (true, Some(k)) = (TANGENT, k.as_deref_mut()) {
            mirror_into(&upper, k);
            let d = frames.map(|f| f.d);
            if geo.is_some() {
                let feff_geo = kin.director_chain(&fv_geo);
                add_geometric_tangent(k, &symmetric_part(&x), &fv_geo, &feff_geo, &kin, &d);
            } else {
                add_geometric_tangent(k, &symmetric_part(&x), &fv, &feff, &kin, &d);
            }
        }
        Ok((force, energy))
    }

    /// Mid-surface lamina strain and stress at the element centre (for output), from nodal
    /// displacements `u` and current frames.
    pub fn centre_state(&self, u: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4]) -> Result<(Voigt5, Voigt5), ElementFailure> {
        let rule = SectionRule::centre(self.section.thickness, self.section.shear);
        let geom = self.geometry(&rule)?;
        let kin = Kinematics::new(&geom.r, &geom.phi0, u, frames)?;
        let level = &rule.levels[0];
        let df: Vec<Vector3<f64>> = rule.forms.iter().map(|f| f.eval(&kin.dv)).collect();
        let mut e = [0.0; MAX_PAIRS];
        for (et, &(p, q)) in e.iter_mut().zip(&level.pairs) {
            let (pr, dp, qr, dq) = (geom.forms[p], df[p], geom.forms[q], df[q]);
            *et = 0.5 * (pr.dot(&dq) + dp.dot(&qr) + dp.dot(&dq));
        }
        let centre: &RulePoint = &level.centre;
        let mut nat = natural_strain(&centre.comps, &e);
        if let Some(m) = rule.membrane.as_ref() {
            MembraneState::new(m, &geom.tying, &rule.forms, &geom.forms, &df, &kin, false).correct(0, &mut nat.as_mut_slice()[..3]);
        }
        let eps = geom.centres[0].m * nat;
        let res = self.section.material.response(&eps).map_err(ElementFailure::Material)?;
        Ok((eps, res.stress))
    }

    /// Reference mid-surface area (2×2 Gauss).
    pub fn reference_area(&self) -> f64 {
        let (p2, _) = gauss_legendre(2).unwrap_or((&[0.0], &[2.0]));
        let mut area = 0.0;
        for &eta in p2 {
            for &xi in p2 {
                let (_, dxi, deta) = bilinear(xi, eta);
                let mut gx = Vector3::zeros();
                let mut gy = Vector3::zeros();
                for a in 0..4 {
                    gx += self.x0[a] * dxi[a];
                    gy += self.x0[a] * deta[a];
                }
                area += gx.cross(&gy).norm();
            }
        }
        area
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::element::kinematics::arc_factor;
    use crate::material::{Fabric, FabricProperties, LaminaPly, Laminate, NeoHookean, StVenantKirchhoff};
    use nalgebra::{Rotation3, Unit};

    fn section(shear: ShearTreatment, nh: bool) -> Section {
        section_of(shear, if nh { "neo-Hookean" } else { "SVK" })
    }

    /// A section of thickness 0.05 of the named lamina: "SVK", "neo-Hookean", "fabric"
    /// (the cotton broadcloth preset at that thickness, three thickness points) or
    /// "laminate" (a nonsymmetric stack of those three, 0.02 + 0.01 + 0.02).
    pub(in crate::element) fn section_of(shear: ShearTreatment, material: &str) -> Section {
        let (material, thickness_points): (Arc<dyn ShellMaterial>, usize) = match material {
            "neo-Hookean" => (Arc::new(NeoHookean::new(1.0e4 / 3.0, 1.0e4 / 2.6)), 2),
            "fabric" => {
                let mut p = FabricProperties::preset("cotton_broadcloth").expect("preset");
                p.thickness = 0.05;
                (Arc::new(Fabric::new(p)), 3)
            }
            "laminate" => {
                let mut p = FabricProperties::preset("cotton_broadcloth").expect("preset");
                p.thickness = 0.02;
                let ply = |name: &str, material: Arc<dyn ShellMaterial>, thickness: f64| LaminaPly { name: name.into(), material, thickness, areal_density: None };
                let plies = vec![
                    ply("SVK", section_of(shear, "SVK").material, 0.02),
                    ply("neo-Hookean", section_of(shear, "neo-Hookean").material, 0.01),
                    ply("fabric", Arc::new(Fabric::new(p)), 0.02),
                ];
                (Arc::new(Laminate::new(plies).expect("laminate")), 2)
            }
            _ => (Arc::new(StVenantKirchhoff::new(1.0e4, 0.3, 5.0 / 6.0)), 2),
        };
        Section { thickness: 0.05, shear, thickness_points, material }
    }

    /// A distorted, slightly warped quad with non-parallel directors.
    pub(in crate::element) fn geometry() -> ([Vector3<f64>; 4], [Vector3<f64>; 4]) {
        let x0 = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.1, 0.1, 0.02),
            Vector3::new(1.0, 0.9, -0.03),
            Vector3::new(-0.1, 1.2, 0.01),
        ];
        let d0 = [
            Vector3::new(0.05, -0.02, 1.0).normalize(),
            Vector3::new(-0.03, 0.04, 1.0).normalize(),
            Vector3::new(0.02, 0.03, 1.0).normalize(),
            Vector3::new(-0.01, -0.05, 1.0).normalize(),
        ];
        (x0, d0)
    }

    /// Nodal increments of a strongly deformed state of an element with reference nodes
    /// `x0`: stretch, shear, bending and large director rotations.
    pub(in crate::element) fn strongly_deformed(x0: &[Vector3<f64>; 4]) -> ElemVec {
        let mut u = ElemVec::zeros();
        for a in 0..4 {
            u[5 * a] = 0.15 * x0[a].y + 0.05 * a as f64;
            u[5 * a + 1] = -0.1 * x0[a].x;
            u[5 * a + 2] = 0.3 * x0[a].x * x0[a].y;
            u[5 * a + 3] = 0.4 - 0.1 * a as f64;
            u[5 * a + 4] = -0.3 + 0.2 * a as f64;
        }
        u
    }

    pub(in crate::element) fn frames(d: &[Vector3<f64>; 4]) -> [DirectorFrame; 4] {
        std::array::from_fn(|a| DirectorFrame::new(d[a], Some(Vector3::x())))
    }

    /// Applies an element DOF increment (translations added, tilts by the exponential map).
    pub(in crate::element) fn apply(u: &[Vector3<f64>; 4], f: &[DirectorFrame; 4], du: &ElemVec) -> ([Vector3<f64>; 4], [DirectorFrame; 4]) {
        let x2 = std::array::from_fn(|a| u[a] + Vector3::new(du[5 * a], du[5 * a + 1], du[5 * a + 2]));
        let f2 = std::array::from_fn(|a| f[a].tilted([du[5 * a + 3], du[5 * a + 4]]));
        (x2, f2)
    }

    #[test]
    fn arc_factor_is_asin_ratio_with_consistent_derivatives() {
        let exact = |w: f64| {
            let s = 0.5 * w.sqrt();
            s.asin() / s
        };
        for w in [1e-5, 0.01, 0.0799, 0.0801, 0.5, 1.5, 3.0] {
            let [f, d1, d2] = arc_factor(w).unwrap();
            assert!((f - exact(w)).abs() < 1e-14, "w={w}: {f} vs {}", exact(w));
            let hw = 1e-4 * w.max(1e-2);
            let [fp, p1, _] = arc_factor(w + hw).unwrap();
            let [fm, m1, _] = arc_factor(w - hw).unwrap();
            let fd1 = (fp - fm) / (2.0 * hw);
            let fd2 = (p1 - m1) / (2.0 * hw);
            assert!((d1 - fd1).abs() < 1e-7 * d1.abs(), "w={w}: φ' {d1} vs {fd1}");
            assert!((d2 - fd2).abs() < 1e-6 * d2.abs(), "w={w}: φ'' {d2} vs {fd2}");
        }
        // Series branch and closed form agree at the switch (y = w/4 = 0.02).
        let (lo, hi) = (arc_factor(0.08 - 1e-12).unwrap(), arc_factor(0.08 + 1e-12).unwrap());
        for i in 0..3 {
            assert!((lo[i] - hi[i]).abs() < 1e-9 * hi[i].abs(), "component {i}: {} vs {}", lo[i], hi[i]);
        }
        assert!(arc_factor(4.0).is_none());
    }

    /// Uniform bending of one element by Δθ (chord kept at length L and normal to the mean
    /// director, so membrane and shear strains vanish): the stored energy equals the
    /// Euler–Bernoulli value EI Δθ²/(2L) (ν = 0). Linearly interpolated directors would give
    /// (2 sin(Δθ/2)/Δθ)² of it, 1.3 % low at Δθ = 0.4.
    #[test]
    fn uniform_bending_energy_is_exact_for_large_element_rotation() {
        let (e, h, l) = (1.0e6, 0.001, 1.0);
        let material: Arc<dyn ShellMaterial> = Arc::new(StVenantKirchhoff::new(e, 0.0, 5.0 / 6.0));
        let sec = Section { thickness: h, shear: ShearTreatment::Mitc4, thickness_points: 2, material };
        let x0 = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(l, 0.0, 0.0), Vector3::new(l, 1.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
        let el = ShellElement { x0, d0: [Vector3::z(); 4], grain: None, section: &sec };
        let f0 = DirectorFrame::new(Vector3::z(), Some(Vector3::x()));
        for dtheta in [0.1f64, 0.4, 1.0] {
            let rot = |a: f64| Rotation3::from_axis_angle(&Vector3::y_axis(), -a);
            let tip = rot(0.5 * dtheta) * Vector3::new(l, 0.0, 0.0);
            let u = [Vector3::zeros(), tip - x0[1], tip + Vector3::y() - x0[2], Vector3::zeros()];
            let f = [f0, f0.rotated(&rot(dtheta)), f0.rotated(&rot(dtheta)), f0];
            let energy = el.response(&u, &f, false).unwrap().energy;
            let exact = e * h.powi(3) / 12.0 * dtheta * dtheta / (2.0 * l);
            assert!((energy / exact - 1.0).abs() < 1e-5, "Δθ = {dtheta}: energy ratio {}", energy / exact);
        }
    }

    /// A free, distorted and warped MITC4 element with non-parallel directors keeps exactly
    /// the six rigid-body zero-energy modes (Dvorkin & Bathe 1984) with the centre-sampled
    /// in-plane shear and the geodesic director gradients.
    /// MITC4+ (Ko, Lee & Bathe 2017) keeps exactly six on the same element.
    #[test]
    fn free_warped_element_has_six_zero_energy_modes() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            let sec = section(shear, false);
            let el = ShellElement { x0, d0, grain: None, section: &sec };
            let k = el.response(&[Vector3::zeros(); 4], &frames(&d0), true).unwrap().stiffness.unwrap();
            let eig = nalgebra::DMatrix::from_fn(20, 20, |i, j| k[(i, j)]).symmetric_eigen();
            let max = eig.eigenvalues.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            let zero = eig.eigenvalues.iter().filter(|v| v.abs() < 1e-10 * max).count();
            assert_eq!(zero, 6, "{shear:?}: eigenvalues {:?}", eig.eigenvalues.as_slice());
        }
    }

    /// Every formulation with every supported thickness rule (1–5 points) fits the kernel's
    /// fixed-size scratch, so no section is refused for its rule.
    #[test]
    fn every_thickness_rule_fits_the_kernel() {
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            for thickness_points in 1..=5 {
                let sec = Section { thickness_points, ..section(shear, false) };
                assert!(SectionRule::new(&sec).unwrap().fits(), "{shear:?}, {thickness_points} points");
            }
        }
    }

    /// Mixed-integration-point tangent (`element::mixed`): with stresses extrapolated from a
    /// record at the same configuration it equals the standard tangent; from a record a step
    /// h away it differs by O(h²) (the extrapolated stress's error), and the force never
    /// changes. Every material, MITC4 and SRI (MITC4+ ignores mixed stresses).
    #[test]
    fn mixed_tangent_is_standard_at_the_record_and_second_order_away() {
        use super::super::mixed::{extrapolate, point_count, unknown_change, Mixed, PointRecord};
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri] {
            for material in ["SVK", "neo-Hookean", "fabric", "laminate"] {
                let sec = section_of(shear, material);
                let el = ShellElement { x0, d0, grain: None, section: &sec };
                let rule = SectionRule::new(&sec).unwrap();
                let geom = el.geometry(&rule).unwrap();
                let n = point_count(&geom);
                let mut u = ElemVec::zeros();
                let mut dir = ElemVec::zeros();
                for a in 0..4 {
                    u[5 * a] = 0.05 * x0[a].y;
                    u[5 * a + 2] = 0.2 * x0[a].x * x0[a].y;
                    u[5 * a + 3] = 0.3 - 0.1 * a as f64;
                    u[5 * a + 4] = -0.2 + 0.1 * a as f64;
                    for i in 0..5 {
                        dir[5 * a + i] = 0.3 * (((7 * a + 3 * i) % 5) as f64 - 2.0);
                    }
                }
                let (xa, fa) = apply(&[Vector3::zeros(); 4], &frames(&d0), &u);
                let mut records = vec![PointRecord::default(); n];
                let mut k_rec = ElemMat::zeros();
                el.response_mixed(&rule, &geom, &xa, &fa, Some(&mut k_rec), Some(Mixed { geo: None, record: &mut records })).unwrap();
                let mismatch = |h: f64| {
                    let (xb, fb) = apply(&xa, &fa, &(dir * h));
                    let mut geo = vec![Voigt5::zeros(); n];
                    extrapolate(&rule, &geom, &xa, &fa, &unknown_change(&xa, &fa, &xb, &fb), &records, &mut geo).unwrap();
                    let mut scratch = vec![PointRecord::default(); n];
                    let (mut k_std, mut k_mix) = (ElemMat::zeros(), ElemMat::zeros());
                    let (f_std, _) = el.response_into(&rule, &geom, &xb, &fb, Some(&mut k_std)).unwrap();
                    let (f_mix, _) = el.response_mixed(&rule, &geom, &xb, &fb, Some(&mut k_mix), Some(Mixed { geo: Some(&geo), record: &mut scratch })).unwrap();
                    assert_eq!(f_std, f_mix, "{material} {shear:?}: the force must not change");
                    (k_std - k_mix).abs().max() / k_std.abs().max()
                };
                let (at, h1, h2) = (mismatch(0.0), mismatch(1e-2), mismatch(5e-3));
                assert!(at < 1e-13, "{material} {shear:?}: {at:e} at the record");
                assert!(h1 > 0.0 && (h1 / h2 - 4.0).abs() < 0.4, "{material} {shear:?}: mismatch {h1:e} at h, {h2:e} at h/2 (not second order)");
            }
        }
    }

    #[test]
    fn tangent_matches_central_differences_of_residual() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            for material in ["SVK", "neo-Hookean", "fabric", "laminate"] {
                let sec = section_of(shear, material);
                if material == "laminate" && shear == ShearTreatment::Mitc4 {
                    let n = SectionRule::new(&sec).unwrap().forms.len();
                    assert!(n > MAX_FORMS, "the laminate's {n} forms take the kernel's heap scratch");
                }
                let el = ShellElement { x0, d0, grain: None, section: &sec };
                // A strongly deformed state: stretch, shear, large rotation of the directors.
                let u = strongly_deformed(&x0);
                let (x, f) = apply(&[Vector3::zeros(); 4], &frames(&d0), &u);
                let out = el.response(&x, &f, true).unwrap();
                let k = out.stiffness.unwrap();
                let h = 1e-6;
                let scale = k.abs().max();
                let mut worst: f64 = 0.0;
                for j in 0..ELEMENT_DOFS {
                    let mut e = ElemVec::zeros();
                    e[j] = h;
                    let (xp, fp) = apply(&x, &f, &e);
                    let (xm, fm) = apply(&x, &f, &(-e));
                    let rp = el.response(&xp, &fp, false).unwrap().force;
                    let rm = el.response(&xm, &fm, false).unwrap().force;
                    let col = (rp - rm) / (2.0 * h);
                    worst = worst.max((col - k.column(j)).abs().max() / scale);
                    // The residual is the derivative of the energy.
                    let de = (el.response(&xp, &fp, false).unwrap().energy - el.response(&xm, &fm, false).unwrap().energy) / (2.0 * h);
                    assert!((de - out.force[j]).abs() < 1e-6 * out.force.abs().max(), "force {j}: {de} vs {}", out.force[j]);
                }
                assert!(worst < 1e-6, "{shear:?} {material}: tangent error {worst}");
                // Symmetric tangent of a conservative element.
                assert!((*k - k.transpose()).abs().max() < 1e-9 * scale);
            }
        }
    }

    #[test]
    fn rigid_rotation_of_any_size_is_strain_free() {
        let (x0, d0) = geometry();
        for (shear, deg) in [(ShearTreatment::Mitc4, 170.0f64), (ShearTreatment::Mitc4, 400.0), (ShearTreatment::Mitc4Plus, 170.0), (ShearTreatment::Mitc4Plus, 400.0), (ShearTreatment::Mitc4PlusCentre, 400.0)] {
            let sec = section(shear, true);
            let el = ShellElement { x0, d0, grain: None, section: &sec };
            let axis = Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8));
            // Apply in 20 increments through the nodal update path.
            let mut x = x0;
            let mut f = frames(&d0);
            let step = Rotation3::from_axis_angle(&axis, deg.to_radians() / 20.0);
            let c = Vector3::new(0.4, 0.2, 0.0);
            for _ in 0..20 {
                x = std::array::from_fn(|a| c + step * (x[a] - c) + Vector3::new(0.01, 0.0, -0.02));
                f = std::array::from_fn(|a| f[a].rotated(&step));
            }
            let u: [Vector3<f64>; 4] = std::array::from_fn(|a| x[a] - x0[a]);
            let e = el.response(&u, &f, false).unwrap().energy;
            assert!(e.abs() < 1e-14, "{shear:?} {deg}°: energy {e}");
        }
    }
}
