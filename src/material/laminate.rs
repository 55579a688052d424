//! A laminate: bonded plies stacked through the thickness of one shell section.
//!
//! Each ply keeps its own lamina law (St. Venant–Kirchhoff, neo-Hookean, fabric, …) and is
//! integrated through its own thickness band [z_{k−1}, z_k] of the stack, measured from the
//! laminate's mid-surface, with its own Gauss rule (the ply material's `thickness_points`,
//! else 2). The element sees one section of thickness H = Σ h_k whose thickness rule is the
//! union of the plies' rules mapped to their bands ([`ShellMaterial::thickness_rule`]); at a
//! point of ply k the ply's law is evaluated at its own thickness coordinate
//! ζ_k = (z − z̄_k)/(h_k/2), z̄_k the ply's mid-plane.
//!
//! This is classical lamination theory (Jones, *Mechanics of Composite Materials*, 2nd ed.
//! 1999, §4.2, eqs. 4.22–4.24): with strains linear through the thickness, E = ε⁰ + z κ, the
//! stress resultants are N = A ε⁰ + B κ, M = B ε⁰ + D κ with
//! A = Σ Q_k (z_k − z_{k−1}), B = ½ Σ Q_k (z_k² − z_{k−1}²), D = ⅓ Σ Q_k (z_k³ − z_{k−1}³).
//! For a homogeneous ply the integrand Q_k (1, z, z²) is a polynomial of degree 2 in z, so a
//! 2-point Gauss rule per ply integrates A, B and D exactly; a nonsymmetric stack has B ≠ 0
//! (membrane–bending coupling), which the element picks up with no further change, since
//! the section's reference surface is the laminate's geometric mid-surface.
//!
//! Fabric plies. A fabric's bending rigidity B_f is far below its A h²/12 (yarns slide within
//! the ply; `fabric`). Within its band a fabric ply keeps its own through-thickness split
//! C(ζ_k) = α + β ζ_k², which gives ∫C dz = A_k and ∫C (z − z̄_k)² dz = D_k (its own
//! rigidity about its own mid-plane) and ∫C (z − z̄_k) dz = 0. About the laminate mid-surface
//! the ply therefore contributes A_k to A, A_k z̄_k to B and D_k + A_k z̄_k² to D: its own
//! rigidity plus the parallel-axis (Steiner) term of its membrane stiffness. This is the
//! equivalent-single-layer rule of classical lamination theory with each ply's Q_k h_k³/12
//! replaced by its measured bending rigidity; it assumes that the plies are bonded (no slip
//! *between* plies — the Laminate model's premise), while slip *within* a ply stays in D_k.
//! The 3-point rule of a fabric ply integrates the quartic C(ζ)(z̄ + z)² exactly.
//!
//! Transverse shear: each ply's own transverse shear law, integrated over its band (a
//! first-order shear-deformation laminate; the shear correction factors stay the plies').

use std::sync::Arc;

use nalgebra::SMatrix;

use super::{MaterialFailure, PointResponse, ShellMaterial, Voigt5};
use crate::element::quadrature::gauss_legendre;

/// One ply of a laminate.
#[derive(Clone, Debug)]
pub struct LaminaPly {
    /// Name (for output and errors).
    pub name: String,
    /// The ply's lamina law.
    pub material: Arc<dyn ShellMaterial>,
    /// Ply thickness h_k (m).
    pub thickness: f64,
    /// Mass per area (kg/m²), if known.
    pub areal_density: Option<f64>,
}

/// Membrane–bending stiffness of a section: [[A, B], [B, D]] over (ε⁰₁₁, ε⁰₂₂, γ⁰₁₂, κ₁₁,
/// κ₂₂, κ₁₂) (N/m, N, N·m).
pub type Abd = SMatrix<f64, 6, 6>;

/// A laminate section law (see the module documentation).
#[derive(Clone, Debug)]
pub struct Laminate {
    /// Plies from the bottom (ζ = −1, against the director) to the top (ζ = +1).
    plies: Vec<LaminaPly>,
    /// Total thickness H.
    total: f64,
    /// Band [ζ_lo, ζ_hi] of each ply in the section's thickness coordinate.
    bands: Vec<(f64, f64)>,
    /// Thickness rule of the section: (ζ, weight), weights summing to 2.
    rule: Vec<[f64; 2]>,
}

