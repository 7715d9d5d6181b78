//! A binned-SAH bounding volume hierarchy over [`Prim`]s plus a list of infinite planes: the
//! acceleration structure behind every ray the reference casts (depth buffers, shadow maps,
//! exact visibility).

use crate::geometry::{Aabb, Plane, Prim, Ray, Tagged, lower};
use crate::scene::Shape;
use glam::DVec3;

const BINS: usize = 16;
const LEAF_MAX: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first primitive; inner: index of the second child (the first follows the node).
    offset: u32,
    /// Leaf: primitive count (> 0); inner: 0.
    count: u32,
    /// Inner: split axis (for front-to-back order).
    axis: u8,
}

/// A closest hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    /// Index into `Scene::geometry`.
    pub shape: u32,
    /// Outward geometric normal (not flipped towards the ray).
    pub normal: DVec3,
}

/// Acceleration structure for one scene.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    prims: Vec<Tagged>,
    planes: Vec<Plane>,
}

impl Bvh {
    /// Builds the hierarchy for a scene's shapes.
    pub fn build(shapes: &[Shape]) -> Bvh {
        let (mut prims, planes) = lower(shapes);
        let mut nodes = Vec::with_capacity(2 * prims.len() / LEAF_MAX + 1);
        if !prims.is_empty() {
            let bounds: Vec<Aabb> = prims.iter().map(|p| p.prim.bounds()).collect();
            let centers: Vec<DVec3> = bounds.iter().map(Aabb::center).collect();
            let mut order: Vec<usize> = (0..prims.len()).collect();
            build_rec(&mut nodes, &mut order, 0, &bounds, &centers);
            prims = order.iter().map(|&i| prims[i]).collect();
        }
        Bvh {
            nodes,
            prims,
            planes,
        }
    }

    /// Number of bounded primitives (triangles count individually).
    pub fn prim_count(&self) -> usize {
        self.prims.len()
    }

    /// Bounds of all bounded primitives (infinite planes excluded); `Aabb::EMPTY` if none.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

    /// Closest hit with parameter in (tmin, tmax).
    pub fn closest(&self, ray: &Ray, tmin: f64, tmax: f64) -> Option<Hit> {
        let mut best_t = tmax;
        let mut best: Option<(u32, Option<Prim>)> = None;
        for p in &self.planes {
            if let Some(t) = p.hit(ray, tmin, best_t) {
                best_t = t;
                best = Some((p.shape, None));
            }
        }
        if !self.nodes.is_empty() {
            let mut stack = [0u32; 64];
            let mut sp = 0usize;
            let mut idx = 0u32;
            loop {
                let node = &self.nodes[idx as usize];
                let mut next = None;
                if node.bounds.hit(ray, tmin, best_t).is_some() {
                    if node.count > 0 {
                        let first = node.offset as usize;
                        for tp in &self.prims[first..first + node.count as usize] {
                            if let Some(t) = tp.prim.hit(ray, tmin, best_t) {
                                best_t = t;
                                best = Some((tp.shape, Some(tp.prim)));
                            }
                        }
                    } else {
                        let (mut a, mut b) = (idx + 1, node.offset);
                        if ray.dir[node.axis as usize] < 0.0 {
                            std::mem::swap(&mut a, &mut b);
                        }
                        stack[sp] = b;
                        sp += 1;
                        next = Some(a);
                    }
                }
                match next {
                    Some(n) => idx = n,
                    None if sp > 0 => {
                        sp -= 1;
                        idx = stack[sp];
                    }
                    None => break,
                }
            }
        }
        best.map(|(shape, prim)| {
            let normal = match prim {
                Some(p) => p.normal(ray.at(best_t)),
                None => self
                    .planes
                    .iter()
                    .find(|p| p.shape == shape)
                    .map_or(DVec3::Y, |p| p.normal),
            };
            Hit {
                t: best_t,
                shape,
                normal,
            }
        })
    }

