//! Integration rule of a shell section and the per-element reference data it needs.
//!
//! A section is integrated with 2×2 points in the plane times a Gauss rule through the
//! thickness. Every natural strain component at a point is a weighted sum of *pair strains*
//! ½(p·q − P·Q) of two covariant base-vector forms p, q (see `kinematics::base_forms`):
//! E_ξξ, E_ηη and E_ξη at the point itself; the transverse shears at the MITC4 tying points
//! (Dvorkin & Bathe 1984: E_ξζ = ½(1−η) E_ξζ(0,−1) + ½(1+η) E_ξζ(0,1), E_ηζ likewise with
//! (∓1, 0)) or at the element centre (SRI). The rule lists the distinct forms once for the
//! whole section and the distinct pairs once per thickness level, so an element evaluates
//! each tying-point strain, and each base vector shared by several points, once per state.
//!
//! MITC4+ (`ShearTreatment::Mitc4Plus`, `Mitc4PlusCentre`) adds the membrane tying of `membrane`: the in-plane
//! strains of every point get the ζ-independent correction ê^m − e^m (assumed minus
//! mid-surface membrane strains), evaluated once per element from its own pairs.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::kinematics::{base_forms, base_forms_split, edge_gradient, Lin, EDGES, NV, VD, VE};
use super::membrane::{MembraneTying, TyingWeights, MAX_MPAIRS};
use super::quadrature::gauss_legendre;
use super::shell4::{ElementFailure, Section, ShearTreatment, ShellElement};

/// Largest number of distinct base-vector forms of a rule kept in the kernel's stack
/// scratch (5 thickness levels of MITC4 need 54, MITC4+ at most 10 more mid-surface forms;
/// laminate rules with more levels use heap scratch) and of distinct pair strains of one
/// thickness level (MITC4: 15).
pub(super) const MAX_FORMS: usize = 64 + 8;
/// See [`MAX_FORMS`].
pub(super) const MAX_PAIRS: usize = 16;
/// Fewest thickness levels for which the kernel sums the pair stresses through the thickness
/// into resultants before forming the internal force and the geometric stiffness
/// ([`SectionRule::resultants`]). Their fixed cost is that of a few levels: measured
/// (`examples/assembly_speed.rs --kernel`, shared machine) the 3-level fabric section's
/// tangent took about 8 % longer with resultants, the 9-level suit laminate's 6–14 % less
/// (residual 10–25 % less); only laminates reach six levels.
pub(super) const RESULTANT_LEVELS: usize = 6;

/// A pair strain of a level split by thickness: its forms p = a_p + ζ b_p and q = a_q + ζ b_q
/// as rule form indices [a_p, b_p, a_q, b_q] (None: an empty form, b of g_ζ).
pub(super) type SplitPair = [Option<usize>; 4];

/// A natural strain component at a point: Σ w_t (pair strain t of the level), one or two terms.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Comp {
    /// Number of terms (1 or 2).
    pub n: usize,
    /// Pair indices within the level.
    pub pair: [usize; 2],
    /// Weights.
    pub w: [f64; 2],
}

impl Comp {
    /// The (pair, weight) terms.
    pub(super) fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.pair[..self.n].iter().copied().zip(self.w[..self.n].iter().copied())
    }
}

/// One point of a thickness level: its weight, its base-vector forms (for the reference
/// metric) and its five natural strain components [E_ξξ, E_ηη, E_ξη, E_ξζ, E_ηζ].
#[derive(Clone, Debug)]
pub(super) struct RulePoint {
    /// Gauss weight (in-plane × thickness).
    pub w: f64,
    /// Base-vector forms g_ξ, g_η, g_ζ at the point.
    pub g: [Lin; 3],
    /// The natural strain components.
    pub comps: [Comp; 5],
}

/// One thickness level ζ of a rule: its pair strains, its 4 in-plane points and its centre
/// point (ξ = η = 0), where the lamina's in-plane shear strain is sampled.
#[derive(Clone, Debug)]
pub(super) struct Level {
    /// Thickness coordinate ζ (for through-thickness material laws).
    pub zeta: f64,
    /// Distinct pair strains ½(p·q − P·Q) of the level, as form indices (p, q) of the rule.
    pub pairs: Vec<(usize, usize)>,
    /// In-plane points.
    pub points: Vec<RulePoint>,
    /// Element centre at this level.
    pub centre: RulePoint,
    /// The pairs' forms split by thickness, [a_p, b_p, a_q, b_q] with p = a_p + ζ b_p (see
    /// [`SectionRule::resultants`]).
    splits: Vec<[Lin; 4]>,
}