impl Laminate {
    /// A laminate of `plies` listed from the bottom (ζ = −1) to the top (ζ = +1, the
    /// director side). Errors: fewer than two plies, a non-positive or non-finite thickness,
    /// or a ply whose material asks for an unsupported thickness rule.
    pub fn new(plies: Vec<LaminaPly>) -> Result<Self, String> {
        if plies.len() < 2 {
            return Err(format!("a laminate needs at least two plies, found {}", plies.len()));
        }
        if let Some(p) = plies.iter().find(|p| !(p.thickness.is_finite() && p.thickness > 0.0)) {
            return Err(format!("ply \"{}\": expected a positive thickness, found {}", p.name, p.thickness));
        }
        let total: f64 = plies.iter().map(|p| p.thickness).sum();
        let (mut bands, mut rule) = (Vec::with_capacity(plies.len()), Vec::new());
        let mut below = 0.0;
        for p in &plies {
            let n = p.material.thickness_points().unwrap_or(2);
            let (pz, wz) = gauss_legendre(n).ok_or_else(|| format!("ply \"{}\": {n} thickness points (1 to 5 supported)", p.name))?;
            let (lo, hi) = (2.0 * below / total - 1.0, 2.0 * (below + p.thickness) / total - 1.0);
            below += p.thickness;
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            rule.extend(pz.iter().zip(wz).map(|(&z, &w)| [mid + half * z, half * w]));
            bands.push((lo, hi));
        }
        Ok(Self { plies, total, bands, rule })
    }

    /// The plies, bottom to top.
    pub fn plies(&self) -> &[LaminaPly] {
        &self.plies
    }

    /// Total thickness H = Σ h_k.
    pub fn thickness(&self) -> f64 {
        self.total
    }

    /// The ply at section coordinate ζ and the ply's own coordinate ζ_k ∈ [−1, 1]; a point on
    /// an interface belongs to the ply below it.
    fn ply_at(&self, zeta: f64) -> (&LaminaPly, f64) {
        let k = self.bands.iter().position(|&(_, hi)| zeta <= hi).unwrap_or(self.bands.len() - 1);
        let (lo, hi) = self.bands[k];
        (&self.plies[k], ((2.0 * zeta - lo - hi) / (hi - lo)).clamp(-1.0, 1.0))
    }

    /// Small-strain ABD matrix about the mid-surface, integrated with the section's own
    /// thickness rule from each ply's tangent at zero strain (exact for the plies of this
    /// crate: see the module documentation).
    pub fn abd(&self) -> Result<Abd, MaterialFailure> {
        let mut abd = Abd::zeros();
        for &[zeta, w] in &self.rule {
            let c = self.response_at(&Voigt5::zeros(), zeta)?.tangent;
            let z = 0.5 * self.total * zeta;
            let dz = 0.5 * self.total * w;
            for i in 0..3 {
                for j in 0..3 {
                    let q = c[(i, j)] * dz;
                    abd[(i, j)] += q;
                    abd[(i, j + 3)] += q * z;
                    abd[(i + 3, j)] += q * z;
                    abd[(i + 3, j + 3)] += q * z * z;
                }
            }
        }
        Ok(abd)
    }
}

