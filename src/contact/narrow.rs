//! Narrow phase: the step's constraints of the passes' slave nodes and the walls' nodes
//! (`collect_passes`, `collect_walls`): for each node the choice among its candidate segments
//! (selection key, the corner and convex-corner rules), by the pure rules of [`super::rules`]
//! that the GPU kernel shares.

use super::rules::{
    line_gap, outside_convex_corner, penetrates, project, ties, vertex, Projection, TIE_TOLERANCE,
};
use super::solve::{augmented_impulse, consistent_penetration, penalty_impulse};
use super::{dot, sub, Constraint, ContactSet, Law, Pass};
use crate::scene::ContactMethod;

impl ContactSet {
    /// dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n (per direction, constrained directions rigid).
    pub(super) fn weight(
        &self,
        s: u32,
        ab: Option<(u32, u32)>,
        xi: f64,
        n: [f64; 2],
        dt: f64,
    ) -> f64 {
        let along = |l: u32| {
            let im = self.inv_mass[l as usize];
            n[0] * n[0] * im[0] + n[1] * n[1] * im[1]
        };
        let mut w = along(s);
        if let Some((a, b)) = ab {
            w += (1.0 - xi) * (1.0 - xi) * along(a) + xi * xi * along(b);
        }
        dt * w * self.inv_mass_scale
    }

    pub(super) fn free_relative(
        &self,
        s: u32,
        ab: Option<(u32, u32)>,
        xi: f64,
        n: [f64; 2],
    ) -> f64 {
        let vs = self.v_free[s as usize];
        let mut r = dot(vs, n);
        if let Some((a, b)) = ab {
            r -=
                (1.0 - xi) * dot(self.v_free[a as usize], n) + xi * dot(self.v_free[b as usize], n);
        }
        r
    }

    /// Whether slave `s` (own outward normal `own`) is in contact with segment `j` of pass `p`,
    /// and if so its selection key (larger is better) and projection.
    ///
    /// Lagrange: projection at the trial positions; the node penetrates and came from the
    /// segment's front (see [`penetrates`]); key (gap before the step clamped at 0, trial gap):
    /// the segment the node came from the front of, then the closest. Springs: projection at
    /// u_n, penetrating by less than half the segment; key (gap, 0). The augmented Lagrangian's
    /// node stays in contact while its multiplier `lambda` outweighs the spring's pull, at a gap
    /// below lambda / k.
    fn qualify(
        &self,
        p: &Pass,
        s: u32,
        own: [f64; 2],
        j: usize,
        lambda: f64,
    ) -> Option<((f64, f64), Projection)> {
        let [a, b] = p.segments[j];
        let (sl, al, bl) = (s as usize, a as usize, b as usize);
        // Only segments that face the node's own surface: at a corner shared by two segments
        // this keeps the face the node meets, not the edge it touches end-on. A free node (of
        // eroded elements only: no neighbours, no normal) faces every segment.
        let seg_t = sub(self.x_n[bl], self.x_n[al]);
        if own != [0.0; 2] && dot(own, [seg_t[1], -seg_t[0]]) >= 0.0 {
            return None;
        }
        match p.method {
            ContactMethod::Lagrange => {
                let pr = project(
                    self.x_tr[sl],
                    self.x_tr[al],
                    self.x_tr[bl],
                    self.on_axis([a, b]),
                )?;
                // Gap before the step, to the segment's line at u_n.
                let before = line_gap(self.x_n[sl], self.x_n[al], self.x_n[bl]);
                penetrates(pr.gap, before, pr.length).then_some(((before.min(0.0), pr.gap), pr))
            }
            ContactMethod::Penalty
            | ContactMethod::PerturbedLagrange
            | ContactMethod::AugmentedLagrange => {
                let pr = project(
                    self.x_n[sl],
                    self.x_n[al],
                    self.x_n[bl],
                    self.on_axis([a, b]),
                )?;
                let reach = if lambda > 0.0 {
                    lambda / p.stiffness[j]
                } else {
                    0.0
                };
                (pr.gap < reach && pr.gap > -0.5 * pr.length).then_some(((pr.gap, 0.0), pr))
            }
        }
    }

