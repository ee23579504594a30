//! Solving the step's constraints: the bounded penalty impulses, and the Lagrange correction
//! (projected Gauss-Seidel sweeps with the diagonal mass, extrapolated between sweeps, warm-started
//! from the last step, with an active-set re-check at the corrected positions); the penalty
//! springs' stable step.

use super::{warm_key, Constraint, ContactSet};

/// Projected Gauss-Seidel sweeps at most per solve: the sweeps of a step before its first
/// active-set re-check, and those after each re-check that adds constraints (so at most
/// (1 + [`ACTIVE_SET_ROUNDS`]) x this a step).
pub const MAX_SWEEPS: usize = 500;
/// Sweeps stop when no gap changes by more than this fraction of the search margin: 1e-5, ten
/// times below the device's stop in an impact (`gpu::contact::solve::TOLERANCE`, 1e-4) and the
/// device's tightest (`STOP_FLOOR` of it, under a steady load), so that the reference is at
/// least as converged as what it checks, and far above what f64 resolves (gaps of coordinates
/// about 10^3 margins wide to about 1e-13 of the margin).
///
/// Below it, what the sweeps still change are the near-null modes of two passes' constraints on
/// one interface (a smooth push of one pass against the other, which moves the gaps by a fraction
/// of a percent a sweep) after the fast modes are gone in 5 to 50 sweeps. Measured 2026-11-27 on
/// the CPU reference with the 2 x 2 blocks of `ContactSet::pair_blocks`: near the old stop
/// (1e-13; 1e-12 measured) the 10^4-element striker's first 1e-5 s stopped at the sweep limit in
/// 15 of 379 steps, `ring_crush.toml` in 26 of 401; at 1e-6 the striker converged in every step (33.6 sweeps a
/// step) and ring_crush stopped in 10 steps with residuals up to 3.2e-6; at 1e-5 every shipped
/// scene converges in every step.
pub const SWEEP_TOLERANCE: f64 = 1e-5;

/// No partner in [`ContactSet::pair_blocks`].
const NO_PARTNER: u32 = u32::MAX;
/// Rounds of the Lagrange active-set update per step (re-checks of the free nodes at the
/// corrected positions, each followed by sweeps when it adds constraints).
pub const ACTIVE_SET_ROUNDS: usize = 4;

/// Extrapolation factor of the sweeps once under way (see [`extrapolation`]).
pub const EXTRAPOLATION: f64 = 0.9;

/// Extrapolation factor before the `k`-th sweep (from 0) since the sweeps started or restarted:
/// 0 for the first two, then [`EXTRAPOLATION`].
///
/// Between two projected Gauss-Seidel sweeps every Lagrange multiplier (and friction impulse)
/// moves on by this factor times its change over the last sweep, and so do the velocity
/// corrections of its nodes (they are linear in the multipliers, so no impulse is applied; an
/// extrapolated multiplier may be negative until its own update in the sweep projects it). The
/// count restarts when a sweep changes a gap by more than the sweep before it (an adaptive
/// restart, as O'Donoghue and Candes restart accelerated gradient methods). The two-pass
/// constraints of two meshes make the Delassus operator nearly singular along the interface (a
/// smooth push of one pass against the other nearly cancels on the nodes), and plain sweeps
/// reduce those modes by about 1 % a sweep.
///
/// Measured on the striker bench scene, CPU reference, the whole run at the device's tolerance
/// (1e-4 of the margin), mean / max sweeps a step: 41 x 41 striker cells (10^4 elements) 19 / 126
/// with Nesterov's factor (k - 1) / (k + 2), 15 / 59 with this one (the device's plain sweeps:
/// 51 / 500); 80 x 80 (38 400 elements) 30 / 218 Nesterov, 19 / 75 this; 141 x 141 (1.2e5
/// elements) 33 / 158 Nesterov, 20 / 79 this (factors 0.8, 0.85 and 0.95: 24, 22 and 23 there).
/// BENCHMARKS.md, 2026-11-24 (ab4eb8f).
pub fn extrapolation(k: u32) -> f64 {
    if k < 2 {
        0.0
    } else {
        EXTRAPOLATION
    }
}

