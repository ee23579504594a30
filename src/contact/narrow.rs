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

/// Tolerance, relative to the segment length, within which two candidate segments' selection
/// keys tie (the node sits on the bisector of a master corner, up to round-off, f32 included).
pub const TIE_TOLERANCE: f64 = 1e-4;

/// Whether two selection keys (see the contact passes) tie within [`TIE_TOLERANCE`] of `length`.
#[inline]
pub fn ties(k1: (f64, f64), k2: (f64, f64), length: f64) -> bool {
    let tol = TIE_TOLERANCE * length;
    (k1.0 - k2.0).abs() <= tol && (k1.1 - k2.1).abs() <= tol
}

/// Contact of a node with a master node (a corner shared by two segments).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// The corner's averaged outward unit normal.
    pub normal: [f64; 2],
    /// Signed gap of the node along it (negative: penetration).
    pub gap: f64,
}

/// Contact of node `p` with master node `m` whose two segments have unit normals `n1`, `n2`:
/// the normal is their normalised sum; `None` when they are opposite (a degenerate sliver).
#[inline]
pub fn vertex(p: [f64; 2], m: [f64; 2], n1: [f64; 2], n2: [f64; 2]) -> Option<Vertex> {
    let n = [n1[0] + n2[0], n1[1] + n2[1]];
    let l = n[0].hypot(n[1]);
    if l.is_nan() || l <= 1e-6 {
        return None;
    }
    let normal = [n[0] / l, n[1] / l];
    Some(Vertex {
        normal,
        gap: (p[0] - m[0]) * normal[0] + (p[1] - m[1]) * normal[1],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_below_a_right_angled_corner_meets_it_along_the_bisector() {
        let s = 0.5f64.sqrt();
        let v = vertex([0.0, -0.2], [0.0, 0.0], [-s, s], [s, s]).expect("a corner");
        assert!((v.normal[0]).abs() < 1e-15 && (v.normal[1] - 1.0).abs() < 1e-15);
        assert!((v.gap + 0.2).abs() < 1e-15);
        // Opposite normals (a zero-thickness sliver) have no corner normal.
        assert!(vertex([0.0, 0.0], [0.0, 0.0], [0.0, 1.0], [0.0, -1.0]).is_none());
    }

    #[test]
    fn keys_tie_within_the_tolerance_of_the_segment_length() {
        assert!(ties((0.0, -1e-3), (0.0, -1e-3 + 0.9e-4), 1.0));
        assert!(!ties((0.0, -1e-3), (0.0, -1e-3 + 1.1e-4), 1.0));
        assert!(!ties((-2e-4, -1e-3), (0.0, -1e-3), 1.0));
    }
}