    /// The constraints of the passes' slave nodes; with `skip` (a re-check, see `recheck`),
    /// Lagrange passes only, and not the nodes that have one (sorted `warm_key`s).
    pub(super) fn collect_passes(&mut self, dt: f64, dt_n: f64, skip: Option<&[[u32; 2]]>) {
        let mut springs = std::mem::take(&mut self.pen_ft_next);
        for pi in 0..self.passes.len() {
            let p = &self.passes[pi];
            if skip.is_some() && p.method != ContactMethod::Lagrange {
                continue;
            }
            let mut k = 0;
            while k < p.candidates.len() {
                let si = p.candidates[k].0;
                let s = p.slaves[si as usize];
                // The slave node's own outward normal (unnormalised), at u_n.
                let [np, nn] = p.neighbours[si as usize];
                let t = sub(self.x_n[nn as usize], self.x_n[np as usize]);
                let own = [t[1], -t[0]];
                let first = k;
                while k < p.candidates.len() && p.candidates[k].0 == si {
                    k += 1;
                }
                let range = &p.candidates[first..k];
                let carried = if p.method == ContactMethod::AugmentedLagrange {
                    self.carried(p.interface as u32, s)
                } else {
                    0.0
                };
                if skip.is_some_and(|d| d.binary_search(&[p.interface as u32, s]).is_ok()) {
                    continue;
                }
                // (key, segment, projection) of the best candidate.
                let mut best: Option<((f64, f64), usize, Projection)> = None;
                for &(_, j) in range {
                    let j = j as usize;
                    if let Some((key, pr)) = self.qualify(p, s, own, j, carried) {
                        if best.is_none_or(|(bk, _, _)| key > bk) {
                            best = Some((key, j, pr));
                        }
                    }
                }
                let Some((key, j, mut pr)) = best else {
                    continue;
                };
                let [a, b] = p.segments[j];
                // The positions the candidates were judged at. Outside the master body at a
                // convex corner of the segment: no contact.
                let x = if p.method == ContactMethod::Lagrange {
                    &self.x_tr
                } else {
                    &self.x_n
                };
                let came_from_behind =
                    p.method == ContactMethod::Lagrange && key.0 < -TIE_TOLERANCE * pr.length;
                let outside = range.iter().any(|&(_, j2)| {
                    let [a2, b2] = p.segments[j2 as usize];
                    let (chain, near) = if a2 == b && b2 != a {
                        ([a, b, b2], pr.xi >= 0.5)
                    } else if b2 == a && a2 != b {
                        ([a2, a, b], pr.xi <= 0.5)
                    } else {
                        return false;
                    };
                    outside_convex_corner(
                        x[s as usize],
                        chain.map(|n| x[n as usize]),
                        [x[a2 as usize], x[b2 as usize]],
                        near,
                        came_from_behind,
                    )
                });
                if outside {
                    continue;
                }
                // A tie with the neighbouring segment at a shared master node: the node meets
                // that master node (a corner met end-on, e.g. corner to corner), not either
                // face. Contact with the node itself along its averaged normal, so that the
                // choice does not fall to round-off (which breaks symmetry).
                for &(_, j2) in range {
                    let j2 = j2 as usize;
                    let [a2, b2] = p.segments[j2];
                    let m = if a2 == b && b2 != a {
                        b
                    } else if b2 == a && a2 != b {
                        a
                    } else {
                        continue;
                    };
                    let Some((key2, pr2)) = self.qualify(p, s, own, j2, carried) else {
                        continue;
                    };
                    if !ties(key, key2, pr.length) {
                        continue;
                    }
                    if let Some(v) = vertex(x[s as usize], x[m as usize], pr.normal, pr2.normal) {
                        pr.normal = v.normal;
                        pr.gap = v.gap;
                        pr.xi = if m == b { 1.0 } else { 0.0 };
                    }
                    break;
                }
                let w = self.weight(s, Some((a, b)), pr.xi, pr.normal, dt);
                if w.is_nan() || w <= 0.0 {
                    continue;
                }
                let mut c = Constraint {
                    interface: p.interface as u32,
                    s,
                    a,
                    b,
                    xi: pr.xi,
                    n: pr.normal,
                    g0: pr.gap,
                    w,
                    lambda: 0.0,
                    sign: p.sign(si as usize, j),
                    penetration: 0.0,
                    mu: 0.0,
                    wt: 0.0,
                    lt: 0.0,
                };
                if p.law.friction > 0.0 && p.method == ContactMethod::Lagrange {
                    self.lagrange_friction(&mut c, p.law.friction);
                }
                if p.method.has_springs() {
                    let rate = self.free_relative(s, Some((a, b)), pr.xi, pr.normal);
                    let g = if p.method == ContactMethod::PerturbedLagrange {
                        self.consistent_pass_gap(p, si, pr.gap)
                    } else {
                        pr.gap
                    };
                    let Some(bounded) = self.spring(
                        &mut c,
                        &p.law,
                        [p.stiffness[j], g, rate, g + dt * rate, carried, pr.gap],
                        dt,
                        dt_n,
                        &mut springs,
                    ) else {
                        continue;
                    };
                    self.penalty_bounded += u64::from(bounded);
                }
                self.cons.push(c);
            }
        }
        self.pen_ft_next = springs;
    }