/// Projected Gauss-Seidel sweeps of the Lagrange correction over a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepStats {
    /// Sweeps of the current step.
    pub step: u64,
    /// Sweeps over the steps with Lagrange constraints.
    pub total: u64,
    /// Most sweeps in one step.
    pub max: u64,
    /// Steps with Lagrange constraints.
    pub steps: u64,
    /// Steps whose residual stayed above [`SWEEP_TOLERANCE`] (their last solve stopped at
    /// [`MAX_SWEEPS`]).
    pub unconverged: u64,
    /// The largest residual of a step: the largest change of a gap (or tangential slip) in its
    /// last sweep, over the search margin.
    #[serde(default)]
    pub residual_max: f64,
}

impl SweepStats {
    /// Mean sweeps per step with Lagrange constraints (0 without).
    pub fn mean(&self) -> f64 {
        if self.steps > 0 {
            self.total as f64 / self.steps as f64
        } else {
            0.0
        }
    }
}

impl ContactSet {
    /// The stable step the penalty springs alone allow, 2 / omega with
    /// omega^2 = k (1/m_slave + 1/m_master), and what sets it; `None` without penalty contact.
    pub fn penalty_step(&self) -> Option<(f64, &str)> {
        self.penalty_step.as_ref().map(|(d, s)| (*d, s.as_str()))
    }

    pub(super) fn compute_penalty_step(&self) -> Option<(f64, String)> {
        let mut best: Option<(f64, String)> = None;
        let mut consider = |omega2: f64, name: &str| {
            if omega2 > 0.0 {
                let dt = 2.0 / omega2.sqrt();
                if best.as_ref().is_none_or(|b| dt < b.0) {
                    best = Some((dt, name.to_string()));
                }
            }
        };
        // The mass form (k = s m* / dt^2) is chosen for the step and left out; the tangential
        // spring of penalty friction (k_t = friction_stiffness x k) acts along the tangent, apart
        // from the normal one: the stiffer of the two counts.
        let tangential = |mu: f64, r: f64| if mu > 0.0 { r.max(1.0) } else { 1.0 };
        for p in self
            .passes
            .iter()
            .filter(|p| p.method.has_springs() && !p.law.mass_form)
        {
            let ms = p
                .slaves
                .iter()
                .map(|&l| self.mass[l as usize])
                .fold(f64::INFINITY, f64::min);
            let mm = p
                .segments
                .iter()
                .flatten()
                .map(|&l| self.mass[l as usize])
                .fold(f64::INFINITY, f64::min);
            // A node of a two-pass contact is slave in one pass and master in the other, and a
            // node of a group is both in its one pass (each spring at half the stiffness): both
            // springs act on it.
            let passes = if p.two_pass { 2.0 } else { 1.0 };
            let k = passes
                * tangential(p.law.friction, p.law.friction_stiffness)
                * p.stiffness.iter().copied().fold(0.0f64, f64::max);
            consider(
                k * (1.0 / ms + 1.0 / mm),
                &format!("contact {:?}", self.interfaces[p.interface].name),
            );
        }
        for w in self
            .walls
            .iter()
            .filter(|w| w.method.has_springs() && !w.law.mass_form)
        {
            let kt = tangential(w.law.friction, w.law.friction_stiffness);
            let omega2 = kt
                * w.nodes
                    .iter()
                    .zip(&w.stiffness)
                    .map(|(&l, k)| k / self.mass[l as usize])
                    .fold(0.0f64, f64::max);
            consider(
                omega2,
                &format!("rigid wall {:?}", self.interfaces[w.interface].name),
            );
        }
        best
    }

    /// Combines the element stable step with the penalty springs':
    /// 1 / dt^2 = 1 / dt_element^2 + 1 / dt_penalty^2 (dt0 / sqrt(1 + k_p / k_e) for a node on a mesh).
    pub fn limit_step(&self, dt_element: f64) -> f64 {
        match self.penalty_step {
            Some((dp, _)) => 1.0 / (1.0 / (dt_element * dt_element) + 1.0 / (dp * dp)).sqrt(),
            None => dt_element,
        }
    }

