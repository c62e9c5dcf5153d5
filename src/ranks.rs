//! The processes of a distributed run (MPI, with the `mpi` cargo feature) and how the work of a
//! step is split between them.
//!
//! **Own ranges, halos, replicated storage.** Every rank holds storage for every particle and
//! takes every step, but computes and advances only its own contiguous range of particles in
//! cell order, the ranges balanced by measured cost (see `simulation::rebalance`) and starting
//! at multiples of the sums' block. Each step a rank
//! - receives the state of its halo (the other ranks' particles that its own particles' lists
//!   name, directly or through a symmetry plane's ghost) from their owners, point to point
//!   ([`Plan`], rebuilt with the lists: [`Ranks::plan`], [`Ranks::all_to_all`]);
//! - computes CN-SPH's corrections and the colour states of its range and sends them to the
//!   ranks whose halo holds them (over the halo's plan; of the colour states only those
//!   other than the default, which few particles have);
//! - computes the rates of its range and advances it (the rates are not exchanged);
//! - sends the positions and smoothing lengths of its particles to the ranks whose neighbour
//!   refresh reads them (those in the blocks of cells near their own particles, see
//!   `neighbors::NeighborList::near_members`), point to point over a second plan set at each
//!   full search, and shares its blocks' sums for the history (gathered and added in block
//!   order);
//! - decides with the others whether the lists still hold: the largest displacement and
//!   smoothing length by an exact reduction, the dirty particles by a sum
//!   (`neighbors::NeighborList::refresh`);
//! - takes the smallest time step, the checks and the mixing figures by exact reductions.
//!
//! At a full search (at least every `REORDER_EVERY` steps, where the ranges may change) the
//! ranks all-gather every particle's position and smoothing length (what the cell order and
//! the lists are made of) and its neighbour count (what weighs the new ranges); then each
//! rank receives, point to point, the whole state of the particles of its new range and halo
//! that another rank advanced last (the migration of the particles that change ranks: every
//! rank knows who held each from the old ranges and the reordering, [`Ranks::plan_from`]).
//! Before a checkpoint or a cross-section the ranks all-gather every particle's state. A
//! particle's results come from exactly the arithmetic of the serial run whichever rank
//! computes them, and the sums are added in the serial order, so an MPI run is bit-identical
//! to the serial one on any number of ranks, and a checkpoint restarts on any number. What it
//! does not give yet is memory per rank falling with the ranks (each holds storage for every
//! particle, most of it stale) or scaling past a few dozen ranks (the positions are
//! all-gathered at each full search, and the slabs' halos grow): see the README's "Not yet".
//!
//! **What a range needs of the others.** The cell order is a raster scan of the cells (the last
//! axis fastest), so a contiguous range is a slab across the first axis: it touches at most two
//! other ranges, and its [`Halo`] (counted by `strike bench`, `Simulation::halo_census`) grows
//! with the ranks as a slab thins, not as a compact piece's surface. Halos for many ranks will
//! want ranges along a space-filling curve through blocks of cells, or bisection.
//!
//! Without the feature, or when the program was not started by an MPI launcher, there is one
//! rank and nothing is exchanged.

use crate::mixing::PairMixing;
use rayon::prelude::*;
use std::ops::Range;

/// This process's rank and the number of ranks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ranks {
    rank: usize,
    size: usize,
}

impl Default for Ranks {
    fn default() -> Self {
        Ranks::SERIAL
    }
}

impl Ranks {
    /// One process: nothing is split or exchanged.
    pub const SERIAL: Ranks = Ranks { rank: 0, size: 1 };

    /// The ranks of this run: MPI's world after [`start`], otherwise [`Ranks::SERIAL`].
    pub fn world() -> Ranks {
        #[cfg(feature = "mpi")]
        if mpi::is_initialized() {
            use mpi::topology::Communicator;
            let world = mpi::topology::SimpleCommunicator::world();
            return Ranks {
                rank: world.rank() as usize,
                size: world.size() as usize,
            };
        }
        Ranks::SERIAL
    }