    /// A Lagrange constraint's Coulomb friction `mu`: its tangential weight, and no friction
    /// where no node can move along the tangent.
    fn lagrange_friction(&self, c: &mut Constraint, mu: f64) {
        let ab = (c.a != u32::MAX).then_some((c.a, c.b));
        c.wt = self.weight(c.s, ab, c.xi, c.tangent(), 1.0);
        c.mu = if c.wt > 0.0 { mu } else { 0.0 };
    }

    /// Makes `c` (of weight `c.w`) a spring method's constraint under the law `law`, from
    /// `[k, g, rate, g_trial, carried, gap]`: its impulse over the step ([`spring_impulse`] with
    /// the normal stiffness k, the gap g it acts on (the perturbed Lagrangian's consistent one),
    /// its rate, the trial gap and the multiplier carried from the last step), the penetration
    /// it reports from the node's own gap `gap`, and with friction its tangential spring
    /// ([`Self::penalty_friction`]). `None` where the node has left the contact, else whether
    /// the penalty's bound acted.
    fn spring(
        &self,
        c: &mut Constraint,
        law: &Law,
        [k, g, rate, g_trial, carried, gap]: [f64; 6],
        dt: f64,
        dt_n: f64,
        springs: &mut Vec<([u32; 2], f64)>,
    ) -> Option<bool> {
        let (w, r) = (c.w, law.augmentation);
        let impulse = [k, g, rate, g_trial, carried, w, dt, dt_n, r];
        let (lambda, bounded) = spring_impulse(impulse, [c.interface, c.s], springs)?;
        c.lambda = lambda;
        c.penetration = (-gap).max(0.0);
        c.w = -w;
        if law.friction > 0.0 {
            let kt = law.friction_stiffness * k;
            self.penalty_friction(c, kt, law.friction, dt, dt_n, springs);
        }
        Some(bounded)
    }

    /// Penalty friction (the Curnier-Mroz regularization of Coulomb's law): a tangential spring
    /// of stiffness `k` (the normal spring's times `friction_stiffness`) at the contact point, its force carried from the
    /// last step and incremented by -k dt v_t (the relative tangential velocity of the free
    /// update), returned onto the slip limit |f_t| <= mu f_n, f_n = lambda / dt_n the normal
    /// spring's force; its impulse dt_n f_t goes into `c.lt`, the force into `springs` (for
    /// the next step). A constraint without a spring last step starts from 0.
    fn penalty_friction(
        &self,
        c: &mut Constraint,
        k: f64,
        mu: f64,
        dt: f64,
        dt_n: f64,
        springs: &mut Vec<([u32; 2], f64)>,
    ) {
        let t = c.tangent();
        let ab = (c.a != u32::MAX).then_some((c.a, c.b));
        let wt = self.weight(c.s, ab, c.xi, t, 1.0);
        let ok = wt > 0.0 && c.lambda > 0.0 && dt_n > 0.0;
        if !ok {
            return;
        }
        let key = [c.interface, c.s];
        let prev = self.carried(c.interface, c.s);
        let vt = self.free_relative(c.s, ab, c.xi, t);
        let limit = mu * c.lambda / dt_n;
        let ft = (prev - k * dt * vt).clamp(-limit, limit);
        c.mu = mu;
        c.wt = wt;
        c.lt = dt_n * ft;
        springs.push((key, ft));
    }

