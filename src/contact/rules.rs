//! The pure rules of node-to-segment contact, shared by the CPU reference's narrow phase
//! ([`super::narrow`]) and the GPU kernels (`contact_search.wgsl`, `contact_narrow.wgsl`), which
//! implement the same: which slave nodes and segments may pair at all ([`admissible`]), a node
//! against a segment (closest point, parameter, normal, gap: [`project`], with the vertex at an
//! end on the axis of an axisymmetric body), whether it came from the front ([`penetrates`]),
//! whether it passes over a convex corner ([`outside_convex_corner`]), and a node against a
//! master corner ([`ties`], [`vertex`]).

use super::{dot, sub};

/// Whether master segment a->b (body `seg_body`) may be paired with slave node s (body
/// `slave_body`, neighbours np, nn along its own surface) in a pass that admits self-contact
/// when `self_contact`. `xs, xa, xb`: reference (undeformed) positions of s, a, b.
///
/// Never a segment of the node itself; always a segment of another body; within one body (with
/// self-contact only) neither a segment next to the node (one holding np or nn) nor one that, in
/// the reference configuration, the node projects onto (xi in [0, 1]) and lies strictly behind
/// (negative gap along its outward normal): the far side of the same body, e.g. a thin strip's
/// other face. A free node (of eroded elements only, its own neighbour on both sides: see
/// [`super::erosion`]) takes no self-contact: squeezed between another body and its own body's
/// surface, a massless-looking point between two constraints with no room, it made the Lagrange
/// solve pump energy into the surface (a perforated plate eroded 178 elements instead of 48,
/// with a negative eroded energy, 2026-11-27); it still meets other bodies and the walls.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn admissible(
    s: u32,
    [np, nn]: [u32; 2],
    slave_body: u32,
    [a, b]: [u32; 2],
    seg_body: u32,
    self_contact: bool,
    xs: [f64; 2],
    xa: [f64; 2],
    xb: [f64; 2],
) -> bool {
    if a == s || b == s {
        return false;
    }
    if slave_body != seg_body {
        return true;
    }
    if !self_contact || (np == s && nn == s) {
        return false;
    }
    if a == np || a == nn || b == np || b == nn {
        return false;
    }
    let t = [xb[0] - xa[0], xb[1] - xa[1]];
    let l2 = t[0] * t[0] + t[1] * t[1];
    if l2 > 0.0 {
        let d = [xs[0] - xa[0], xs[1] - xa[1]];
        let xi = (d[0] * t[0] + d[1] * t[1]) / l2;
        // Gap along the outward normal (t_y, -t_x) / |t|: its sign is that of d . (t_y, -t_x).
        let behind = d[0] * t[1] - d[1] * t[0] < 0.0;
        if (0.0..=1.0).contains(&xi) && behind {
            return false;
        }
    }
    true
}

/// Tolerance on the segment parameter: a node just past a segment end (round-off at a shared
/// corner) still projects onto it, clamped.
pub const XI_TOLERANCE: f64 = 1e-6;

/// A node's projection on a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Parameter of the closest point along a -> b, clamped to [0, 1].
    pub xi: f64,
    /// Outward unit normal: the segment's, or along the axis at the vertex it makes with its
    /// mirror image past an end on the axis ([`project`]).
    pub normal: [f64; 2],
    /// Signed normal gap (negative: penetration).
    pub gap: f64,
    /// Segment length.
    pub length: f64,
}

