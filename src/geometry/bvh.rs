//! A bounding volume hierarchy over a triangle soup (median split on the longest axis), with
//! closest-hit and any-hit queries.

use bevy::math::Vec3;

use super::triangles::Triangle;

/// A ray hit: distance along the ray and the triangle index.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray (ray-direction units).
    pub t: f32,
    /// Index into [`Bvh::triangles`].
    pub triangle: usize,
    /// Barycentric coordinates of the hit (weights of vertices 1 and 2).
    pub uv: (f32, f32),
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Triangles in the leaf; 0 for an inner node.
    count: u32,
}

/// The BVH. It owns a copy of the triangles.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    triangles: Vec<Triangle>,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Builds the hierarchy. An empty soup gives a BVH that never hits.
    pub fn new(triangles: Vec<Triangle>) -> Self {
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (t.vertices[0] + t.vertices[1] + t.vertices[2]) / 3.0)
            .collect();
        let mut bvh = Self {
            nodes: Vec::with_capacity(triangles.len() * 2),
            order: (0..triangles.len() as u32).collect(),
            triangles,
        };
        if !bvh.triangles.is_empty() {
            bvh.nodes.push(Node {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
                start: 0,
                count: 0,
            });
            bvh.build(0, 0, bvh.order.len(), &centroids);
        }
        bvh
    }

    /// The triangles, indexed as in [`Hit::triangle`].
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    fn build(&mut self, node: usize, start: usize, end: usize, centroids: &[Vec3]) {
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &i in &self.order[start..end] {
            for v in self.triangles[i as usize].vertices {
                min = min.min(v);
                max = max.max(v);
            }
        }
        self.nodes[node].min = min;
        self.nodes[node].max = max;
        if end - start <= LEAF_SIZE {
            self.nodes[node].start = start as u32;
            self.nodes[node].count = (end - start) as u32;
            return;
        }
        let extent = max - min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
        });
        let left = self.nodes.len();
        self.nodes.push(Node {
            min,
            max,
            start: 0,
            count: 0,
        });
        self.nodes.push(Node {
            min,
            max,
            start: 0,
            count: 0,
        });
        self.nodes[node].start = left as u32;
        self.nodes[node].count = 0;
        self.build(left, start, mid, centroids);
        self.build(left + 1, mid, end, centroids);
    }

    /// The nearest hit with t in (t_min, t_max).
    pub fn closest_hit(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<Hit> {
        self.traverse(origin, direction, t_min, t_max, false)
    }

    /// Whether anything is hit with t in (t_min, t_max).
    pub fn any_hit(&self, origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> bool {
        self.traverse(origin, direction, t_min, t_max, true)
            .is_some()
    }

    fn traverse(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        mut t_max: f32,
        any: bool,
    ) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inv = direction.recip();
        let mut best = None;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if !slab(node.min, node.max, origin, inv, t_min, t_max) {
                continue;
            }
            if node.count == 0 {
                if top + 2 > stack.len() {
                    continue;
                }
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
                continue;
            }
            for &i in &self.order[node.start as usize..(node.start + node.count) as usize] {
                if let Some((t, uv)) = intersect(&self.triangles[i as usize], origin, direction)
                    && t > t_min
                    && t < t_max
                {
                    t_max = t;
                    best = Some(Hit {
                        t,
                        triangle: i as usize,
                        uv,
                    });
                    if any {
                        return best;
                    }
                }
            }
        }
        best
    }
}

fn slab(min: Vec3, max: Vec3, origin: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> bool {
    let t0 = (min - origin) * inv;
    let t1 = (max - origin) * inv;
    let near = t0.min(t1).max_element().max(t_min);
    let far = t0.max(t1).min_element().min(t_max);
    near <= far
}

/// Möller–Trumbore, both sides.
fn intersect(triangle: &Triangle, origin: Vec3, direction: Vec3) -> Option<(f32, (f32, f32))> {
    let [a, b, c] = triangle.vertices;
    let e1 = b - a;
    let e2 = c - a;
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv_det, (u, v)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f32) -> Vec<Triangle> {
        let v = [
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ];
        vec![
            Triangle {
                vertices: [v[0], v[1], v[2]],
                normals: None,
            },
            Triangle {
                vertices: [v[0], v[2], v[3]],
                normals: None,
            },
        ]
    }

    #[test]
    fn finds_the_nearest_of_many_layers() {
        let triangles: Vec<Triangle> = (0..50).flat_map(|i| quad(i as f32)).collect();
        let bvh = Bvh::new(triangles);
        let hit = bvh
            .closest_hit(Vec3::new(0.2, 0.3, -5.0), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert!((hit.t - 5.0).abs() < 1e-5);
        let hit = bvh
            .closest_hit(Vec3::new(0.2, 0.3, 60.0), -Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert!((hit.t - 11.0).abs() < 1e-4);
        assert!(!bvh.any_hit(Vec3::new(0.2, 0.3, -5.0), Vec3::Z, 0.0, 4.9));
        assert!(!bvh.any_hit(Vec3::new(3.0, 0.0, -5.0), Vec3::Z, 0.0, 100.0));
    }

    #[test]
    fn empty_scene_never_hits() {
        let bvh = Bvh::new(Vec::new());
        assert!(bvh.closest_hit(Vec3::ZERO, Vec3::X, 0.0, 1e9).is_none());
    }
}
