//! Ray-primitive intersection for the reference ray caster.
//!
//! Scene shapes are lowered to [`Prim`]s: boxes, spheres and capped cylinders stay analytic,
//! heightfields and meshes become triangles. Infinite planes are kept apart (they have no
//! bounding box) and tested after the BVH.

use crate::scene::Shape;
use glam::DVec3;

/// A ray `origin + t * dir`, `dir` unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Start point.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
    /// Component-wise 1 / dir (infinities allowed), for slab tests.
    pub inv_dir: DVec3,
}

impl Ray {
    /// A ray from `origin` along the unit vector `dir`.
    pub fn new(origin: DVec3, dir: DVec3) -> Ray {
        Ray {
            origin,
            dir,
            inv_dir: DVec3::ONE / dir,
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: DVec3,
    /// Maximum corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (union identity).
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// Smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Smallest box holding `self` and `p`.
    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Centre point.
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area (0 for an empty box).
    pub fn area(&self) -> f64 {
        let d = (self.max - self.min).max(DVec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// The eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }

    /// Slab test: the entry parameter if the ray overlaps the box within (tmin, tmax).
    #[inline]
    pub fn hit(&self, ray: &Ray, tmin: f64, tmax: f64) -> Option<f64> {
        let t0 = (self.min - ray.origin) * ray.inv_dir;
        let t1 = (self.max - ray.origin) * ray.inv_dir;
        // NaN (0 * inf) comparisons fall through `max`/`min` to the finite operand.
        let near = t0.min(t1).max_element().max(tmin);
        let far = t0.max(t1).min_element().min(tmax);
        (near <= far).then_some(near)
    }
}

/// A bounded primitive.
#[derive(Clone, Copy, Debug)]
pub enum Prim {
    /// Triangle `v0, v0 + e1, v0 + e2`.
    Triangle {
        /// First vertex.
        v0: DVec3,
        /// Edge to the second vertex.
        e1: DVec3,
        /// Edge to the third vertex.
        e2: DVec3,
    },
    /// Sphere.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// Capped cylinder.
    Cylinder {
        /// Centre of cap A.
        a: DVec3,
        /// Unit axis from A to B.
        axis: DVec3,
        /// Distance from A to B.
        length: f64,
        /// Radius.
        radius: f64,
    },
    /// Axis-aligned box.
    Box(Aabb),
}

/// A primitive tagged with the scene shape it came from.
#[derive(Clone, Copy, Debug)]
pub struct Tagged {
    /// The primitive.
    pub prim: Prim,
    /// Index into `Scene::geometry`.
    pub shape: u32,
}

/// An infinite plane `dot(n, x) = d`.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// Unit normal.
    pub normal: DVec3,
    /// Offset.
    pub d: f64,
    /// Index into `Scene::geometry`.
    pub shape: u32,
}

impl Plane {
    /// Ray parameter of the hit within (tmin, tmax).
    #[inline]
    pub fn hit(&self, ray: &Ray, tmin: f64, tmax: f64) -> Option<f64> {
        let den = self.normal.dot(ray.dir);
        if den.abs() < 1e-15 {
            return None;
        }
        let t = (self.d - self.normal.dot(ray.origin)) / den;
        (t > tmin && t < tmax).then_some(t)
    }
}

impl Prim {
    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        match *self {
            Prim::Triangle { v0, e1, e2 } => Aabb::EMPTY.grow(v0).grow(v0 + e1).grow(v0 + e2),
            Prim::Sphere { center, radius } => Aabb {
                min: center - DVec3::splat(radius),
                max: center + DVec3::splat(radius),
            },
            Prim::Cylinder {
                a,
                axis,
                length,
                radius,
            } => {
                let b = a + axis * length;
                // Extent of a disc of radius r with normal `axis` along each world axis.
                let e = radius * (DVec3::ONE - axis * axis).max(DVec3::ZERO).sqrt();
                Aabb {
                    min: a.min(b) - e,
                    max: a.max(b) + e,
                }
            }
            Prim::Box(b) => b,
        }
    }

    /// Nearest hit parameter within (tmin, tmax).
    #[inline]
    pub fn hit(&self, ray: &Ray, tmin: f64, tmax: f64) -> Option<f64> {
        match *self {
            Prim::Triangle { v0, e1, e2 } => {
                // Moeller-Trumbore, two-sided.
                let p = ray.dir.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-18 {
                    return None;
                }
                let inv = 1.0 / det;
                let s = ray.origin - v0;
                let u = s.dot(p) * inv;
                if !(0.0..=1.0).contains(&u) {
                    return None;
                }
                let q = s.cross(e1);
                let v = ray.dir.dot(q) * inv;
                if v < 0.0 || u + v > 1.0 {
                    return None;
                }
                let t = e2.dot(q) * inv;
                (t > tmin && t < tmax).then_some(t)
            }
            Prim::Sphere { center, radius } => {
                let oc = ray.origin - center;
                let b = oc.dot(ray.dir);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                let t0 = -b - sq;
                if t0 > tmin && t0 < tmax {
                    return Some(t0);
                }
                let t1 = -b + sq;
                (t1 > tmin && t1 < tmax).then_some(t1)
            }
            Prim::Cylinder {
                a,
                axis,
                length,
                radius,
            } => cylinder_hit(ray, a, axis, length, radius, tmin, tmax).map(|(t, _)| t),
            Prim::Box(b) => {
                let t0 = (b.min - ray.origin) * ray.inv_dir;
                let t1 = (b.max - ray.origin) * ray.inv_dir;
                let near = t0.min(t1).max_element();
                let far = t0.max(t1).min_element();
                if near > far {
                    return None;
                }
                if near > tmin && near < tmax {
                    Some(near)
                } else if far > tmin && far < tmax {
                    Some(far)
                } else {
                    None
                }
            }
        }
    }

    /// Outward unit normal at the surface point `p`.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        match *self {
            Prim::Triangle { e1, e2, .. } => e1.cross(e2).normalize(),
            Prim::Sphere { center, .. } => (p - center).normalize(),
            Prim::Cylinder {
                a,
                axis,
                length,
                radius,
            } => {
                let h = (p - a).dot(axis);
                let radial = p - a - axis * h;
                let cap_dist = h.min(length - h);
                if cap_dist < (radial.length() - radius).abs() {
                    if h < length * 0.5 { -axis } else { axis }
                } else {
                    radial.normalize()
                }
            }
            Prim::Box(b) => {
                let c = b.center();
                let half = (b.max - b.min) * 0.5;
                let d = (p - c) / half;
                let a = d.abs();
                if a.x >= a.y && a.x >= a.z {
                    DVec3::new(d.x.signum(), 0.0, 0.0)
                } else if a.y >= a.z {
                    DVec3::new(0.0, d.y.signum(), 0.0)
                } else {
                    DVec3::new(0.0, 0.0, d.z.signum())
                }
            }
        }
    }
}