/// Integration rule of a section: 2×2 points in the plane times the thickness rule, each with
/// its strain terms (MITC4 tying or SRI centre sampling). Depends only on thickness, shear
/// treatment and thickness points, so one rule serves every element of a section.
#[derive(Clone, Debug)]
pub struct SectionRule {
    /// Distinct base-vector forms of all levels.
    pub(super) forms: Vec<Lin>,
    /// Thickness levels.
    pub(super) levels: Vec<Level>,
    /// MITC4+ membrane tying (None: the displacement-based membrane strains).
    pub(super) membrane: Option<MembraneTying>,
    /// Whether the lamina's in-plane shear 2E12 is sampled at the element centre (else at
    /// each point, from the point's own natural strains).
    pub(super) centre_shear: bool,
    /// Through-thickness resultants of the pair strains, for rules of at least
    /// [`RESULTANT_LEVELS`] levels whose levels have the same pairs in the same order (always,
    /// for the rules built here): pair t of every level is ½(p·q − P·Q) with
    /// p = a_p + ζ b_p, q = a_q + ζ b_q, the split forms being common to all levels. The
    /// kernel then sums the pairs' stress weights σ_t(ζ) over the levels into
    /// S_t^n = Σ σ_t ζⁿ (n = 0, 1, 2) and forms the internal force
    /// Σ_ζ σ ∂(½ p·q) = ½[a_p ⊗ (S⁰q_a + S¹q_b) + b_p ⊗ (S¹q_a + S²q_b) + (p ↔ q)] and the
    /// second-derivative matrix ½[S⁰ a_p⊗a_q + S¹(a_p⊗b_q + b_p⊗a_q) + S² b_p⊗b_q] once per
    /// pair instead of once per pair and level — the stress resultants (N, M and the
    /// quadratic moment) of a degenerated shell with straight fibres (Hughes 2000, ch. 6;
    /// the same sums in a different order, so equal to rounding).
    pub(super) resultants: Option<Vec<SplitPair>>,
}

/// Builder state: the distinct forms and the pairs of the current level.
struct Tables {
    forms: Vec<Lin>,
    pairs: Vec<(usize, usize)>,
    /// The split forms [a_p, b_p, a_q, b_q] of the current level's pairs.
    splits: Vec<[Lin; 4]>,
}

impl Tables {
    fn form(&mut self, l: Lin) -> usize {
        self.forms.iter().position(|f| *f == l).unwrap_or_else(|| {
            self.forms.push(l);
            self.forms.len() - 1
        })
    }

    /// The index of pair ½(p·q − P·Q) in the current level, with its forms split by
    /// thickness, `sp` = [a_p, b_p] and `sq` = [a_q, b_q].
    fn pair(&mut self, p: Lin, q: Lin, sp: [Lin; 2], sq: [Lin; 2]) -> usize {
        let key = (self.form(p), self.form(q));
        self.pairs.iter().position(|f| *f == key).unwrap_or_else(|| {
            self.pairs.push(key);
            self.splits.push([sp[0], sp[1], sq[0], sq[1]]);
            self.pairs.len() - 1
        })
    }