/// Projects `p` on the segment `a -> b`; `None` when the segment is degenerate or `p` projects
/// outside it (beyond [`XI_TOLERANCE`]), except past an end on the axis of an axisymmetric body
/// (`axis`: whether a, b lie on it). There the segment meets its mirror image across the axis,
/// and the node meets the [`vertex`] they make: the parameter at that end, the normal along the
/// axis, `None` when the segment is parallel to the axis. Without that vertex a node on the axis
/// (which moves only along it) slipped past the end of a nose whose axis node lagged behind its
/// neighbour, into the body, and was thrown out at 3-9 km/s when a constraint caught it
/// (`assets/long_rod_penetration.toml`, 2026-11-28).
#[inline]
pub fn project(p: [f64; 2], a: [f64; 2], b: [f64; 2], axis: [bool; 2]) -> Option<Projection> {
    let t = [b[0] - a[0], b[1] - a[1]];
    let l2 = t[0] * t[0] + t[1] * t[1];
    if l2.is_nan() || l2 <= 0.0 {
        return None;
    }
    let length = l2.sqrt();
    let d = [p[0] - a[0], p[1] - a[1]];
    let xi = (d[0] * t[0] + d[1] * t[1]) / l2;
    let normal = [t[1] / length, -t[0] / length];
    if !(-XI_TOLERANCE..=1.0 + XI_TOLERANCE).contains(&xi) {
        let (end, m) = if xi < 0.0 { (0, a) } else { (1, b) };
        if !axis[end] {
            return None;
        }
        let v = vertex(p, m, normal, [-normal[0], normal[1]])?;
        return Some(Projection {
            xi: end as f64,
            normal: v.normal,
            gap: v.gap,
            length,
        });
    }
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

/// Whether a node at `p` passes over the convex corner `m` where its segment `a -> m` (or
/// `m -> b`) meets its neighbour, outside the master body: it `came_from_behind` the segment's
/// line (behind it by more than [`TIE_TOLERANCE`] of the segment's length at the start of the
/// step, so it did not come through the segment: Lagrange), it projects onto the half of the
/// segment at `m` (`near`), the corner turns left (the body on the left: convex), and it is on
/// or in front of the neighbour's line (to the same tolerance of the neighbour's length). Such
/// a node takes no constraint from the segment, however far behind its line it lies. `chain`:
/// the corner's three nodes in order along the surface (the neighbour's other end first or
/// last). Without this a flat nose's node that came round a crater's acute corner, behind the
/// line of the corner's side but above its top face, was taken as penetrating the side by 35 um
/// and thrown sideways at 1.9 km/s (`assets/long_rod_penetration.toml`, 2026-11-28). The region
/// is empty at a right or obtuse corner: only acute ones meet the rule. (Dropping the constraint
/// of every node in front of the neighbour's line, whichever way it came, made the blunt
/// projectile of `perforation_blunt` unstable at n = 24: nodes of its crushed plug's surface
/// took no constraint and passed through.)
#[inline]
pub fn outside_convex_corner(
    p: [f64; 2],
    chain: [[f64; 2]; 3],
    neighbour: [[f64; 2]; 2],
    near: bool,
    came_from_behind: bool,
) -> bool {
    let (t1, t2) = (sub(chain[1], chain[0]), sub(chain[2], chain[1]));
    if !came_from_behind || !near || t1[0] * t2[1] - t1[1] * t2[0] <= 0.0 {
        return false;
    }
    let t = sub(neighbour[1], neighbour[0]);
    line_gap(p, neighbour[0], neighbour[1]) > -TIE_TOLERANCE * t[0].hypot(t[1])
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

/// Signed distance of `p` to the line of `a -> b` (outward normal side positive).
#[inline]
pub(super) fn line_gap(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let t = sub(b, a);
    let l = t[0].hypot(t[1]);
    if l > 0.0 {
        dot(sub(p, a), [t[1] / l, -t[0] / l])
    } else {
        0.0
    }
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
    fn a_node_past_an_end_on_the_axis_meets_the_vertex_with_the_mirror_image() {
        // A nose segment from its axis node a = (0, 0.5) down to b = (1, 0) (body above: a
        // dimple at the axis); its outward normal points down and towards the axis.
        let (a, b) = ([0.0, 0.5], [1.0, 0.0]);
        // A node on the axis above a (inside the nose) projects before a.
        let p = [0.0, 0.6];
        assert!(project(p, a, b, [false; 2]).is_none());
        let pr = project(p, a, b, [true, false]).expect("the vertex at the axis");
        assert_eq!(pr.xi, 0.0);
        assert!(pr.normal[0].abs() < 1e-15 && (pr.normal[1] + 1.0).abs() < 1e-15);
        assert!((pr.gap + 0.1).abs() < 1e-15, "{}", pr.gap);
        // Below a it still projects onto the segment, with the segment's normal.
        let pr = project([0.0, 0.4], a, b, [true, false]).expect("on the segment");
        assert!(pr.xi > 0.0 && pr.gap > 0.0 && pr.normal[0] < 0.0);
        // Past b, which is not on the axis: nothing.
        assert!(project([1.5, 0.2], a, b, [true, false]).is_none());
        // The same at the other end, and nothing for a segment parallel to the axis.
        let pr = project([0.0, 0.6], b, a, [false, true]).expect("the vertex at the axis");
        assert_eq!(pr.xi, 1.0);
        assert!((pr.normal[1] - 1.0).abs() < 1e-15 && (pr.gap - 0.1).abs() < 1e-15);
        assert!(project([0.0, 2.0], [0.0, 0.0], [0.0, 1.0], [true, true]).is_none());
    }

    #[test]
    fn a_node_in_front_of_a_convex_corner_s_neighbour_is_outside() {
        // A wedge's apex (0, 0), its surface (the body on the left) a top face from (1, -0.5) up
        // to the apex, then a side down to (-0.1, -2): a left turn, a convex corner. The node's
        // segment is the side, the neighbour the top face.
        let chain = [[1.0, -0.5], [0.0, 0.0], [-0.1, -2.0]];
        let top = [chain[0], chain[1]];
        // Behind the side's line and above the top face: outside.
        let p = [0.05, -0.01];
        assert!(line_gap(p, chain[1], chain[2]) < 0.0);
        assert!(outside_convex_corner(p, chain, top, true, true));
        // Not when it came through the side (in front of its line at the start of the step),
        // nor when it projects onto the side's far half, nor below the top face (inside).
        assert!(!outside_convex_corner(p, chain, top, true, false));
        assert!(!outside_convex_corner(p, chain, top, false, true));
        assert!(!outside_convex_corner([0.05, -0.1], chain, top, true, true));
        // On the top face's line (to round-off): outside.
        let on = [0.05, -0.025];
        assert!(line_gap(on, top[0], top[1]).abs() < 1e-12);
        assert!(outside_convex_corner(on, chain, top, true, true));
        // A concave corner (the body on the other side, the chain reversed): never.
        let back = [chain[2], chain[1], chain[0]];
        let reversed = [chain[1], chain[0]];
        assert!(!outside_convex_corner(
            [0.05, 0.1],
            back,
            reversed,
            true,
            true
        ));
    }

    #[test]
    fn admissible_pairs_follow_bodies_neighbours_and_the_far_side() {
        // Segment a=10 -> b=11 along +x (outward normal -y: its body lies above it).
        let (xa, xb) = ([0.0, 0.0], [1.0, 0.0]);
        let front = [0.5, -0.1];
        let behind = [0.5, 0.1];
        // Never the node's own segment.
        assert!(!admissible(10, [9, 11], 0, [10, 11], 1, true, xa, xa, xb));
        assert!(!admissible(11, [10, 12], 0, [10, 11], 1, true, xb, xa, xb));
        // Another body: always, behind or not.
        assert!(admissible(1, [0, 2], 0, [10, 11], 1, false, behind, xa, xb));
        assert!(admissible(1, [0, 2], 1, [10, 11], 0, false, front, xa, xb));
        // The same body: only with self-contact ...
        assert!(!admissible(1, [0, 2], 3, [10, 11], 3, false, front, xa, xb));
        assert!(admissible(1, [0, 2], 3, [10, 11], 3, true, front, xa, xb));
        // ... never a free node (of eroded elements only: its own neighbours), which meets
        // other bodies only ...
        assert!(!admissible(1, [1, 1], 3, [10, 11], 3, true, front, xa, xb));
        assert!(admissible(1, [1, 1], 3, [10, 11], 4, true, behind, xa, xb));
        // ... never next to the node ...
        assert!(!admissible(1, [10, 2], 3, [10, 11], 3, true, front, xa, xb));
        assert!(!admissible(1, [0, 11], 3, [10, 11], 3, true, front, xa, xb));
        // ... never the far side (projects onto the segment and lies behind it) ...
        assert!(!admissible(1, [0, 2], 3, [10, 11], 3, true, behind, xa, xb));
        assert!(!admissible(
            1,
            [0, 2],
            3,
            [10, 11],
            3,
            true,
            [1.0, 0.1],
            xa,
            xb
        ));
        // ... but behind the segment's line beyond its ends, or on it, is admissible.
        assert!(admissible(
            1,
            [0, 2],
            3,
            [10, 11],
            3,
            true,
            [1.5, 0.1],
            xa,
            xb
        ));
        assert!(admissible(
            1,
            [0, 2],
            3,
            [10, 11],
            3,
            true,
            [-0.5, 0.1],
            xa,
            xb
        ));
        assert!(admissible(
            1,
            [0, 2],
            3,
            [10, 11],
            3,
            true,
            [0.5, 0.0],
            xa,
            xb
        ));
    }

    #[test]
    fn keys_tie_within_the_tolerance_of_the_segment_length() {
        assert!(ties((0.0, -1e-3), (0.0, -1e-3 + 0.9e-4), 1.0));
        assert!(!ties((0.0, -1e-3), (0.0, -1e-3 + 1.1e-4), 1.0));
        assert!(!ties((-2e-4, -1e-3), (0.0, -1e-3), 1.0));
    }
}
