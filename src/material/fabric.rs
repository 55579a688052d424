//! Orthotropic woven-fabric lamina with bending decoupled from the membrane.
//!
//! Fabric is specified by sheet quantities: tensile stiffnesses along warp and weft
//! (N/m, uniaxial-stress force per width over strain), in-plane shear stiffness (N/m), a
//! Poisson coupling ν₁₂ (weft contraction under warp tension), bending rigidities (N·m)
//! along warp and weft, areal density and thickness h. The lamina basis e1 is the warp (the
//! element's `grain`), e2 the weft.
//!
//! Membrane: orthotropic St. Venant–Kirchhoff in the convected lamina frame,
//! N = A·E with the plane-stress membrane stiffness (Jones, *Mechanics of Composite
//! Materials*, 2nd ed., eq. 2.61)
//! A₁₁ = E₁h/(1−ν₁₂ν₂₁), A₂₂ = E₂h/(1−ν₁₂ν₂₁), A₁₂ = ν₁₂A₂₂, A₆₆ = G₁₂h, ν₂₁ = ν₁₂E₂/E₁.
//! Green–Lagrange strains in the convected frame make it objective, so large rotations
//! store no energy.
//!
//! Bending: a fabric's bending rigidity is two to three orders of magnitude below Eh³/12
//! of its membrane stiffness, so the through-thickness stiffness is made to vary as
//! C(ζ) = α + β ζ² (per unit volume, ζ ∈ [−1, 1]) with α, β chosen so that
//! ∫C dz = A and ∫C z² dz = D (bending stiffness matrix, diag(B₁, B₂) plus the twisting
//! rigidity B₆₆): h(α + β/3) = A and (h³/4)(α/3 + β/5) = D, i.e.
//! β = 45D/h³ − 15A/(4h), α = 9A/(4h) − 15D/h³.
//! Any symmetric Gauss rule with three or more points integrates these quartic products
//! exactly, so membrane and bending stiffnesses are reproduced independently, and the
//! odd (coupling) moments vanish. Each D_ii is limited to 0.15·A_ii·h² so that α ≥ 0 (no
//! negative-stiffness layer); for the in-plane shear/twist pair this caps the twisting
//! rigidity of real fabrics well below √(B₁B₂) (see [`twist_default`]). With the 3-point rule the stiffness at ζ = ±√(3/5) is
//! exactly 12D/h³, as for a homogeneous section of rigidity D. The total quadratic form in
//! (membrane strain, curvature) is block diagonal [A, D] and positive definite. This is the "thickness-integrated layers with a
//! bending scale" construction of the issue; no element change beyond passing ζ.
//!
//! Transverse shear: S₁₃ = (T/h)·2E₁₃, S₂₃ = (T/h)·2E₂₃ with a transverse shear stiffness T
//! (N/m) large enough that fibres stay straight (√(B/T) ≪ element size) — MITC4 keeps it
//! free of locking.
//!
//! Optional tension stiffening: a table of (strain, factor) multiplies A₁₁ (warp) and A₂₂
//! (weft) as functions of their own tensile strain, integrated so that the stress is the
//! derivative of an energy: ψ(E) = ∫∫ A f(E) dE dE (piecewise-linear f).

use super::{MaterialFailure, PointResponse, ShellMaterial, Tangent5, Voigt5};