    /// Applies the step's penalty impulses, then solves the Lagrange constraints (the velocity
    /// corrections accumulate in `dv`); keeps the multipliers for the next step's warm start.
    pub(super) fn solve(&mut self, dt: f64, dt_n: f64) {
        // Penalty impulses (marked by w < 0, impulse in lambda): fixed, applied first.
        let n_pen = self.cons.iter().filter(|c| c.w < 0.0).count();
        for k in 0..self.cons.len() {
            let c = self.cons[k];
            if c.w < 0.0 {
                self.impulse(&c, c.lambda);
                if c.lt != 0.0 {
                    self.impulse_along(&c, c.tangent(), c.lt, true);
                }
            }
        }
        // The penalty friction springs of this step, for the next.
        std::mem::swap(&mut self.pen_ft, &mut self.pen_ft_next);
        self.pen_ft_next.clear();
        self.pen_ft.sort_unstable_by_key(|e| e.0);
        // Lagrange: projected Gauss-Seidel in the fixed constraint order, warm-started from the
        // multipliers of the previous step (the same slave node of the same interface), scaled by
        // the ratio of the steps. In a persistent contact (a pressure carried across an
        // interface) the sweeps then continue where they stopped instead of starting from zero
        // each step: with the redundant constraints of two passes on non-matching meshes a cold
        // start leaves a residual of about 1e-5 of the load after MAX_SWEEPS sweeps.
        if !self.warm.is_empty() && self.warm_dt > 0.0 {
            let ratio = dt_n / self.warm_dt;
            for k in 0..self.cons.len() {
                let c = self.cons[k];
                if c.w < 0.0 {
                    continue;
                }
                if let Ok(i) = self.warm.binary_search_by_key(&warm_key(&c), |w| w.0) {
                    let lambda = self.warm[i].1 * ratio;
                    if lambda > 0.0 {
                        self.impulse(&c, lambda);
                        self.cons[k].lambda = lambda;
                    }
                }
            }
        }
        if self.cons.len() > n_pen {
            self.sweep_stats.step = 0;
            let mut residual = self.sweep();
            // Active-set update: the sweeps move master nodes, which can carry a segment onto
            // a slave node that was free at the trial positions (a node beside a dent, or at
            // a kink, whose neighbours are pushed back). Such a node would end the step inside
            // the other body, unconstrained. Check the free nodes again at the corrected
            // positions and sweep again with any that penetrate, a few rounds at most.
            for _ in 0..ACTIVE_SET_ROUNDS {
                let before = self.cons.len();
                self.recheck(dt, dt_n);
                if self.cons.len() == before {
                    break;
                }
                residual = self.sweep();
            }
            let residual = residual / self.margin.max(f64::MIN_POSITIVE);
            let s = &mut self.sweep_stats;
            s.residual_max = s.residual_max.max(residual);
            if residual > SWEEP_TOLERANCE {
                s.unconverged += 1;
            }
            s.total += s.step;
            s.max = s.max.max(s.step);
            s.steps += 1;
        }
        self.warm.clear();
        for c in &self.cons {
            if c.w >= 0.0 && c.lambda > 0.0 {
                self.warm.push((warm_key(c), c.lambda));
            }
        }
        self.warm.sort_unstable_by_key(|w| w.0);
        self.warm_dt = dt_n;
    }