impl ShellMaterial for Laminate {
    /// The response of the ply at the mid-surface (ζ = 0), for output.
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        self.response_at(strain, 0.0)
    }

    fn response_at(&self, strain: &Voigt5, zeta: f64) -> Result<PointResponse, MaterialFailure> {
        let (ply, local) = self.ply_at(zeta);
        ply.material.response_at(strain, local)
    }

    fn stress_at(&self, strain: &Voigt5, zeta: f64) -> Result<(Voigt5, f64), MaterialFailure> {
        let (ply, local) = self.ply_at(zeta);
        ply.material.stress_at(strain, local)
    }

    /// Thickness-weighted mean modulus and Poisson ratio of the plies (E_mean H = Σ E_k h_k:
    /// the membrane stiffness, for penalty scaling).
    fn small_strain_moduli(&self) -> (f64, f64) {
        let (mut e, mut nu) = (0.0, 0.0);
        for p in &self.plies {
            let (ek, nuk) = p.material.small_strain_moduli();
            e += ek * p.thickness / self.total;
            nu += nuk * p.thickness / self.total;
        }
        (e, nu)
    }

    /// The smaller of the two bending rigidities about the neutral axis, D_ii − B_ii²/A_ii
    /// (the transformed section; `h` is ignored: the laminate has its own thickness).
    fn bending_rigidity(&self, _h: f64) -> f64 {
        let Ok(abd) = self.abd() else { return 0.0 };
        (0..2).map(|i| abd[(i + 3, i + 3)] - abd[(i, i + 3)].powi(2) / abd[(i, i)]).fold(f64::INFINITY, f64::min)
    }

    fn thickness_rule(&self) -> Option<Vec<[f64; 2]>> {
        Some(self.rule.clone())
    }

    fn intrinsic_thickness(&self) -> Option<f64> {
        Some(self.total)
    }

    fn as_laminate(&self) -> Option<(&Laminate, f64)> {
        Some((self, 1.0))
    }

    /// Σ of the plies' areal densities when every ply has one.
    fn areal_density(&self) -> Option<f64> {
        self.plies.iter().map(|p| p.areal_density.or_else(|| p.material.areal_density())).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Fabric, FabricProperties, NeoHookean, StVenantKirchhoff};

    fn svk(name: &str, e: f64, nu: f64, h: f64) -> LaminaPly {
        LaminaPly { name: name.into(), material: Arc::new(StVenantKirchhoff::new(e, nu, 5.0 / 6.0)), thickness: h, areal_density: None }
    }

    /// Plane-stress stiffness Q of an isotropic ply over (ε11, ε22, γ12) (Jones eq. 2.61).
    fn q_iso(e: f64, nu: f64) -> SMatrix<f64, 3, 3> {
        let c = e / (1.0 - nu * nu);
        SMatrix::<f64, 3, 3>::new(c, c * nu, 0.0, c * nu, c, 0.0, 0.0, 0.0, e / (2.0 * (1.0 + nu)))
    }

    /// A nonsymmetric stack of three SVK plies (different E, ν, h): A, B, D from the section
    /// rule equal classical lamination theory (Jones 1999, eqs. 4.22–4.24) to rounding.
    #[test]
    fn abd_of_a_nonsymmetric_stack_is_classical_lamination_theory() {
        let plies = [("bottom", 2.0e8, 0.25, 0.8e-3), ("core", 2.0e7, 0.3, 1.5e-3), ("top", 1.0e8, 0.2, 0.4e-3)];
        let lam = Laminate::new(plies.iter().map(|&(n, e, nu, h)| svk(n, e, nu, h)).collect()).expect("laminate");
        let total: f64 = plies.iter().map(|p| p.3).sum();
        let mut expected = Abd::zeros();
        let mut z0 = -0.5 * total;
        for &(_, e, nu, h) in &plies {
            let z1 = z0 + h;
            let q = q_iso(e, nu);
            for i in 0..3 {
                for j in 0..3 {
                    expected[(i, j)] += q[(i, j)] * (z1 - z0);
                    expected[(i, j + 3)] += q[(i, j)] * 0.5 * (z1 * z1 - z0 * z0);
                    expected[(i + 3, j)] += q[(i, j)] * 0.5 * (z1 * z1 - z0 * z0);
                    expected[(i + 3, j + 3)] += q[(i, j)] * (z1.powi(3) - z0.powi(3)) / 3.0;
                }
            }
            z0 = z1;
        }
        let abd = lam.abd().expect("abd");
        for (blk, (r, c)) in [("A", (0, 0)), ("B", (0, 3)), ("D", (3, 3))] {
            let (got, want) = (abd.fixed_view::<3, 3>(r, c), expected.fixed_view::<3, 3>(r, c));
            let err = (got - want).abs().max() / want.abs().max();
            assert!(err < 1e-12, "{blk}: {got} vs {want} (relative error {err:e})");
        }
        assert!(expected[(0, 3)].abs() > 0.05 * (expected[(0, 0)] * expected[(3, 3)]).sqrt(), "the stack is coupled");
        assert!((lam.thickness() - total).abs() < 1e-15);
    }

    /// With ν = 0 the neutral-axis rigidity D − B²/A of a stack is the transformed section of
    /// beam theory (Timoshenko & Gere, *Mechanics of Materials*, composite beams):
    /// Σ E_k (h_k³/12 + h_k (z̄_k − z_n)²), z_n = Σ E_k h_k z̄_k / Σ E_k h_k.
    #[test]
    fn neutral_axis_rigidity_is_the_transformed_section() {
        let plies = [(2.0e8, 1.0e-3), (1.0e8, 1.0e-3), (2.0e7, 1.0e-3)];
        let lam = Laminate::new(plies.iter().map(|&(e, h)| svk("p", e, 0.0, h)).collect()).expect("laminate");
        let (mut z, mut zs) = (-1.5e-3, Vec::new());
        for &(_, h) in &plies {
            zs.push(z + 0.5 * h);
            z += h;
        }
        let zn = plies.iter().zip(&zs).map(|((e, h), z)| e * h * z).sum::<f64>() / plies.iter().map(|(e, h)| e * h).sum::<f64>();
        let ei: f64 = plies.iter().zip(&zs).map(|((e, h), z)| e * (h.powi(3) / 12.0 + h * (z - zn).powi(2))).sum();
        let got = lam.bending_rigidity(0.0);
        assert!((got / ei - 1.0).abs() < 1e-12, "{got} vs {ei}");
    }

    /// Fabric plies contribute their own A_k, their own rigidity D_k about their mid-plane and
    /// the parallel-axis term A_k z̄_k² (module documentation); B = Σ A_k z̄_k.
    #[test]
    fn fabric_plies_add_own_rigidity_and_parallel_axis_term() {
        let fabric = |name: &str| {
            let p = FabricProperties::preset(name).expect("preset");
            let h = p.thickness;
            (LaminaPly { name: name.into(), material: Arc::new(Fabric::new(p.clone())), thickness: h, areal_density: None }, p)
        };
        let stack = [fabric("ripstop"), fabric("polyester_faille"), fabric("knit_liner")];
        let lam = Laminate::new(stack.iter().map(|(l, _)| l.clone()).collect()).expect("laminate");
        let total: f64 = stack.iter().map(|(_, p)| p.thickness).sum();
        let (mut z0, mut a, mut b, mut d, mut rho) = (-0.5 * total, 0.0, 0.0, 0.0, 0.0);
        for (_, p) in &stack {
            let zbar = z0 + 0.5 * p.thickness;
            let a11 = p.warp_tensile / (1.0 - p.poisson * p.poisson * p.weft_tensile / p.warp_tensile);
            a += a11;
            b += a11 * zbar;
            d += p.warp_bending + a11 * zbar * zbar;
            rho += p.areal_density;
            z0 += p.thickness;
        }
        let abd = lam.abd().expect("abd");
        assert!((abd[(0, 0)] / a - 1.0).abs() < 1e-12, "A11 {} vs {a}", abd[(0, 0)]);
        assert!((abd[(0, 3)] / b - 1.0).abs() < 1e-9, "B11 {} vs {b}", abd[(0, 3)]);
        assert!((abd[(3, 3)] / d - 1.0).abs() < 1e-9, "D11 {} vs {d}", abd[(3, 3)]);
        assert!((lam.areal_density().expect("density") / rho - 1.0).abs() < 1e-12);
    }

    /// The shell element integrates the laminate's section rule: a flat 1 m × 1 m element
    /// stretched by the Green–Lagrange strain e along x (width held) and bent uniformly by
    /// κ about y (the chord normal to the mean director, as in shell4's uniform-bending test,
    /// so no transverse shear) stores ½ A₁₁ e² + B₁₁ e κ + ½ D₁₁ κ² per area — the CLT
    /// energy of the nonsymmetric stack, membrane, coupling and bending terms each to 10⁻⁵
    /// (the rest: the strains' O(e², z²κ²) terms).
    #[test]
    fn element_energy_is_the_clt_energy_of_the_stack() {
        use crate::element::{DirectorFrame, Section, ShearTreatment, ShellElement};
        use nalgebra::{Rotation3, Vector3};
        let plies = [("bottom", 2.0e8, 0.25, 0.8e-3), ("core", 2.0e7, 0.3, 1.5e-3), ("top", 1.0e8, 0.2, 0.4e-3)];
        let lam = Laminate::new(plies.iter().map(|&(n, e, nu, h)| svk(n, e, nu, h)).collect()).expect("laminate");
        let abd = lam.abd().expect("abd");
        let sec = Section { thickness: lam.thickness(), shear: ShearTreatment::Mitc4, thickness_points: 2, material: Arc::new(lam) };
        let x0 = [Vector3::new(0.0, 0.0, 0.0), Vector3::x(), Vector3::new(1.0, 1.0, 0.0), Vector3::y()];
        let el = ShellElement { x0, d0: [Vector3::z(); 4], grain: Some(Vector3::x()), section: &sec };
        let f0 = DirectorFrame::new(Vector3::z(), Some(Vector3::x()));
        let energy = |e: f64, kappa: f64| {
            // Bent down (top fibres stretched: κ₁₁ > 0 with E₁₁ = e + z κ).
            let rot = |a: f64| Rotation3::from_axis_angle(&Vector3::y_axis(), a);
            let tip = rot(0.5 * kappa) * Vector3::new((1.0 + 2.0 * e).sqrt(), 0.0, 0.0);
            let u = [Vector3::zeros(), tip - x0[1], tip + Vector3::y() - x0[2], Vector3::zeros()];
            let f = [f0, f0.rotated(&rot(kappa)), f0.rotated(&rot(kappa)), f0];
            el.response(&u, &f, false).expect("element").energy
        };
        let e = 1.0e-6;
        let kappa = e * (abd[(0, 0)] / abd[(3, 3)]).sqrt();
        let (em, eb, both) = (energy(e, 0.0), energy(0.0, kappa), energy(e, kappa));
        let coupling = both - em - eb;
        for (what, got, want) in [("membrane", em, 0.5 * abd[(0, 0)] * e * e), ("bending", eb, 0.5 * abd[(3, 3)] * kappa * kappa), ("coupling", coupling, abd[(0, 3)] * e * kappa)] {
            assert!((got / want - 1.0).abs() < 1e-5, "{what}: element {got:e} vs CLT {want:e}");
        }
    }

    /// Every point of the rule lies in its ply's band and the weights of a ply sum to
    /// 2 h_k / H; stresses come from the ply law at the ply's own coordinate.
    #[test]
    fn rule_and_ply_lookup_follow_the_bands() {
        let nh: Arc<dyn ShellMaterial> = Arc::new(NeoHookean::new(1.0e6, 4.0e5));
        let plies = vec![svk("a", 1.0e7, 0.3, 1.0e-3), LaminaPly { name: "b".into(), material: nh, thickness: 3.0e-3, areal_density: Some(0.2) }];
        let lam = Laminate::new(plies).expect("laminate");
        let rule = lam.thickness_rule().expect("rule");
        assert_eq!(rule.len(), 4);
        let w: f64 = rule.iter().map(|p| p[1]).sum();
        assert!((w - 2.0).abs() < 1e-14);
        assert!(rule[..2].iter().all(|p| p[0] < -0.5) && rule[2..].iter().all(|p| p[0] > -0.5));
        assert!((rule[0][1] + rule[1][1] - 0.5).abs() < 1e-14);
        let e = Voigt5::new(1e-3, -2e-4, 5e-4, 0.0, 0.0);
        let own = StVenantKirchhoff::new(1.0e7, 0.3, 5.0 / 6.0).response(&e).expect("svk").stress;
        assert!((lam.response_at(&e, -0.8).expect("laminate").stress - own).norm() < 1e-9 * own.norm());
        assert_eq!(lam.areal_density(), None, "the SVK ply has no density");
        assert!(Laminate::new(vec![svk("only", 1.0, 0.0, 1.0)]).is_err());
    }
}