/// Ray against a capped cylinder: nearest parameter in (tmin, tmax) and whether it is a cap.
#[allow(clippy::too_many_arguments, reason = "plain geometric parameters")]
fn cylinder_hit(
    ray: &Ray,
    a: DVec3,
    axis: DVec3,
    length: f64,
    radius: f64,
    tmin: f64,
    tmax: f64,
) -> Option<(f64, bool)> {
    let mut best: Option<(f64, bool)> = None;
    let mut take = |t: f64, cap: bool| {
        if t > tmin && t < tmax && best.is_none_or(|(b, _)| t < b) {
            best = Some((t, cap));
        }
    };
    // Side: components perpendicular to the axis.
    let oc = ray.origin - a;
    let d_perp = ray.dir - axis * ray.dir.dot(axis);
    let o_perp = oc - axis * oc.dot(axis);
    let qa = d_perp.length_squared();
    if qa > 1e-18 {
        let qb = o_perp.dot(d_perp);
        let qc = o_perp.length_squared() - radius * radius;
        let disc = qb * qb - qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            for t in [(-qb - sq) / qa, (-qb + sq) / qa] {
                let h = (oc + ray.dir * t).dot(axis);
                if (0.0..=length).contains(&h) {
                    take(t, false);
                }
            }
        }
    }
    // Caps.
    let den = ray.dir.dot(axis);
    if den.abs() > 1e-15 {
        for h in [0.0, length] {
            let t = (h - oc.dot(axis)) / den;
            let p = oc + ray.dir * t - axis * h;
            if p.length_squared() <= radius * radius {
                take(t, true);
            }
        }
    }
    best
}

/// Lowers scene shapes to bounded primitives and infinite planes.
pub fn lower(shapes: &[Shape]) -> (Vec<Tagged>, Vec<Plane>) {
    let mut prims = Vec::new();
    let mut planes = Vec::new();
    for (i, s) in shapes.iter().enumerate() {
        let shape = i as u32;
        let mut push = |prim| prims.push(Tagged { prim, shape });
        let mut tri = |a: DVec3, b: DVec3, c: DVec3| {
            if (b - a).cross(c - a).length_squared() > 0.0 {
                push(Prim::Triangle {
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                });
            }
        };
        match s {
            Shape::Plane { point, normal, .. } => {
                let n = normal.normalize();
                planes.push(Plane {
                    normal: n,
                    d: n.dot(*point),
                    shape,
                });
            }
            Shape::Box { min, max, .. } => prims.push(Tagged {
                prim: Prim::Box(Aabb {
                    min: *min,
                    max: *max,
                }),
                shape,
            }),
            Shape::Sphere { center, radius, .. } => prims.push(Tagged {
                prim: Prim::Sphere {
                    center: *center,
                    radius: *radius,
                },
                shape,
            }),
            Shape::Cylinder { a, b, radius, .. } => prims.push(Tagged {
                prim: Prim::Cylinder {
                    a: *a,
                    axis: (*b - *a).normalize(),
                    length: (*b - *a).length(),
                    radius: *radius,
                },
                shape,
            }),
            Shape::Heightfield {
                origin,
                size,
                samples,
                heights,
                ..
            } => {
                let (nx, nz) = (samples[0] as usize, samples[1] as usize);
                let p = |ix: usize, iz: usize| {
                    *origin
                        + DVec3::new(
                            size[0] * ix as f64 / (nx - 1) as f64,
                            heights[iz * nx + ix],
                            size[1] * iz as f64 / (nz - 1) as f64,
                        )
                };
                for iz in 0..nz - 1 {
                    for ix in 0..nx - 1 {
                        let (a, b, c, d) =
                            (p(ix, iz), p(ix + 1, iz), p(ix, iz + 1), p(ix + 1, iz + 1));
                        tri(a, c, b);
                        tri(b, c, d);
                    }
                }
            }
            Shape::Mesh {
                vertices,
                triangles,
                ..
            } => {
                for t in triangles {
                    tri(
                        vertices[t[0] as usize],
                        vertices[t[1] as usize],
                        vertices[t[2] as usize],
                    );
                }
            }
        }
    }
    (prims, planes)
}