/// Sheet properties of a woven or knitted fabric (SI units).
#[derive(Clone, Debug, PartialEq)]
pub struct FabricProperties {
    /// Tensile stiffness along the warp (e1), N/m.
    pub warp_tensile: f64,
    /// Tensile stiffness along the weft (e2), N/m.
    pub weft_tensile: f64,
    /// In-plane shear stiffness, N/m.
    pub shear: f64,
    /// Poisson coupling ν₁₂ (weft contraction under warp tension).
    pub poisson: f64,
    /// Bending rigidity about the weft axis (curvature along the warp), N·m.
    pub warp_bending: f64,
    /// Bending rigidity along the weft, N·m.
    pub weft_bending: f64,
    /// Twisting rigidity, N·m (default: ½√(B₁B₂) capped by [`twist_default`]).
    pub twist_bending: f64,
    /// Transverse shear stiffness, N/m.
    pub transverse_shear: f64,
    /// Areal density, kg/m².
    pub areal_density: f64,
    /// Thickness, m.
    pub thickness: f64,
    /// Tension stiffening: (tensile strain, stiffness factor) pairs, strain ascending from 0.
    pub tension_table: Vec<(f64, f64)>,
    /// Sub-element buckling: (compressive strain magnitude, stiffness factor) pairs, strain
    /// ascending from 0, scaling the membrane part of the warp and weft stiffnesses under
    /// compressive membrane strain (see the module documentation); empty: no softening.
    pub compression_table: Vec<(f64, f64)>,
}

/// Named, representative fabric presets. Values lie in the ranges of
/// `reference/README.md` (woven shell fabrics: 0.1–0.3 kg/m², 0.2–0.6 mm,
/// 10²–10⁴ N/m tensile, 1–10 N/m shear, 10⁻⁶–10⁻⁵ N·m bending); the two bending rigidities
/// of `cotton_broadcloth` and `polyester_faille` are the measured ones quoted there
/// (Matsudaira et al. 2015: 0.118 and 0.019 gf·cm²/cm). The others are representative,
/// not measured values of a particular fabric.
pub const FABRIC_PRESETS: [&str; 5] = ["light_cotton", "cotton_broadcloth", "polyester_faille", "ripstop", "knit_liner"];

impl FabricProperties {
    /// The preset called `name`, if there is one (see [`FABRIC_PRESETS`]).
    pub fn preset(name: &str) -> Option<Self> {
        // (warp, weft, shear N/m, ν12, B1, B2 N·m, density kg/m², thickness m)
        let (e1, e2, g, nu, b1, b2, rho, h) = match name {
            "light_cotton" => (1500.0, 1200.0, 2.0, 0.2, 2.5e-6, 2.0e-6, 0.10, 0.25e-3),
            "cotton_broadcloth" => (3000.0, 2000.0, 5.0, 0.2, 1.157e-5, 0.9e-5, 0.12, 0.30e-3),
            "polyester_faille" => (2500.0, 2000.0, 3.0, 0.2, 1.863e-6, 1.5e-6, 0.15, 0.30e-3),
            "ripstop" => (6000.0, 5000.0, 8.0, 0.15, 8.0e-6, 7.0e-6, 0.20, 0.35e-3),
            "knit_liner" => (300.0, 150.0, 3.0, 0.3, 1.0e-6, 0.7e-6, 0.15, 0.60e-3),
            _ => return None,
        };
        Some(Self {
            warp_tensile: e1,
            weft_tensile: e2,
            shear: g,
            poisson: nu,
            warp_bending: b1,
            weft_bending: b2,
            twist_bending: twist_default(b1, b2, g, h),
            transverse_shear: e1.max(e2),
            areal_density: rho,
            thickness: h,
            tension_table: Vec::new(),
            compression_table: Vec::new(),
        })
    }