    /// Projected Gauss-Seidel sweeps over the Lagrange constraints, in their fixed order, until
    /// the largest change of a gap is below [`SWEEP_TOLERANCE`] x margin or [`MAX_SWEEPS`];
    /// extrapolated between sweeps (see [`extrapolation`]) unless `plain_sweeps`; returns the
    /// last sweep's largest change of a gap (m), the step's residual when it is its last solve.
    pub(super) fn sweep(&mut self) -> f64 {
        let tol = SWEEP_TOLERANCE * self.margin.max(f64::MIN_POSITIVE);
        let dt = self.dt;
        let extrapolate = !self.plain_sweeps;
        if extrapolate {
            self.gather_touched();
        }
        self.pair_blocks();
        // Sweeps since the extrapolation (re)started, and the last sweep's change.
        let mut run = 0u32;
        let mut last = f64::INFINITY;
        for sweep in 0..MAX_SWEEPS {
            self.sweep_stats.step += 1;
            // (At the start of a run, before sweep 0 and the first sweep after a restart, the
            // values kept would not be used: the next factor is 0 as well, and its call keeps
            // them again.)
            if extrapolate && sweep > 0 {
                if run > 0 {
                    self.extrapolate(extrapolation(run));
                }
                run += 1;
            }
            let mut change: f64 = 0.0;
            for k in 0..self.cons.len() {
                let c = self.cons[k];
                if c.w < 0.0 {
                    continue;
                }
                match self.partner[k] {
                    NO_PARTNER => {}
                    j if (j as usize) > k => {
                        change = change.max(self.block(k, j as usize));
                        continue;
                    }
                    _ => continue,
                }
                let g = c.g0 + dt * self.relative(&c);
                let lambda = (c.lambda - g / c.w).max(0.0);
                let d = lambda - c.lambda;
                if d != 0.0 {
                    self.impulse(&c, d);
                    self.cons[k].lambda = lambda;
                    change = change.max((d * c.w).abs());
                }
                if c.mu > 0.0 {
                    // Coulomb: the tangential impulse that stops the relative tangential
                    // velocity, inside the cone |lt| <= mu lambda (stick), else on its edge
                    // against the slip (slip).
                    let t = c.tangent();
                    let vt = self.free_relative_constraint(&c, t) + self.relative_along(&c, t);
                    let bound = c.mu * lambda;
                    let lt = (c.lt - vt / c.wt).clamp(-bound, bound);
                    let d = lt - c.lt;
                    if d != 0.0 {
                        self.impulse_along(&c, t, d, true);
                        self.cons[k].lt = lt;
                        change = change.max((d * c.wt * dt).abs());
                    }
                }
            }
            if change > last {
                run = 0;
            }
            last = change;
            if change <= tol {
                break;
            }
        }
        last
    }

    /// Pairs the constraints solved together as 2 x 2 blocks (see [`ContactSet::block`]) into
    /// `partner`. (The GPU's one-workgroup solve pairs the same candidates by mutual best score
    /// instead of greedily, `pair_constraints` in `shaders/contact_colour.wgsl`: a rule that
    /// threads apply in any order.) Candidates: two frictionless Lagrange constraints against segments of the same
    /// interface, each one's slave node a node of the other's segment (the same contact met from
    /// both passes: a node and the nearby node of the other body, each the other's master).
    /// A node at a corner can have several; the most nearly parallel pairs (the largest
    /// |coupling| / sqrt(w_k w_j), where one-at-a-time sweeps are slowest) are taken first, then
    /// by constraint order, each constraint in one pair at most.
    fn pair_blocks(&mut self) {
        let n = self.cons.len();
        self.partner.clear();
        self.partner.resize(n, NO_PARTNER);
        let eligible = |c: &Constraint| c.w > 0.0 && c.a != u32::MAX && c.mu == 0.0;
        let mut by_slave = std::mem::take(&mut self.by_slave);
        by_slave.clear();
        by_slave.extend(
            self.cons
                .iter()
                .enumerate()
                .filter(|(_, c)| eligible(c))
                .map(|(k, c)| (c.s, k as u32)),
        );
        by_slave.sort_unstable();
        let mut pairs = std::mem::take(&mut self.pairs);
        pairs.clear();
        for k in 0..n {
            let c = self.cons[k];
            if !eligible(&c) {
                continue;
            }
            for m in [c.a, c.b] {
                let from = by_slave.partition_point(|e| e.0 < m);
                for &(_, j) in by_slave[from..].iter().take_while(|e| e.0 == m) {
                    let d = self.cons[j as usize];
                    if (j as usize) > k && d.interface == c.interface && (d.a == c.s || d.b == c.s)
                    {
                        let corr = self.coupling(&c, &d).abs() / (c.w * d.w).sqrt();
                        pairs.push((corr, k as u32, j));
                    }
                }
            }
        }
        pairs.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        for &(_, k, j) in &pairs {
            if self.partner[k as usize] == NO_PARTNER && self.partner[j as usize] == NO_PARTNER {
                self.partner[k as usize] = j;
                self.partner[j as usize] = k;
            }
        }
        self.pairs = pairs;
        self.by_slave = by_slave;
    }

