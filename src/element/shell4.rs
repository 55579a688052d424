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
//! Every strain component is a sum of terms ½(p·q − P·Q) with p, q linear in the nodal
//! positions and directors, so the residual B·S and the consistent tangent
//! BᵀDB + Σ S ∂²E (material + geometric part, with ∂²d = −(δα·Δα) d from the exponential
//! director map) follow exactly from one small set of coefficients.

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
}

impl std::fmt::Display for ElementFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementFailure::Geometry { det_j } => write!(f, "degenerate reference geometry (det J = {det_j:.3e})"),
            ElementFailure::Material(m) => write!(f, "{m}"),
            ElementFailure::ThicknessRule(n) => write!(f, "{n} thickness points (1 to 5 supported)"),
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

/// Linear form p = Σ_a cx_a x̄_a + cd_a d_a of the nodal positions and directors.
#[derive(Clone, Copy, Debug, Default)]
struct Lin {
    cx: [f64; 4],
    cd: [f64; 4],
}

impl Lin {
    fn eval(&self, x: &[Vector3<f64>; 4], d: &[Vector3<f64>; 4]) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        for a in 0..4 {
            v += x[a] * self.cx[a] + d[a] * self.cd[a];
        }
        v
    }
}

/// One term w·½(p·q − P·Q) of a natural strain component.
#[derive(Clone, Copy, Debug)]
struct Term {
    w: f64,
    p: Lin,
    q: Lin,
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

/// Covariant base-vector forms at (ξ, η, ζ): g_ξ, g_η, g_ζ.
fn base_forms(xi: f64, eta: f64, zeta: f64, h: f64) -> [Lin; 3] {
    let (n, dxi, deta) = bilinear(xi, eta);
    let mut g = [Lin::default(); 3];
    for a in 0..4 {
        g[0].cx[a] = dxi[a];
        g[0].cd[a] = 0.5 * zeta * h * dxi[a];
        g[1].cx[a] = deta[a];
        g[1].cd[a] = 0.5 * zeta * h * deta[a];
        g[2].cd[a] = 0.5 * h * n[a];
    }
    g
}

/// Integration-point data that depends only on the reference state.
struct PointGeometry {
    /// Natural → local Voigt strain map, rows [E11, E22, 2E12, 2E13, 2E23], columns
    /// [E_ξξ, E_ηη, E_ξη, E_ξζ, E_ηζ].
    m: SMatrix<f64, 5, 5>,
    /// Weight × det J.
    wdet: f64,
    /// Strain terms of the five natural components.
    terms: [[Option<Term>; 2]; 5],
}

impl<'a> ShellElement<'a> {
    /// Reference geometry of the integration point (ξ, η, ζ) with weight `w`.
    fn point_geometry(&self, xi: f64, eta: f64, zeta: f64, w: f64) -> Result<PointGeometry, ElementFailure> {
        let h = self.section.thickness;
        let g = base_forms(xi, eta, zeta, h);
        let gr: Vec<Vector3<f64>> = g.iter().map(|l| l.eval(&self.x0, &self.d0)).collect();
        let jm = Matrix3::from_columns(&[gr[0], gr[1], gr[2]]);
        let det = jm.determinant();
        if !(det > 0.0) {
            return Err(ElementFailure::Geometry { det_j: det });
        }
        let jinv = jm.try_inverse().ok_or(ElementFailure::Geometry { det_j: det })?;
        let e3 = gr[0].cross(&gr[1]).normalize();
        let r = self.grain.unwrap_or(gr[0]);
        let mut e1 = r - e3 * e3.dot(&r);
        if e1.norm() < 1e-8 * r.norm().max(1e-300) {
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
        let one = |p: Lin, q: Lin| [Some(Term { w: 1.0, p, q }), None];
        let tied = |pts: [(f64, f64, f64); 2], comp: usize| {
            let mut out = [None, None];
            for (slot, &(xt, yt, wt)) in pts.iter().enumerate() {
                if wt != 0.0 {
                    let gt = base_forms(xt, yt, zeta, h);
                    out[slot] = Some(Term { w: wt, p: gt[comp], q: gt[2] });
                }
            }
            out
        };
        let (xz, yz) = match self.section.shear {
            ShearTreatment::Mitc4 => (
                tied([(0.0, -1.0, 0.5 * (1.0 - eta)), (0.0, 1.0, 0.5 * (1.0 + eta))], 0),
                tied([(-1.0, 0.0, 0.5 * (1.0 - xi)), (1.0, 0.0, 0.5 * (1.0 + xi))], 1),
            ),
            ShearTreatment::Sri => (tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 0), tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 1)),
        };
        let terms = [one(g[0], g[0]), one(g[1], g[1]), one(g[0], g[1]), xz, yz];
        Ok(PointGeometry { m, wdet: w * det, terms })
    }