    /// Checks the constants; returns the offending field and why.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        for (name, v) in [
            ("warp_tensile", self.warp_tensile),
            ("weft_tensile", self.weft_tensile),
            ("shear", self.shear),
            ("warp_bending", self.warp_bending),
            ("weft_bending", self.weft_bending),
            ("twist_bending", self.twist_bending),
            ("transverse_shear", self.transverse_shear),
            ("areal_density", self.areal_density),
            ("thickness", self.thickness),
        ] {
            if !pos(v) {
                return Err((name, format!("expected a positive value, found {v}")));
            }
        }
        let cap = |a: f64| SPLIT_LIMIT * a * self.thickness * self.thickness;
        for (name, d, a) in [
            ("warp_bending", self.warp_bending, self.warp_tensile),
            ("weft_bending", self.weft_bending, self.weft_tensile),
            ("twist_bending", self.twist_bending, self.shear),
        ] {
            if d > cap(a) * (1.0 + 1e-12) {
                return Err((
                    name,
                    format!(
                        "{d:e} N·m exceeds {SPLIT_LIMIT}·(membrane stiffness)·h² = {:e} N·m: the through-thickness split would need a negative-stiffness mid layer (raise the stiffness or thickness, or lower the rigidity)",
                        cap(a)
                    ),
                ));
            }
        }
        let nu21 = self.poisson * self.weft_tensile / self.warp_tensile;
        if !(self.poisson.is_finite() && self.poisson >= 0.0 && self.poisson * nu21 < 1.0) {
            return Err(("poisson", format!("expected 0 ≤ ν12 with ν12·ν21 < 1 (ν21 = ν12·weft/warp), found ν12 = {}", self.poisson)));
        }
        for (name, table) in [("tension_table", &self.tension_table), ("compression_table", &self.compression_table)] {
            let mut last = 0.0;
            for (i, &(e, f)) in table.iter().enumerate() {
                if !(e.is_finite() && f.is_finite() && f > 0.0) || (i == 0 && e != 0.0) || (i > 0 && e <= last) {
                    return Err((name, format!("entry {i} ({e}, {f}): expected strains ascending from 0 and positive factors")));
                }
                last = e;
            }
        }
        Ok(())
    }
}

/// (f(m), ∫₀ᵐ f, ∫₀ᵐ∫₀ˢ f) for m ≥ 0 of the piecewise-linear factor f of a (strain, factor)
/// table whose strains ascend from 0, held constant past its last entry.
fn table_integrals(t: &[(f64, f64)], m: f64) -> (f64, f64, f64) {
    let (mut f_int, mut ff_int) = (0.0, 0.0);
    let mut seg = |e0: f64, f0: f64, e1: f64, f1: f64| {
        let l = e1 - e0;
        let k = if l > 0.0 { (f1 - f0) / l } else { 0.0 };
        // ∫_{e0}^{e1} (F(e0) + ∫_{e0}^{s} f) ds with f = f0 + k(s − e0).
        ff_int += f_int * l + 0.5 * f0 * l * l + k * l * l * l / 6.0;
        f_int += f0 * l + 0.5 * k * l * l;
    };
    for w in t.windows(2) {
        let ((e0, f0), (e1, f1)) = (w[0], w[1]);
        if m <= e1 {
            let fm = f0 + (f1 - f0) * (m - e0) / (e1 - e0);
            seg(e0, f0, m, fm);
            return (fm, f_int, ff_int);
        }
        seg(e0, f0, e1, f1);
    }
    let (el, fl) = t[t.len() - 1];
    seg(el, fl, m, fl);
    (fl, f_int, ff_int)
}

/// Largest bending-to-membrane ratio D/(A h²) for which the mid-layer stiffness
/// α = 9A/(4h) − 15D/h³ stays non-negative.
pub const SPLIT_LIMIT: f64 = 0.15;

/// Default twisting rigidity: ½√(B₁B₂), capped at [`SPLIT_LIMIT`]·G·h² (fabric's in-plane
/// shear stiffness G is so low that the uncapped value would need a negative-stiffness mid
/// layer, whose spurious geometric stiffness destabilises folding drapes — measured on the
/// Cusick test).
pub fn twist_default(b1: f64, b2: f64, shear: f64, h: f64) -> f64 {
    (0.5 * (b1 * b2).sqrt()).min(SPLIT_LIMIT * shear * h * h)
}

/// The fabric lamina law (see the module documentation).
#[derive(Clone, Debug)]
pub struct Fabric {
    /// Sheet properties.
    pub props: FabricProperties,
    /// Membrane stiffness A (3×3, N/m) over [E11, E22, 2E12].
    a: [[f64; 3]; 3],
    /// Through-thickness stiffness coefficients α, β (per volume) over [E11, E22, 2E12].
    alpha: [[f64; 3]; 3],
    beta: [[f64; 3]; 3],
    /// Transverse shear modulus T/h.
    g_transverse: f64,
    /// 12 B_i/h³ (warp, weft): the homogeneous stiffness that alone gives the bending
    /// rigidity B_i; the rest of C_ii(ζ) = α + β ζ² integrates to the membrane stiffness
    /// with no second moment, and vanishes at the outer points ζ = ±√(3/5) of the 3-point rule.
    bending_part: [f64; 2],
}

