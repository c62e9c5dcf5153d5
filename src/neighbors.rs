//! Neighbour search: a cell-linked list with no fixed domain box.
//!
//! Cells have the size of the largest smoothing length plus half the skin, h_max + s/2, so every
//! neighbour of a particle (r_ij < h_i + h_j + s ≤ 2 h_max + s) lies within two cells of its own. Cells are keyed by integer
//! coordinates from the particles' current bounding box, the last axis varying fastest, so the
//! five cells along the last axis around a particle are one contiguous run of the sorted
//! particles: a particle's candidates are 5^(D−1) contiguous runs.
//!
//! When the box is compact (its cell count at most a few times the particle count) the grid is
//! dense and built by counting sort in O(N); when debris has spread the box, only occupied cells
//! are kept, sorted by key, and a run is found by binary search. Either way the lists hold, for
//! each real particle i, every particle j ≠ i (real or ghost) with r_ij < h_i + h_j (= 2 h_ij,
//! the support of W(r, h_ij)), in a fixed order, so results do not depend on the thread count.
//!
//! The one list serves both the conservation equations and the contact: each pair is classified
//! by its bodies when it is used (see `physics::PairTable`), so there is no second search.
//!
//! **Verlet skin.** Lists are built with the support widened by a skin s, r_ij < h_i + h_j + s,
//! and kept while no pair can have crossed into the support: the positions may move by d and
//! the smoothing lengths grow by δ (both the largest since the build) as long as
//! 2 d + 2 δ < s. Users of the list test r_ij < h_i + h_j themselves, so the physics is that of
//! an exact list; the skin only saves searches (a run at a few % of the sound speed searches
//! every few tens of steps).

use crate::particles::Vector;
use rayon::prelude::*;

/// Cells reach this many cells either side (cell size h_max, support ≤ 2 h_max).
const REACH: i64 = 2;
/// A dense grid is used while it has at most this many cells per particle.
const DENSE_CELLS_PER_PARTICLE: usize = 8;
/// Bits per axis of a sparse cell key.
const KEY_BITS: u32 = 21;
const KEY_MAX: i64 = (1 << KEY_BITS) - 1;

/// Neighbour lists of the real particles, with the buffers of the search kept between steps so
/// that rebuilding allocates nothing once the run has settled.
#[derive(Debug, Default, Clone)]
pub struct NeighborList {
    /// lists[i]: neighbours of real particle i.
    pub lists: Vec<Vec<u32>>,
    /// Particles in cell order.
    sorted: Vec<u32>,
    /// Dense: start of each cell in `sorted` (len cells + 1). Sparse: start of each occupied
    /// cell, with its key in `cell_key`.
    cell_start: Vec<u32>,
    cell_key: Vec<u64>,
    /// Next free slot of each cell during the counting sort.
    fill: Vec<u32>,
    /// Cell coordinates of each particle, and (sparse) key-index pairs for sorting.
    coords: Vec<[i64; 3]>,
    keyed: Vec<(u64, u32)>,
    /// Positions and support radii (h + skin/2) in cell order, so that scanning a run of
    /// candidates reads memory in sequence.
    xs: Vec<Vector<3>>,
    hs: Vec<f64>,
    /// Skin of the last build, and the positions and smoothing lengths it was built for.
    skin: f64,
    x_built: Vec<f64>,
    h_built: Vec<f64>,
}

/// The cell geometry of one build.
#[derive(Debug, Clone, Copy)]
struct Grid<const D: usize> {
    lo: Vector<D>,
    cell: f64,
    dims: [i64; 3],
    dense: bool,
}

impl<const D: usize> Grid<D> {
    fn coords(&self, x: &Vector<D>) -> [i64; 3] {
        let mut c = [0i64; 3];
        for (k, ck) in c.iter_mut().enumerate().take(D) {
            *ck = (((x[k] - self.lo[k]) / self.cell).floor() as i64).clamp(0, self.dims[k] - 1);
        }
        c
    }

    /// Dense cell index (last axis fastest).
    fn index(&self, c: [i64; 3]) -> usize {
        let mut idx = 0i64;
        for (&dk, &ck) in self.dims.iter().zip(&c).take(D) {
            idx = idx * dk + ck;
        }
        idx as usize
    }

    /// Sparse key (last axis fastest, KEY_BITS per axis).
    fn key(&self, c: [i64; 3]) -> u64 {
        let mut key = 0u64;
        for &ck in c.iter().take(D) {
            key = (key << KEY_BITS) | ck as u64;
        }
        key
    }
}

impl NeighborList {
    /// Total number of (i, j) entries.
    pub fn total(&self) -> usize {
        self.lists.iter().map(Vec::len).sum()
    }

    /// Particle indices (real and ghost) in cell order from the last build: a locality-friendly
    /// order for the particle store.
    pub fn cell_order(&self) -> &[u32] {
        &self.sorted
    }