    pub fn rank(&self) -> usize {
        self.rank
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// Rank `rank` of `size`, as a test would have MPI give it (nothing is exchanged).
    #[cfg(test)]
    pub(crate) fn pretend(rank: usize, size: usize) -> Ranks {
        Ranks { rank, size }
    }

    /// The rank that writes the outputs and prints.
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// Split 0..n into one contiguous range per rank with about equal total `cost` (of each
    /// particle, ≥ 0). Deterministic: the same on every rank for the same costs.
    pub fn split(&self, n: usize, cost: impl Fn(usize) -> f64) -> Vec<Range<usize>> {
        split_by_cost(self.size, n, cost)
    }

    /// After each rank has filled its own range `parts[rank]` of `v`, give every rank all of
    /// `v` (MPI all-gather; nothing to do on one rank).
    pub fn share<T: Copy + Send>(&self, v: &mut [T], parts: &[Range<usize>]) {
        if self.size == 1 {
            return;
        }
        #[cfg(feature = "mpi")]
        exchange::all_gather(v, parts, self.rank);
        #[cfg(not(feature = "mpi"))]
        unreachable!(
            "more than one rank without the mpi feature ({parts:?}, {})",
            v.len()
        );
    }

    /// Each rank's `value`, in rank order (on one rank: `[value]`).
    pub fn gather_each(&self, value: f64) -> Vec<f64> {
        let mut all = vec![0.0; self.size];
        all[self.rank] = value;
        let parts: Vec<Range<usize>> = (0..self.size).map(|r| r..r + 1).collect();
        self.share(&mut all, &parts);
        all
    }

    /// Whether `flag` is raised on any rank (on one rank: `flag`).
    pub fn any(&self, flag: bool) -> bool {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            return exchange::all_reduce(i32::from(flag), SystemOperation::max()) != 0;
        }
        flag
    }