impl Fabric {
    /// Builds the material from validated properties.
    pub fn new(props: FabricProperties) -> Self {
        let h = props.thickness;
        let nu12 = props.poisson;
        let nu21 = nu12 * props.weft_tensile / props.warp_tensile;
        let den = 1.0 - nu12 * nu21;
        let a22 = props.weft_tensile / den;
        let a = [[props.warp_tensile / den, nu12 * a22, 0.0], [nu12 * a22, a22, 0.0], [0.0, 0.0, props.shear]];
        let d = [[props.warp_bending, 0.0, 0.0], [0.0, props.weft_bending, 0.0], [0.0, 0.0, props.twist_bending]];
        let mut alpha = [[0.0; 3]; 3];
        let mut beta = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                beta[i][j] = 45.0 * d[i][j] / h.powi(3) - 15.0 * a[i][j] / (4.0 * h);
                alpha[i][j] = 9.0 * a[i][j] / (4.0 * h) - 15.0 * d[i][j] / h.powi(3);
            }
        }
        let bending_part = [12.0 * props.warp_bending / h.powi(3), 12.0 * props.weft_bending / h.powi(3)];
        Self { g_transverse: props.transverse_shear / h, props, a, alpha, beta, bending_part }
    }

    /// Factor integrals (f(e), ∫₀ᵉ f, ∫₀ᵉ∫₀ˢ f) of a normal strain e: for e > 0 the tension
    /// table's f, for e < 0 the compression table's f(|e|) (by symmetry ∫₀ᵉ f = −∫₀^{|e|} f and
    /// the double integral is the same), f = 1 where the side's table is empty. Piecewise-linear
    /// f, integrated exactly segment by segment.
    fn stiffening(&self, e: f64) -> (f64, f64, f64) {
        let (table, m) = if e > 0.0 { (&self.props.tension_table, e) } else { (&self.props.compression_table, -e) };
        if table.is_empty() || e == 0.0 {
            return (1.0, e, 0.5 * e * e);
        }
        let (f, f_int, ff_int) = table_integrals(table, m);
        (f, f_int.copysign(e), ff_int)
    }

    /// Stress, tangent and energy with in-plane stiffness C (3×3) and the stiffening law
    /// applied to the normal components.
    /// `exempt[i]` is the part of C_ii that the compression table leaves unscaled (the
    /// bending part of the through-thickness split, see `response_at`).
    fn evaluate(&self, strain: &Voigt5, c: &[[f64; 3]; 3], exempt: [f64; 2]) -> Result<PointResponse, MaterialFailure> {
        if strain.iter().any(|v| !v.is_finite()) {
            return Err(MaterialFailure::NotFinite);
        }
        let mut stress = Voigt5::zeros();
        let mut tangent = Tangent5::zeros();
        let mut energy = 0.0;
        let e = [strain[0], strain[1], strain[2]];
        for i in 0..2 {
            let (f, fi, ffi) = self.stiffening(e[i]);
            if e[i] < 0.0 && !self.props.compression_table.is_empty() {
                let (cb, cm) = (exempt[i], c[i][i] - exempt[i]);
                stress[i] += cb * e[i] + cm * fi;
                tangent[(i, i)] += cb + cm * f;
                energy += 0.5 * cb * e[i] * e[i] + cm * ffi;
                continue;
            }
            stress[i] += c[i][i] * fi;
            tangent[(i, i)] += c[i][i] * f;
            energy += c[i][i] * ffi;
        }
        for i in 0..3 {
            for j in 0..3 {
                if i == j && i < 2 {
                    continue;
                }
                stress[i] += c[i][j] * e[j];
                tangent[(i, j)] += c[i][j];
                energy += 0.5 * e[i] * c[i][j] * e[j];
            }
        }
        for k in 3..5 {
            stress[k] = self.g_transverse * strain[k];
            tangent[(k, k)] = self.g_transverse;
            energy += 0.5 * self.g_transverse * strain[k] * strain[k];
        }
        Ok(PointResponse { stress, tangent, energy })
    }

    /// Membrane stiffness A (N/m) over [E11, E22, 2E12].
    pub fn membrane_stiffness(&self) -> [[f64; 3]; 3] {
        self.a
    }
}

