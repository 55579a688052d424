//! Forward-mode dual numbers: a scalar carrying its gradient with respect to the [`NV`]
//! translations of the nodes one inter-ply pair acts on, and the vector operations the
//! pair's forces are written in, so that their exact Jacobian comes with them (the tangent
//! of `pair::pair_forces`).

use super::NV;

/// A scalar with its gradient with respect to up to [`NV`] variables (forward-mode dual
/// number): exact first derivatives of the contact forces.
#[derive(Clone, Copy, Debug)]
pub(super) struct D {
    pub(super) v: f64,
    pub(super) d: [f64; NV],
}

pub(super) type V3 = [D; 3];

impl D {
    pub(super) fn c(v: f64) -> Self {
        Self { v, d: [0.0; NV] }
    }
    pub(super) fn var(v: f64, i: usize) -> Self {
        let mut d = [0.0; NV];
        d[i] = 1.0;
        Self { v, d }
    }
    pub(super) fn map(self, v: f64, dv: f64) -> Self {
        Self { v, d: self.d.map(|x| x * dv) }
    }
    pub(super) fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.map(s, 0.5 / s)
    }
    pub(super) fn tanh(self) -> Self {
        let t = self.v.tanh();
        self.map(t, 1.0 - t * t)
    }
}

impl std::ops::Add for D {
    type Output = D;
    fn add(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a += b);
        D { v: self.v + o.v, d }
    }
}

impl std::ops::Sub for D {
    type Output = D;
    fn sub(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a -= b);
        D { v: self.v - o.v, d }
    }
}

impl std::ops::Mul for D {
    type Output = D;
    fn mul(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a = *a * o.v + self.v * b);
        D { v: self.v * o.v, d }
    }
}

impl std::ops::Mul<f64> for D {
    type Output = D;
    fn mul(self, o: f64) -> D {
        self.map(self.v * o, o)
    }
}

impl std::ops::Div for D {
    type Output = D;
    fn div(self, o: D) -> D {
        let inv = 1.0 / o.v;
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a = (*a - self.v * inv * b) * inv);
        D { v: self.v * inv, d }
    }
}

pub(super) fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn scale(a: &V3, s: D) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(super) fn dot(a: &V3, b: &V3) -> D {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: &V3, b: &V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