    /// Strain terms at (ξ, η, ζ) with weight `w` for thickness `h` and shear treatment `shear`.
    fn point(&mut self, xi: f64, eta: f64, zeta: f64, w: f64, h: f64, shear: ShearTreatment) -> RulePoint {
        let g = base_forms(xi, eta, zeta, h);
        let [ga, gb] = base_forms_split(xi, eta, h);
        let mut one = |i: usize, j: usize| Comp { n: 1, pair: [self.pair(g[i], g[j], [ga[i], gb[i]], [ga[j], gb[j]]), 0], w: [1.0, 0.0] };
        let (cxx, cyy, cxy) = (one(0, 0), one(1, 1), one(0, 1));
        let mut tied = |pts: [(f64, f64, f64); 2], comp: usize| {
            let mut out = Comp::default();
            for &(xt, yt, wt) in &pts {
                if wt != 0.0 {
                    let gt = base_forms(xt, yt, zeta, h);
                    let [ta, tb] = base_forms_split(xt, yt, h);
                    out.pair[out.n] = self.pair(gt[comp], gt[2], [ta[comp], tb[comp]], [ta[2], tb[2]]);
                    out.w[out.n] = wt;
                    out.n += 1;
                }
            }
            out
        };
        let (xz, yz) = match shear {
            ShearTreatment::Mitc4 | ShearTreatment::Mitc4Plus | ShearTreatment::Mitc4PlusCentre => (
                tied([(0.0, -1.0, 0.5 * (1.0 - eta)), (0.0, 1.0, 0.5 * (1.0 + eta))], 0),
                tied([(-1.0, 0.0, 0.5 * (1.0 - xi)), (1.0, 0.0, 0.5 * (1.0 + xi))], 1),
            ),
            ShearTreatment::Sri => (tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 0), tied([(0.0, 0.0, 1.0), (0.0, 0.0, 0.0)], 1)),
        };
        RulePoint { w, g, comps: [cxx, cyy, cxy, xz, yz] }
    }

    /// Closes the current level.
    fn level(&mut self, zeta: f64, points: Vec<RulePoint>, centre: RulePoint) -> Level {
        Level { zeta, pairs: std::mem::take(&mut self.pairs), points, centre, splits: std::mem::take(&mut self.splits) }
    }
}

/// Whether formulation `shear` samples the lamina's in-plane shear at the element centre:
/// MITC4, SRI and MITC4+ with centre shear do (see `shell4`); MITC4+ takes it from its
/// assumed field at each point, as Ko, Lee & Bathe (2017), which reproduces their
/// published regular-mesh values.
fn centre_shear(shear: ShearTreatment) -> bool {
    shear != ShearTreatment::Mitc4Plus
}

impl SectionRule {
    /// Builds the rule of `section`.
    pub fn new(section: &Section) -> Result<Self, ElementFailure> {
        // The material's own thickness rule (a laminate's plies, each in its band), else
        // Gauss–Legendre with the section's number of points.
        let through: Vec<[f64; 2]> = match section.material.thickness_rule() {
            Some(r) => r,
            None => {
                let (pz, wz) = gauss_legendre(section.thickness_points).ok_or(ElementFailure::ThicknessRule(section.thickness_points))?;
                pz.iter().zip(wz).map(|(&z, &w)| [z, w]).collect()
            }
        };
        let (p2, _) = gauss_legendre(2).ok_or(ElementFailure::ThicknessRule(2))?;
        let mut t = Tables { forms: Vec::new(), pairs: Vec::new(), splits: Vec::new() };
        let mut levels = Vec::with_capacity(through.len());
        let (h, shear) = (section.thickness, section.shear);
        let mut plane = Vec::with_capacity(5);
        for &eta in p2 {
            for &xi in p2 {
                plane.push((xi, eta));
            }
        }
        for &[z, w] in &through {
            let points = plane.iter().map(|&(xi, eta)| t.point(xi, eta, z, w, h, shear)).collect();
            let centre = t.point(0.0, 0.0, z, 1.0, h, shear);
            levels.push(t.level(z, points, centre));
        }
        plane.push((0.0, 0.0));
        let membrane = shear.assumed_membrane().then(|| MembraneTying::new(&plane, &mut |l| t.form(l)));
        let resultants = (levels.len() >= RESULTANT_LEVELS && levels.iter().all(|l| l.splits == levels[0].splits))
            .then(|| levels[0].splits.iter().map(|s| s.map(|f| (!f.is_empty()).then(|| t.form(f)))).collect());
        Ok(Self { forms: t.forms, levels, membrane, centre_shear: centre_shear(shear), resultants })
    }

    /// The rule of the mid-surface centre alone (ξ = η = ζ = 0), for output.
    pub(super) fn centre(h: f64, shear: ShearTreatment) -> Self {
        let mut t = Tables { forms: Vec::new(), pairs: Vec::new(), splits: Vec::new() };
        let centre = t.point(0.0, 0.0, 0.0, 1.0, h, shear);
        let level = t.level(0.0, Vec::new(), centre);
        let membrane = shear.assumed_membrane().then(|| MembraneTying::new(&[(0.0, 0.0)], &mut |l| t.form(l)));
        Self { forms: t.forms, levels: vec![level], membrane, centre_shear: centre_shear(shear), resultants: None }
    }

