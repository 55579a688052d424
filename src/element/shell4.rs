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

use nalgebra::{Matrix3, Matrix3x2, SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};

use super::director::DirectorFrame;
use super::quadrature::{bilinear, gauss_legendre};
use super::ELEMENT_DOFS;
use crate::material::{MaterialFailure, ShellMaterial, Voigt5};

/// Element residual vector (20).
pub type ElemVec = SVector<f64, ELEMENT_DOFS>;
/// Element tangent matrix (20×20).
pub type ElemMat = SMatrix<f64, ELEMENT_DOFS, ELEMENT_DOFS>;
type BMat = SMatrix<f64, 5, ELEMENT_DOFS>;

/// Transverse shear treatment against shear locking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ShearTreatment {
    /// MITC4 assumed natural shear strains (Dvorkin & Bathe 1984). No spurious modes.
    #[default]
    Mitc4,
    /// Selective reduced integration: shear strains sampled at the element centre.
    Sri,
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
}

impl std::fmt::Display for ElementFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementFailure::Geometry { det_j } => write!(f, "degenerate reference geometry (det J = {det_j:.3e})"),
            ElementFailure::Material(m) => write!(f, "{m}"),
            ElementFailure::ThicknessRule(n) => write!(f, "{n} thickness points (1 to 5 supported)"),
            ElementFailure::DirectorSpread { chord } => write!(f, "directors of neighbouring nodes nearly opposite (|d_b − d_a| = {chord:.6})"),
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
/// directors d_a and 4 edge director gradients E_k.
const NV: usize = 12;
/// First director index among the kinematic vectors.
const VD: usize = 4;
/// First edge-gradient index among the kinematic vectors.
const VE: usize = 8;
/// Element edges (a, b) carrying the geodesic director difference E_k = F(d_b − d_a):
/// E_0, E_1 run along ξ (η = −1, +1), E_2, E_3 along η (ξ = −1, +1).
const EDGES: [(usize, usize); 4] = [(0, 1), (3, 2), (0, 3), (1, 2)];

/// Arc-to-chord factor of the geodesic between two unit vectors whose difference v has
/// w = |v|²: φ = θ / |v| = asin(s)/s with s = |v|/2 = sin(θ/2), θ the angle between them.
/// Returns (φ, dφ/dw, d²φ/dw²), or None when the vectors are (nearly) antipodal, where the
/// geodesic is undefined. Series of asin(s)/s = Σ C(2n,n)/(4ⁿ(2n+1)) s²ⁿ for small s
/// (Abramowitz & Stegun 4.4.40), closed form otherwise.
pub(crate) fn arc_factor(w: f64) -> Option<[f64; 3]> {
    let y = 0.25 * w;
    if !(y < 0.999_999) || y < 0.0 {
        return None;
    }
    let (h, hy, hyy) = if y < 0.02 {
        // h(y) = Σ c_n yⁿ, c_n = β_n/(2n+1), β_n = C(2n,n)/4ⁿ = β_{n−1}(2n−1)/(2n).
        let (mut h, mut h1, mut h2) = (1.0, 0.0, 0.0);
        let mut beta = 1.0;
        let mut y_nm1 = 1.0; // y^{n−1}
        let mut y_nm2 = 0.0; // y^{n−2} (no term for n = 1)
        for n in 1..16 {
            let nf = n as f64;
            beta *= (2.0 * nf - 1.0) / (2.0 * nf);
            let c = beta / (2.0 * nf + 1.0);
            h += c * y_nm1 * y;
            h1 += nf * c * y_nm1;
            h2 += nf * (nf - 1.0) * c * y_nm2;
            y_nm2 = y_nm1;
            y_nm1 *= y;
        }
        (h, h1, h2)
    } else {
        let s = y.sqrt();
        let r = (1.0 - y).sqrt();
        let a = s.asin();
        (a / s, 0.5 / (y * r) - 0.5 * a / (y * s), -0.75 / (y * y * r) + 0.25 / (y * r * r * r) + 0.75 * a / (y * y * s))
    };
    // d/dw = ¼ d/dy.
    Some([h, 0.25 * hy, 0.0625 * hyy])
}

/// Linear form p = Σ_i c_i V_i of the kinematic vectors (at most six non-zero terms).
#[derive(Clone, Copy, Debug, Default)]
struct Lin {
    n: usize,
    idx: [usize; 6],
    c: [f64; 6],
}