    /// Whether the lists built last no longer hold every pair within the support for these
    /// positions and smoothing lengths (always true before the first build or if the particle
    /// count changed).
    pub fn stale<const D: usize>(&self, x: &[Vector<D>], h: &[f64]) -> bool {
        if self.h_built.len() != h.len() || self.x_built.len() != D * x.len() {
            return true;
        }
        let (d2, dh) = x
            .par_iter()
            .zip(h.par_iter())
            .enumerate()
            .map(|(i, (xi, &hi))| {
                let mut d2 = 0.0;
                for k in 0..D {
                    let dk = xi[k] - self.x_built[D * i + k];
                    d2 += dk * dk;
                }
                (d2, hi - self.h_built[i])
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        2.0 * d2.sqrt() + 2.0 * dh.max(0.0) >= self.skin
    }

    /// Rebuild for positions `x` (real then ghosts) and smoothing lengths `h`, with the support
    /// widened by `skin`; lists for the first `n_real` particles.
    pub fn build<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64], n_real: usize, skin: f64) {
        let n = x.len();
        self.skin = skin;
        self.x_built.clear();
        self.x_built
            .extend(x.iter().flat_map(|p| p.iter().copied()));
        self.h_built.clear();
        self.h_built.extend_from_slice(h);
        self.lists.resize_with(n_real, Vec::new);
        self.lists.truncate(n_real);
        if n == 0 {
            self.sorted.clear();
            return;
        }
        let grid = self.bin(x, h, skin);
        self.xs.clear();
        self.xs.par_extend(self.sorted.par_iter().map(|&j| {
            let mut p = Vector::<3>::zeros();
            for k in 0..D {
                p[k] = x[j as usize][k];
            }
            p
        }));
        self.hs.clear();
        self.hs
            .par_extend(self.sorted.par_iter().map(|&j| h[j as usize] + 0.5 * skin));
        let (xs, hs) = (&self.xs, &self.hs);
        let sorted = &self.sorted;
        let cell_start = &self.cell_start;
        let cell_key = &self.cell_key;
        let coords = &self.coords;
        let last = D - 1;
        self.lists.par_iter_mut().enumerate().for_each(|(i, list)| {
            list.clear();
            let xi = x[i];
            let hi = h[i] + 0.5 * skin;
            let c = coords[i];
            // Runs along the last axis for every offset of the other axes.
            let lo_last = (c[last] - REACH).max(0);
            let hi_last = (c[last] + REACH).min(grid.dims[last] - 1);
            let mut xi3 = Vector::<3>::zeros();
            for k in 0..D {
                xi3[k] = xi[k];
            }
            let mut visit = |a: usize, b: usize| {
                for k in a..b {
                    let support = hi + hs[k];
                    if (xi3 - xs[k]).norm_squared() < support * support && sorted[k] as usize != i {
                        list.push(sorted[k]);
                    }
                }
            };
            let mut offsets = [[0i64; 3]; 25];
            let mut count = 0;
            let (r0, r1) = if D == 3 { (REACH, REACH) } else { (REACH, 0) };
            for d0 in -r0..=r0 {
                for d1 in -r1..=r1 {
                    offsets[count] = [d0, d1, 0];
                    count += 1;
                }
            }
            for off in &offsets[..count] {
                let mut first = c;
                let mut inside = true;
                for k in 0..last {
                    first[k] = c[k] + off[k];
                    inside &= (0..grid.dims[k]).contains(&first[k]);
                }
                if !inside {
                    continue;
                }
                let mut end = first;
                first[last] = lo_last;
                end[last] = hi_last;
                if grid.dense {
                    let a = cell_start[grid.index(first)] as usize;
                    let b = cell_start[grid.index(end) + 1] as usize;
                    visit(a, b);
                } else {
                    let (ka, kb) = (grid.key(first), grid.key(end));
                    let a = cell_key.partition_point(|&k| k < ka);
                    let b = cell_key.partition_point(|&k| k <= kb);
                    if a < b {
                        visit(cell_start[a] as usize, cell_start[b] as usize);
                    }
                }
            }
        });
    }