    /// The force constraint (interface, slave node `s`) carried from the last step (`pen_ft`; 0:
    /// none).
    fn carried(&self, interface: u32, s: u32) -> f64 {
        self.pen_ft
            .binary_search_by_key(&[interface, s], |e| e.0)
            .map_or(0.0, |i| self.pen_ft[i].1)
    }

    /// The signed gap at u_n of the pass's slave `sj` (a position in `slaves`) to the closest of
    /// its candidate segments that face its surface and that it projects onto (within half a
    /// segment behind it), `None` without one: the penetration of a neighbour for the perturbed
    /// Lagrangian (`contact_narrow.wgsl`'s `slave_gap`).
    fn slave_gap(&self, p: &Pass, sj: u32) -> Option<f64> {
        let first = p.candidates.partition_point(|c| c.0 < sj);
        let s = p.slaves[sj as usize] as usize;
        let [np, nn] = p.neighbours[sj as usize];
        let t = sub(self.x_n[nn as usize], self.x_n[np as usize]);
        let own = [t[1], -t[0]];
        let mut best: Option<f64> = None;
        for &(_, j) in p.candidates[first..].iter().take_while(|c| c.0 == sj) {
            let ends = p.segments[j as usize];
            let (a, b) = (self.x_n[ends[0] as usize], self.x_n[ends[1] as usize]);
            let seg_t = sub(b, a);
            if dot(own, [seg_t[1], -seg_t[0]]) >= 0.0 {
                continue;
            }
            let Some(pr) = project(self.x_n[s], a, b, self.on_axis(ends)) else {
                continue;
            };
            if pr.gap > -0.5 * pr.length && best.is_none_or(|g| pr.gap.abs() < g.abs()) {
                best = Some(pr.gap);
            }
        }
        best
    }

    /// The perturbed Lagrangian's gap of the pass's slave `si` (a position in `slaves`) at gap
    /// `g` (< 0): minus the [`consistent_penetration`] over its two surface segments, each
    /// neighbour's penetration its own [`Self::slave_gap`] (a side without one is left out).
    fn consistent_pass_gap(&self, p: &Pass, si: u32, g: f64) -> f64 {
        let x = self.x_n[p.slaves[si as usize] as usize];
        let sides = [0, 1].map(|i| {
            let sj = p
                .neighbour_slaves
                .get(si as usize)
                .map_or(u32::MAX, |n| n[i]);
            if sj == u32::MAX {
                return (0.0, 0.0);
            }
            match self.slave_gap(p, sj) {
                Some(gj) => {
                    let d = sub(self.x_n[p.slaves[sj as usize] as usize], x);
                    (d[0].hypot(d[1]), -gj)
                }
                None => (0.0, 0.0),
            }
        });
        -consistent_penetration(-g, sides)
    }

    /// The perturbed Lagrangian's gap of wall node `s` at gap `g` (< 0) along the wall's normal
    /// `n`: minus the [`consistent_penetration`] over its two surface segments (to its
    /// neighbours `nb`, at u_n), each neighbour's penetration its own distance to the wall.
    fn consistent_gap(&self, s: u32, nb: [u32; 2], n: [f64; 2], g: f64) -> f64 {
        let x = self.x_n[s as usize];
        let side = |j: u32| {
            if j == s {
                return (0.0, 0.0);
            }
            let d = sub(self.x_n[j as usize], x);
            (d[0].hypot(d[1]), -g - dot(d, n))
        };
        -consistent_penetration(-g, [side(nb[0]), side(nb[1])])
    }