impl Lin {
    fn push(&mut self, i: usize, c: f64) {
        if c != 0.0 && self.n < 6 {
            self.idx[self.n] = i;
            self.c[self.n] = c;
            self.n += 1;
        }
    }

    fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.idx[..self.n].iter().copied().zip(self.c[..self.n].iter().copied())
    }

    fn eval(&self, v: &[Vector3<f64>; NV]) -> Vector3<f64> {
        let mut out = Vector3::zeros();
        for (i, c) in self.terms() {
            out += v[i] * c;
        }
        out
    }
}

/// One term w·½(p·q − P·Q) of a natural strain component.
#[derive(Clone, Copy, Debug)]
struct Term {
    w: f64,
    p: Lin,
    q: Lin,
    /// p and q are the same form (E_ξξ, E_ηη), evaluated once.
    same: bool,
}

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

/// Covariant base-vector forms at (ξ, η, ζ): g_ξ, g_η, g_ζ. The in-plane director
/// gradients are d,ξ = ¼(1−η) E_0 + ¼(1+η) E_1 and d,η = ¼(1−ξ) E_2 + ¼(1+ξ) E_3 — the
/// bilinear interpolation's edge differences d_b − d_a replaced by the geodesic ones.
fn base_forms(xi: f64, eta: f64, zeta: f64, h: f64) -> [Lin; 3] {
    let (n, dxi, deta) = bilinear(xi, eta);
    let hz = 0.5 * zeta * h;
    let mut g = [Lin::default(); 3];
    for a in 0..4 {
        g[0].push(a, dxi[a]);
        g[1].push(a, deta[a]);
    }
    g[0].push(VE, hz * 0.25 * (1.0 - eta));
    g[0].push(VE + 1, hz * 0.25 * (1.0 + eta));
    g[1].push(VE + 2, hz * 0.25 * (1.0 - xi));
    g[1].push(VE + 3, hz * 0.25 * (1.0 + xi));
    for a in 0..4 {
        g[2].push(VD + a, 0.5 * h * n[a]);
    }
    g
}

/// Strain terms of one integration point of a section rule: the natural base-vector forms at
/// the point and, per natural component, its one or two (tied) terms.
#[derive(Clone, Debug)]
struct RulePoint {
    /// Gauss weight (in-plane × thickness).
    w: f64,
    /// Base-vector forms g_ξ, g_η, g_ζ at the point.
    g: [Lin; 3],
    /// Strain terms of the five natural components.
    terms: [[Option<Term>; 2]; 5],
}

/// Integration rule of a section: 2×2 points in the plane times the thickness rule, each with
/// its strain terms (MITC4 tying or SRI centre sampling). Depends only on thickness, shear
/// treatment and thickness points, so one rule serves every element of a section.
#[derive(Clone, Debug)]
pub struct SectionRule {
    /// In-plane points of each thickness level (4 per level, level-major).
    points: Vec<RulePoint>,
    /// Element-centre point (ξ = η = 0) of each thickness level, where the in-plane shear
    /// strain of that lamina is sampled.
    centres: Vec<RulePoint>,
    /// Thickness coordinate ζ of each level (for through-thickness material laws).
    zetas: Vec<f64>,
}

impl SectionRule {
    /// Builds the rule of `section`.
    pub fn new(section: &Section) -> Result<Self, ElementFailure> {
        let (pz, wz) = gauss_legendre(section.thickness_points).ok_or(ElementFailure::ThicknessRule(section.thickness_points))?;
        let (p2, _) = gauss_legendre(2).ok_or(ElementFailure::ThicknessRule(2))?;
        let mut points = Vec::with_capacity(4 * pz.len());
        let mut centres = Vec::with_capacity(pz.len());
        for (&z, &w) in pz.iter().zip(wz) {
            for &eta in p2 {
                for &xi in p2 {
                    points.push(rule_point(xi, eta, z, w, section.thickness, section.shear));
                }
            }
            centres.push(rule_point(0.0, 0.0, z, 1.0, section.thickness, section.shear));
        }
        Ok(Self { points, centres, zetas: pz.to_vec() })
    }
}

