//! Neighbour search: a cell-linked list on sorted cell keys, with no fixed domain box.
//!
//! Cells have the size of the largest support 2 h_max, so every neighbour of a particle lies in
//! its own or an adjacent cell. Particles are sorted by cell key (ties by index), so the grid
//! needs no bounding box known in advance and only occupied cells cost memory: debris may fly
//! anywhere. The lists hold, for each real particle i, every particle j ≠ i (real or ghost) with
//! r_ij < h_i + h_j (= 2 h_ij, the support of W(r, h_ij)), in a fixed order (cell offset, then
//! index), so results do not depend on the number of threads.
//!
//! The one list serves both the conservation equations and the contact: each pair is classified
//! by its bodies when it is used (see `physics::PairTable`), so there is no second search.

use crate::particles::Vector;
use rayon::prelude::*;

/// Bits per axis in a cell key (cells are clamped to this range; a clamped cell only adds
/// candidates, the distance test keeps the result exact).
const KEY_BITS: u32 = 21;
const KEY_MAX: i64 = (1 << KEY_BITS) - 1;

/// Neighbour lists of the real particles, kept between steps so that rebuilding allocates
/// nothing once the run has settled.
#[derive(Debug, Default, Clone)]
pub struct NeighborList {
    /// lists[i]: neighbours of real particle i.
    pub lists: Vec<Vec<u32>>,
    /// (cell key, particle) sorted; reused buffer.
    sorted: Vec<(u64, u32)>,
    /// Start of each occupied cell in `sorted`, and its key.
    cell_start: Vec<u32>,
    cell_key: Vec<u64>,
}

impl NeighborList {
    /// Total number of (i, j) entries.
    pub fn total(&self) -> usize {
        self.lists.iter().map(Vec::len).sum()
    }

    /// Particle indices in cell order (real and ghost), from the last build: a locality-friendly
    /// ordering for reordering the particle store.
    pub fn cell_order(&self) -> impl Iterator<Item = usize> + '_ {
        self.sorted.iter().map(|&(_, i)| i as usize)
    }

    /// Rebuild for positions `x` (real then ghosts) and smoothing lengths `h`; lists for the
    /// first `n_real` particles.
    pub fn build<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64], n_real: usize) {
        let n = x.len();
        let h_max = h.iter().copied().fold(0.0_f64, f64::max);
        let cell = 2.0 * h_max;
        let mut lo = Vector::<D>::repeat(f64::INFINITY);
        for p in x {
            lo = lo.inf(p);
        }
        let key_of = |p: &Vector<D>| -> u64 {
            let mut key = 0u64;
            for k in 0..D {
                let c = ((p[k] - lo[k]) / cell).floor() as i64;
                key = (key << KEY_BITS) | c.clamp(0, KEY_MAX) as u64;
            }
            key
        };
        let coords_of = |key: u64| -> [i64; 3] {
            let mut c = [0i64; 3];
            for k in 0..D {
                c[k] = ((key >> (KEY_BITS * (D - 1 - k) as u32)) & KEY_MAX as u64) as i64;
            }
            c
        };

        self.sorted.clear();
        self.sorted
            .par_extend((0..n).into_par_iter().map(|i| (key_of(&x[i]), i as u32)));
        self.sorted.par_sort_unstable();
        self.cell_start.clear();
        self.cell_key.clear();
        for (k, &(key, _)) in self.sorted.iter().enumerate() {
            if self.cell_key.last() != Some(&key) {
                self.cell_key.push(key);
                self.cell_start.push(k as u32);
            }
        }
        self.cell_start.push(n as u32);

        self.lists.resize_with(n_real, Vec::new);
        self.lists.truncate(n_real);
        let sorted = &self.sorted;
        let cell_start = &self.cell_start;
        let cell_key = &self.cell_key;
        let offsets: Vec<[i64; 3]> = neighbor_offsets::<D>();
        self.lists.par_iter_mut().enumerate().for_each(|(i, list)| {
            list.clear();
            let xi = x[i];
            let hi = h[i];
            let c = coords_of(key_of(&xi));
            for off in &offsets {
                let mut key = 0u64;
                let mut valid = true;
                for k in 0..D {
                    let ck = c[k] + off[k];
                    if !(0..=KEY_MAX).contains(&ck) {
                        valid = false;
                    }
                    key = (key << KEY_BITS) | (ck.clamp(0, KEY_MAX) as u64);
                }
                if !valid {
                    continue;
                }
                if let Ok(cidx) = cell_key.binary_search(&key) {
                    let (a, b) = (cell_start[cidx] as usize, cell_start[cidx + 1] as usize);
                    for &(_, j) in &sorted[a..b] {
                        let j = j as usize;
                        if j == i {
                            continue;
                        }
                        let support = hi + h[j];
                        if (xi - x[j]).norm_squared() < support * support {
                            list.push(j as u32);
                        }
                    }
                }
            }
        });
    }
}

/// The 3^D cell offsets in a fixed order.
fn neighbor_offsets<const D: usize>() -> Vec<[i64; 3]> {
    let mut out = Vec::new();
    let r = |k: usize| if k < D { -1..=1 } else { 0..=0 };
    for a in r(0) {
        for b in r(1) {
            for c in r(2) {
                out.push([a, b, c]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Compare with brute force on a random cloud spread over wildly different scales.
    #[test]
    fn matches_brute_force() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut x = Vec::new();
        let mut h = Vec::new();
        for k in 0..600 {
            let scale = if k % 50 == 0 { 1e4 } else { 1.0 };
            x.push(Vector::<3>::new(rnd() * scale, rnd(), rnd() - 7.0));
            h.push(0.05 + 0.05 * rnd());
        }
        let mut nl = NeighborList::default();
        nl.build(&x, &h, 500);
        assert_eq!(nl.lists.len(), 500);
        for i in 0..500 {
            let mut expect: Vec<u32> = (0..600)
                .filter(|&j| j != i && (x[i] - x[j]).norm() < h[i] + h[j])
                .map(|j| j as u32)
                .collect();
            let mut got = nl.lists[i].clone();
            expect.sort();
            got.sort();
            assert_eq!(got, expect, "particle {i}");
        }
    }
}