    /// Combine the ranks' mixing figures (each of its own particles): the deepest penetration
    /// and the count of mixed particles of each pair, the same on every rank (exact: a
    /// maximum and an integer sum).
    pub fn combine_mixing(&self, figures: &mut [PairMixing]) {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            use mpi::traits::*;
            let world = mpi::topology::SimpleCommunicator::world();
            let deepest: Vec<f64> = figures.iter().map(|f| f.penetration).collect();
            let mixed: Vec<u64> = figures.iter().map(|f| f.mixed).collect();
            let (mut deepest_all, mut mixed_all) = (deepest.clone(), mixed.clone());
            world.all_reduce_into(&deepest[..], &mut deepest_all[..], SystemOperation::max());
            world.all_reduce_into(&mixed[..], &mut mixed_all[..], SystemOperation::sum());
            for (f, (d, m)) in figures
                .iter_mut()
                .zip(deepest_all.into_iter().zip(mixed_all))
            {
                f.penetration = d;
                f.mixed = m;
            }
        }
        let _ = figures;
    }

    /// The plan of this rank's halo: `needed`, the particles of other ranks that its passes
    /// read (distinct, ascending), asked of their owners under the ranges `parts`; each
    /// owner learns which of its particles to send (an all-to-all of the lists).
    pub fn plan(&self, parts: &[Range<usize>], needed: &[u32]) -> Plan {
        self.plan_from(needed, |j| parts.partition_point(|r| r.end <= j as usize))
    }

    /// The plan that brings this rank the particles `needed` (ascending), each from the rank
    /// `holder` names for it (every rank must name the same one).
    pub fn plan_from(&self, needed: &[u32], holder: impl Fn(u32) -> usize) -> Plan {
        let mut recv = vec![Vec::new(); self.size];
        for &j in needed {
            recv[holder(j).min(self.size - 1)].push(j);
        }
        let send = self.all_to_all(&recv);
        Plan { send, recv }
    }

    /// Send `out[r]` to each rank r and receive, in rank order, what each sent this one (MPI
    /// all-to-all; on one rank the message to itself comes back).
    pub fn all_to_all<T: Copy>(&self, out: &[Vec<T>]) -> Vec<Vec<T>> {
        if self.size == 1 {
            return out.to_vec();
        }
        #[cfg(feature = "mpi")]
        return exchange::all_to_all(out);
        #[cfg(not(feature = "mpi"))]
        unreachable!("more than one rank without the mpi feature ({})", out.len());
    }

    /// Over `plan`, from `state`: the message to each rank r is what `pack` writes for the
    /// particles `plan.send[r]`, and what each rank sends this one is read back by `unpack`
    /// with the particles `plan.recv` names for it (MPI all-to-all; nothing on one rank).
    pub fn exchange<S: ?Sized, T: Copy>(
        &self,
        plan: &Plan,
        state: &mut S,
        pack: impl Fn(&S, &[u32], &mut Vec<T>),
        mut unpack: impl FnMut(&mut S, &[u32], &[T]),
    ) {
        if self.size == 1 {
            return;
        }
        // One buffer for all the messages, read back in place: a message a rank in vectors
        // of its own, joined and split again around the all-to-all, copied every record
        // twice more.
        let mut flat: Vec<T> = Vec::new();
        let counts: Vec<usize> = plan
            .send
            .iter()
            .map(|idx| {
                let before = flat.len();
                pack(state, idx, &mut flat);
                flat.len() - before
            })
            .collect();
        let (got, got_counts) = self.all_to_all_flat(&flat, &counts);
        let mut rest = &got[..];
        for (idx, &c) in plan.recv.iter().zip(&got_counts) {
            let (message, after) = rest.split_at(c);
            rest = after;
            unpack(state, idx, message);
        }
    }

    /// [`Ranks::all_to_all`] from one buffer, `counts[r]` records to rank r in turn; returns
    /// the records received, in rank order, and how many came from each (on one rank the
    /// buffer comes back).
    fn all_to_all_flat<T: Copy>(&self, flat: &[T], counts: &[usize]) -> (Vec<T>, Vec<usize>) {
        if self.size == 1 {
            return (flat.to_vec(), counts.to_vec());
        }
        #[cfg(feature = "mpi")]
        return exchange::all_to_all_flat(flat, counts);
        #[cfg(not(feature = "mpi"))]
        unreachable!(
            "more than one rank without the mpi feature ({})",
            counts.len()
        );
    }

    /// [`Ranks::exchange`] of one value a particle: the `values` of the particles of
    /// `plan.recv` become those their ranks hold.
    pub fn swap<T: Copy>(&self, plan: &Plan, values: &mut [T]) {
        let pack = |v: &[T], idx: &[u32], out: &mut Vec<T>| {
            out.extend(idx.iter().map(|&i| v[i as usize]));
        };
        self.exchange(plan, values, pack, |v, idx, got| {
            for (&i, &g) in idx.iter().zip(got) {
                v[i as usize] = g;
            }
        });
    }

    /// The smallest of the ranks' `value`s (exact in any order; on one rank: `value`).
    pub fn min(&self, value: f64) -> f64 {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            return exchange::all_reduce(value, SystemOperation::min());
        }
        value
    }

    /// The largest of the ranks' `values`, element by element, on every rank (exact in any
    /// order; on one rank they stay).
    pub fn max_each(&self, values: &mut [f64]) {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            use mpi::traits::*;
            let mine = values.to_vec();
            mpi::topology::SimpleCommunicator::world().all_reduce_into(
                &mine[..],
                values,
                SystemOperation::max(),
            );
        }
        let _ = values;
    }

    /// The sum of the ranks' `count`s (exact; on one rank: `count`).
    pub fn sum(&self, count: u64) -> u64 {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            return exchange::all_reduce(count, SystemOperation::sum());
        }
        count
    }

    /// Stop every rank at once (after an error on this one), with `code`; on one rank, return.
    pub fn abort(&self, code: i32) {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::topology::Communicator;
            mpi::topology::SimpleCommunicator::world().abort(code);
        }
        let _ = code;
    }
}