/// Strain terms at (ξ, η, ζ) with weight `w` for thickness `h` and shear treatment `shear`.
fn rule_point(xi: f64, eta: f64, zeta: f64, w: f64, h: f64, shear: ShearTreatment) -> RulePoint {
    let g = base_forms(xi, eta, zeta, h);
    let one = |p: Lin, q: Lin, same: bool| [Some(Term { w: 1.0, p, q, same }), None];
    let tied = |pts: [(f64, f64, f64); 2], comp: usize| {
        let mut out = [None, None];
        for (slot, &(xt, yt, wt)) in pts.iter().enumerate() {
            if wt != 0.0 {
                let gt = base_forms(xt, yt, zeta, h);
                out[slot] = Some(Term { w: wt, p: gt[comp], q: gt[2], same: false });
            }
        }
        out
    };
    let (xz, yz) = match shear {
        ShearTreatment::Mitc4 => (
            tied([(0.0, -1.0, 0.5 * (1.0 - eta)), (0.0, 1.0, 0.5 * (1.0 + eta))], 0),
            tied([(-1.0, 0.0, 0.5 * (1.0 - xi)), (1.0, 0.0, 0.5 * (1.0 + xi))], 1),
        ),
        ShearTreatment::Sri => (tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 0), tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 1)),
    };
    RulePoint { w, g, terms: [one(g[0], g[0], true), one(g[1], g[1], true), one(g[0], g[1], false), xz, yz] }
}

/// Integration-point data that depends only on the reference state of one element.
#[derive(Clone, Debug)]
struct PointGeometry {
    /// Natural → local Voigt strain map, rows [E11, E22, 2E12, 2E13, 2E23], columns
    /// [E_ξξ, E_ηη, E_ξη, E_ξζ, E_ηζ].
    m: SMatrix<f64, 5, 5>,
    /// Weight × det J.
    wdet: f64,
    /// Row 2E12 of the element centre's strain map at the same thickness level (the
    /// point's own row 2 of `m` is zero): the lamina's in-plane shear is sampled there.
    mc: SMatrix<f64, 1, 5>,
}

/// Reference data of one element for a given section rule, computed once per model:
/// reference kinematic vectors, reference edge factors and per-point metric data.
#[derive(Clone, Debug)]
pub struct ElementGeometry {
    /// Reference kinematic vectors X̄_a, D_a, E⁰_k.
    r: [Vector3<f64>; NV],
    /// Arc-to-chord factors φ of the reference edges.
    phi0: [f64; 4],
    /// Per integration point of the rule.
    points: Box<[PointGeometry]>,
}

/// The kinematic vectors of one element state: reference values V⁰_i (X̄_a, D_a, E⁰_k), the
/// changes V_i − V⁰_i, and the derivatives of the geodesic edge gradients.
struct Kinematics<'g> {
    /// Reference values.
    r: &'g [Vector3<f64>; NV],
    /// Changes from the reference (u_a, d_a − D_a, E_k − E⁰_k).
    dv: [Vector3<f64>; NV],
    /// Current edge differences v_k = d_b − d_a.
    v: [Vector3<f64>; 4],
    /// ∂E_k/∂v_k = φ I + 2φ' v vᵀ (symmetric).
    jac: [Matrix3<f64>; 4],
    /// (φ', φ'') of each edge, derivatives with respect to |v|².
    dphi: [[f64; 2]; 4],
}

/// Geodesic edge gradient E = φ(|v|²) v of the director difference v = d_b − d_a: the
/// derivative at the edge midpoint of the great-circle (SLERP) interpolation of the two
/// nodal directors, 2·(θ/2)·(v/|v|), with θ the angle between them.
fn edge_gradient(v: &Vector3<f64>) -> Result<(f64, f64, f64), ElementFailure> {
    let w = v.norm_squared();
    let [phi, d1, d2] = arc_factor(w).ok_or(ElementFailure::DirectorSpread { chord: w.sqrt() })?;
    Ok((phi, d1, d2))
}

