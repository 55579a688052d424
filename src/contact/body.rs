//! Rigid obstacles: parry3d shapes placed by a rigid transform, queried for the signed
//! distance, closest point and outward normal at a point.

use std::sync::Arc;

use nalgebra::{Isometry3, Vector3};
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder, TriMesh, TriMeshFlags};

use super::motion::Motion;
use super::trimesh_io::TriSoup;

/// The geometry of a rigid body in its local frame. Cylinder and capsule axes are the local
/// z axis; the plane is z = 0 with its outward normal +z.
#[derive(Clone)]
pub enum Shape {
    /// Half-space z ≤ 0 (its surface the plane z = 0); its signed distance is exact (z).
    Plane,
    /// Sphere about the origin.
    Sphere(Ball),
    /// Box with half extents.
    Box(Cuboid),
    /// Cylinder along z (parry's axis y, rotated).
    Cylinder(Cylinder),
    /// Capsule along z.
    Capsule(Capsule),
    /// Oriented triangle mesh (`TriMeshFlags::ORIENTED`: pseudo-normals decide inside/outside).
    Mesh(Arc<TriMesh>),
}

impl std::fmt::Debug for Shape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = match self {
            Shape::Plane => "Plane".to_string(),
            Shape::Sphere(b) => format!("Sphere(r = {})", b.radius),
            Shape::Box(c) => format!("Box({:?})", c.half_extents),
            Shape::Cylinder(c) => format!("Cylinder(r = {}, half height {})", c.radius, c.half_height),
            Shape::Capsule(c) => format!("Capsule(r = {})", c.radius),
            Shape::Mesh(m) => format!("TriMesh({} triangles)", m.indices().len()),
        };
        f.write_str(&s)
    }
}

