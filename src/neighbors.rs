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
//! the support of W(r, h_ij)).
//!
//! **Canonical order.** Each list is sorted by particle index. The sums over a particle's
//! neighbours then add the same numbers in the same order whenever and however the list was
//! built (a full build, a partial rebuild, a build after a resume, with or without the skin's
//! extra entries, which the users drop): a run's results do not depend on its search history,
//! so a checkpoint taken at any step resumes bit for bit, and they do not depend on the thread
//! count. Ghosts are numbered plane by plane in the order of their sources (see `boundary`),
//! so two ghost sets of different reach order their common ghosts alike.
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
//!
//! **Partial rebuilds.** In an impact the skin is used up at every step (a projectile at
//! 7 km/s crosses a tenth of h per step), yet most lists are still good: a pair can only enter
//! the support if its two particles moved *relative to each other* by more than the skin, and
//! the far part of a target does not move, nor does a projectile's rear relative to itself.
//! So the full build also sorts the particles into blocks of BLOCK_CELLS³ cells (width B).
//! While 2 h_max + 2 d_max ≤ B (d_max the largest displacement since the full build), a
//! particle that enters i's support was, at the build, in i's block or one of its 3^D − 1
//! neighbours; if every displacement in that neighbourhood is within s − δ_b − δ_N of every
//! displacement in i's block (boxes of displacements per block; δ_b and δ_N the largest growth
//! of a smoothing length in the block and in its neighbourhood), i's list is still complete.
//! Only the particles of the other blocks ("dirty" until the next full build) get new lists,
//! from the current positions, and only the particles of the dirty blocks and their
//! neighbours are binned to find them. Since 2026-12-02 those lists are built with a skin s'
//! of their own (the full build's, where 2 h_max + 2 d_max + s' fits in B) and kept, by the
//! same test against the positions of their rebuild, until a pair around them may have
//! crossed s' or another list turns dirty (before, they were rebuilt with no skin at every
//! step: a Taylor bar's 300 steps made 83 partial rebuilds, now 37; the ogive through its
//! plate 257 and 15 full builds, now 104 and 9; the same results to the bit). Where s' does
//! not last a step (debris), the next few rebuilds take no skin, whose entries would only
//! lengthen the passes.

use crate::particles::Vector;
use crate::ranks::Ranks;
use rayon::prelude::*;

/// Cells reach this many cells either side (cell size h_max, support ≤ 2 h_max).
const REACH: i64 = 2;
/// Cells per block edge for partial rebuilds.
const BLOCK_CELLS: i64 = 6;
/// Partial rebuilds made without a skin after one whose skin did not last a step.
const PLAIN_REBUILDS: usize = 4;
/// A dense grid is used while it has at most this many cells per particle.
const DENSE_CELLS_PER_PARTICLE: usize = 8;
/// Bits per axis of a sparse cell key.
const KEY_BITS: u32 = 21;
const KEY_MAX: i64 = (1 << KEY_BITS) - 1;

/// Neighbour lists of the real particles, with the buffers of the search kept between steps so
/// that rebuilding allocates little once the run has settled (a chunk's array grows only past
/// its largest size so far; each parallel job of a build has its own scratch arrays).
#[derive(Debug, Default, Clone)]
pub struct NeighborList {
    /// The lists of the real particles, CHUNK particles to a chunk (see [`ListChunk`]).
    chunks: Vec<ListChunk>,
    /// Number of real particles (lists).
    n_lists: usize,
    /// Particles in cell order.
    sorted: Vec<u32>,
    /// Dense: start of each cell in `sorted` (len cells + 1). Sparse: start of each occupied
    /// cell, with its key in `cell_key`.
    cell_start: Vec<u32>,
    cell_key: Vec<u64>,
    /// Next free slot of each cell during the counting sort.
    fill: Vec<u32>,
    /// Cell coordinates of the binned particles, in the order binned (i32 is plenty: a grid
    /// has at most 2^KEY_BITS cells an axis), and (sparse) key-index pairs for sorting.
    coords: Vec<[i32; 3]>,
    keyed: Vec<(u64, u32)>,
    /// Positions (from the grid's corner, single precision: see [`rounding`]) and support
    /// radii (h + skin/2) in cell order, so that scanning a run of candidates reads memory in
    /// sequence.
    xs: Vec<[f32; 3]>,
    hs: Vec<f64>,
    /// Skin of the last build, and the positions and smoothing lengths it was built for, in
    /// single precision (positions from `origin`): 12 + 4 bytes a particle in 3D instead of
    /// 24 + 8. `slack` bounds what their rounding can hide (see [`NeighborList::refresh`]).
    skin: f64,
    origin: [f64; 3],
    x_built: Vec<f32>,
    h_built: Vec<f32>,
    slack: f64,
    /// Blocks of BLOCK_CELLS³ cells of the last full build (dense grids only): their width,
    /// counts per axis, members (all particles, by block) and start of each in `members`.
    block_width: f64,
    block_dims: [usize; 3],
    block_start: Vec<u32>,
    block_members: Vec<u32>,
    /// Displacement box (lo, hi) of each block's members since the last full build, and the
    /// largest growth of their smoothing lengths (≥ 0).
    block_box: Vec<[[f64; 3]; 2]>,
    block_grow: Vec<f64>,
    /// Blocks, and real particles, whose lists are rebuilt at every step until the next full
    /// build (see [`NeighborList::refresh`]).
    dirty_block: Vec<bool>,
    dirty: Vec<bool>,
    /// Dirty particles now, lists rebuilt by partial rebuilds since the full build, and
    /// refreshes since it (steps that kept its lists, in whole or in part).
    dirty_count: usize,
    rebuilt: usize,
    refreshes: usize,
    /// The particles a partial rebuild bins (see [`NeighborList::rebuild_dirty`]).
    candidates: Vec<u32>,
    /// The last partial rebuild: the skin its lists were built with (0: none, they must be
    /// rebuilt at the next refresh), the dirty count it rebuilt, the positions and smoothing
    /// lengths of its candidates (in their order, block by block) and where each block's
    /// members start among them (u32::MAX: not a candidate's block), partial rebuilds since
    /// the full build and the refresh of the first. While no list turns dirty and no pair
    /// around the rebuilt ones can have crossed that skin since, the rebuilt lists are kept
    /// (`keep_dirty`).
    rescan_skin: f64,
    rescanned: usize,
    rescan_x: Vec<[f64; 3]>,
    rescan_h: Vec<f64>,
    rescan_at: Vec<u32>,
    /// The dirty blocks whose lists the last partial rebuild built here.
    rescanned_blocks: Vec<u32>,
    rescans: usize,
    first_rescan: usize,
    keep_dirty: bool,
    /// Refreshes that kept the last partial rebuild's lists, and partial rebuilds still to
    /// come without a skin (see [`NeighborList::rebuild_dirty`]).
    kept: usize,
    plain: usize,
    /// The largest displacement since the full build at the last refresh, over every rank.
    d_max: f64,
    /// Per real particle: whether its list holds a particle of another class (body), as of the
    /// last [`NeighborList::classify`].
    pub mixed: Vec<bool>,
    /// The real particles whose lists are built (an MPI rank's share, see `ranks`; None: all),
    /// widened to whole chunks. The others' lists are empty.
    owned: Option<std::ops::Range<usize>>,
    /// Under MPI, where other ranks' particles are not all up to date (see
    /// [`NeighborList::refresh`]): the ghosts that mirror this rank's own particles
    /// ([`NeighborList::own_ghosts`]), and per block of the last full build whether it holds
    /// one of this rank's particles (`home`) or lies within one block of such a block (`near`).
    /// Empty on one process: every block is both.
    owned_ghosts: Vec<u32>,
    home: Vec<bool>,
    near: Vec<bool>,
    /// Dirty particles among those whose lists are built here (all of them on one process);
    /// `dirty_count` is their sum over the ranks.
    dirty_here: usize,
    /// The largest search radius at the last refresh, over every particle of every rank.
    h_max: f64,
}