    /// The same rule evaluated level by level, without resultants (for tests comparing the
    /// two orders of summation).
    #[cfg(test)]
    pub(super) fn level_by_level(mut self) -> Self {
        self.resultants = None;
        self
    }

    /// Whether the rule fits the element kernel's fixed-size scratch: per level at most
    /// [`MAX_PAIRS`] pairs and 4 points, and at most [`MAX_MPAIRS`] membrane pairs (always
    /// true). Rules with more than [`MAX_FORMS`] forms (laminates of many plies) are
    /// evaluated with heap scratch.
    pub(super) fn fits(&self) -> bool {
        self.levels.iter().all(|l| l.pairs.len() <= MAX_PAIRS && l.points.len() <= 4)
            && self.membrane.as_ref().is_none_or(|m| m.pairs.len() <= MAX_MPAIRS && m.points.len() <= 5)
    }
}

/// Integration-point data that depends only on the reference state of one element.
#[derive(Clone, Debug)]
pub(super) struct PointGeometry {
    /// Natural → local Voigt strain map, rows [E11, E22, 2E12, 2E13, 2E23], columns
    /// [E_ξξ, E_ηη, E_ξη, E_ξζ, E_ηζ]. Row 2E12 is zero for in-plane points (their in-plane
    /// shear is the centre's, see `mc`), complete for the centre.
    pub m: SMatrix<f64, 5, 5>,
    /// Weight × det J.
    pub wdet: f64,
    /// Row 2E12 of the element centre's strain map at the same thickness level: the
    /// lamina's in-plane shear is sampled there.
    pub mc: SMatrix<f64, 1, 5>,
}

/// Reference data of one element for a given section rule, computed once per model:
/// reference kinematic vectors, reference edge factors, reference values of the rule's
/// base-vector forms and per-point metric data.
#[derive(Clone, Debug)]
pub struct ElementGeometry {
    /// Reference kinematic vectors X̄_a, D_a, E⁰_k.
    pub(super) r: [Vector3<f64>; NV],
    /// Arc-to-chord factors φ of the reference edges.
    pub(super) phi0: [f64; 4],
    /// Reference values of the rule's forms.
    pub(super) forms: Box<[Vector3<f64>]>,
    /// Per in-plane point of the rule, level-major.
    pub(super) points: Box<[PointGeometry]>,
    /// Per level, the centre (full strain map).
    pub(super) centres: Box<[PointGeometry]>,
    /// MITC4+ tying weights of the rule's membrane points (empty without membrane tying).
    pub(super) tying: Box<[TyingWeights]>,
}

impl<'a> ShellElement<'a> {
    /// Reference data of the element for `rule` (the rule of its section): kinematic
    /// vectors X̄_a, D_a, E⁰_k = φ(|D_b − D_a|²)(D_b − D_a), the reference values of the
    /// rule's forms and, per point, the strain map to the lamina basis and weight × det J.
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
        let centres = rule.levels.iter().map(|l| self.point_geometry(&r, &l.centre.g, l.centre.w, &dir1)).collect::<Result<Vec<_>, _>>()?;
        let mut points = Vec::with_capacity(4 * rule.levels.len());
        for (level, centre) in rule.levels.iter().zip(&centres) {
            for p in &level.points {
                let mut pg = self.point_geometry(&r, &p.g, p.w, &dir1)?;
                if rule.centre_shear {
                    pg.mc = centre.m.fixed_rows::<1>(2).into_owned();
                    pg.m.fixed_rows_mut::<1>(2).fill(0.0);
                } else {
                    pg.mc.fill(0.0);
                }
                points.push(pg);
            }
        }
        let forms = rule.forms.iter().map(|f| f.eval(&r)).collect();
        let tying = rule.membrane.as_ref().map(|m| m.weights(&self.x0)).unwrap_or_default().into_boxed_slice();
        Ok(ElementGeometry { r, phi0, forms, points: points.into_boxed_slice(), centres: centres.into_boxed_slice(), tying })
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
        Ok(PointGeometry { m, wdet: w * det, mc: m.fixed_rows::<1>(2).into_owned() })
    }
}