    /// The coupling of constraints `c` and `d`: the change of `c`'s gap per unit impulse of
    /// `d` (their shared nodes' inverse masses; [`ContactSet::weight`]'s off-diagonal term).
    fn coupling(&self, c: &Constraint, d: &Constraint) -> f64 {
        let shares = |c: &Constraint| [(c.s, 1.0), (c.a, -(1.0 - c.xi)), (c.b, -c.xi)];
        let mut w = 0.0;
        for (p, sp) in shares(c) {
            for (q, sq) in shares(d) {
                if p == q && p != u32::MAX {
                    let im = self.inv_mass[p as usize];
                    w += sp * sq * (c.n[0] * d.n[0] * im[0] + c.n[1] * d.n[1] * im[1]);
                }
            }
        }
        self.dt * w * self.inv_mass_scale
    }

    /// One projected update of the pair (`k`, `j`) together: the 2 x 2 linear complementarity
    /// problem of their multipliers solved exactly (both pushing, either alone, or neither,
    /// the first that holds), where sweeping them one after the other converges at the rate
    /// cos^2 of the angle between them (a node and the nearby node of the other body, each the
    /// other's master: nearly opposite normals, 1 - cos^2 down to 1e-4). Returns the larger
    /// change of their gaps (W times the change of the multipliers).
    fn block(&mut self, k: usize, j: usize) -> f64 {
        let dt = self.dt;
        let (c, d) = (self.cons[k], self.cons[j]);
        let (wk, wj, wkj) = (c.w, d.w, self.coupling(&c, &d));
        let gk = c.g0 + dt * self.relative(&c);
        let gj = d.g0 + dt * self.relative(&d);
        // In increments d of the multipliers from where they are, l: the gaps there, g, are what
        // the sweeps drive to zero, and the gaps at l + d are g + W d. The rounding of the 2 x 2
        // inverse of a nearly redundant pair then scales with g, not with the multipliers, and
        // the fixed point is g = 0 however W is rounded (what the GPU's f32 `block_packed`
        // needs; the same form here).
        let det = wk * wj - wkj * wkj;
        let (lk, lj) = (c.lambda, d.lambda);
        let gap = |dk: f64, dj: f64| (gk + wk * dk + wkj * dj, gj + wkj * dk + wj * dj);
        let both = (det > 1e-12 * wk * wj)
            .then(|| ((-gk * wj + gj * wkj) / det, (-gj * wk + gk * wkj) / det))
            .filter(|&(dk, dj)| lk + dk > 0.0 && lj + dj > 0.0);
        // k alone (j released, k's gap closed), j alone, neither. The gap of the released one is
        // written without the cancellation of its large terms. For a pair that rounding leaves
        // redundant (two nodes that coincide, det 0) either alone holds, and the one that carries
        // the load keeps it, so that the load does not jump between the two from sweep to sweep
        // and step to step (the contact patch test's 8/6 mesh did not settle while it did).
        let det0 = det.max(0.0);
        let k_alone = (-(gk - wkj * lj) / wk, -lj);
        let j_alone = (-lk, -(gj - wkj * lk) / wj);
        let neither = gap(-lk, -lj);
        let k_holds = lk + k_alone.0 > 0.0 && gj - wkj / wk * gk - lj * det0 / wk >= 0.0;
        let j_holds = lj + j_alone.1 > 0.0 && gk - wkj / wj * gj - lk * det0 / wj >= 0.0;
        let (dk, dj) = if let Some(d) = both {
            d
        } else if k_holds && (lk >= lj || !j_holds) {
            k_alone
        } else if j_holds {
            j_alone
        } else if neither.0 >= 0.0 && neither.1 >= 0.0 {
            (-lk, -lj)
        } else {
            // (Only round-off lands here: the two updates one after the other.)
            let dk = (lk - gk / wk).max(0.0) - lk;
            (dk, (lj - (gj + wkj * dk) / wj).max(0.0) - lj)
        };
        if dk != 0.0 {
            self.impulse(&c, dk);
            self.cons[k].lambda = lk + dk;
        }
        if dj != 0.0 {
            self.impulse(&d, dj);
            self.cons[j].lambda = lj + dj;
        }
        (wk * dk + wkj * dj).abs().max((wkj * dk + wj * dj).abs())
    }

