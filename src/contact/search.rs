//! Search: when a new broad-phase search is due, and the search itself (the `parry2d` BVH of
//! [`super::broad`] per pass, its candidates filtered by [`super::rules::admissible`]).

use super::rules::admissible;
use super::{broad, dist2, ContactSet};

impl ContactSet {
    /// Whether some contact node has moved more than half the margin since the last search
    /// (at u_n or at the trial u_{n+1}), or there was none.
    pub(super) fn search_due(&self) -> bool {
        if !self.searched {
            return true;
        }
        let h2 = 0.25 * self.margin * self.margin;
        self.x_ref
            .iter()
            .zip(self.x_n.iter().zip(&self.x_tr))
            .any(|(r, (a, b))| dist2(*r, *a) > h2 || dist2(*r, *b) > h2)
    }

    /// Searches every pass with the nodes at `x_n` and `x_tr` (swept boxes), keeping the
    /// admissible candidates.
    pub(super) fn search(&mut self) {
        let x0 = &self.reference;
        for p in &mut self.passes {
            let mut c =
                broad::candidates(&p.slaves, &p.segments, &self.x_n, &self.x_tr, self.margin);
            c.retain(|&(si, j)| {
                let (si, j) = (si as usize, j as usize);
                let (s, [a, b]) = (p.slaves[si], p.segments[j]);
                admissible(
                    s,
                    p.neighbours[si],
                    p.slave_body[si],
                    [a, b],
                    p.segment_body[j],
                    p.self_contact,
                    x0[s as usize],
                    x0[a as usize],
                    x0[b as usize],
                )
            });
            p.candidates = c;
        }
        self.x_ref.copy_from_slice(&self.x_tr);
        self.searched = true;
        self.searches += 1;
    }
}