/// Split 0..n into `count` (≥ 1) contiguous ranges with about equal total `cost` (of each
/// element, ≥ 0): [`Ranks::split`] for any number of ranks.
pub fn split_by_cost(count: usize, n: usize, cost: impl Fn(usize) -> f64) -> Vec<Range<usize>> {
    if count <= 1 {
        return std::iter::once(0..n).collect();
    }
    let total: f64 = (0..n).map(&cost).sum();
    let mut parts = Vec::with_capacity(count);
    let (mut start, mut acc, mut i) = (0, 0.0, 0);
    for r in 1..count {
        let target = total * r as f64 / count as f64;
        while i < n && acc < target {
            acc += cost(i);
            i += 1;
        }
        parts.push(start..i);
        start = i;
    }
    parts.push(start..n);
    parts
}

/// The halo exchange of one rank (DESIGN.md §8): which of its particles it sends to each rank
/// and which of each rank's it receives, both ascending. Built from the rank's neighbour lists
/// after each search ([`Ranks::plan`]); the entries for the rank itself are empty.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Plan {
    pub send: Vec<Vec<u32>>,
    pub recv: Vec<Vec<u32>>,
}

/// What one rank's share of the particles needs of the others' each step: the halo a domain
/// decomposition exchanges (DESIGN.md §8). The rate pass of a share reads its particles'
/// neighbours, so the halo is every particle of another share that the share's neighbour
/// lists name, directly or as the source of a symmetry plane's ghost; the lists reach
/// h_i + h_j plus the skin, the "2 h_max plus the skin" of the design. Its messages are the
/// ranks it comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Halo {
    /// Particles of the share.
    pub own: usize,
    /// Distinct particles of other shares that the share's lists name.
    pub halo: usize,
    /// The shares (ranks) those come from.
    pub neighbour_ranks: usize,
}

/// The [`Halo`] of each of the shares `parts` of positions 0..n, position k holding particle
/// `order[k]` (k itself without an order); `neighbours(i, out)` puts the particles that i's
/// list names into `out` (ghosts already resolved to their real sources). `only`: the one
/// share whose lists exist here (an MPI rank's; the others' are left at their `own`).
pub fn halos(
    parts: &[Range<usize>],
    order: Option<&[u32]>,
    only: Option<usize>,
    neighbours: impl Fn(usize, &mut Vec<usize>) + Sync,
) -> Vec<Halo> {
    let n = parts.last().map_or(0, |r| r.end);
    let particle = |k: usize| order.map_or(k, |o| o[k] as usize);
    let mut owner = vec![0_u32; n];
    for (r, range) in parts.iter().enumerate() {
        for k in range.clone() {
            owner[particle(k)] = r as u32;
        }
    }
    parts
        .par_iter()
        .enumerate()
        .map(|(r, range)| {
            let mut halo = Halo {
                own: range.len(),
                ..Halo::default()
            };
            if only.is_some_and(|o| o != r) {
                return halo;
            }
            let (mut found, mut buf) = (Vec::new(), Vec::new());
            for k in range.clone() {
                neighbours(particle(k), &mut buf);
                found.extend(
                    buf.iter()
                        .filter(|&&j| owner[j] != r as u32)
                        .map(|&j| j as u32),
                );
            }
            found.par_sort_unstable();
            found.dedup();
            let mut from: Vec<u32> = found.iter().map(|&j| owner[j as usize]).collect();
            from.sort_unstable();
            from.dedup();
            halo.halo = found.len();
            halo.neighbour_ranks = from.len();
            halo
        })
        .collect()
}

/// An order of the particles for splitting them into ranges ([`crate::simulation::Simulation::halo_census`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Curve {
    /// The run's own: cell order, a raster scan of the cells (the last axis fastest).
    Cells,
    /// Morton's Z-order curve through the cells: each range a compact piece, as a
    /// decomposition for many ranks would want.
    Morton,
}