    /// The constraints of the walls' nodes; `skip` as for [`Self::collect_passes`].
    pub(super) fn collect_walls(&mut self, dt: f64, dt_n: f64, skip: Option<&[[u32; 2]]>) {
        let mut springs = std::mem::take(&mut self.pen_ft_next);
        for wi in 0..self.walls.len() {
            let w = &self.walls[wi];
            if skip.is_some() && w.method != ContactMethod::Lagrange {
                continue;
            }
            for (idx, &l) in w.nodes.iter().enumerate() {
                if skip.is_some_and(|d| d.binary_search(&[w.interface as u32, l]).is_ok()) {
                    continue;
                }
                let n = w.normal;
                let (g, g_tr) = (
                    dot(sub(self.x_n[l as usize], w.point), n),
                    dot(sub(self.x_tr[l as usize], w.point), n),
                );
                let weight = self.weight(l, None, 0.0, n, dt);
                if weight.is_nan() || weight <= 0.0 {
                    continue;
                }
                let mut c = Constraint {
                    interface: w.interface as u32,
                    s: l,
                    a: u32::MAX,
                    b: u32::MAX,
                    xi: 0.0,
                    n,
                    g0: g_tr,
                    w: weight,
                    lambda: 0.0,
                    sign: 1.0,
                    penetration: 0.0,
                    mu: 0.0,
                    wt: 0.0,
                    lt: 0.0,
                };
                if w.law.friction > 0.0 && w.method == ContactMethod::Lagrange {
                    self.lagrange_friction(&mut c, w.law.friction);
                }
                match w.method {
                    ContactMethod::Lagrange => {
                        if g_tr >= 0.0 {
                            continue;
                        }
                    }
                    ContactMethod::Penalty
                    | ContactMethod::PerturbedLagrange
                    | ContactMethod::AugmentedLagrange => {
                        let carried = if w.method == ContactMethod::AugmentedLagrange {
                            self.carried(w.interface as u32, l)
                        } else {
                            0.0
                        };
                        if g >= carried / w.stiffness[idx] {
                            continue;
                        }
                        let rate = dot(self.v_free[l as usize], n);
                        let (gs, gs_tr) = if w.method == ContactMethod::PerturbedLagrange {
                            let nb = w.neighbours.get(idx).copied().unwrap_or([l, l]);
                            let gs = self.consistent_gap(l, nb, n, g);
                            (gs, gs + dt * rate)
                        } else {
                            (g, g_tr)
                        };
                        let Some(bounded) = self.spring(
                            &mut c,
                            &w.law,
                            [w.stiffness[idx], gs, rate, gs_tr, carried, g],
                            dt,
                            dt_n,
                            &mut springs,
                        ) else {
                            continue;
                        };
                        self.penalty_bounded += u64::from(bounded);
                    }
                }
                self.cons.push(c);
            }
        }
        self.pen_ft_next = springs;
    }
}

/// A spring method's impulse over the step and whether its bound acted, from
/// `[k, g, rate, g_trial, carried, w, dt, dt_n, r]`: the penalty's ([`penalty_impulse`]; the
/// perturbed Lagrangian's with its consistent g), or with an augmentation rate r > 0 the augmented
/// Lagrangian's ([`augmented_impulse`]) with the multiplier `carried` of the last step, its next
/// multiplier pushed to `springs` under `key`; `None` where that node has left the contact.
fn spring_impulse(
    [k, g, rate, g_trial, carried, w, dt, dt_n, r]: [f64; 9],
    key: [u32; 2],
    springs: &mut Vec<([u32; 2], f64)>,
) -> Option<(f64, bool)> {
    if r > 0.0 {
        let (lambda, next, bounded) =
            augmented_impulse(k, g, rate, g_trial, carried, w, dt, dt_n, r)?;
        springs.push((key, next));
        Some((lambda, bounded))
    } else {
        Some(penalty_impulse(k, g, rate, g_trial, w, dt, dt_n))
    }
}