/// Particles per chunk of lists (a power of two).
const CHUNK_SHIFT: usize = 8;
const CHUNK: usize = 1 << CHUNK_SHIFT;
/// Particles per page: particle k lies on page k / PAGE, and the lists of the particles of page
/// c are chunk c's (see [`NeighborList::named`]).
pub const PAGE: usize = CHUNK;

/// The neighbour lists of CHUNK consecutive real particles, one after another in one array of
/// exactly their size. A vector per particle would cost its 24-byte header and, filled by
/// pushes, up to twice its length in spare capacity (in 3D about 200 bytes per particle, a
/// sixth of the whole state); a single array for all particles could not take the partial
/// rebuilds' new lengths without moving everything. A chunk is rewritten whole when any of its
/// particles is dirty.
///
/// Each list is packed ([`pack`]): an entry is its 16-bit offset from the first of its
/// segment, so a list takes about half the bytes of plain indices: in 3D about 160 bytes a
/// particle instead of 310, the largest single share of a run's memory after the state (issue
/// 14 asks for 800 bytes a particle in all).
#[derive(Debug, Default, Clone)]
struct ListChunk {
    /// End of each particle's packed list in `words` (its start is the previous end, or 0).
    ends: Vec<u32>,
    words: Vec<u16>,
    /// The real particles that the lists name lie in this range (see [`NeighborList::named`]).
    named: std::ops::Range<usize>,
}

impl ListChunk {
    fn list(&self, k: usize) -> Listed<'_> {
        Listed::new(self.packed(k))
    }

    /// Particle k's list as packed.
    fn packed(&self, k: usize) -> &[u16] {
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.words[start..self.ends[k] as usize]
    }
}

/// The first and the last entry below `n` of a packed list ([`pack`]), if any: a list is
/// increasing, so they are the first entry and the last of the segments' entries below n.
fn real_span(packed: &[u16], n: usize) -> Option<(u32, u32)> {
    let below = |j: u32| (j as usize) < n;
    let mut span = None;
    for (base, offsets) in Listed::new(packed).segments() {
        let inside = offsets.partition_point(|&o| below(base + u32::from(o)));
        if inside == 0 {
            break;
        }
        let first = span.map_or(base + u32::from(offsets[0]), |(a, _)| a);
        span = Some((first, base + u32::from(offsets[inside - 1])));
        if inside < offsets.len() {
            break;
        }
    }
    span
}

/// Append `list` (increasing indices) packed: in segments of entries within 2^16 of the
/// segment's first, each segment a 16-bit count, its first index in two 16-bit halves (high
/// first), and each entry's 16-bit offset from that index. In cell order a list spans a few
/// slabs of cells, so it is one segment up to about a million particles in a cube and a few
/// beyond; unpacking a segment is an add per entry, which the compiler vectorises.
fn pack(list: &[u32], words: &mut Vec<u16>) {
    let mut rest = list;
    while let Some(&base) = rest.first() {
        let len = rest
            .iter()
            .take(usize::from(u16::MAX))
            .position(|&j| j - base > u32::from(u16::MAX))
            .unwrap_or(rest.len().min(usize::from(u16::MAX)));
        words.extend([len as u16, (base >> 16) as u16, base as u16]);
        words.extend(rest[..len].iter().map(|&j| (j - base) as u16));
        rest = &rest[len..];
    }
}

/// A packed neighbour list ([`pack`]), read in order: the neighbours' indices.
#[derive(Debug, Clone)]
pub struct Listed<'a> {
    words: &'a [u16],
    /// The current segment's first index, and its entries not yet read.
    base: u32,
    left: &'a [u16],
}

impl<'a> Listed<'a> {
    fn new(words: &'a [u16]) -> Self {
        Listed {
            words,
            base: 0,
            left: &[],
        }
    }

    /// The next segment: its first index and its offsets.
    #[inline]
    fn segment(words: &mut &'a [u16]) -> Option<(u32, &'a [u16])> {
        let (&[len, hi, lo], rest) = words.split_first_chunk::<3>()?;
        let (offsets, rest) = rest.split_at(usize::from(len));
        *words = rest;
        Some(((u32::from(hi) << 16) | u32::from(lo), offsets))
    }

    /// The list's segments, each its first index and the offsets of its entries from it:
    /// for the scans that test every entry against an array indexed by particle, which can
    /// then skip a segment whose index range holds nothing to find.
    #[inline]
    pub fn segments(mut self) -> impl Iterator<Item = (u32, &'a [u16])> {
        let first = (!self.left.is_empty()).then_some((self.base, self.left));
        first
            .into_iter()
            .chain(std::iter::from_fn(move || Self::segment(&mut self.words)))
    }

    /// The whole list appended to `out` (cleared first) as plain indices.
    #[inline]
    pub fn unpack_into(mut self, out: &mut Vec<u32>) {
        out.clear();
        out.extend(self.left.iter().map(|&o| self.base + u32::from(o)));
        while let Some((base, offsets)) = Self::segment(&mut self.words) {
            out.extend(offsets.iter().map(|&o| base + u32::from(o)));
        }
    }
}

impl Iterator for Listed<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        loop {
            if let Some((&o, rest)) = self.left.split_first() {
                self.left = rest;
                return Some(self.base + u32::from(o));
            }
            (self.base, self.left) = Self::segment(&mut self.words)?;
        }
    }
}

/// What the lists need before they can be used at the current positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refresh {
    /// Nothing: every pair within the support is in the lists.
    Valid,
    /// Particles have moved beyond the skin, but only relative to far particles: the lists of
    /// the particles marked dirty (if any) must be rebuilt ([`NeighborList::rebuild_dirty`],
    /// which keeps those of the last partial rebuild while they hold). Whatever else depends
    /// on the skin (ghost layers) must be checked by the caller.
    Partial,
    /// A full build.
    Full,
}

/// The cell geometry of one build.
#[derive(Debug, Clone, Copy)]
struct Grid<const D: usize> {
    /// The particles' box: its lowest corner and its largest side.
    lo: Vector<D>,
    extent: f64,
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
    /// Number of lists (the real particles of the last build).
    pub fn len(&self) -> usize {
        self.n_lists
    }

    /// Whether there are no lists.
    pub fn is_empty(&self) -> bool {
        self.n_lists == 0
    }