    /// Sort the particles into cells; fills `sorted`, `cell_start` (and `cell_key` when sparse)
    /// and `coords`.
    fn bin<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64], skin: f64) -> Grid<D> {
        let n = x.len();
        let h_max = h.iter().copied().fold(0.0_f64, f64::max) + 0.5 * skin;
        let mut lo = Vector::<D>::repeat(f64::INFINITY);
        let mut hi = Vector::<D>::repeat(f64::NEG_INFINITY);
        for p in x {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let cell = h_max.max(f64::MIN_POSITIVE);
        let mut dims = [1i64; 3];
        let mut total: f64 = 1.0;
        for k in 0..D {
            let d = ((hi[k] - lo[k]) / cell).floor() + 1.0;
            total *= d;
            dims[k] = d.min(KEY_MAX as f64) as i64;
        }
        let dense = total <= (DENSE_CELLS_PER_PARTICLE * n + 64) as f64;
        let grid = Grid {
            lo,
            cell,
            dims,
            dense,
        };
        self.coords.clear();
        self.coords.par_extend(x.par_iter().map(|p| grid.coords(p)));
        self.sorted.clear();
        self.cell_start.clear();
        self.cell_key.clear();
        if dense {
            // Counting sort by cell: O(N), stable (index order within a cell).
            let cells = total as usize;
            self.cell_start.resize(cells + 1, 0);
            for c in &self.coords {
                self.cell_start[grid.index(*c) + 1] += 1;
            }
            for k in 0..cells {
                self.cell_start[k + 1] += self.cell_start[k];
            }
            self.sorted.resize(n, 0);
            self.fill.clear();
            self.fill.extend_from_slice(&self.cell_start[..cells]);
            for (i, c) in self.coords.iter().enumerate() {
                let slot = &mut self.fill[grid.index(*c)];
                self.sorted[*slot as usize] = i as u32;
                *slot += 1;
            }
        } else {
            self.keyed.clear();
            let coords = &self.coords;
            self.keyed.par_extend(
                (0..n)
                    .into_par_iter()
                    .map(|i| (grid.key(coords[i]), i as u32)),
            );
            self.keyed.par_sort_unstable();
            for (k, &(key, i)) in self.keyed.iter().enumerate() {
                if self.cell_key.last() != Some(&key) {
                    self.cell_key.push(key);
                    self.cell_start.push(k as u32);
                }
                self.sorted.push(i);
            }
            self.cell_start.push(n as u32);
        }
        grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute<const D: usize>(x: &[Vector<D>], h: &[f64], n_real: usize) -> Vec<Vec<u32>> {
        (0..n_real)
            .map(|i| {
                (0..x.len())
                    .filter(|&j| j != i && (x[i] - x[j]).norm() < h[i] + h[j])
                    .map(|j| j as u32)
                    .collect()
            })
            .collect()
    }

    fn compare<const D: usize>(x: &[Vector<D>], h: &[f64], n_real: usize) {
        let mut nl = NeighborList::default();
        nl.build(x, h, n_real, 0.0);
        let expect = brute(x, h, n_real);
        assert_eq!(nl.lists.len(), n_real);
        for (i, (list, expect)) in nl.lists.iter().zip(&expect).enumerate() {
            let mut got = list.clone();
            got.sort();
            assert_eq!(&got, expect, "particle {i}");
        }
    }

    /// With a skin the lists hold every pair within the support until `stale` says otherwise.
    #[test]
    fn skin_lists_stay_complete_until_stale() {
        let mut seed = 7u64;
        let mut x: Vec<Vector<3>> = (0..400)
            .map(|_| Vector::<3>::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)))
            .collect();
        let h = vec![0.06; 400];
        let mut nl = NeighborList::default();
        nl.build(&x, &h, 400, 0.02);
        let mut moves = 0;
        while !nl.stale(&x, &h) {
            let exact = brute(&x, &h, 400);
            for (i, e) in exact.iter().enumerate() {
                assert!(
                    e.iter().all(|j| nl.lists[i].contains(j)),
                    "pair lost at move {moves}"
                );
            }
            for p in x.iter_mut() {
                *p += Vector::<3>::new(
                    rnd(&mut seed) - 0.5,
                    rnd(&mut seed) - 0.5,
                    rnd(&mut seed) - 0.5,
                ) * 0.004;
            }
            moves += 1;
        }
        assert!(
            moves >= 2,
            "the skin should last a few moves, lasted {moves}"
        );
    }

    fn rnd(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A compact cloud (dense grid) and one with far-flung debris (sparse grid), 2D and 3D,
    /// against brute force.
    #[test]
    fn matches_brute_force() {
        let mut seed = 12345u64;
        for spread in [1.0, 1e4] {
            let mut x3 = Vec::new();
            let mut x2 = Vec::new();
            let mut h = Vec::new();
            for k in 0..600 {
                let scale = if k % 50 == 0 { spread } else { 1.0 };
                x3.push(Vector::<3>::new(
                    rnd(&mut seed) * scale,
                    rnd(&mut seed),
                    rnd(&mut seed) - 7.0,
                ));
                x2.push(Vector::<2>::new(
                    rnd(&mut seed) * scale,
                    rnd(&mut seed) + 3.0,
                ));
                h.push(0.03 + 0.05 * rnd(&mut seed));
            }
            compare(&x3, &h, 500);
            compare(&x2, &h, 500);
        }
    }
}