impl ShellMaterial for Fabric {
    /// Membrane-equivalent response (stiffness A/h): used for output at the mid-surface.
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        let h = self.props.thickness;
        let c = self.a.map(|r| r.map(|v| v / h));
        self.evaluate(strain, &c, [0.0; 2])
    }

    fn response_at(&self, strain: &Voigt5, zeta: f64) -> Result<PointResponse, MaterialFailure> {
        let z2 = zeta * zeta;
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = self.alpha[i][j] + self.beta[i][j] * z2;
            }
        }
        self.evaluate(strain, &c, self.bending_part)
    }

    fn thickness_points(&self) -> Option<usize> {
        Some(3)
    }

    fn intrinsic_thickness(&self) -> Option<f64> {
        Some(self.props.thickness)
    }

    fn areal_density(&self) -> Option<f64> {
        Some(self.props.areal_density)
    }

    /// Equivalent isotropic modulus from the larger tensile stiffness over the thickness.
    fn small_strain_moduli(&self) -> (f64, f64) {
        (self.props.warp_tensile.max(self.props.weft_tensile) / self.props.thickness, self.props.poisson)
    }

    /// The smaller of the warp and weft bending rigidities (the sheet's own, not E h³/12).
    fn bending_rigidity(&self, _h: f64) -> f64 {
        self.props.warp_bending.min(self.props.weft_bending)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::quadrature::gauss_legendre;
    use crate::material::test_util::consistency;

    fn props() -> FabricProperties {
        FabricProperties::preset("cotton_broadcloth").expect("preset")
    }

    #[test]
    fn tangent_and_stress_are_derivatives_with_stiffening() {
        let mut p = props();
        p.tension_table = vec![(0.0, 1.0), (0.01, 3.0), (0.03, 6.0)];
        let m = Fabric::new(p);
        for e in [Voigt5::new(0.02, -0.004, 0.03, 0.004, -0.002), Voigt5::new(0.005, 0.04, -0.01, 0.0, 0.001)] {
            let mut worst: (f64, f64) = (0.0, 0.0);
            struct At<'a>(&'a Fabric, f64);
            impl std::fmt::Debug for At<'_> {
                fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                    write!(f, "At")
                }
            }
            impl ShellMaterial for At<'_> {
                fn response(&self, s: &Voigt5) -> Result<PointResponse, MaterialFailure> {
                    self.0.response_at(s, self.1)
                }
                fn small_strain_moduli(&self) -> (f64, f64) {
                    (1.0, 0.0)
                }
            }
            for z in [0.0, 0.77] {
                let (t, s) = consistency(&At(&m, z), &e);
                worst = (worst.0.max(t), worst.1.max(s));
            }
            assert!(worst.0 < 1e-6 && worst.1 < 1e-6, "{worst:?}");
        }
    }

    /// ∫C dz = A and ∫C z² dz = D with the 3-, 4- and 5-point rules (exact quartic).
    #[test]
    fn section_integrals_reproduce_membrane_and_bending() {
        let m = Fabric::new(props());
        let h = m.props.thickness;
        for n in 3..=5 {
            let (pz, wz) = gauss_legendre(n).expect("rule");
            let (mut a, mut d) = (0.0, 0.0);
            for (&z, &w) in pz.iter().zip(wz) {
                let c = m.alpha[0][0] + m.beta[0][0] * z * z;
                a += 0.5 * h * w * c;
                d += 0.5 * h * w * c * (0.5 * h * z).powi(2);
            }
            assert!((a / m.a[0][0] - 1.0).abs() < 1e-12, "{n}: {a}");
            assert!((d / m.props.warp_bending - 1.0).abs() < 1e-9, "{n}: {d}");
        }
    }

    /// The compression table's stress and tangent are the derivatives of its energy, on both
    /// sides of the table's kink and across zero strain.
    #[test]
    fn tangent_and_stress_are_derivatives_with_compression_table() {
        let mut p = props();
        p.compression_table = vec![(0.0, 1.0), (0.001, 0.05)];
        let m = Fabric::new(p);
        for e in [Voigt5::new(-0.0004, -0.003, 0.01, 0.002, -0.001), Voigt5::new(0.002, -0.0007, -0.02, 0.0, 0.001)] {
            for z in [0.0, 0.77] {
                let (c, zeta) = (&m, z);
                let at = |s: &Voigt5| c.response_at(s, zeta).expect("finite");
                // Central differences of energy and stress in each strain component.
                let r = at(&e);
                for k in 0..5 {
                    let step = 1e-8;
                    let mut ep = e;
                    let mut em = e;
                    ep[k] += step;
                    em[k] -= step;
                    let (rp, rm) = (at(&ep), at(&em));
                    let ds = (rp.energy - rm.energy) / (2.0 * step);
                    assert!((ds - r.stress[k]).abs() <= 1e-5 * r.stress.norm().max(1.0), "z {z} k {k}: dψ {ds} vs S {}", r.stress[k]);
                    for i in 0..5 {
                        let dt = (rp.stress[i] - rm.stress[i]) / (2.0 * step);
                        assert!((dt - r.tangent[(i, k)]).abs() <= 1e-5 * r.tangent.norm(), "z {z} ({i},{k}): {dt} vs {}", r.tangent[(i, k)]);
                    }
                }
            }
        }
    }

    /// Sub-element buckling scales the membrane stiffness under compression by the table's
    /// factor and leaves the bending rigidity and the tensile response unchanged (3-point
    /// rule: ∫C dz and ∫C z² dz of the tangent at a compressive membrane strain).
    #[test]
    fn compression_table_softens_membrane_not_bending() {
        let soft = {
            let mut p = props();
            p.compression_table = vec![(0.0, 1.0), (0.001, 0.05)];
            Fabric::new(p)
        };
        let plain = Fabric::new(props());
        let h = plain.props.thickness;
        let (pz, wz) = gauss_legendre(3).expect("rule");
        // Membrane strain −0.005 along the warp plus a curvature κ whose fibre strains stay
        // compressive: the tangent's section integrals.
        let section = |m: &Fabric, e0: f64, kappa: f64| {
            let (mut a, mut d) = (0.0, 0.0);
            for (&z, &w) in pz.iter().zip(wz) {
                let zz = 0.5 * h * z;
                let t = m.response_at(&Voigt5::new(e0 + kappa * zz, 0.0, 0.0, 0.0, 0.0), z).expect("finite").tangent[(0, 0)];
                a += 0.5 * h * w * t;
                d += 0.5 * h * w * t * zz * zz;
            }
            (a, d)
        };
        let (a_soft, d_soft) = section(&soft, -0.005, 2.0);
        let (a_plain, d_plain) = section(&plain, -0.005, 2.0);
        let bending = 12.0 * plain.props.warp_bending / h.powi(3) * h;
        assert!(((a_soft - bending) / (a_plain - bending) - 0.05).abs() < 1e-9, "membrane factor {}", (a_soft - bending) / (a_plain - bending));
        assert!((d_soft / d_plain - 1.0).abs() < 1e-9, "bending {d_soft} vs {d_plain}");
        let (a_t, d_t) = section(&soft, 0.005, 2.0);
        assert_eq!((a_t, d_t), section(&plain, 0.005, 2.0));
    }
}