/// The particles at `x` along Morton's Z-order curve through cells of side `cell` (ties, in
/// one cell, by index): the bits of the cell's coordinates interleaved, 21 an axis.
pub fn morton_order<const D: usize>(x: &[crate::particles::Vector<D>], cell: f64) -> Vec<u32> {
    let mut lo = [f64::INFINITY; D];
    for p in x {
        for k in 0..D {
            lo[k] = lo[k].min(p[k]);
        }
    }
    let cell = cell.max(f64::MIN_POSITIVE);
    let key = |p: &crate::particles::Vector<D>| {
        let c: [u64; D] =
            std::array::from_fn(|k| (((p[k] - lo[k]) / cell).floor() as u64).min((1 << 21) - 1));
        let mut key = 0_u64;
        for bit in (0..21).rev() {
            for ck in c {
                key = (key << 1) | ((ck >> bit) & 1);
            }
        }
        key
    };
    let mut keyed: Vec<(u64, u32)> = x
        .par_iter()
        .enumerate()
        .map(|(i, p)| (key(p), i as u32))
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Fill `out[i] = f(i)` for i in `owned` (in parallel), `out` holding n entries; those outside
/// `owned` are left as they are, for [`Ranks::share`] to fill.
pub fn fill<T: Send + Default + Clone>(
    out: &mut Vec<T>,
    n: usize,
    owned: &Range<usize>,
    f: impl Fn(usize) -> T + Sync + Send,
) {
    out.resize(n, T::default());
    let start = owned.start;
    out[owned.clone()]
        .par_iter_mut()
        .enumerate()
        .for_each(|(k, o)| *o = f(start + k));
}

/// Whether MPI may be called from any thread, one at a time (`Threading::Serialized`).
#[cfg(feature = "mpi")]
static SERIALIZED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a step may run on a worker of rayon's pool: always on one rank; under MPI where
/// MPI was initialised for calls from any thread, one at a time.
pub fn steps_in_pool(ranks: Ranks) -> bool {
    #[cfg(feature = "mpi")]
    if ranks.size() > 1 {
        return SERIALIZED.load(std::sync::atomic::Ordering::Relaxed);
    }
    let _ = ranks;
    true
}

/// Keeps MPI initialised for the life of the process (finalised when dropped).
pub struct Session {
    #[cfg(feature = "mpi")]
    _universe: Option<mpi::environment::Universe>,
}

/// Initialise MPI where the program was started by an MPI launcher (mpirun, mpiexec, srun),
/// so that a plain `strike run` of the MPI build stays a serial run that needs no launcher.
pub fn start() -> Session {
    #[cfg(feature = "mpi")]
    {
        let launched = [
            "OMPI_COMM_WORLD_SIZE",
            "PMI_SIZE",
            "PMIX_RANK",
            "MPI_LOCALNRANKS",
        ]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
        // MPI is called by one thread at a time: the step's, a worker of rayon's pool where
        // MPI allows it (`Threading::Serialized`, see `Simulation::step`), else the main one.
        let universe = launched
            .then(|| mpi::initialize_with_threading(mpi::Threading::Serialized))
            .flatten()
            .map(|(u, provided)| {
                let any_thread = matches!(
                    provided,
                    mpi::Threading::Serialized | mpi::Threading::Multiple
                );
                SERIALIZED.store(any_thread, std::sync::atomic::Ordering::Relaxed);
                u
            });
        Session {
            _universe: universe,
        }
    }
    #[cfg(not(feature = "mpi"))]
    Session {}
}

#[cfg(feature = "mpi")]
mod exchange {
    use mpi::datatype::{DynBuffer, DynBufferMut, Partition, PartitionMut, UserDatatype};
    use mpi::traits::*;
    use std::ops::Range;

    /// `value` reduced over the ranks by `op`, the same on every rank.
    pub fn all_reduce<T: Equivalence + Copy>(value: T, op: mpi::collective::SystemOperation) -> T {
        let mut out = value;
        mpi::topology::SimpleCommunicator::world().all_reduce_into(&value, &mut out, op);
        out
    }

    /// All-to-all of variable length: `out[r]` to rank r, and back what each rank sent this
    /// one, as opaque records (plain data of this same program on every rank).
    pub fn all_to_all<T: Copy>(out: &[Vec<T>]) -> Vec<Vec<T>> {
        let counts: Vec<usize> = out.iter().map(Vec::len).collect();
        let (got, got_counts) = all_to_all_flat(&out.concat(), &counts);
        let mut rest = &got[..];
        got_counts
            .iter()
            .map(|&c| {
                let (mine, after) = rest.split_at(c);
                rest = after;
                mine.to_vec()
            })
            .collect()
    }

    /// All-to-all of variable length from one buffer: the first `counts[0]` records of
    /// `flat` to rank 0, the next `counts[1]` to rank 1, and so on; returns what the ranks
    /// sent this one, in rank order in one buffer, and how many records came from each.
    pub fn all_to_all_flat<T: Copy>(flat: &[T], counts: &[usize]) -> (Vec<T>, Vec<usize>) {
        let world = mpi::topology::SimpleCommunicator::world();
        let record = UserDatatype::contiguous(
            std::mem::size_of::<T>() as mpi::Count,
            &u8::equivalent_datatype(),
        );
        let count = |n: usize| mpi::Count::try_from(n).expect("fewer than 2³¹ records a message");
        let send_counts: Vec<mpi::Count> = counts.iter().map(|&c| count(c)).collect();
        let mut recv_counts = vec![0 as mpi::Count; counts.len()];
        world.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let displs = |counts: &[mpi::Count]| -> Vec<mpi::Count> {
            counts
                .iter()
                .scan(0, |at, &c| {
                    let d = *at;
                    *at += c;
                    Some(d)
                })
                .collect()
        };
        let (send_displs, recv_displs) = (displs(&send_counts), displs(&recv_counts));
        // Never an empty vector's dangling pointer: for one-byte records it is 0x1, which
        // OpenMPI reads as MPI_IN_PLACE (and refuses, MPI_ERR_ARG).
        let placeholder: Vec<T> = Vec::with_capacity(usize::from(flat.is_empty()));
        let send_ptr = if flat.is_empty() {
            placeholder.as_ptr()
        } else {
            flat.as_ptr()
        };
        let total: usize = recv_counts.iter().map(|&c| c as usize).sum();
        let mut got: Vec<T> = Vec::with_capacity(total.max(1));
        // SAFETY: the send buffer holds the records the counts say (none where it is the
        // placeholder); the receive buffer has room for `total` records, which the all-to-all
        // fills completely before `set_len`; a T is plain data (Copy), so its bytes may be
        // copied between processes as they are.
        unsafe {
            let send = DynBuffer::from_raw(send_ptr, count(flat.len()), record.as_ref());
            let mut recv = DynBufferMut::from_raw(got.as_mut_ptr(), count(total), record.as_ref());
            let send = Partition::new(&send, &send_counts[..], &send_displs[..]);
            let mut recv = PartitionMut::new(&mut recv, &recv_counts[..], &recv_displs[..]);
            world.all_to_all_varcount_into(&send, &mut recv);
            got.set_len(total);
        }
        (got, recv_counts.iter().map(|&c| c as usize).collect())
    }

    /// All-gather of the ranks' ranges of `v`, element by element as opaque bytes (the
    /// records are plain data of this same program on every rank).
    pub fn all_gather<T: Copy>(v: &mut [T], parts: &[Range<usize>], rank: usize) {
        let world = mpi::topology::SimpleCommunicator::world();
        let record = UserDatatype::contiguous(
            std::mem::size_of::<T>() as mpi::Count,
            &u8::equivalent_datatype(),
        );
        let count = |n: usize| mpi::Count::try_from(n).expect("fewer than 2³¹ particles a rank");
        // Never an empty vector's dangling pointer (see `all_to_all`).
        let mut mine: Vec<T> = Vec::with_capacity(parts[rank].len().max(1));
        mine.extend_from_slice(&v[parts[rank].clone()]);
        let counts: Vec<mpi::Count> = parts.iter().map(|r| count(r.len())).collect();
        let displs: Vec<mpi::Count> = parts.iter().map(|r| count(r.start)).collect();
        // SAFETY: both buffers hold as many records of `record`'s size as the counts say, and
        // a T is plain data (Copy), so its bytes may be copied between processes as they are.
        unsafe {
            let send = DynBuffer::from_raw(mine.as_ptr(), count(mine.len()), record.as_ref());
            let mut recv = DynBufferMut::from_raw(v.as_mut_ptr(), count(v.len()), record.as_ref());
            let mut part = PartitionMut::new(&mut recv, &counts[..], &displs[..]);
            world.all_gather_varcount_into(&send, &mut part);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ranges cover 0..n in order, and balance the weight.
    #[test]
    fn split_covers_and_balances() {
        let ranks = Ranks { rank: 0, size: 3 };
        let cost = |i: usize| if i < 500 { 100.0 } else { 10.0 };
        let parts = ranks.split(1000, cost);
        assert_eq!(parts.len(), 3);
        assert_eq!(parts[0].start, 0);
        assert_eq!(parts[2].end, 1000);
        for w in parts.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        let sum = |r: &Range<usize>| r.clone().map(cost).sum::<f64>();
        let total: f64 = parts.iter().map(sum).sum();
        for r in &parts {
            assert!((sum(r) / total - 1.0 / 3.0).abs() < 0.01, "{parts:?}");
        }
        assert_eq!(
            Ranks::SERIAL.split(7, |_| 1.0),
            std::iter::once(0..7).collect::<Vec<_>>()
        );
    }

    /// Morton's curve visits the four cells of a 2 × 2 square in Z order, and a 4 × 4 square
    /// quadrant by quadrant.
    #[test]
    fn morton_order_visits_quadrants_in_turn() {
        use crate::particles::Vector;
        let x: Vec<Vector<2>> = (0..16)
            .map(|i| Vector::<2>::new((i % 4) as f64 + 0.5, (i / 4) as f64 + 0.5))
            .collect();
        let order = morton_order(&x, 1.0);
        // x = (column, row): of each pair of bits the column's is the more significant, so
        // in a 2 × 2 square the curve takes one column's two rows, then the next column's.
        assert_eq!(
            order,
            vec![0, 4, 1, 5, 8, 12, 9, 13, 2, 6, 3, 7, 10, 14, 11, 15]
        );
    }

    /// A chain of particles each naming those within 3 places: split in four, the end shares
    /// need 3 particles of one other share, the middle ones 6 of two; with the chain stored
    /// backwards (an order) the same.
    #[test]
    fn halos_of_a_chain() {
        let n = 100;
        let near = |i: usize, out: &mut Vec<usize>| {
            out.clear();
            out.extend((i.saturating_sub(3)..(i + 4).min(n)).filter(|&j| j != i));
        };
        let parts = split_by_cost(4, n, |_| 1.0);
        let expect = |own| {
            [(3, 1), (6, 2), (6, 2), (3, 1)].map(|(halo, neighbour_ranks)| Halo {
                own,
                halo,
                neighbour_ranks,
            })
        };
        assert_eq!(halos(&parts, None, None, near), expect(25));
        let backwards: Vec<u32> = (0..n as u32).rev().collect();
        let mut got = halos(&parts, Some(&backwards), None, near);
        got.reverse();
        assert_eq!(got, expect(25));
        // One share's lists only: the others are left at their size.
        let one = halos(&parts, None, Some(1), near);
        assert_eq!(one[1], expect(25)[1]);
        assert_eq!(
            one[0],
            Halo {
                own: 25,
                halo: 0,
                neighbour_ranks: 0
            }
        );
        // One share needs nothing.
        assert_eq!(
            halos(&split_by_cost(1, n, |_| 1.0), None, None, near),
            vec![Halo {
                own: n,
                halo: 0,
                neighbour_ranks: 0
            }]
        );
    }
}