fn pv(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

fn nv(v: PVec) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

impl Shape {
    /// An oriented parry3d triangle mesh from a checked soup.
    pub fn mesh(soup: &TriSoup) -> Result<Self, String> {
        let vertices = soup.vertices.iter().map(pv).collect();
        let m = TriMesh::with_flags(vertices, soup.triangles.clone(), TriMeshFlags::ORIENTED)
            .map_err(|e| format!("parry3d rejected the triangle mesh: {e}"))?;
        Ok(Shape::Mesh(Arc::new(m)))
    }
}

/// Closest-point data of a query point.
#[derive(Clone, Copy, Debug)]
pub struct Proximity {
    /// Signed distance (negative inside the body).
    pub distance: f64,
    /// Closest point on the surface (global).
    pub point: Vector3<f64>,
    /// Outward unit normal at the query (∇ of the signed distance).
    pub normal: Vector3<f64>,
}

/// A placed rigid body with its friction coefficients.
#[derive(Clone, Debug)]
pub struct RigidBody {
    /// Name from the scene.
    pub name: String,
    /// Geometry in the local frame.
    pub shape: Shape,
    /// Local → global placement.
    pub pose: Isometry3<f64>,
    /// Static friction coefficient.
    pub mu_static: f64,
    /// Kinetic friction coefficient.
    pub mu_kinetic: f64,
    /// Edge rounding radius: the body is the shape (already shrunk by it) swept by a ball of
    /// this radius, so its signed distance is the shape's minus the radius.
    pub rounding: f64,
    /// Prescribed motion, if any: the placement at analysis time t is `motion.at(t) · base`
    /// ([`super::motion`]); `pose` is then the placement the contact currently uses.
    pub motion: Option<Arc<Motion>>,
    /// The placement from the scene's `translation` and `rotation` (before any motion).
    pub base: Isometry3<f64>,
}

impl RigidBody {
    /// The body's placement at analysis time `t` (its fixed pose when it has no motion).
    pub fn placement_at(&self, t: f64) -> Isometry3<f64> {
        match &self.motion {
            Some(m) => m.at(t) * self.base,
            None => self.pose,
        }
    }

    /// A copy of the body placed where it is at analysis time `t`.
    pub fn at_time(&self, t: f64) -> RigidBody {
        RigidBody { pose: self.placement_at(t), ..self.clone() }
    }

    /// Signed distance, closest point and outward normal at global point `x`, or None when
    /// the surface is farther than `max_dist` (bounded BVH search for meshes).
    pub fn proximity(&self, x: &Vector3<f64>, max_dist: f64) -> Option<Proximity> {
        self.proximity_at(&self.pose, x, max_dist)
    }

    /// [`RigidBody::proximity`] with the body at placement `pose` instead of its own.
    pub fn proximity_at(&self, pose: &Isometry3<f64>, x: &Vector3<f64>, max_dist: f64) -> Option<Proximity> {
        let xl = pose.inverse_transform_point(&(*x).into()).coords;
        // Cylinder and capsule axes: parry's y → our z (rotate (x, y, z) → (x, z, −y)...).
        let to_y = |v: &Vector3<f64>| Vector3::new(v.x, v.z, -v.y);
        let from_y = |v: &Vector3<f64>| Vector3::new(v.x, -v.z, v.y);
        let (dist, pl, nl) = match &self.shape {
            Shape::Plane => {
                // Exact: signed distance z, normal +z.
                (xl.z, Vector3::new(xl.x, xl.y, 0.0), Vector3::z())
            }
            Shape::Sphere(b) => {
                let r = xl.norm();
                let n = if r > 0.0 { xl / r } else { Vector3::z() };
                (r - b.radius, n * b.radius, n)
            }
            Shape::Box(c) => project(c, &xl, max_dist + self.rounding)?,
            Shape::Cylinder(c) => {
                let (d, p, n) = project(c, &to_y(&xl), max_dist + self.rounding)?;
                (d, from_y(&p), from_y(&n))
            }
            Shape::Capsule(c) => {
                let (d, p, n) = project(c, &to_y(&xl), max_dist)?;
                (d, from_y(&p), from_y(&n))
            }
            Shape::Mesh(m) => project(m.as_ref(), &xl, max_dist)?,
        };
        let dist = dist - self.rounding;
        let pl = pl + nl * self.rounding;
        if dist > max_dist {
            return None;
        }
        Some(Proximity {
            distance: dist,
            point: pose.transform_point(&pl.into()).coords,
            normal: pose.transform_vector(&nl),
        })
    }
}

/// Clearance of each participating node's shell face to the nearest body: min over the
/// bodies of the signed distance of the node minus its face offset h/2 (m; negative inside
/// a body), written into `out[node]`; nodes not listed keep their value (NaN by the callers:
/// not in contact). Bodies farther than `CLEARANCE_RANGE` are not searched (mesh BVH bound),
/// so clearances beyond it read `CLEARANCE_RANGE`.
pub fn clearances(bodies: &[RigidBody], nodes: &[usize], offset: &[f64], position: impl Fn(usize) -> Vector3<f64>, out: &mut [f64]) {
    for (&a, &r) in nodes.iter().zip(offset) {
        let x = position(a);
        out[a] = bodies.iter().filter_map(|b| b.proximity(&x, CLEARANCE_RANGE + r)).map(|p| p.distance - r).fold(CLEARANCE_RANGE, f64::min);
    }
}

/// Farthest clearance [`clearances`] resolves (m).
pub const CLEARANCE_RANGE: f64 = 0.5;

/// Projection of a local point on a parry shape's boundary: (signed distance, closest
/// point, outward normal). The normal is (x − p)/|x − p| (flipped inside); a point on the
/// surface itself gets the normal from a tiny probe along the shape's local gradient.
fn project<S: PointQuery + ?Sized>(s: &S, x: &Vector3<f64>, max_dist: f64) -> Option<(f64, Vector3<f64>, Vector3<f64>)> {
    let p = s.project_local_point_with_max_dist(pv(x), false, max_dist.max(0.0))?;
    let pt = nv(p.point);
    let d = x - pt;
    let len = d.norm();
    let sign = if p.is_inside { -1.0 } else { 1.0 };
    let scale = x.norm().max(pt.norm()).max(1e-3);
    let n = if len > 1e-12 * scale {
        d * (sign / len)
    } else {
        // On the surface: central differences of the unsigned distance off the point would
        // vanish; use the direction to the centroid-free probe along each axis.
        let h = 1e-7 * scale;
        let mut g = Vector3::zeros();
        for k in 0..3 {
            let mut e = Vector3::zeros();
            e[k] = h;
            let f = |y: Vector3<f64>| {
                let q = s.project_local_point(pv(&y), false);
                let l = (y - nv(q.point)).norm();
                if q.is_inside { -l } else { l }
            };
            g[k] = (f(x + e) - f(x - e)) / (2.0 * h);
        }
        if g.norm() > 0.0 { g.normalize() } else { Vector3::z() }
    };
    Some((sign * len, pt, n))
}