    /// The neighbours of real particle `i`, in increasing index (the canonical order); none
    /// outside the particles [`NeighborList::own`]s.
    #[inline]
    pub fn list(&self, i: usize) -> Listed<'_> {
        self.chunks[i >> CHUNK_SHIFT].list(i & (CHUNK - 1))
    }

    /// Runs `f` on the neighbours of real particle `i` as a slice of indices (unpacked into a
    /// buffer of the calling thread's: the passes that read a list more than once, or by
    /// index).
    #[inline]
    pub fn with_list<R>(&self, i: usize, f: impl FnOnce(&[u32]) -> R) -> R {
        thread_local! {
            /// Buffers for nested calls (a pass that reads a second list while holding one).
            static POOL: std::cell::RefCell<Vec<Vec<u32>>> = const { std::cell::RefCell::new(Vec::new()) };
        }
        let mut buf = POOL.with(|p| p.borrow_mut().pop()).unwrap_or_default();
        self.list(i).unpack_into(&mut buf);
        let r = f(&buf);
        POOL.with(|p| p.borrow_mut().push(buf));
        r
    }

    /// The range of indices within which lie the real particles that the lists of the
    /// particles of page `c` ([`PAGE`] particles) name (empty where none, or where those lists
    /// are not built here): what a pass over part of the particles needs of the rest
    /// (`physics`, whose neighbour records are made a window of pages at a time).
    pub fn named(&self, c: usize) -> std::ops::Range<usize> {
        self.chunks.get(c).map_or(0..0, |chunk| chunk.named.clone())
    }

    /// Build the lists of only these real particles from the next full build on (an MPI
    /// rank's share; they must cover the particles the passes ask for until then).
    pub fn own(&mut self, owned: std::ops::Range<usize>) {
        self.owned = Some(owned);
    }

    /// The ghosts that mirror this rank's own particles (ascending), after a full build under
    /// MPI: with the rank's own real particles, they are the particles whose displacements it
    /// measures in [`NeighborList::refresh`].
    pub fn own_ghosts(&mut self, ghosts: Vec<u32>) {
        self.owned_ghosts = ghosts;
    }

    /// Under MPI, the particles (real and ghost, by block) whose current positions and
    /// smoothing lengths [`NeighborList::refresh`] and [`NeighborList::rebuild_dirty`] read:
    /// the members of the blocks within one block of a block holding one of this rank's own
    /// particles. Empty where the last full build made no blocks (a sparse grid: then the
    /// refresh reads only this rank's own particles and their ghosts), or on one process.
    pub fn near_members(&self) -> impl Iterator<Item = u32> + '_ {
        let (starts, members) = (&self.block_start, &self.block_members);
        self.near
            .iter()
            .enumerate()
            .filter(|(_, &n)| n)
            .flat_map(move |(b, _)| &members[starts[b] as usize..starts[b + 1] as usize])
            .copied()
    }

    /// The largest search radius at the last [`NeighborList::refresh`] that measured one,
    /// over every rank's particles.
    pub fn h_max(&self) -> f64 {
        self.h_max
    }

    /// Whether real particle `i`'s list was rebuilt since the last full build (a partial
    /// rebuild's "dirty" list: [`Refresh::Partial`]); the others are those of that build.
    pub fn rebuilt_since_build(&self, i: usize) -> bool {
        self.dirty.get(i).copied().unwrap_or(false)
    }

    /// Whether real particle `i` has its list here (an MPI rank builds only its share's).
    pub fn listed(&self, i: usize) -> bool {
        i < self.n_lists && self.chunk_owned(i >> CHUNK_SHIFT)
    }

    /// Whether the lists of chunk `ci` are built.
    fn chunk_owned(&self, ci: usize) -> bool {
        self.owned
            .as_ref()
            .is_none_or(|o| ci * CHUNK < o.end && o.start < (ci + 1) * CHUNK)
    }

    /// The particles at `x` (with smoothing lengths `h`) in cell order: a locality-friendly
    /// order for the particle store, and a function of `x` and `h` alone (so that reordering
    /// does not depend on when the lists were last built). Leaves the lists to be rebuilt.
    pub fn cell_order<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64]) -> &[u32] {
        self.h_built.clear();
        if x.is_empty() {
            self.sorted.clear();
        } else {
            self.bin(x, h, 0.0, None);
        }
        &self.sorted
    }

    /// What the lists need for these positions and smoothing lengths (the particles, real
    /// and ghost, must be those of the last full build, in the same order). Marks the dirty
    /// blocks and particles when the answer is `Partial`.
    ///
    /// **Under MPI** (`ranks`, after [`NeighborList::own`]) only some positions are current: a
    /// rank's own particles and the ghosts that mirror them, and the members of its `near`
    /// blocks, whose positions their owners send after each step. Each rank measures the
    /// displacements of its own particles and ghosts, and the ranks take the largest (exact in
    /// any order); each rank boxes the displacements of its near blocks and marks which of its
    /// home blocks are dirty, and the ranks add their counts of dirty particles. Every rank
    /// then gives the answer one process would, and reads no position it does not have.
    pub fn refresh<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64], ranks: Ranks) -> Refresh {
        if self.h_built.len() != h.len() || self.x_built.len() != D * x.len() {
            return Refresh::Full;
        }
        self.refreshes += 1;
        let (x_built, origin) = (&self.x_built, self.origin);
        let disp = |i: usize| -> [f64; 3] {
            let mut d = [0.0; 3];
            for k in 0..D {
                d[k] = x[i][k] - (origin[k] + f64::from(x_built[D * i + k]));
            }
            d
        };
        let measure = |i: usize| {
            let d = disp(i);
            [
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2],
                h[i] - f64::from(self.h_built[i]),
                h[i],
            ]
        };
        let most = |a: [f64; 3], b: [f64; 3]| [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])];
        let mut m = match &self.owned {
            None => (0..x.len())
                .into_par_iter()
                .map(measure)
                .reduce(|| [0.0; 3], most),
            Some(own) => (own.start.min(self.n_lists)..own.end.min(self.n_lists))
                .into_par_iter()
                .map(measure)
                .chain(self.owned_ghosts.par_iter().map(|&g| measure(g as usize)))
                .reduce(|| [0.0; 3], most),
        };
        ranks.max_each(&mut m);
        let [d2, dh, h_max] = m;
        self.h_max = h_max;
        // The stored positions and smoothing lengths are rounded: every displacement may be
        // longer than it reads by up to √D·e and every growth larger by e_h, so the tests below
        // take `slack` = 2 √D e + 2 e_h out of the skin (see [`rounding`]).
        let (d_max, grow, slack) = (d2.sqrt(), 2.0 * dh.max(0.0), self.slack);
        self.d_max = d_max;
        self.keep_dirty = false;
        if 2.0 * d_max + grow + slack < self.skin && self.dirty_count == 0 {
            return Refresh::Valid;
        }
        if self.block_start.is_empty() || 2.0 * h_max + 2.0 * d_max + slack > self.block_width {
            return Refresh::Full;
        }
        // Displacement box and smoothing-length growth of each block.
        let (starts, members) = (&self.block_start, &self.block_members);
        let (near, h_built) = (&self.near, &self.h_built);
        self.block_box
            .par_iter_mut()
            .zip(&mut self.block_grow)
            .enumerate()
            .filter(|(b, _)| near.get(*b).is_none_or(|&n| n))
            .for_each(|(b, (bx, gr))| {
                let list = &members[starts[b] as usize..starts[b + 1] as usize];
                (*bx, *gr) = displacement_box(list, |_, i| (disp(i), h[i] - f64::from(h_built[i])));
            });
        // A block stays clean while the farthest pair of displacements between it and its
        // neighbourhood is below s − δ_b − δ_N, δ_b the largest growth of a smoothing length
        // in the block and δ_N in its neighbourhood: a pair (i in the block, j around it) that
        // was at least h_i + h_j + s apart at the build is then still outside h_i + h_j. Until
        // 2026-12-01 both were the largest growth of any particle, so that one expanding
        // particle anywhere made every block dirty at once (the sphere–plate demo: every
        // list rebuilt every 5–9 steps, its debris growing its smoothing lengths).
        let (dims, boxes, skin) = (self.block_dims, &self.block_box, self.skin);
        let grows = &self.block_grow;
        let home = &self.home;
        self.dirty_block
            .par_iter_mut()
            .enumerate()
            .for_each(|(b, dirty)| {
                if *dirty || starts[b] == starts[b + 1] || home.get(b).is_some_and(|&h| !h) {
                    return;
                }
                *dirty = closing(dims, b, boxes, grows) + slack >= skin;
            });
        let n_real = self.n_lists;
        let (starts, members) = (&self.block_start, &self.block_members);
        for (b, _) in self.dirty_block.iter().enumerate().filter(|(_, &d)| d) {
            for &i in &members[starts[b] as usize..starts[b + 1] as usize] {
                let i = i as usize;
                if i < n_real && !self.dirty[i] && self.listed(i) {
                    self.dirty[i] = true;
                    self.dirty_here += 1;
                }
            }
        }
        self.dirty_count = ranks.sum(self.dirty_here as u64) as usize;
        // No list has turned dirty since the last partial rebuild, built with a skin: its lists
        // are kept while no pair around them can have crossed that skin since (the same test
        // as above, against the positions of that rebuild), on every rank.
        if self.dirty_count == self.rescanned && self.rescan_skin > 0.0 {
            let stale = self.rescanned_stale(x, h);
            if !ranks.any(stale) {
                self.keep_dirty = true;
                self.kept += 1;
                return Refresh::Partial;
            }
        }
        // A full build costs about as much as building every list (n lists), a partial
        // rebuild its dirty lists, and the dirty set only grows until the next full build. The
        // cheapest run of searches, if each full build's cycle is like the last, rebuilds in
        // full once this step's partial rebuild would cost more than the cycle's mean per step
        // so far, the full build included: dirty·k ≥ n + rebuilt after k steps (the renewal
        // argument for replacement: stop when the marginal cost passes the mean). A slow flow
        // keeps its lists for many steps; an impact whose dirty set stays a fifth of the
        // particles keeps them until a block's width forces a full build, where the old rule
        // (a full build once the partial rebuilds had cost one, rebuilt + dirty ≥ n) rebuilt
        // every five steps (the sphere–plate demo: 48 full searches in 200 steps).
        // Since partial rebuilds keep their lists while they hold, a partial rebuild's cost
        // per step is its dirty lists times the share of steps that rebuild, (r + 1) / m over
        // the m steps since the first of the r so far: full when dirty·(r + 1)·k ≥
        // (n + rebuilt)·m, which is the rule above when every step rebuilds.
        let k = self.refreshes;
        let span = if self.rescans == 0 {
            1
        } else {
            k + 1 - self.first_rescan
        };
        if self.dirty_count * (self.rescans + 1) * k >= (n_real + self.rebuilt) * span {
            return Refresh::Full;
        }
        Refresh::Partial
    }

    /// Whether a pair around the lists of the last partial rebuild (those of its blocks,
    /// `rescanned_blocks`) may have entered the support since: the farthest pair of
    /// displacements since that rebuild between such a block and its neighbourhood, with the
    /// largest growth of a smoothing length in each, at or past the rebuild's skin.
    fn rescanned_stale<const D: usize>(&self, x: &[Vector<D>], h: &[f64]) -> bool {
        let (starts, members, at) = (&self.block_start, &self.block_members, &self.rescan_at);
        let (rx, rh) = (&self.rescan_x, &self.rescan_h);
        // Displacement box and growth of each candidate block since the rebuild.
        let (boxes, grows): (Vec<_>, Vec<_>) = (0..at.len())
            .into_par_iter()
            .map(|b| {
                let list = match at[b] {
                    u32::MAX => &[][..],
                    _ => &members[starts[b] as usize..starts[b + 1] as usize],
                };
                let base = at[b] as usize;
                displacement_box(list, |k, i| {
                    let mut d = [0.0; 3];
                    for a in 0..D {
                        d[a] = x[i][a] - rx[base + k][a];
                    }
                    (d, h[i] - rh[base + k])
                })
            })
            .unzip();
        let (dims, slack, skin) = (self.block_dims, self.slack, self.rescan_skin);
        self.rescanned_blocks
            .par_iter()
            .any(|&b| closing(dims, b as usize, &boxes, &grows) + slack >= skin)
    }

    /// Whether block `b` is dirty and holds a dirty particle whose list is built here.
    fn rebuilt_block(&self, b: usize) -> bool {
        let (starts, members) = (&self.block_start, &self.block_members);
        self.dirty_block[b]
            && members[starts[b] as usize..starts[b + 1] as usize]
                .iter()
                .any(|&i| self.listed(i as usize) && self.dirty[i as usize])
    }

    /// Mark the lists that hold a particle of another class (`class[j]`: its body): all of them
    /// after a full build, the dirty ones after a partial rebuild. Most particles meet no other
    /// body; passes over contacts can skip them without reading their lists.
    pub fn classify(&mut self, class: &[u32], only_dirty: bool) {
        let n = self.n_lists;
        self.mixed.resize(n, false);
        let mut mixed = std::mem::take(&mut self.mixed);
        let (nl, dirty) = (&*self, &self.dirty);
        mixed
            .par_iter_mut()
            .enumerate()
            .filter(|(i, _)| (!only_dirty || dirty[*i]) && nl.chunk_owned(i >> CHUNK_SHIFT))
            .for_each(|(i, m)| *m = nl.list(i).any(|j| class[j as usize] != class[i]));
        self.mixed = mixed;
    }

    /// Rebuild the lists of the dirty particles from the current positions, with the skin
    /// that the blocks' width leaves (at most the full build's): `refresh` keeps them while no
    /// pair around them can have crossed it, and asks again when one may have, or when another
    /// list turns dirty. Nothing when `refresh` kept them; returns whether it rebuilt.
    ///
    /// Only the candidates are binned: the members of the dirty blocks whose lists are built
    /// here and of the blocks around them. That is all a dirty particle's neighbours can be,
    /// because `refresh` asks for a full build once 2 h_max + 2 d_max could pass a block's
    /// width (see the module doc); binning every particle, as a full build does, made most of
    /// a partial rebuild's cost where few blocks are dirty (a projectile's path through a
    /// large target). The lists are the same either way but for pairs within the rounding of
    /// the single-precision positions, which the lists' users drop.
    pub fn rebuild_dirty<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64]) -> bool {
        if self.dirty_count == 0 || self.keep_dirty {
            return false;
        }
        self.rebuilt += self.dirty_count;
        if self.rescans == 0 {
            self.first_rescan = self.refreshes;
        }
        self.rescans += 1;
        self.rescanned = self.dirty_count;
        // A dirty particle's neighbours within the support and this skin must lie in the
        // blocks around its own: 2 h_max + 2 d_max + skin within a block's width. Where the
        // last skin was spent before the next step (debris, whose lists go stale at every
        // step), the skin's extra entries only cost the passes: the next PLAIN_REBUILDS
        // rebuilds take none, as before 2026-12-02, and then the skin is tried again.
        if self.rescan_skin > 0.0 && self.kept == 0 {
            self.plain = PLAIN_REBUILDS;
        }
        let room = self.block_width - 2.0 * self.h_max - 2.0 * self.d_max - self.slack;
        let skin = if self.plain > 0 {
            self.plain -= 1;
            0.0
        } else {
            room.min(self.skin).max(0.0)
        };
        self.rescan_skin = skin;
        self.kept = 0;
        let mut candidates = std::mem::take(&mut self.candidates);
        self.near_dirty(&mut candidates);
        self.rescan_x.clear();
        self.rescan_h.clear();
        self.rescan_x.extend(candidates.iter().map(|&i| {
            let mut p = [0.0; 3];
            p[..D].copy_from_slice(x[i as usize].as_slice());
            p
        }));
        self.rescan_h
            .extend(candidates.iter().map(|&i| h[i as usize]));
        if !candidates.is_empty() {
            let grid = self.bin(x, h, skin, Some(&candidates));
            self.scan(x, h, skin, grid, true);
        }
        self.candidates = candidates;
        true
    }

    /// The members of the blocks within one block of a dirty block that holds a dirty
    /// particle whose list is built here, in block order (and where each block's start in
    /// them, `rescan_at`).
    fn near_dirty(&mut self, out: &mut Vec<u32>) {
        out.clear();
        let (dims, starts, members) = (self.block_dims, &self.block_start, &self.block_members);
        let mut near = vec![false; self.dirty_block.len()];
        self.rescanned_blocks.clear();
        for b in 0..self.dirty_block.len() {
            if self.rebuilt_block(b) {
                around(dims, b, |o| near[o] = true);
                self.rescanned_blocks.push(b as u32);
            }
        }
        self.rescan_at.clear();
        self.rescan_at.resize(near.len(), u32::MAX);
        for (b, _) in near.iter().enumerate().filter(|(_, &n)| n) {
            self.rescan_at[b] = out.len() as u32;
            out.extend_from_slice(&members[starts[b] as usize..starts[b + 1] as usize]);
        }
    }

    /// Rebuild for positions `x` (real then ghosts) and smoothing lengths `h`, with the support
    /// widened by `skin`; lists for the first `n_real` particles.
    pub fn build<const D: usize>(&mut self, x: &[Vector<D>], h: &[f64], n_real: usize, skin: f64) {
        let n = x.len();
        self.skin = skin;
        self.x_built.clear();
        self.h_built.clear();
        self.n_lists = n_real;
        self.chunks
            .resize_with(n_real.div_ceil(CHUNK), ListChunk::default);
        self.dirty.clear();
        self.dirty.resize(n_real, false);
        self.dirty_count = 0;
        self.dirty_here = 0;
        self.rebuilt = 0;
        self.refreshes = 0;
        self.rescan_skin = 0.0;
        self.rescanned = 0;
        self.rescans = 0;
        self.first_rescan = 0;
        self.keep_dirty = false;
        self.kept = 0;
        self.plain = 0;
        self.block_start.clear();
        self.home.clear();
        self.near.clear();
        if n == 0 {
            self.sorted.clear();
            return;
        }
        let grid = self.bin(x, h, skin, None);
        // The positions and smoothing lengths of this build, from the grid's corner, in single
        // precision, and the slack their rounding asks of the skin (see `refresh`).
        let lo = grid.lo;
        self.origin = [0.0; 3];
        self.origin[..D].copy_from_slice(lo.as_slice());
        self.x_built.par_extend(
            x.par_iter()
                .flat_map_iter(|p| (0..D).map(move |k| (p[k] - lo[k]) as f32)),
        );
        self.h_built.extend(h.iter().map(|&v| v as f32));
        let h_max = h.iter().copied().fold(0.0_f64, f64::max);
        self.slack = 2.0 * (D as f64).sqrt() * rounding(grid.extent) + 2.0 * rounding(h_max);
        if grid.dense {
            self.make_blocks(&grid);
        }
        self.scan(x, h, skin, grid, false);
    }

    /// Sort all particles into blocks of BLOCK_CELLS³ cells (counting sort by block).
    fn make_blocks<const D: usize>(&mut self, grid: &Grid<D>) {
        // Unused axes (z in 2D) have one cell, hence one block; the last axis varies fastest.
        let dims = grid
            .dims
            .map(|d| (d as usize).div_ceil(BLOCK_CELLS as usize));
        let count = dims[0] * dims[1] * dims[2];
        let block = |c: &[i32; 3]| {
            let b = |k: usize| (c[k] as i64 / BLOCK_CELLS) as usize;
            (b(0) * dims[1] + b(1)) * dims[2] + b(2)
        };
        self.block_dims = dims;
        self.block_width = BLOCK_CELLS as f64 * grid.cell;
        counting_sort(
            &self.coords,
            block,
            count,
            &mut self.block_start,
            &mut self.block_members,
            &mut self.fill,
        );
        self.block_box.resize(count, [[0.0; 3]; 2]);
        self.block_grow.resize(count, 0.0);
        self.dirty_block.clear();
        self.dirty_block.resize(count, false);
        if self.owned.is_some() {
            self.mark_home();
        }
    }

    /// Under MPI: the blocks that hold a particle whose list is built here (`home`), and
    /// those within one block of one (`near`).
    fn mark_home(&mut self) {
        let (dims, starts, members) = (self.block_dims, &self.block_start, &self.block_members);
        let count = starts.len() - 1;
        let home: Vec<bool> = (0..count)
            .map(|b| {
                members[starts[b] as usize..starts[b + 1] as usize]
                    .iter()
                    .any(|&i| self.listed(i as usize))
            })
            .collect();
        self.home = home;
        self.near.clear();
        self.near.resize(count, false);
        for (b, _) in self.home.iter().enumerate().filter(|(_, &h)| h) {
            around(dims, b, |o| self.near[o] = true);
        }
    }

    /// Fill the lists (of the dirty real particles only, if `dirty_only`) from the binned
    /// particles, with the support widened by `skin`.
    fn scan<const D: usize>(
        &mut self,
        x: &[Vector<D>],
        h: &[f64],
        skin: f64,
        grid: Grid<D>,
        dirty_only: bool,
    ) {
        let lo = grid.lo;
        self.xs.clear();
        self.xs.par_extend(self.sorted.par_iter().map(|&j| {
            let mut p = [0.0_f32; 3];
            for k in 0..D {
                p[k] = (x[j as usize][k] - lo[k]) as f32;
            }
            p
        }));
        // A candidate's rounded position reads its distance wrong by up to √D e: the test is
        // widened by that much, so that no pair within the support (plus skin) is missed; the
        // few extra entries are dropped by the lists' users, as the skin's are.
        let widen = (D as f64).sqrt() * rounding(grid.extent);
        self.hs.clear();
        self.hs
            .par_extend(self.sorted.par_iter().map(|&j| h[j as usize] + 0.5 * skin));
        let (xs, hs) = (&self.xs, &self.hs);
        let sorted = &self.sorted;
        let cell_start = &self.cell_start;
        let cell_key = &self.cell_key;
        let last = D - 1;
        let dirty = &self.dirty;
        let n_lists = self.n_lists;
        let owned = self.owned.clone();
        // The neighbours of real particle i, appended to `list`.
        let search = |i: usize, list: &mut Vec<u32>| {
            let xi = x[i];
            let hi = h[i] + 0.5 * skin;
            let c = grid.coords(&xi);
            // Runs along the last axis for every offset of the other axes.
            let lo_last = (c[last] - REACH).max(0);
            let hi_last = (c[last] + REACH).min(grid.dims[last] - 1);
            let mut xi3 = [0.0_f64; 3];
            for k in 0..D {
                xi3[k] = xi[k] - lo[k];
            }
            let mut visit = |a: usize, b: usize| {
                for k in a..b {
                    let support = hi + hs[k] + widen;
                    let r2: f64 = (0..3)
                        .map(|a| {
                            let d = xi3[a] - f64::from(xs[k][a]);
                            d * d
                        })
                        .sum();
                    if r2 < support * support && sorted[k] as usize != i {
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
        };
        self.chunks.par_iter_mut().enumerate().for_each_init(
            || (Vec::new(), Vec::new(), Vec::new()),
            |(list, words, ends), (ci, chunk)| {
                let range = ci * CHUNK..((ci + 1) * CHUNK).min(n_lists);
                if owned
                    .as_ref()
                    .is_some_and(|o| range.end <= o.start || o.end <= range.start)
                {
                    // Another rank's: no lists.
                    chunk.ends.clear();
                    chunk.ends.resize(range.len(), 0);
                    chunk.words = Vec::new();
                    chunk.named = 0..0;
                    return;
                }
                if dirty_only && !dirty[range.clone()].contains(&true) {
                    return;
                }
                words.clear();
                ends.clear();
                let mut named = 0..0;
                for (k, i) in range.enumerate() {
                    let span = if dirty_only && !dirty[i] {
                        // A clean list is copied as it is packed (packing is canonical, so
                        // unpacking and packing it again gave the same words): in the
                        // sphere–plate demo two clean lists share the chunks of each dirty
                        // one, and copying them took the partial rebuilds' scans from 0.196 /
                        // 0.211 s to 0.183 / 0.200 s over 30 steps (2026-12-02).
                        let packed = chunk.packed(k);
                        words.extend_from_slice(packed);
                        real_span(packed, n_lists)
                    } else {
                        list.clear();
                        search(i, list);
                        // Canonical order (see the module doc); cell runs are nearly sorted
                        // already.
                        list.sort_unstable();
                        pack(list, words);
                        let real = &list[..list.partition_point(|&j| (j as usize) < n_lists)];
                        real.first().zip(real.last()).map(|(&a, &b)| (a, b))
                    };
                    ends.push(words.len() as u32);
                    if let Some((a, b)) = span {
                        let (a, b) = (a as usize, b as usize + 1);
                        named = if named.is_empty() {
                            a..b
                        } else {
                            named.start.min(a)..named.end.max(b)
                        };
                    }
                }
                chunk.ends.clear();
                chunk.ends.extend_from_slice(ends);
                chunk.words.clear();
                chunk.words.reserve_exact(words.len());
                chunk.words.extend_from_slice(words);
                chunk.named = named;
            },
        );
    }

    /// Sort the particles (or `only` these) into cells; fills `sorted`, `cell_start` (and
    /// `cell_key` when sparse) and `coords` (the binned particles', in the order binned).
    fn bin<const D: usize>(
        &mut self,
        x: &[Vector<D>],
        h: &[f64],
        skin: f64,
        only: Option<&[u32]>,
    ) -> Grid<D> {
        let n = only.map_or(x.len(), <[u32]>::len);
        let id = |k: usize| only.map_or(k, |s| s[k] as usize);
        let h_max = (0..n).map(|k| h[id(k)]).fold(0.0_f64, f64::max) + 0.5 * skin;
        let mut lo = Vector::<D>::repeat(f64::INFINITY);
        let mut hi = Vector::<D>::repeat(f64::NEG_INFINITY);
        for k in 0..n {
            let p = &x[id(k)];
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
            extent: (hi - lo).max(),
            cell,
            dims,
            dense,
        };
        self.coords.clear();
        self.coords.par_extend(
            (0..n)
                .into_par_iter()
                .map(|k| grid.coords(&x[id(k)]).map(|c| c as i32)),
        );
        self.sorted.clear();
        self.cell_start.clear();
        self.cell_key.clear();
        if dense {
            counting_sort(
                &self.coords,
                |c| grid.index(c.map(i64::from)),
                total as usize,
                &mut self.cell_start,
                &mut self.sorted,
                &mut self.fill,
            );
            if let Some(only) = only {
                for k in self.sorted.iter_mut() {
                    *k = only[*k as usize];
                }
            }
        } else {
            self.keyed.clear();
            let coords = &self.coords;
            self.keyed.par_extend(
                (0..n)
                    .into_par_iter()
                    .map(|k| (grid.key(coords[k].map(i64::from)), id(k) as u32)),
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

/// Calls `f` with block `b` and each of its 3^D − 1 neighbours within the blocks' `dims`
/// (the last axis fastest).
fn around(dims: [usize; 3], b: usize, mut f: impl FnMut(usize)) {
    let c = [
        b / (dims[1] * dims[2]),
        (b / dims[2]) % dims[1],
        b % dims[2],
    ];
    for n0 in c[0].saturating_sub(1)..(c[0] + 2).min(dims[0]) {
        for n1 in c[1].saturating_sub(1)..(c[1] + 2).min(dims[1]) {
            for n2 in c[2].saturating_sub(1)..(c[2] + 2).min(dims[2]) {
                f((n0 * dims[1] + n1) * dims[2] + n2);
            }
        }
    }
}

/// The box (lowest and highest, per axis) of the displacements of `members` and the largest
/// growth of their smoothing lengths (at least 0), `moved(k, i)` giving both for the k-th
/// member, particle i (unused axes: 0).
fn displacement_box(
    members: &[u32],
    moved: impl Fn(usize, usize) -> ([f64; 3], f64),
) -> ([[f64; 3]; 2], f64) {
    let mut bx = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    let mut grow = 0.0_f64;
    for (k, &i) in members.iter().enumerate() {
        let (d, g) = moved(k, i as usize);
        for a in 0..3 {
            bx[0][a] = bx[0][a].min(d[a]);
            bx[1][a] = bx[1][a].max(d[a]);
        }
        grow = grow.max(g);
    }
    (bx, grow)
}

/// How far a pair between block `b` and its neighbourhood may have closed since the positions
/// its boxes are measured from: the farthest pair of displacements between the block's box
/// and the union of its 3^D neighbourhood's, plus the largest growth of a smoothing length in
/// the block and in the neighbourhood (see `NeighborList::refresh`).
fn closing(dims: [usize; 3], b: usize, boxes: &[[[f64; 3]; 2]], grows: &[f64]) -> f64 {
    let (mut union, mut grow_near) = (boxes[b], grows[b]);
    around(dims, b, |o| {
        grow_near = grow_near.max(grows[o]);
        let o = &boxes[o];
        for k in 0..3 {
            union[0][k] = union[0][k].min(o[0][k]);
            union[1][k] = union[1][k].max(o[1][k]);
        }
    });
    let own = &boxes[b];
    let mut far2 = 0.0;
    for k in 0..3 {
        let e = (own[1][k] - union[0][k]).max(union[1][k] - own[0][k]);
        far2 += e * e;
    }
    far2.sqrt() + grows[b] + grow_near
}

/// A bound on the error of a length of at most `magnitude` kept in single precision (round to
/// nearest: half an ulp, 2⁻²⁴ of it), doubled for the double-precision arithmetic around it.
/// Positions are kept from a corner of their box, so the bound follows the box's size, not
/// where the box lies: a 0.1 m domain is read to 1.2e-8 m, a thousandth of the skin of a 0.1 mm
/// lattice.
fn rounding(magnitude: f64) -> f64 {
    magnitude * f64::from(f32::EPSILON)
}

/// Counting sort of the items by `key` (< `count`): O(N), stable (index order within a key).
/// `start[k]..start[k + 1]` are the positions in `sorted` of the items with key k; `fill` is
/// a work buffer.
fn counting_sort<T>(
    items: &[T],
    key: impl Fn(&T) -> usize,
    count: usize,
    start: &mut Vec<u32>,
    sorted: &mut Vec<u32>,
    fill: &mut Vec<u32>,
) {
    start.clear();
    start.resize(count + 1, 0);
    for item in items {
        start[key(item) + 1] += 1;
    }
    for k in 0..count {
        start[k + 1] += start[k];
    }
    sorted.resize(items.len(), 0);
    fill.clear();
    fill.extend_from_slice(&start[..count]);
    for (i, item) in items.iter().enumerate() {
        let slot = &mut fill[key(item)];
        sorted[*slot as usize] = i as u32;
        *slot += 1;
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

    /// The lists hold every pair within the support, in index order, and nothing beyond it but
    /// pairs within the rounding of the single-precision positions (see [`rounding`]).
    fn compare<const D: usize>(x: &[Vector<D>], h: &[f64], n_real: usize) {
        let mut nl = NeighborList::default();
        nl.build(x, h, n_real, 0.0);
        let expect = brute(x, h, n_real);
        assert_eq!(nl.len(), n_real);
        let (lo, hi) = x
            .iter()
            .fold((x[0], x[0]), |(l, u), p| (l.inf(p), u.sup(p)));
        let widen = 2.0 * (D as f64).sqrt() * rounding((hi - lo).max());
        for (i, expect) in expect.iter().enumerate() {
            let list: Vec<u32> = nl.list(i).collect();
            assert!(
                list.windows(2).all(|w| w[0] < w[1]),
                "particle {i}: {list:?}"
            );
            for j in expect {
                assert!(list.contains(j), "particle {i} misses {j}");
            }
            for &j in &list {
                let j = j as usize;
                assert!(
                    (x[i] - x[j]).norm() < h[i] + h[j] + widen,
                    "particle {i} lists {j}, beyond its support"
                );
            }
        }
    }

    proptest::proptest! {
        /// A packed list reads back as the list, whether read entry by entry or unpacked
        /// whole: steps from 1 to past 2^16 (a new segment), and lists longer than a segment
        /// holds.
        #[test]
        fn packed_lists_read_back(
            steps in proptest::collection::vec((1u32..70_000, 0u32..4), 0..300),
            first in 0u32..3_000_000,
            long in proptest::bool::ANY,
            cut in 0u32..6_000_000,
        ) {
            let mut list = Vec::new();
            let mut j = first;
            for (step, kind) in steps {
                // Mostly short steps, as in cell order.
                j += if kind == 0 { step } else { step % 40 + 1 };
                list.push(j);
            }
            if long {
                list.extend((1..=70_000).map(|k| j + k));
            }
            let mut words = Vec::new();
            pack(&list, &mut words);
            proptest::prop_assert!(words.len() < 2 * list.len() + 3 * (list.len() / 65_535 + 1) + 3 * 300);
            let read: Vec<u32> = Listed::new(&words).collect();
            proptest::prop_assert_eq!(&read, &list);
            let mut out = vec![7];
            Listed::new(&words).unpack_into(&mut out);
            proptest::prop_assert_eq!(&out, &list);
            let by_segment: Vec<u32> = Listed::new(&words)
                .segments()
                .flat_map(|(base, offsets)| offsets.iter().map(move |&o| base + u32::from(o)))
                .collect();
            proptest::prop_assert_eq!(&by_segment, &list);
            // The first and last entries below a cut (the real particles of a list that also
            // names ghosts), read off the packed words.
            let below: Vec<u32> = list.iter().copied().filter(|&j| j < cut).collect();
            let span = below.first().zip(below.last()).map(|(&a, &b)| (a, b));
            proptest::prop_assert_eq!(real_span(&words, cut as usize), span);
        }
    }

    /// With a skin the lists hold every pair within the support while `refresh` says they are valid.
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
        while nl.refresh(&x, &h, Ranks::SERIAL) == Refresh::Valid {
            let exact = brute(&x, &h, 400);
            for (i, e) in exact.iter().enumerate() {
                assert!(
                    e.iter().all(|&j| nl.list(i).any(|k| k == j)),
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

    /// An impact in miniature: a still cloud and a smaller one flying into it (plus a little
    /// jitter everywhere). After every move the lists, refreshed as `refresh` asks, hold every
    /// pair within the support; partial rebuilds happen, and cost fewer lists than full ones.
    #[test]
    fn partial_rebuilds_keep_lists_complete() {
        let mut seed = 3u64;
        let target = 1500;
        let mut x = clouds(target, [1.04, 0.35, 0.35], 0.3, &mut seed);
        let n = x.len();
        let h = vec![0.05; n];
        let skin = 0.01;
        let mut nl = NeighborList::default();
        nl.build(&x, &h, n, skin);
        let (mut full, mut partial, mut lists) = (0, 0, 0);
        for step in 0..60 {
            fly(&mut x, target, 0.004, 2e-4, &mut seed);
            match nl.refresh(&x, &h, Ranks::SERIAL) {
                Refresh::Full => {
                    nl.build(&x, &h, n, skin);
                    full += 1;
                    lists += n;
                }
                Refresh::Partial => {
                    if nl.rebuild_dirty(&x, &h) {
                        lists += nl.dirty_count;
                    }
                    partial += 1;
                }
                Refresh::Valid => {}
            }
            assert_complete(&nl, &x, &h, step);
        }
        println!("60 moves: {full} full builds, {partial} partial, {lists} lists rebuilt");
        assert!(partial >= 10 && full >= 1, "{full} full, {partial} partial");
        assert!(lists < 60 * n / 2, "{lists} lists rebuilt");
    }

    /// Every pair within the support (by brute force) is in the lists.
    fn assert_complete(nl: &NeighborList, x: &[Vector<3>], h: &[f64], step: usize) {
        for (i, e) in brute(x, h, x.len()).iter().enumerate() {
            assert!(
                e.iter().all(|&j| nl.list(i).any(|k| k == j)),
                "step {step}: pair of particle {i} lost"
            );
        }
    }

    /// `target` particles at random in the unit cube, then 300 in a cube of side `size` at
    /// `corner`.
    fn clouds(target: usize, corner: [f64; 3], size: f64, seed: &mut u64) -> Vec<Vector<3>> {
        let mut at = |c: [f64; 3], a: f64| {
            Vector::<3>::from(c) + Vector::<3>::new(rnd(seed), rnd(seed), rnd(seed)) * a
        };
        let mut x: Vec<Vector<3>> = (0..target).map(|_| at([0.0; 3], 1.0)).collect();
        x.extend((0..300).map(|_| at(corner, size)));
        x
    }

    /// Jitter every particle by up to `jitter` / 2 along each axis, and move those from
    /// `from` on by `speed` towards −x.
    fn fly(x: &mut [Vector<3>], from: usize, speed: f64, jitter: f64, seed: &mut u64) {
        for (i, p) in x.iter_mut().enumerate() {
            *p += Vector::<3>::new(rnd(seed) - 0.5, rnd(seed) - 0.5, rnd(seed) - 0.5) * jitter;
            if i >= from {
                p[0] -= speed;
            }
        }
    }

    /// A striker that stops: a small cloud flies into a larger one by more than the skin in a
    /// few steps, then creeps on at a tenth of the speed. The lists of its blocks and theirs,
    /// rebuilt with a skin once they turn dirty, are kept while the creep has not used that
    /// skin up, and every pair within the support is in the lists at every step (fails, tried,
    /// with the kept lists never judged stale).
    #[test]
    fn partial_rebuilds_keep_their_lists_while_they_hold() {
        let mut seed = 5u64;
        let target = 6000;
        let mut x = clouds(target, [1.01, 0.4, 0.4], 0.15, &mut seed);
        let n = x.len();
        let h = vec![0.03; n];
        let skin = 0.006;
        let mut nl = NeighborList::default();
        nl.build(&x, &h, n, skin);
        let (mut full, mut rebuilt, mut kept) = (0, 0, 0);
        for step in 0..40 {
            let speed = if step < 4 { 0.0024 } else { 0.00024 };
            fly(&mut x, target, speed, 2e-5, &mut seed);
            match nl.refresh(&x, &h, Ranks::SERIAL) {
                Refresh::Full => {
                    nl.build(&x, &h, n, skin);
                    full += 1;
                }
                Refresh::Partial if nl.rebuild_dirty(&x, &h) => rebuilt += 1,
                Refresh::Partial if nl.dirty_count > 0 => kept += 1,
                Refresh::Partial => {}
                Refresh::Valid => {}
            }
            assert_complete(&nl, &x, &h, step);
        }
        println!("40 moves: {full} full builds, {rebuilt} partial rebuilds, {kept} kept");
        assert!(rebuilt >= 2 && kept >= 10, "{rebuilt} rebuilt, {kept} kept");
    }

    /// Smoothing lengths growing in one corner (debris expanding) dirty only the blocks
    /// within reach of the growth: a pair (i, j) can enter the support through the growth of
    /// h_i and h_j alone, so a block stays clean while its own growth and its neighbourhood's
    /// leave the skin unspent. A cloud four blocks long, its first block's smoothing lengths
    /// growing by 0.4 skins a step: at the second step only that block is dirty (with one
    /// largest growth for every block, as until 2026-12-01, every block was), and at the
    /// third its neighbour must be too (fails, tried, with the neighbourhood's growth left
    /// out: pairs across the two blocks' boundary are lost). Half the lists dirty at the third
    /// step cost more than the cycle's mean: a full build there (at the fourth with the rule
    /// before 2026-12-01, a full build once the partial rebuilds had cost one: tried).
    #[test]
    fn growing_smoothing_lengths_dirty_only_their_neighbourhood() {
        let mut seed = 11u64;
        let n = 2000;
        let x: Vec<Vector<3>> = (0..n)
            .map(|_| {
                Vector::<3>::new(
                    1.32 * rnd(&mut seed),
                    0.33 * rnd(&mut seed),
                    0.33 * rnd(&mut seed),
                )
            })
            .collect();
        let (mut h, skin) = (vec![0.05; n], 0.01);
        let mut nl = NeighborList::default();
        nl.build(&x, &h, n, skin);
        let width = nl.block_width;
        assert!((width - 0.33).abs() < 1e-9 && nl.block_dims == [4, 1, 1]);
        let mut first_full = None;
        for step in 1..=6 {
            for (hi, p) in h.iter_mut().zip(&x) {
                if p[0] < 0.32 {
                    *hi += 0.4 * skin;
                }
            }
            match nl.refresh(&x, &h, Ranks::SERIAL) {
                Refresh::Full => {
                    nl.build(&x, &h, n, skin);
                    first_full.get_or_insert(step);
                }
                Refresh::Partial => {
                    nl.rebuild_dirty(&x, &h);
                }
                Refresh::Valid => {}
            }
            assert_complete(&nl, &x, &h, step);
            if step == 2 {
                let dirty: Vec<usize> = (0..n).filter(|&i| nl.rebuilt_since_build(i)).collect();
                assert!(!dirty.is_empty(), "the growing block is dirty");
                assert!(
                    dirty.iter().all(|&i| x[i][0] < width + 1e-3),
                    "only the growing block is dirty: {} of {n}",
                    dirty.len()
                );
            }
        }
        assert_eq!(first_full, Some(3));
    }

    /// An MPI rank's refresh and partial rebuilds read only its own particles and the members
    /// of its near blocks: here every other position is moved far away after each full build
    /// (as a rank's store holds them, stale), yet the share answers as a share given the true
    /// positions does, and its lists hold every pair. The moving particles are the share's own,
    /// so that its own largest displacement is every rank's (the reduction is MPI's).
    #[test]
    fn a_share_reads_only_its_near_blocks() {
        let mut seed = 11u64;
        let own = 0..768;
        // The share: a slab of the target (x < 0.3) and a projectile flying at it along x.
        let mut x: Vec<Vector<3>> = (0..468)
            .map(|_| Vector::<3>::new(0.3 * rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)))
            .collect();
        x.extend((0..300).map(|_| {
            Vector::<3>::new(-0.2, 0.35, 0.35)
                + Vector::<3>::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.25
        }));
        // The other ranks': the rest of the target.
        x.extend(
            (0..1800).map(|_| {
                Vector::<3>::new(0.3 + 0.7 * rnd(&mut seed), rnd(&mut seed), rnd(&mut seed))
            }),
        );
        let n = x.len();
        let h = vec![0.05; n];
        let skin = 0.01;
        let (mut share, mut truth) = (NeighborList::default(), NeighborList::default());
        share.own(own.clone());
        truth.own(own.clone());
        share.build(&x, &h, n, skin);
        truth.build(&x, &h, n, skin);
        let mut near = vec![false; n];
        let mark = |nl: &NeighborList, near: &mut Vec<bool>| {
            near.iter_mut()
                .enumerate()
                .for_each(|(i, m)| *m = own.contains(&i));
            nl.near_members().for_each(|j| near[j as usize] = true);
        };
        mark(&share, &mut near);
        let far = near.iter().filter(|&&m| !m).count();
        assert!(far > 500, "only {far} particles outside the near blocks");
        let (mut partial, mut rebuilt) = (0, 0);
        for step in 0..40 {
            for p in &mut x[468..768] {
                p[0] += 0.006;
            }
            let stale: Vec<Vector<3>> = x
                .iter()
                .zip(&near)
                .map(|(p, &m)| {
                    if m {
                        *p
                    } else {
                        p + Vector::<3>::repeat(100.0)
                    }
                })
                .collect();
            let need = share.refresh(&stale, &h, Ranks::SERIAL);
            assert_eq!(need, truth.refresh(&x, &h, Ranks::SERIAL), "step {step}");
            match need {
                Refresh::Full => {
                    share.build(&x, &h, n, skin);
                    truth.build(&x, &h, n, skin);
                    mark(&share, &mut near);
                }
                Refresh::Partial => {
                    rebuilt += share.dirty_count;
                    share.rebuild_dirty(&stale, &h);
                    truth.rebuild_dirty(&x, &h);
                    partial += 1;
                }
                Refresh::Valid => {}
            }
            let expect = brute(&x, &h, n);
            for i in own.clone() {
                assert!(
                    expect[i].iter().all(|&j| share.list(i).any(|k| k == j)),
                    "step {step}: a pair of particle {i} lost"
                );
            }
        }
        assert!(partial >= 10 && rebuilt > 0, "{partial} partial rebuilds");
    }
    fn rnd(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// An MPI rank's share (`own`): the lists of its particles' chunks are those of the full
    /// build, the other particles' are empty.
    #[test]
    fn owned_lists_are_those_of_the_full_build() {
        let mut seed = 777u64;
        let x: Vec<Vector<3>> = (0..2000)
            .map(|_| Vector::<3>::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)))
            .collect();
        let h = vec![0.06; x.len()];
        let mut full = NeighborList::default();
        full.build(&x, &h, 1800, 0.01);
        let mut share = NeighborList::default();
        share.own(600..1100);
        share.build(&x, &h, 1800, 0.01);
        share.classify(&vec![0; x.len()], false);
        let chunks = |i: usize| i / CHUNK;
        for i in 0..1800 {
            if (chunks(600)..=chunks(1099)).contains(&chunks(i)) {
                assert!(share.list(i).eq(full.list(i)), "particle {i}");
                assert!(share.list(i).next().is_some());
            } else {
                assert!(
                    share.list(i).next().is_none(),
                    "particle {i} is another rank's"
                );
            }
        }
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