    /// The nodes of the Lagrange constraints, each once in constraint order, into `touched`.
    fn gather_touched(&mut self) {
        self.mark.resize(self.dv.len(), false);
        self.touched.clear();
        for c in self.cons.iter().filter(|c| c.w >= 0.0) {
            for node in [c.s, c.a, c.b] {
                if node != u32::MAX && !self.mark[node as usize] {
                    self.mark[node as usize] = true;
                    self.touched.push(node);
                }
            }
        }
        for &node in &self.touched {
            self.mark[node as usize] = false;
        }
        self.last_lambda.resize(self.cons.len(), [0.0; 2]);
        self.last_dv.resize(self.touched.len(), [[0.0; 2]; 2]);
    }

    /// Moves each Lagrange multiplier and friction impulse, and the velocity corrections of the
    /// touched nodes, on by `beta` times their change since the last call, and keeps the values
    /// reached for the next (`beta` = 0: only keeps them).
    fn extrapolate(&mut self, beta: f64) {
        let on = |x: f64, last: f64| x + beta * (x - last);
        for (c, last) in self.cons.iter_mut().zip(&mut self.last_lambda) {
            if c.w < 0.0 {
                continue;
            }
            let now = [c.lambda, c.lt];
            if beta != 0.0 {
                c.lambda = on(now[0], last[0]);
                c.lt = on(now[1], last[1]);
            }
            *last = now;
        }
        let friction = !self.dvt.is_empty();
        for (&node, last) in self.touched.iter().zip(&mut self.last_dv) {
            let l = node as usize;
            let now = [self.dv[l], if friction { self.dvt[l] } else { [0.0; 2] }];
            if beta != 0.0 {
                self.dv[l] = [on(now[0][0], last[0][0]), on(now[0][1], last[0][1])];
                if friction {
                    self.dvt[l] = [on(now[1][0], last[1][0]), on(now[1][1], last[1][1])];
                }
            }
            *last = now;
        }
    }

    /// Adds the Lagrange constraints of the slave and wall nodes without one that penetrate at
    /// the corrected positions x_tr + dt dv (see `apply`). Their gaps are stored at the free
    /// trial positions, as for every constraint, so that the sweeps treat them alike.
    pub(super) fn recheck(&mut self, dt: f64, dt_n: f64) {
        let mut done = std::mem::take(&mut self.done);
        done.clear();
        done.extend(self.cons.iter().map(warm_key));
        done.sort_unstable();
        for l in 0..self.x_tr.len() {
            let (x, d) = (self.x_tr[l], self.dv[l]);
            self.x_c[l] = [x[0] + dt * d[0], x[1] + dt * d[1]];
        }
        std::mem::swap(&mut self.x_tr, &mut self.x_c);
        let first = self.cons.len();
        self.collect_passes(dt, dt_n, Some(&done));
        self.collect_walls(dt, dt_n, Some(&done));
        std::mem::swap(&mut self.x_tr, &mut self.x_c);
        for k in first..self.cons.len() {
            let c = self.cons[k];
            self.cons[k].g0 = c.g0 - dt * self.relative(&c);
        }
        self.done = done;
    }