    /// Integration points (ξ, η, ζ, weight): 2×2 in the plane times the thickness rule.
    fn points(&self) -> Result<Vec<(f64, f64, f64, f64)>, ElementFailure> {
        let (pz, wz) = gauss_legendre(self.section.thickness_points)
            .ok_or(ElementFailure::ThicknessRule(self.section.thickness_points))?;
        let (p2, _) = gauss_legendre(2).ok_or(ElementFailure::ThicknessRule(2))?;
        let mut out = Vec::with_capacity(4 * pz.len());
        for &eta in p2 {
            for &xi in p2 {
                for (&z, &w) in pz.iter().zip(wz) {
                    out.push((xi, eta, z, w));
                }
            }
        }
        Ok(out)
    }

    /// Green–Lagrange lamina strain, its B matrix (when `with_b`) at a point, from nodal
    /// displacements `u` and current frames. Each term is evaluated as
    /// ½(P·Δq + Δp·Q + Δp·Δq) with Δp = p − P built from displacements and director changes,
    /// so small strains carry no cancellation error (½(p·q − P·Q) would lose about
    /// |X|²/|E| of precision and leave a residual floor on stiff, thin shells).
    fn strain(
        &self,
        pg: &PointGeometry,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        with_b: bool,
    ) -> (Voigt5, BMat, [[(Vector3<f64>, Vector3<f64>); 2]; 5]) {
        let dd: [Vector3<f64>; 4] = std::array::from_fn(|a| frames[a].d - self.d0[a]);
        let mut nat = Voigt5::zeros();
        let mut bn = BMat::zeros();
        let mut pq = [[(Vector3::zeros(), Vector3::zeros()); 2]; 5];
        for c in 0..5 {
            for (s, term) in pg.terms[c].iter().enumerate() {
                let Some(t) = term else { continue };
                let pr = t.p.eval(&self.x0, &self.d0);
                let qr = t.q.eval(&self.x0, &self.d0);
                let dp = t.p.eval(u, &dd);
                let dq = t.q.eval(u, &dd);
                nat[c] += t.w * 0.5 * (pr.dot(&dq) + dp.dot(&qr) + dp.dot(&dq));
                let (p, q) = (pr + dp, qr + dq);
                pq[c][s] = (p, q);
                if with_b {
                    for a in 0..4 {
                        let vu = (q * t.p.cx[a] + p * t.q.cx[a]) * (0.5 * t.w);
                        let vd = (q * t.p.cd[a] + p * t.q.cd[a]) * (0.5 * t.w);
                        for k in 0..3 {
                            bn[(c, 5 * a + k)] += vu[k];
                        }
                        bn[(c, 5 * a + 3)] += vd.dot(&frames[a].t1);
                        bn[(c, 5 * a + 4)] += vd.dot(&frames[a].t2);
                    }
                }
            }
        }
        (pg.m * nat, pg.m * bn, pq)
    }

