//! Growth of an assembler's pattern by node-pair couplings (contact pairs that come near):
//! the pattern [`Assembler::with_couplings`] would build with the new couplings, obtained by
//! merging their entries into the old pattern, with every element slot moved to its new
//! position and the reference data (integration rules, element geometry, orientation signs,
//! colouring) taken over instead of being computed again. The result is the same assembler,
//! slot for slot, at a fraction of the cost (on the 5 cm NBC hood, 383 growths: the rebuild
//! took 13 of the 23 ms of a growth, the rest being the symbolic analysis).

use std::sync::Mutex;

use super::store::MixedStore;
use super::{Assembler, Pattern, NO_SLOT};
use crate::element::NODE_DOFS;
use crate::model::Model;

/// Adds the entries (row ≤ column) that couple the translations of nodes `a` and `b`, taken
/// through their ties, to the row lists `cols` — the entries [`Assembler::with_couplings`]
/// stores for a coupling (a, b).
pub(super) fn push_coupling(model: &Model, a: usize, b: usize, cols: &mut [Vec<usize>]) {
    let ea: Vec<usize> = (0..3).flat_map(|k| model.dofs.expand(NODE_DOFS * a + k)).map(|(e, _)| e).collect();
    let eb: Vec<usize> = (0..3).flat_map(|k| model.dofs.expand(NODE_DOFS * b + k)).map(|(e, _)| e).collect();
    for &r in &ea {
        for &c in &eb {
            cols[r.max(c)].push(r.min(c));
        }
    }
}

impl Pattern {
    /// This pattern with the couplings `added` as well (their entries merged into each
    /// column's sorted rows), and the position in it of every stored entry of this one.
    pub fn with_pairs(&self, model: &Model, added: &[(usize, usize)]) -> (Pattern, Vec<usize>) {
        let mut extra: Vec<Vec<usize>> = vec![Vec::new(); self.n];
        for &(a, b) in added {
            push_coupling(model, a, b, &mut extra);
        }
        let mut col_ptr = Vec::with_capacity(self.n + 1);
        let mut row_idx = Vec::with_capacity(self.row_idx.len() + added.len() * 9);
        let mut pos = Vec::with_capacity(self.row_idx.len());
        col_ptr.push(0);
        for (c, new) in extra.iter_mut().enumerate() {
            new.sort_unstable();
            new.dedup();
            let old = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
            let (mut i, mut j) = (0, 0);
            while i < old.len() || j < new.len() {
                if j == new.len() || (i < old.len() && old[i] <= new[j]) {
                    if j < new.len() && old[i] == new[j] {
                        j += 1;
                    }
                    pos.push(row_idx.len());
                    row_idx.push(old[i]);
                    i += 1;
                } else {
                    row_idx.push(new[j]);
                    j += 1;
                }
            }
            col_ptr.push(row_idx.len());
        }
        (Pattern { n: self.n, col_ptr, row_idx }, pos)
    }
}

impl Assembler {
    /// The assembler for `pattern`, grown from this one's (`pos`: the new position of each
    /// old entry, [`Pattern::with_pairs`]): the slots moved there, the reference data, the
    /// settings and the kept element responses taken over ([`Assembler::take_over`]). The
    /// mixed-stress records start afresh, as those of a rebuilt assembler do. This assembler
    /// is left without its reference data: it is to be dropped.
    pub fn regrown(&mut self, pattern: Pattern, pos: &[usize]) -> Assembler {
        let moved = |s: u32| if s == NO_SLOT { NO_SLOT } else { pos[s as usize] as u32 };
        let slots = self.slots.iter().map(|el| el.map(moved)).collect();
        let tied = self.tied.iter().map(|l| l.iter().map(|&(ij, s, w)| (ij, moved(s), w)).collect()).collect();
        let linked = self.linked.iter().map(|l| l.iter().map(|&(ij, s, a, b)| (ij, moved(s), a, b)).collect()).collect();
        let offsets = self.records.lock().map(|r| r.offsets.clone()).unwrap_or_else(|p| p.into_inner().offsets.clone());
        let mut grown = Assembler {
            pattern,
            slots,
            rules: std::mem::take(&mut self.rules),
            geometry: std::mem::take(&mut self.geometry),
            orientation: std::mem::take(&mut self.orientation),
            tied,
            linked,
            colours: std::mem::take(&mut self.colours),
            serial: std::mem::take(&mut self.serial),
            project: false,
            mixed: false,
            records: Mutex::new(MixedStore { offsets, ..Default::default() }),
            keep_responses: false,
            cache: Default::default(),
        };
        grown.take_over(self);
        grown
    }
}

#[cfg(test)]
mod tests {
    use crate::assembly::Assembler;
    use crate::scene;

    /// On the two-panel sleeve (tied, non-matching seams): growing an assembler by node pairs
    /// gives the pattern, slots, tied entries and colouring of the one rebuilt with every
    /// coupling, and the old entries' positions in it.
    #[test]
    fn grown_assembler_equals_the_rebuilt_one() {
        let text = include_str!("../../garments/sleeve_two_panel.ron");
        let sc = scene::parse("sleeve", text).expect("scene");
        let built = scene::build(&sc, "sleeve", text).expect("build");
        let model = &built.model;
        let n = model.n_nodes();
        let first = [(0, n - 1), (3, n / 2)];
        let added = [(1, n - 2), (0, n - 1), (5, n / 3), (n / 3, 5), (n / 4, 3 * n / 4)];
        let mut old = Assembler::with_couplings(model, &first);
        let (pattern, pos) = old.pattern.with_pairs(model, &added);
        let mut all: Vec<(usize, usize)> = first.iter().chain(&added).copied().collect();
        all.sort_unstable();
        all.dedup();
        let rebuilt = Assembler::with_couplings(model, &all);
        assert_eq!(pattern.col_ptr, rebuilt.pattern.col_ptr);
        assert_eq!(pattern.row_idx, rebuilt.pattern.row_idx);
        assert!(pattern.row_idx.len() > old.pattern.row_idx.len(), "the pairs add entries");
        for c in 0..old.pattern.n {
            for q in old.pattern.col_ptr[c]..old.pattern.col_ptr[c + 1] {
                assert_eq!(pattern.row_idx[pos[q]], old.pattern.row_idx[q], "entry {q} of column {c}");
                assert!((pattern.col_ptr[c]..pattern.col_ptr[c + 1]).contains(&pos[q]));
            }
        }
        let grown = old.regrown(pattern, &pos);
        assert!(!rebuilt.tied.iter().all(|t| t.is_empty()), "the sleeve's seams tie DOFs");
        assert!(grown.slots == rebuilt.slots);
        assert_eq!(grown.tied, rebuilt.tied);
        assert_eq!(grown.linked, rebuilt.linked);
        assert_eq!(grown.colours, rebuilt.colours);
        assert_eq!(grown.serial, rebuilt.serial);
        assert_eq!(grown.geometry.len(), rebuilt.geometry.len());
    }
}