    /// Relative normal velocity change of constraint `c` from the impulses so far.
    #[inline]
    pub(super) fn relative(&self, c: &Constraint) -> f64 {
        self.relative_along(c, c.n)
    }

    /// Relative velocity change of constraint `c` along `dir` from the impulses so far.
    #[inline]
    pub(super) fn relative_along(&self, c: &Constraint, dir: [f64; 2]) -> f64 {
        let ds = self.dv[c.s as usize];
        let mut r = ds[0] * dir[0] + ds[1] * dir[1];
        if c.a != u32::MAX {
            let da = self.dv[c.a as usize];
            let db = self.dv[c.b as usize];
            r -= (1.0 - c.xi) * (da[0] * dir[0] + da[1] * dir[1])
                + c.xi * (db[0] * dir[0] + db[1] * dir[1]);
        }
        r
    }

    /// Relative velocity of constraint `c` along `dir` of the free update.
    #[inline]
    fn free_relative_constraint(&self, c: &Constraint, dir: [f64; 2]) -> f64 {
        let ab = (c.a != u32::MAX).then_some((c.a, c.b));
        self.free_relative(c.s, ab, c.xi, dir)
    }

    /// Applies impulse `lambda` along `c.n` (slave) and its reaction (master nodes).
    #[inline]
    pub(super) fn impulse(&mut self, c: &Constraint, lambda: f64) {
        self.impulse_along(c, c.n, lambda, false);
    }

    /// Applies impulse `lambda` along `dir` (slave) and its reaction (master nodes); `friction`:
    /// also into the friction share `dvt`.
    #[inline]
    pub(super) fn impulse_along(
        &mut self,
        c: &Constraint,
        dir: [f64; 2],
        lambda: f64,
        friction: bool,
    ) {
        let sc = self.inv_mass_scale;
        let mut nodes = [(c.s, 1.0), (u32::MAX, 0.0), (u32::MAX, 0.0)];
        if c.a != u32::MAX {
            nodes[1] = (c.a, -(1.0 - c.xi));
            nodes[2] = (c.b, -c.xi);
        }
        for (node, share) in nodes {
            if node == u32::MAX {
                continue;
            }
            let im = self.inv_mass[node as usize].map(|x| x * sc);
            let dd = [
                share * lambda * dir[0] * im[0],
                share * lambda * dir[1] * im[1],
            ];
            let d = &mut self.dv[node as usize];
            d[0] += dd[0];
            d[1] += dd[1];
            if friction {
                let d = &mut self.dvt[node as usize];
                d[0] += dd[0];
                d[1] += dd[1];
            }
        }
    }
}

/// (omega dt)^2 = k dt_n w of a penalty spring above which its impulse is bounded (see
/// [`penalty_impulse`]): omega dt = 1, three times the omega dt = 0.3 that keeps a two-mass
/// restitution within 1 % (REFERENCES.md section 6) and half the linear stability limit of 2. The
/// default scale (2) passes it in an impact's first steps (the short striker: 20 impulses).
pub const STIFF_SPRING: f64 = 1.0;

/// Penalty impulse over the step for a spring of stiffness `k` at gap `g` (< 0): dt_n k (-g), the
/// spring unchanged, as long as it is soft for the step ((omega dt)^2 = k dt_n w at most
/// [`STIFF_SPRING`]): it then stores and returns its energy like any spring, and the release gives
/// back what the impact stored. A stiffer spring (a fixed step above its limit, or a stiff
/// mass-form scale) would chatter and gain energy (REFERENCES.md section 6); its impulse is bounded
/// so that one step never does more than the perfectly plastic impulse (Belytschko X.6):
/// - while the free update approaches (`rate` < 0, the relative normal velocity), at most the
///   impulse that stops the approach: no release within the impact step, no velocity reversal;
/// - while it separates, at most the impulse that brings the node back onto the surface by
///   u_{n+1} (the gap `g_trial` of the free update closed), so a spring never throws it off.
///
/// The bounded spring loses energy (kept as contact energy); the second value says whether the
/// bound acted. `w` is dt (1/m_s + ...).
#[inline]
pub fn penalty_impulse(
    k: f64,
    g: f64,
    rate: f64,
    g_trial: f64,
    w: f64,
    dt: f64,
    dt_n: f64,
) -> (f64, bool) {
    let spring = dt_n * k * (-g).max(0.0);
    if k * dt_n * w <= STIFF_SPRING {
        return (spring, false);
    }
    let bound = if rate < 0.0 {
        -rate * dt / w
    } else {
        (-g_trial / w).max(0.0)
    };
    (spring.min(bound), bound < spring)
}