    /// Internal force, tangent (if `with_tangent`) and energy in the configuration given by
    /// nodal displacements `u` and current director frames `frames`.
    pub fn response(
        &self,
        u: &[Vector3<f64>; 4],
        frames: &[DirectorFrame; 4],
        with_tangent: bool,
    ) -> Result<ElementOutput, ElementFailure> {
        let mut force = ElemVec::zeros();
        let mut k = if with_tangent { Some(Box::new(ElemMat::zeros())) } else { None };
        let mut energy = 0.0;
        // Geometric-stiffness coefficients per node pair.
        let mut sxx = [[0.0; 4]; 4];
        let mut sxd = [[0.0; 4]; 4];
        let mut sdd = [[0.0; 4]; 4];
        let mut sdiag = [0.0; 4];
        for (xi, eta, zeta, w) in self.points()? {
            let pg = self.point_geometry(xi, eta, zeta, w)?;
            let (eps, b, pq) = self.strain(&pg, u, frames, true);
            let r = self.section.material.response_at(&eps, zeta).map_err(ElementFailure::Material)?;
            energy += pg.wdet * r.energy;
            force += b.transpose() * (r.stress * pg.wdet);
            if let Some(k) = k.as_mut() {
                let db = r.tangent * b;
                **k += b.transpose() * (db * pg.wdet);
                let sn = pg.m.transpose() * (r.stress * pg.wdet);
                for c in 0..5 {
                    for (s, term) in pg.terms[c].iter().enumerate() {
                        let Some(t) = term else { continue };
                        let sw = 0.5 * sn[c] * t.w;
                        let (p, q) = pq[c][s];
                        for a in 0..4 {
                            for bb in 0..4 {
                                sxx[a][bb] += sw * (t.p.cx[a] * t.q.cx[bb] + t.q.cx[a] * t.p.cx[bb]);
                                sxd[a][bb] += sw * (t.p.cx[a] * t.q.cd[bb] + t.q.cx[a] * t.p.cd[bb]);
                                sdd[a][bb] += sw * (t.p.cd[a] * t.q.cd[bb] + t.q.cd[a] * t.p.cd[bb]);
                            }
                            sdiag[a] -= sw * (t.p.cd[a] * q.dot(&frames[a].d) + t.q.cd[a] * p.dot(&frames[a].d));
                        }
                    }
                }
            }
        }
        if let Some(k) = k.as_mut() {
            let maps: [Matrix3x2<f64>; 4] = std::array::from_fn(|a| frames[a].tangent_map());
            for a in 0..4 {
                for bb in 0..4 {
                    let (ra, cb) = (5 * a, 5 * bb);
                    for i in 0..3 {
                        k[(ra + i, cb + i)] += sxx[a][bb];
                    }
                    let ud = maps[bb] * sxd[a][bb];
                    let dd = maps[a].transpose() * maps[bb] * sdd[a][bb];
                    for i in 0..3 {
                        for j in 0..2 {
                            k[(ra + i, cb + 3 + j)] += ud[(i, j)];
                            k[(cb + 3 + j, ra + i)] += ud[(i, j)];
                        }
                    }
                    for i in 0..2 {
                        for j in 0..2 {
                            k[(ra + 3 + i, cb + 3 + j)] += dd[(i, j)];
                        }
                    }
                }
                k[(5 * a + 3, 5 * a + 3)] += sdiag[a];
                k[(5 * a + 4, 5 * a + 4)] += sdiag[a];
            }
        }
        Ok(ElementOutput { force, stiffness: k, energy })
    }

    /// Mid-surface lamina strain and stress at the element centre (for output), from nodal
    /// displacements `u` and current frames.
    pub fn centre_state(&self, u: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4]) -> Result<(Voigt5, Voigt5), ElementFailure> {
        let pg = self.point_geometry(0.0, 0.0, 0.0, 1.0)?;
        let (eps, _, _) = self.strain(&pg, u, frames, false);
        let r = self.section.material.response(&eps).map_err(ElementFailure::Material)?;
        Ok((eps, r.stress))
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