    /// Whether anything is hit with parameter in (tmin, tmax) (shadow rays).
    pub fn occluded(&self, ray: &Ray, tmin: f64, tmax: f64) -> bool {
        if self.planes.iter().any(|p| p.hit(ray, tmin, tmax).is_some()) {
            return true;
        }
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [0u32; 64];
        let mut sp = 0usize;
        let mut idx = 0u32;
        loop {
            let node = &self.nodes[idx as usize];
            let mut next = None;
            if node.bounds.hit(ray, tmin, tmax).is_some() {
                if node.count > 0 {
                    let first = node.offset as usize;
                    if self.prims[first..first + node.count as usize]
                        .iter()
                        .any(|tp| tp.prim.hit(ray, tmin, tmax).is_some())
                    {
                        return true;
                    }
                } else {
                    stack[sp] = node.offset;
                    sp += 1;
                    next = Some(idx + 1);
                }
            }
            match next {
                Some(n) => idx = n,
                None if sp > 0 => {
                    sp -= 1;
                    idx = stack[sp];
                }
                None => return false,
            }
        }
    }
}

/// Builds the subtree over `order` (reordered in place), which starts at position `base` of
/// the final primitive order; returns the node index.
fn build_rec(
    nodes: &mut Vec<Node>,
    order: &mut [usize],
    base: usize,
    bounds: &[Aabb],
    centers: &[DVec3],
) -> u32 {
    let idx = nodes.len() as u32;
    let bb = order.iter().fold(Aabb::EMPTY, |b, &i| b.union(bounds[i]));
    nodes.push(Node {
        bounds: bb,
        offset: 0,
        count: 0,
        axis: 0,
    });
    let cb = order.iter().fold(Aabb::EMPTY, |b, &i| b.grow(centers[i]));
    let ext = cb.max - cb.min;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if order.len() <= LEAF_MAX || ext[axis] <= 0.0 {
        make_leaf(nodes, idx, base, order.len());
        return idx;
    }
    // Binned SAH along the widest centroid axis.
    let mut bin_bb = [Aabb::EMPTY; BINS];
    let mut bin_n = [0usize; BINS];
    let scale = BINS as f64 / ext[axis];
    let bin_of = |i: usize| (((centers[i][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1);
    for &i in order.iter() {
        let b = bin_of(i);
        bin_n[b] += 1;
        bin_bb[b] = bin_bb[b].union(bounds[i]);
    }
    let mut best = (f64::INFINITY, 0usize);
    for split in 1..BINS {
        let (mut lb, mut ln, mut rb, mut rn) = (Aabb::EMPTY, 0, Aabb::EMPTY, 0);
        for b in 0..split {
            lb = lb.union(bin_bb[b]);
            ln += bin_n[b];
        }
        for b in split..BINS {
            rb = rb.union(bin_bb[b]);
            rn += bin_n[b];
        }
        if ln == 0 || rn == 0 {
            continue;
        }
        let cost = lb.area() * ln as f64 + rb.area() * rn as f64;
        if cost < best.0 {
            best = (cost, split);
        }
    }
    let leaf_cost = bb.area() * order.len() as f64;
    if best.1 == 0 || (order.len() <= 2 * LEAF_MAX && best.0 + bb.area() >= leaf_cost) {
        if order.len() <= 4 * LEAF_MAX {
            make_leaf(nodes, idx, base, order.len());
            return idx;
        }
        // Degenerate binning: median split.
        order.sort_by(|&a, &b| centers[a][axis].total_cmp(&centers[b][axis]));
        best.1 = usize::MAX;
    }
    let mid = if best.1 == usize::MAX {
        order.len() / 2
    } else {
        let mut l = 0;
        for k in 0..order.len() {
            if bin_of(order[k]) < best.1 {
                order.swap(l, k);
                l += 1;
            }
        }
        l
    };
    let (left, right) = order.split_at_mut(mid);
    nodes[idx as usize].axis = axis as u8;
    build_rec(nodes, left, base, bounds, centers);
    let r = build_rec(nodes, right, base + mid, bounds, centers);
    nodes[idx as usize].offset = r;
    idx
}

fn make_leaf(nodes: &mut [Node], idx: u32, base: usize, count: usize) {
    nodes[idx as usize].offset = base as u32;
    nodes[idx as usize].count = count as u32;
}