impl<'a> ShellElement<'a> {
    /// Reference data of the element for `rule` (the rule of its section): kinematic
    /// vectors X̄_a, D_a, E⁰_k = φ(|D_b − D_a|²)(D_b − D_a) and, per point, the strain map
    /// to the lamina basis and weight × det J.
    pub fn geometry(&self, rule: &SectionRule) -> Result<ElementGeometry, ElementFailure> {
        let mut r = [Vector3::zeros(); NV];
        let mut phi0 = [1.0; 4];
        for a in 0..4 {
            r[a] = self.x0[a];
            r[VD + a] = self.d0[a];
        }
        for (k, &(a, b)) in EDGES.iter().enumerate() {
            let v = self.d0[b] - self.d0[a];
            phi0[k] = edge_gradient(&v)?.0;
            r[VE + k] = v * phi0[k];
        }
        // Lamina basis direction e1, common to the element: the grain, or ∂X/∂ξ at the centre.
        let dir1 = self.grain.unwrap_or_else(|| (self.x0[1] - self.x0[0] + self.x0[2] - self.x0[3]) * 0.25);
        let centres = rule.centres.iter().map(|p| self.point_geometry(&r, &p.g, p.w, &dir1)).collect::<Result<Vec<_>, _>>()?;
        let per_level = rule.points.len() / rule.centres.len().max(1);
        let points = rule
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut pg = self.point_geometry(&r, &p.g, p.w, &dir1)?;
                pg.mc = centres[i / per_level.max(1)].m.fixed_rows::<1>(2).into_owned();
                pg.m.fixed_rows_mut::<1>(2).fill(0.0);
                Ok(pg)
            })
            .collect::<Result<Vec<_>, ElementFailure>>()?;
        Ok(ElementGeometry { r, phi0, points: points.into_boxed_slice() })
    }

    /// Kinematic vectors of the state given by displacements `u` and director `frames`.
    fn kinematics<'g>(&self, geom: &'g ElementGeometry, u: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4]) -> Result<Kinematics<'g>, ElementFailure> {
        let mut dv = [Vector3::zeros(); NV];
        for a in 0..4 {
            dv[a] = u[a];
            dv[VD + a] = frames[a].d - self.d0[a];
        }
        let mut v = [Vector3::zeros(); 4];
        let mut jac = [Matrix3::identity(); 4];
        let mut dphi = [[0.0; 2]; 4];
        for (k, &(a, b)) in EDGES.iter().enumerate() {
            let v0 = self.d0[b] - self.d0[a];
            v[k] = frames[b].d - frames[a].d;
            let (phi, d1, d2) = edge_gradient(&v[k])?;
            // E − E⁰ = φ (v − v⁰) + (φ − φ⁰) v⁰, free of cancellation for small changes.
            dv[VE + k] = (dv[VD + b] - dv[VD + a]) * phi + v0 * (phi - geom.phi0[k]);
            jac[k] = Matrix3::identity() * phi + v[k] * v[k].transpose() * (2.0 * d1);
            dphi[k] = [d1, d2];
        }
        Ok(Kinematics { r: &geom.r, dv, v, jac, dphi })
    }

    /// Reference metric of an integration point with base-vector forms `g` and weight `w`:
    /// det J and the map of natural strains to the local lamina basis (e3 normal to g_ξ, g_η;
    /// e1 along `dir1` projected into the lamina, or along g_ξ if `dir1` is normal to it).
    fn point_geometry(&self, r: &[Vector3<f64>; NV], g: &[Lin; 3], w: f64, dir1: &Vector3<f64>) -> Result<PointGeometry, ElementFailure> {
        let gr = [g[0].eval(r), g[1].eval(r), g[2].eval(r)];
        let jm = Matrix3::from_columns(&gr);
        let det = jm.determinant();
        if !(det > 0.0) {
            return Err(ElementFailure::Geometry { det_j: det });
        }
        let jinv = jm.try_inverse().ok_or(ElementFailure::Geometry { det_j: det })?;
        let e3 = gr[0].cross(&gr[1]).normalize();
        let rg = *dir1;
        let mut e1 = rg - e3 * e3.dot(&rg);
        if e1.norm() < 1e-8 * rg.norm().max(1e-300) {
            e1 = gr[0] - e3 * e3.dot(&gr[0]);
        }
        let e1 = e1.normalize();
        let e2 = e3.cross(&e1);
        let t = jinv * Matrix3::from_columns(&[e1, e2, e3]);
        const NAT: [(usize, usize); 5] = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2)];
        const LOC: [(usize, usize); 5] = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2)];
        let mut m = SMatrix::<f64, 5, 5>::zeros();
        for (r_, &(k, l)) in LOC.iter().enumerate() {
            let voigt = if k == l { 1.0 } else { 2.0 };
            for (c, &(i, j)) in NAT.iter().enumerate() {
                let v = if i == j { t[(i, k)] * t[(i, l)] } else { t[(i, k)] * t[(j, l)] + t[(j, k)] * t[(i, l)] };
                m[(r_, c)] = voigt * v;
            }
        }
        Ok(PointGeometry { m, wdet: w * det, mc: SMatrix::<f64, 1, 5>::zeros() })
    }

    /// Natural Green–Lagrange strains at a point and (when `grad` is given) their gradients
    /// with respect to the kinematic vectors, written into `grad`. Each term is evaluated as
    /// ½(P·Δq + Δp·Q + Δp·Δq) with Δp = p − P built from the changes of the kinematic vectors,
    /// so small strains carry no cancellation error (½(p·q − P·Q) would lose about |X|²/|E|
    /// of precision and leave a residual floor on stiff, thin shells).
    /// Gradients: ∂(½ w p·q)/∂V_i = ½ w (c^p_i q + c^q_i p).
    fn natural_strain(terms: &[[Option<Term>; 2]; 5], kin: &Kinematics, mut grad: Option<&mut [[Vector3<f64>; NV]; 5]>) -> Voigt5 {
        let mut nat = Voigt5::zeros();
        if let Some(g) = grad.as_deref_mut() {
            for gc in g.iter_mut() {
                gc.iter_mut().for_each(|v| *v = Vector3::zeros());
            }
        }
        for c in 0..5 {
            for t in terms[c].iter().flatten() {
                let pr = t.p.eval(kin.r);
                let dp = t.p.eval(&kin.dv);
                let (qr, dq) = if t.same { (pr, dp) } else { (t.q.eval(kin.r), t.q.eval(&kin.dv)) };
                nat[c] += t.w * 0.5 * (pr.dot(&dq) + dp.dot(&qr) + dp.dot(&dq));
                if let Some(g) = grad.as_deref_mut() {
                    let (p, q) = ((pr + dp) * (0.5 * t.w), (qr + dq) * (0.5 * t.w));
                    for (i, ci) in t.p.terms() {
                        g[c][i] += q * ci;
                    }
                    for (i, ci) in t.q.terms() {
                        g[c][i] += p * ci;
                    }
                }
            }
        }
        nat
    }

    /// Maps a gradient over the kinematic vectors to the director side of node a: the 3-vector
    /// g_{d_a} + Σ_k ±J_k g_{E_k} (+ when a is the edge's end node b, − when its start a).
    fn director_chain(g: &[Vector3<f64>; NV], kin: &Kinematics) -> [Vector3<f64>; 4] {
        let mut eff = [g[VD], g[VD + 1], g[VD + 2], g[VD + 3]];
        for (k, &(a, b)) in EDGES.iter().enumerate() {
            if g[VE + k] != Vector3::zeros() {
                let je = kin.jac[k] * g[VE + k];
                eff[b] += je;
                eff[a] -= je;
            }
        }
        eff
    }

    /// Natural strain–DOF matrix (5×20) from the kinematic gradients: δx̄_a = δu_a,
    /// δd_a = t1 δα1 + t2 δα2, δE_k = J_k (δd_b − δd_a).
    fn natural_b(grad: &[[Vector3<f64>; NV]; 5], kin: &Kinematics, frames: &[DirectorFrame; 4]) -> BMat {
        let mut bn = BMat::zeros();
        for c in 0..5 {
            let eff = Self::director_chain(&grad[c], kin);
            for a in 0..4 {
                for i in 0..3 {
                    bn[(c, 5 * a + i)] = grad[c][a][i];
                }
                bn[(c, 5 * a + 3)] = eff[a].dot(&frames[a].t1);
                bn[(c, 5 * a + 4)] = eff[a].dot(&frames[a].t2);
            }
        }
        bn
    }

    /// Internal force, tangent (if `with_tangent`) and energy in the configuration given by
    /// nodal displacements `u` and current director frames `frames`. Builds the section rule
    /// and the element's reference geometry on every call; the assembler caches both and
    /// calls `response_with`.
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
    ///
    /// Tangent = Σ BᵀDB (material) + Aᵀ(S⊗I)A (second derivatives of the strain terms in the
    /// kinematic vectors, S_ij = Σ ½ w s (c^p_i c^q_j + c^q_i c^p_j), A = ∂V/∂DOF) + f·∂²V
    /// (second derivatives of the kinematic vectors: ∂²d_a = −(δα·Δα) d_a from the exponential
    /// map, and ∂²E_k = J_k ∂²v_k + ∂²F[δv_k, Δv_k]).
    pub fn response_with(
        &self,
        rule: &SectionRule,
        geom: &ElementGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        with_tangent: bool,
    ) -> Result<ElementOutput, ElementFailure> {
        let kin = self.kinematics(geom, u, frames)?;
        let mut k = if with_tangent { Some(Box::new(ElemMat::zeros())) } else { None };
        let mut energy = 0.0;
        // Generalised forces on the kinematic vectors and the second-derivative matrix S.
        let mut fv = [Vector3::zeros(); NV];
        let mut s = [[0.0; NV]; NV];
        let mut grad = [[Vector3::zeros(); NV]; 5];
        let mut grad_c = [[Vector3::zeros(); NV]; 5];
        let per_level = rule.points.len() / rule.centres.len().max(1);
        for (level, centre) in rule.centres.iter().enumerate() {
            // The lamina's centre strains (in-plane shear sampling), shared by its 4 points.
            let nat_c = Self::natural_strain(&centre.terms, &kin, Some(&mut grad_c));
            let bn_c = if with_tangent { Self::natural_b(&grad_c, &kin, frames) } else { BMat::zeros() };
            let mut sn_c = Voigt5::zeros();
            let range = level * per_level..(level + 1) * per_level;
            for (rp, pg) in rule.points[range.clone()].iter().zip(geom.points[range].iter()) {
                let nat = Self::natural_strain(&rp.terms, &kin, Some(&mut grad));
                let mut eps = pg.m * nat;
                eps[2] = (pg.mc * nat_c)[0];
                let res = self.section.material.response_at(&eps, rule.zetas[level]).map_err(ElementFailure::Material)?;
                energy += pg.wdet * res.energy;
                let sn = pg.m.transpose() * (res.stress * pg.wdet);
                sn_c += pg.mc.transpose() * (res.stress[2] * pg.wdet);
                for c in 0..5 {
                    for i in 0..NV {
                        fv[i] += grad[c][i] * sn[c];
                    }
                }
                if let Some(k) = k.as_mut() {
                    let mut b = pg.m * Self::natural_b(&grad, &kin, frames);
                    b.fixed_rows_mut::<1>(2).copy_from(&(pg.mc * bn_c));
                    let db = (res.tangent * pg.wdet) * b;
                    // Material part BᵀDB (columns of Bᵀ are contiguous: vectorised axpys).
                    **k += b.transpose() * db;
                    Self::accumulate_second_derivatives(&mut s, &rp.terms, &sn);
                }
            }
            for c in 0..5 {
                for i in 0..NV {
                    fv[i] += grad_c[c][i] * sn_c[c];
                }
            }
            if with_tangent {
                Self::accumulate_second_derivatives(&mut s, &centre.terms, &sn_c);
            }
        }
        let feff = Self::director_chain(&fv, &kin);
        let mut force = ElemVec::zeros();
        for a in 0..4 {
            for i in 0..3 {
                force[5 * a + i] = fv[a][i];
            }
            force[5 * a + 3] = feff[a].dot(&frames[a].t1);
            force[5 * a + 4] = feff[a].dot(&frames[a].t2);
        }
        if let Some(k) = k.as_mut() {
            Self::add_geometric_tangent(k, &s, &fv, &feff, &kin, frames);
        }
        Ok(ElementOutput { force, stiffness: k, energy })
    }

    /// Adds Σ ½ w s_c (c^p ⊗ c^q + c^q ⊗ c^p) of every strain term to `s`, with `sn` the
    /// stresses conjugate to the natural components (weighted).
    fn accumulate_second_derivatives(s: &mut [[f64; NV]; NV], terms: &[[Option<Term>; 2]; 5], sn: &Voigt5) {
        for c in 0..5 {
            if sn[c] == 0.0 {
                continue;
            }
            for t in terms[c].iter().flatten() {
                let sw = 0.5 * sn[c] * t.w;
                for (i, ci) in t.p.terms() {
                    for (j, cj) in t.q.terms() {
                        let v = sw * ci * cj;
                        s[i][j] += v;
                        s[j][i] += v;
                    }
                }
            }
        }
    }

    /// Adds Aᵀ(S⊗I)A and the f·∂²V terms (see `response`) to the tangent `k`.
    fn add_geometric_tangent(
        k: &mut ElemMat,
        s: &[[f64; NV]; NV],
        fv: &[Vector3<f64>; NV],
        feff: &[Vector3<f64>; 4],
        kin: &Kinematics,
        frames: &[DirectorFrame; 4],
    ) {
        let tm: [Matrix3x2<f64>; 4] = std::array::from_fn(|a| frames[a].tangent_map());
        // ∂E_k/∂α at the edge's start and end nodes: −J_k T_a and +J_k T_b.
        let jt: [[Matrix3x2<f64>; 2]; 4] = std::array::from_fn(|e| {
            let (a, b) = EDGES[e];
            [-(kin.jac[e] * tm[a]), kin.jac[e] * tm[b]]
        });
        // Y[i][b] = Σ_j S_ij ∂V_j/∂α_b over the director-side vectors j.
        let mut y = [[Matrix3x2::<f64>::zeros(); 4]; NV];
        for (i, yi) in y.iter_mut().enumerate() {
            for (b, yib) in yi.iter_mut().enumerate() {
                *yib = tm[b] * s[i][VD + b];
            }
            for (e, &(a, b)) in EDGES.iter().enumerate() {
                let se = s[i][VE + e];
                if se != 0.0 {
                    yi[a] += jt[e][0] * se;
                    yi[b] += jt[e][1] * se;
                }
            }
        }
        for a in 0..4 {
            for b in 0..4 {
                let (ra, cb) = (5 * a, 5 * b);
                for i in 0..3 {
                    k[(ra + i, cb + i)] += s[a][b];
                }
                // Translation–tilt coupling.
                let ud = &y[a][b];
                for i in 0..3 {
                    for j in 0..2 {
                        k[(ra + i, cb + 3 + j)] += ud[(i, j)];
                        k[(cb + 3 + j, ra + i)] += ud[(i, j)];
                    }
                }
                // Tilt–tilt: Σ_i (∂V_i/∂α_a)ᵀ Y[i][b].
                let mut dd = tm[a].transpose() * y[VD + a][b];
                for (e, &(ea, eb)) in EDGES.iter().enumerate() {
                    if ea == a {
                        dd += jt[e][0].transpose() * y[VE + e][b];
                    }
                    if eb == a {
                        dd += jt[e][1].transpose() * y[VE + e][b];
                    }
                }
                for i in 0..2 {
                    for j in 0..2 {
                        k[(ra + 3 + i, cb + 3 + j)] += dd[(i, j)];
                    }
                }
            }
            // f·∂²d_a through the director and the edges: −(δα·Δα)(feff_a·d_a).
            let diag = -feff[a].dot(&frames[a].d);
            k[(5 * a + 3, 5 * a + 3)] += diag;
            k[(5 * a + 4, 5 * a + 4)] += diag;
        }
        // f_E·∂²F[δv, Δv] with ∂²(f·F)/∂v² = 2φ'(f vᵀ + v fᵀ + (f·v) I) + 4φ''(f·v) v vᵀ.
        for (e, &(a, b)) in EDGES.iter().enumerate() {
            let f = fv[VE + e];
            if f == Vector3::zeros() {
                continue;
            }
            let v = kin.v[e];
            let [d1, d2] = kin.dphi[e];
            let fvd = f.dot(&v);
            let q = (f * v.transpose() + v * f.transpose() + Matrix3::identity() * fvd) * (2.0 * d1) + v * v.transpose() * (4.0 * d2 * fvd);
            for (na, sa) in [(a, -1.0), (b, 1.0)] {
                for (nb, sb) in [(a, -1.0), (b, 1.0)] {
                    let blk = tm[na].transpose() * q * tm[nb] * (sa * sb);
                    for i in 0..2 {
                        for j in 0..2 {
                            k[(5 * na + 3 + i, 5 * nb + 3 + j)] += blk[(i, j)];
                        }
                    }
                }
            }
        }
    }

    /// Mid-surface lamina strain and stress at the element centre (for output), from nodal
    /// displacements `u` and current frames.
    pub fn centre_state(&self, u: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4]) -> Result<(Voigt5, Voigt5), ElementFailure> {
        let rp = rule_point(0.0, 0.0, 0.0, 1.0, self.section.thickness, self.section.shear);
        let rule = SectionRule { points: vec![rp.clone()], centres: vec![rp.clone()], zetas: vec![0.0] };
        let geom = self.geometry(&rule)?;
        let kin = self.kinematics(&geom, u, frames)?;
        let nat = Self::natural_strain(&rp.terms, &kin, None);
        // At the centre the sampled in-plane shear is the point's own.
        let pg = &geom.points[0];
        let mut eps = pg.m * nat;
        eps[2] = (pg.mc * nat)[0];
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
mod tests {
    use super::*;
    use crate::material::{NeoHookean, StVenantKirchhoff};
    use nalgebra::{Rotation3, Unit};

    fn section(shear: ShearTreatment, nh: bool) -> Section {
        let material: Arc<dyn ShellMaterial> = if nh {
            Arc::new(NeoHookean::new(1.0e4 / 3.0, 1.0e4 / 2.6))
        } else {
            Arc::new(StVenantKirchhoff::new(1.0e4, 0.3, 5.0 / 6.0))
        };
        Section { thickness: 0.05, shear, thickness_points: 2, material }
    }

    /// A distorted, slightly warped quad with non-parallel directors.
    fn geometry() -> ([Vector3<f64>; 4], [Vector3<f64>; 4]) {
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

    fn frames(d: &[Vector3<f64>; 4]) -> [DirectorFrame; 4] {
        std::array::from_fn(|a| DirectorFrame::new(d[a], Some(Vector3::x())))
    }

    /// Applies an element DOF increment (translations added, tilts by the exponential map).
    fn apply(u: &[Vector3<f64>; 4], f: &[DirectorFrame; 4], du: &ElemVec) -> ([Vector3<f64>; 4], [DirectorFrame; 4]) {
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
    #[test]
    fn free_warped_element_has_six_zero_energy_modes() {
        let (x0, d0) = geometry();
        let sec = section(ShearTreatment::Mitc4, false);
        let el = ShellElement { x0, d0, grain: None, section: &sec };
        let k = el.response(&[Vector3::zeros(); 4], &frames(&d0), true).unwrap().stiffness.unwrap();
        let eig = nalgebra::DMatrix::from_fn(20, 20, |i, j| k[(i, j)]).symmetric_eigen();
        let max = eig.eigenvalues.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let zero = eig.eigenvalues.iter().filter(|v| v.abs() < 1e-10 * max).count();
        assert_eq!(zero, 6, "eigenvalues {:?}", eig.eigenvalues.as_slice());
    }

    #[test]
    fn tangent_matches_central_differences_of_residual() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri] {
            for nh in [false, true] {
                let sec = section(shear, nh);
                let el = ShellElement { x0, d0, grain: None, section: &sec };
                // A strongly deformed state: stretch, shear, large rotation of the directors.
                let mut u = ElemVec::zeros();
                for a in 0..4 {
                    u[5 * a] = 0.15 * x0[a].y + 0.05 * a as f64;
                    u[5 * a + 1] = -0.1 * x0[a].x;
                    u[5 * a + 2] = 0.3 * x0[a].x * x0[a].y;
                    u[5 * a + 3] = 0.4 - 0.1 * a as f64;
                    u[5 * a + 4] = -0.3 + 0.2 * a as f64;
                }
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
                assert!(worst < 1e-6, "{shear:?} nh={nh}: tangent error {worst}");
                // Symmetric tangent of a conservative element.
                assert!((*k - k.transpose()).abs().max() < 1e-9 * scale);
            }
        }
    }

    #[test]
    fn rigid_rotation_of_any_size_is_strain_free() {
        let (x0, d0) = geometry();
        let sec = section(ShearTreatment::Mitc4, true);
        let el = ShellElement { x0, d0, grain: None, section: &sec };
        for deg in [170.0f64, 400.0] {
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
            assert!(e.abs() < 1e-14, "{deg}°: energy {e}");
        }
    }
}