/// The augmented Lagrangian's impulse over the step, its next multiplier and whether the bound
/// acted (Belytschko X.5.7), for a spring `k` at gap `g` (< 0 penetrates) carrying the multiplier
/// `lambda` (a force >= 0) of the last step; `rate`, `g_trial`, `w` as for [`penalty_impulse`].
///
/// The contact force is lambda + k (-g) while positive (so a node stays in contact at a gap up to
/// lambda / k); `None` otherwise: the node has left and drops its multiplier. The spring's share
/// is bounded as in [`penalty_impulse`] when stiff for the step. The next multiplier is Uzawa's
/// update at the rate `r` (1/s), max(0, lambda + r dt_n k (-g)): the multiplier integrates the
/// penetration, so a persistent contact's grows until the penetration is gone and carries the
/// whole force. That integral is stable only under mass damping alpha > r (see
/// [`crate::scene::ContactMethod::AugmentedLagrange`]).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn augmented_impulse(
    k: f64,
    g: f64,
    rate: f64,
    g_trial: f64,
    lambda: f64,
    w: f64,
    dt: f64,
    dt_n: f64,
    r: f64,
) -> Option<(f64, f64, bool)> {
    // (NaN is not a push either.)
    let force = lambda - k * g;
    if force.is_nan() || force <= 0.0 {
        return None;
    }
    let (spring, bounded) = if g < 0.0 {
        penalty_impulse(k, g, rate, g_trial, w, dt, dt_n)
    } else {
        (-dt_n * k * g, false)
    };
    let next = (lambda - r * dt_n * k * g).max(0.0);
    Some((dt_n * lambda + spring, next, bounded))
}

/// The perturbed Lagrangian's penetration of a slave node (Belytschko X.5.8): the penetration
/// `a` (> 0) of the node and, for each of its two surface segments, the segment's length and the
/// penetration of its other end along the node's contact normal (negative: apart). With the
/// multipliers interpolated by the surface's shape functions, H = (1/beta) int N^T N dGamma
/// (Eq. X.5.44) is the consistent "mass" of the surface, and eliminating them (Eq. X.5.45) gives
/// each node the consistent nodal force f_I = beta int N_I max(0, p(x)) dGamma of the linear
/// penetration field p(x): no system to solve. With beta_I = k_I / int N_I dGamma over the part in
/// contact, f_I = k_I times the value returned, the N_I-weighted mean of p over the node's
/// contact support: a uniform penetration gives the penalty's force k a, a linear one the
/// consistent nodal forces of the linear pressure beta p(x), where the penalty lumps them
/// (f_I = k p_I). A segment of zero length (no neighbour) is skipped.
pub fn consistent_penetration(a: f64, sides: [(f64, f64); 2]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (l, b) in sides {
        if l.is_nan() || a.is_nan() || l <= 0.0 || a <= 0.0 {
            continue;
        }
        if b >= 0.0 {
            // int_0^1 (1 - s) (a + (b - a) s) ds and int_0^1 (1 - s) ds.
            num += l * (2.0 * a + b) / 6.0;
            den += l * 0.5;
        } else {
            // The penetration ends inside the segment, at s0 = a / (a - b).
            let s0 = a / (a - b);
            let c = b - a;
            num += l * (a * s0 + (c - a) * s0 * s0 / 2.0 - c * s0 * s0 * s0 / 3.0);
            den += l * (s0 - s0 * s0 / 2.0);
        }
    }
    if den > 0.0 {
        num / den
    } else {
        a
    }
}
