//! Broad phase: candidate (slave node, master segment) pairs from a `parry2d` BVH over the master
//! segments' boxes.

use glam::Vec2;
use parry2d::bounding_volume::Aabb;
use parry2d::partitioning::{Bvh, BvhBuildStrategy};

/// Box of points in f32, rounded outward and inflated by `margin`.
fn aabb(points: &[[f64; 2]], margin: f64) -> Aabb {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    // f32 rounding: widen by a relative epsilon on top of the margin.
    let pad = |x: f64| margin + 1e-6 * x.abs() + f64::from(f32::MIN_POSITIVE);
    Aabb::new(
        Vec2::new((lo[0] - pad(lo[0])) as f32, (lo[1] - pad(lo[1])) as f32),
        Vec2::new((hi[0] + pad(hi[0])) as f32, (hi[1] + pad(hi[1])) as f32),
    )
}

/// Pairs (position in `slaves`, segment index) whose swept boxes (positions at u_n and at the trial u_{n+1})
/// come within `margin` of each other, sorted.
pub fn candidates(
    slaves: &[u32],
    segments: &[[u32; 2]],
    x_n: &[[f64; 2]],
    x_tr: &[[f64; 2]],
    margin: f64,
) -> Vec<(u32, u32)> {
    if slaves.is_empty() || segments.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = segments
        .iter()
        .map(|&[a, b]| {
            let (a, b) = (a as usize, b as usize);
            aabb(&[x_n[a], x_n[b], x_tr[a], x_tr[b]], margin)
        })
        .collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut out = Vec::new();
    for (si, &s) in slaves.iter().enumerate() {
        let q = aabb(&[x_n[s as usize], x_tr[s as usize]], 0.0);
        let start = out.len();
        for j in bvh.intersect_aabb(&q) {
            let [a, b] = segments[j as usize];
            if a != s && b != s {
                out.push((si as u32, j));
            }
        }
        out[start..].sort_unstable();
    }
    out
}

/// Pairs (point index, polygon index) where the point lies in the polygon's box (exact bounds, f32
/// rounding outward), from a BVH over the polygons' boxes; in point order.
pub fn points_in_boxes(points: &[[f64; 2]], polygons: &[[[f64; 2]; 4]]) -> Vec<(usize, usize)> {
    if points.is_empty() || polygons.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = polygons.iter().map(|p| aabb(p, 0.0)).collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut out = Vec::new();
    for (k, p) in points.iter().enumerate() {
        let start = out.len();
        out.extend(
            bvh.intersect_aabb(&aabb(&[*p], 0.0))
                .map(|j| (k, j as usize)),
        );
        out[start..].sort_unstable();
    }
    out
}
