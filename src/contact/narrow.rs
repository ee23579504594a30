//! Narrow phase: a node against a segment (closest point, parameter, normal, gap), and the
//! choice among a node's candidate segments. Pure functions shared by every contact pass.

/// Tolerance on the segment parameter: a node just past a segment end (round-off at a shared
/// corner) still projects onto it, clamped.
pub const XI_TOLERANCE: f64 = 1e-6;

/// A node's projection on a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Parameter of the closest point along a -> b, clamped to [0, 1].
    pub xi: f64,
    /// Outward unit normal of the segment.
    pub normal: [f64; 2],
    /// Signed normal gap (negative: penetration).
    pub gap: f64,
    /// Segment length.
    pub length: f64,
}

/// Projects `p` on the segment `a -> b`; `None` when the segment is degenerate or `p` projects
/// outside it (beyond [`XI_TOLERANCE`]).
#[inline]
pub fn project(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Option<Projection> {
    let t = [b[0] - a[0], b[1] - a[1]];
    let l2 = t[0] * t[0] + t[1] * t[1];
    if l2.is_nan() || l2 <= 0.0 {
        return None;
    }
    let length = l2.sqrt();
    let d = [p[0] - a[0], p[1] - a[1]];
    let xi = (d[0] * t[0] + d[1] * t[1]) / l2;
    if !(-XI_TOLERANCE..=1.0 + XI_TOLERANCE).contains(&xi) {
        return None;
    }
    let normal = [t[1] / length, -t[0] / length];
    Some(Projection {
        xi: xi.clamp(0.0, 1.0),
        normal,
        gap: d[0] * normal[0] + d[1] * normal[1],
        length,
    })
}

/// Whether a node whose gap is `gap` now and was `gap_before` at the start of the step (on the
/// same segment) is in contact with it: it penetrates now, and it came from the front side (its
/// earlier gap is above minus half the segment length), so that segments on the far side of the
/// master body, or of a thin plate the node crossed within the step, are not taken.
#[inline]
pub fn penetrates(gap: f64, gap_before: f64, length: f64) -> bool {
    gap < 0.0 && gap_before > -0.5 * length
}
