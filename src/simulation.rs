//! The time loop of one run: neighbours → physics + contact + boundary → integration, with the
//! diagnostics of each step and the checks that stop an unstable run.

use crate::boundary;
use crate::boundary::Plane;
use crate::case::{Case, Formulation, KernelKind};
use crate::contact::colour::{self, ColourStates};
use crate::error::{Error, Result};
use crate::integrate;
use crate::kernel::{CubicSpline, WendlandC2};
use crate::mixing::{self, PairMixing};
use crate::neighbors::{NeighborList, Refresh};
use crate::particles::{to3, Particles, Tensor};
use crate::physics::{self, Model, Rates};
use crate::ranks::{Curve, Ranks};
use crate::setup;
use rayon::prelude::*;
use std::any::Any;
use std::ops::Range;
use std::time::Instant;

/// Global quantities at t_n (the start of the step that produced them).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Diagnostics {
    pub time: f64,
    pub dt: f64,
    /// Kinetic energy, the mean of the half-step values ½ Σ m |v^{n±½}|² (J).
    pub kinetic: f64,
    /// Σ m e (J), the mean of the half-step values.
    pub internal: f64,
    /// Contact potential Φ (J).
    pub contact: f64,
    /// Gravitational potential −Σ m g·x (J), 0 without gravity.
    pub gravity: f64,
    /// kinetic + internal + contact + gravity.
    pub total: f64,
    /// Σ m v at t_n (mean of the half-step momenta), z = 0 in 2D.
    pub momentum: [f64; 3],
    /// Σ m |v| (scale for the relative momentum error).
    pub momentum_scale: f64,
    pub max_pressure: f64,
    /// Smallest distance between particles of different bodies (in contact or welded), / their
    /// mean initial spacing (None: no such pair within the kernel support).
    pub min_interbody_distance: Option<f64>,
    /// Contact force on each body (N), z = 0 in 2D.
    pub body_contact_force: Vec<[f64; 3]>,
    /// Mixing figures of each pair of bodies, in [`crate::mixing::pair_index`] order.
    pub mixing: Vec<PairMixing>,
    /// CN-SPH: particles that kept the uncorrected gradient this step (A_i near singular).
    pub correction_fallbacks: usize,
    /// Neighbour entries of the real particles this step (particle-neighbour interactions).
    pub interactions: usize,
    /// Particles that have failed (damage 1).
    pub failed: usize,
}

/// A run in progress.
#[derive(Debug)]
pub struct Simulation<const D: usize> {
    pub particles: Particles<D>,
    pub model: Model<D>,
    pub kernel: KernelKind,
    pub symmetry: Vec<Plane>,
    pub body_names: Vec<String>,
    /// Lattice spacing of each body (m).
    pub spacing: Vec<f64>,
    /// Time, step and the other scalars a checkpoint keeps.
    pub state: SimState,
    pub stats: SearchStats,
    neighbors: NeighborList,
    ghosts: boundary::Ghosts,
    rates: Rates<D>,
    order: Vec<usize>,
    /// Work buffers of the per-step sums (one entry per block of `BLOCK` particles).
    sums_old: Vec<Sums>,
    sums_new: Vec<Sums>,
    body_force_blocks: Vec<[f64; 3]>,
    /// The colour-law state of every particle, ghosts included (empty without such pairs).
    colour: ColourStates,
    /// Search radii max(h, h0): the colour law reaches 2 h0 also where h has shrunk.
    h_search: Vec<f64>,
    /// CN-SPH: each particle's correction, and B of every particle, ghosts included.
    corrections: Vec<physics::correction::Correction<D>>,
    corr: Vec<Tensor<D>>,
    /// CN-SPH: the surface indicator λ_min of every particle, ghosts included.
    lambda: Vec<f64>,
    /// The ranks the passes are split over (see `ranks`), and each one's range of particles,
    /// set at each full search.
    ranks: Ranks,
    parts: Vec<Range<usize>>,
    /// This rank's halo: which particles it sends to and receives from the others each step.
    plan: crate::ranks::Plan,
    /// The particles of other ranks that this rank's lists named at the last full build.
    halo: Vec<u32>,
    /// Which positions (and smoothing lengths) this rank sends and receives after each step:
    /// those of the particles near its own that the next neighbour refresh reads (see
    /// `NeighborList::near_members`), set at each full search.
    positions: crate::ranks::Plan,
    /// Between a full search's reordering and its halo: the ranges before it and, where the
    /// particles were reordered, each one's index before (see `receive_halo`).
    moved: Option<(Vec<Range<usize>>, Vec<usize>)>,
    /// Seconds this rank spent on its own share since the ranges were set (to balance the
    /// next ones; the full search that set them left out), and in the exchanges between ranks
    /// in all.
    busy: f64,
    exchanging: f64,
    /// Seconds in all in the neighbour search (refreshes, partial rebuilds and full builds,
    /// their exchanges left out) and in the passes (`busy`'s share, summed over the whole run):
    /// with `exchanging`, where a rank's time goes ([`Simulation::phase_seconds`]).
    searching: f64,
    passing: f64,
    /// Seconds this rank's last full search took, its exchanges included: what new ranges
    /// cost (see `lagging_rank`).
    rebuild: f64,
    /// Steps of the last comparison of the ranks' loads, and of the last full search that
    /// set the ranges.
    balanced: u64,
    ranged: u64,
    /// The ranges of the last measure of the ranks' loads over `BALANCE_EVERY` steps or
    /// more, with each rank's seconds on its own over them, while the particles keep the
    /// order they were measured in (see `measure`).
    measured: Option<Measure>,
    /// The rank whose load was worth new ranges at the last comparison since the ranges were
    /// set (see `unbalanced`).
    lagging: Option<usize>,
    /// Full searches made early, to balance the ranks' loads (0 on one rank).
    pub rebalances: u64,
}

/// The scalar state of a run in progress, beside its particles: what a checkpoint keeps.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimState {
    /// Simulated time t_n (s) and step n.
    pub time: f64,
    pub step: u64,
    /// Δt of the last step (0 before the first).
    pub dt_prev: f64,
    /// Δt of the first step, for the collapse check.
    pub dt_first: Option<f64>,
    /// A particle faster than this has gone unstable (m/s).
    pub speed_limit: f64,
    /// Step of the last reordering into cell order.
    pub last_reorder: u64,
}

/// Neighbour searches made so far: full builds, and steps with partial rebuilds (see
/// `neighbors`). Bookkeeping only: when a search happens does not change the results (the
/// lists are in canonical order), and a resumed run searches at its first step.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SearchStats {
    pub searches: u64,
    pub partial_searches: u64,
    /// CN-SPH: particle-steps that kept the uncorrected gradient (A_i near singular).
    pub correction_fallbacks: u64,
}

/// Sums over the particles are taken per block of this many particles, in parallel, and the
/// blocks' sums are then added in block order: the same additions whatever the thread count.
/// Under MPI each rank sums its own blocks, the ranks' ranges starting at multiples of it
/// (`rebalance`), and the blocks' sums are gathered before they are added, so the sums are
/// those of one process to the bit.
const BLOCK: usize = 256;

/// Partial sums of one block of particles (see [`block_sums`]).
#[derive(Debug, Clone, Copy)]
struct Sums {
    /// ½ Σ m |v^{n±½}|², Σ m e^{n±½}, Σ m v^{n±½}, Σ m |v^{n±½}|.
    kinetic: f64,
    internal: f64,
    momentum: [f64; 3],
    momentum_scale: f64,
    contact: f64,
    gravity: f64,
    max_pressure: f64,
    gap: f64,
    /// Particles with damage 1.
    failed: usize,
}

impl Default for Sums {
    fn default() -> Self {
        Sums {
            kinetic: 0.0,
            internal: 0.0,
            momentum: [0.0; 3],
            momentum_scale: 0.0,
            contact: 0.0,
            gravity: 0.0,
            max_pressure: f64::NEG_INFINITY,
            gap: f64::INFINITY,
            failed: 0,
        }
    }
}

impl Sums {
    /// Add particle i's kinetic and internal energy and momentum at the half step.
    #[inline]
    fn add_half_step<const D: usize>(&mut self, p: &Particles<D>, i: usize) {
        self.kinetic += 0.5 * p.m[i] * p.vh[i].norm_squared();
        self.internal += p.m[i] * p.eh[i];
        let mv = to3(&(p.vh[i] * p.m[i]));
        for (sum, c) in self.momentum.iter_mut().zip(mv) {
            *sum += c;
        }
    }

    fn merge(mut self, o: &Sums) -> Sums {
        self.kinetic += o.kinetic;
        self.internal += o.internal;
        for k in 0..3 {
            self.momentum[k] += o.momentum[k];
        }
        self.momentum_scale += o.momentum_scale;
        self.contact += o.contact;
        self.gravity += o.gravity;
        self.max_pressure = self.max_pressure.max(o.max_pressure);
        self.gap = self.gap.min(o.gap);
        self.failed += o.failed;
        self
    }
}

/// `f` over the blocks of `BLOCK` particles of 0..n in parallel (into `scratch`), then the
/// blocks merged in order. Under MPI each rank takes the blocks of its own range (see
/// [`blocks_of`]) and the ranks then share them.
fn block_sums(
    n: usize,
    scratch: &mut Vec<Sums>,
    (ranks, parts): (Ranks, &[Range<usize>]),
    f: impl Fn(std::ops::Range<usize>) -> Sums + Sync,
) -> Sums {
    scratch.resize(n.div_ceil(BLOCK), Sums::default());
    let blocks = blocks_of(parts, 1);
    let mine = blocks[ranks.rank()].clone();
    scratch[mine.clone()]
        .par_iter_mut()
        .enumerate()
        .for_each(|(k, s)| {
            let b = mine.start + k;
            *s = f(b * BLOCK..n.min((b + 1) * BLOCK))
        });
    ranks.share(scratch, &blocks);
    scratch.iter().fold(Sums::default(), |a, s| a.merge(s))
}

/// The blocks of `BLOCK` particles of each range of `parts` (whose ranges start at multiples
/// of `BLOCK`: `rebalance`), as ranges of entries of `per` entries a block.
fn blocks_of(parts: &[Range<usize>], per: usize) -> Vec<Range<usize>> {
    parts
        .iter()
        .map(|r| {
            if r.is_empty() {
                r.start / BLOCK * per..r.start / BLOCK * per
            } else {
                r.start / BLOCK * per..r.end.div_ceil(BLOCK) * per
            }
        })
        .collect()
}

/// Where a rank's time goes, in seconds since the run started. Under MPI the ranks meet at the
/// halo (after the search) and at the step's reductions (after the passes), so a step lasts
/// about the slowest rank's search plus the slowest rank's passes: a rank's wait for the others
/// shows in its `exchanges`.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct PhaseSeconds {
    /// The neighbour search: refreshes, partial rebuilds, full builds (their exchanges aside).
    pub search: f64,
    /// The passes over this rank's own particles: CN-SPH's corrections, the colour states and
    /// the rates.
    pub passes: f64,
    /// The exchanges between ranks, the waits for slower ranks included (next to nothing on
    /// one rank, whose exchange calls return at once).
    pub exchanges: f64,
}

/// Real particles are put back in cell order at least this often (steps), for memory locality.
pub const REORDER_EVERY: u64 = 50;
/// Under MPI, the ranks compare their loads this often (steps), and take new ranges early only
/// where the slowest is past this multiple of the mean (the measured times scatter by a few
/// per cent from step to step) and the time it loses pays for a full search
/// (`lagging_rank`).
const BALANCE_EVERY: u64 = 5;
const IMBALANCE: f64 = 1.1;
/// Verlet skin of the neighbour lists, as a fraction of the largest smoothing length.
pub const SKIN: f64 = 0.1;

/// The library's one compiled copy of a run in 2D and in 3D. `Simulation::new` and `step` are
/// generic in D, and a crate that calls a generic function compiles its own copy of it and of
/// everything it calls: each integration test that ran a `Simulation` compiled the whole
/// physics again (45–97 s apiece in release, half of the test build). The generic methods
/// therefore only pick one of these non-generic functions, which other crates link to.
#[inline(never)]
fn new_2d(case: &Case) -> Result<Simulation<2>> {
    Simulation::set_up(case)
}

#[inline(never)]
fn new_3d(case: &Case) -> Result<Simulation<3>> {
    Simulation::set_up(case)
}

#[inline(never)]
fn step_2d(sim: &mut Simulation<2>, dt_max: f64) -> Result<Diagnostics> {
    sim.step_here(dt_max)
}

#[inline(never)]
fn step_3d(sim: &mut Simulation<3>, dt_max: f64) -> Result<Diagnostics> {
    sim.step_here(dt_max)
}

/// The error of a dimension other than 2 or 3.
fn no_dimension(d: usize) -> Error {
    Error::Invalid(format!("strike runs in 2 or 3 dimensions, not {d}"))
}

impl<const D: usize> Simulation<D> {
    /// Set up a case (the deck's dimension must be D, 2 or 3).
    pub fn new(case: &Case) -> Result<Self> {
        // Through the non-generic `new_2d` / `new_3d` (see there); the downcast only names the
        // type that D already is.
        let mut made: Option<Result<Self>> = None;
        let slot: &mut dyn Any = &mut made;
        if let Some(slot) = slot.downcast_mut::<Option<Result<Simulation<2>>>>() {
            *slot = Some(new_2d(case));
        } else if let Some(slot) = slot.downcast_mut::<Option<Result<Simulation<3>>>>() {
            *slot = Some(new_3d(case));
        }
        made.unwrap_or_else(|| Err(no_dimension(D)))
    }

    fn set_up(case: &Case) -> Result<Self> {
        let (particles, model) = setup::build::<D>(case)?;
        let n = particles.n_real;
        let v0 = (0..n).map(|i| particles.v[i].norm()).fold(0.0, f64::max);
        let c0 = (0..n).map(|i| particles.c[i]).fold(0.0, f64::max);
        Ok(Simulation {
            particles,
            model,
            kernel: case.simulation.kernel,
            symmetry: setup::symmetry_planes(case),
            body_names: case.bodies.iter().map(|b| b.name.clone()).collect(),
            spacing: case.bodies.iter().map(|b| b.spacing).collect(),
            state: SimState {
                time: 0.0,
                step: 0,
                dt_prev: 0.0,
                dt_first: None,
                // DESIGN.md: 10× the fastest initial speed. Bodies starting at rest (a block on
                // an incline) would trip that at once, so the sound speed bounds it from below.
                speed_limit: 10.0 * v0.max(c0),
                last_reorder: 0,
            },
            stats: SearchStats::default(),
            neighbors: NeighborList::default(),
            ghosts: boundary::Ghosts::default(),
            rates: Rates::default(),
            order: Vec::new(),
            sums_old: Vec::new(),
            sums_new: Vec::new(),
            body_force_blocks: Vec::new(),
            colour: ColourStates::default(),
            h_search: Vec::new(),
            corrections: Vec::new(),
            corr: Vec::new(),
            lambda: Vec::new(),
            ranks: Ranks::SERIAL,
            parts: Vec::new(),
            plan: Default::default(),
            halo: Vec::new(),
            positions: Default::default(),
            moved: None,
            busy: 0.0,
            searching: 0.0,
            passing: 0.0,
            exchanging: 0.0,
            rebuild: 0.0,
            balanced: 0,
            ranged: 0,
            measured: None,
            lagging: None,
            rebalances: 0,
        })
    }

    /// Split the passes of each step over `ranks` (every rank must call this and then take the
    /// same steps); the results do not change by a bit.
    pub fn distribute(&mut self, ranks: Ranks) {
        self.ranks = ranks;
        self.parts.clear();
    }

    /// Each rank's range of the real particles, as the ranks split the work now (an even
    /// split by count before the first step has set them): the pieces of a parallel snapshot.
    pub fn rank_ranges(&self) -> Vec<Range<usize>> {
        let n = self.particles.n_real;
        if self.parts.len() == self.ranks.size() && self.parts.last().is_some_and(|r| r.end == n) {
            self.parts.clone()
        } else {
            self.ranks.split(n, |_| 1.0)
        }
    }

    /// Under MPI, give every rank every particle's current state: between full searches each
    /// rank advances only its own range (and the halo it reads), so the root must gather before
    /// it writes what holds all of them (a checkpoint, a cross-section). Nothing on one rank
    /// or before the first step.
    pub fn gather(&mut self) {
        if self.distributed() {
            let lap = Instant::now();
            self.particles.share_real(self.ranks, &self.parts);
            self.exchanging += lap.elapsed().as_secs_f64();
        }
    }

    /// Whether the ranks each advance a range of their own (MPI, once the first step has set
    /// the ranges).
    fn distributed(&self) -> bool {
        self.ranks.size() > 1 && self.parts.len() == self.ranks.size()
    }

    /// Whether the ranks' loads have drifted apart since their ranges were set, far enough
    /// that new ranges pay for the full search that makes them: every `BALANCE_EVERY` steps
    /// (the first `BALANCE_EVERY` steps after a full search) they compare their time on their
    /// own shares and the cost of their last full search (`lagging_rank`). If new ranges pay,
    /// and did at the last comparison too with the same rank the slowest, this step's search
    /// is a full one, with new ranges (which changes no result: see `neighbors`). The second
    /// look and the blocks' rounding are for small runs, whose times per step are a few hundred
    /// microseconds and scatter by tens of per cent, and whose ranges whole blocks cannot
    /// balance finely: on the 2D plate of `examples/plate_2d.toml` (700 particles, 2 ranks) the
    /// cost alone bought 344 early searches in 2000 steps, with the second look 131 in 3447,
    /// with the rounding none. The figures are gathered, so every rank decides alike. Always
    /// false on one rank.
    fn unbalanced(&mut self) -> bool {
        let step = self.state.step;
        if self.ranks.size() == 1 || step < self.balanced.max(self.ranged) + BALANCE_EVERY {
            return false;
        }
        self.balanced = step;
        let times = self.ranks.gather_each(self.busy);
        let mut cost = [self.rebuild];
        self.ranks.max_each(&mut cost);
        let left = (self.state.last_reorder + REORDER_EVERY).saturating_sub(step);
        // Ranges start at whole blocks: each may end up to half a block from its balance.
        let rounding = (BLOCK / 2 * self.ranks.size()) as f64 / self.particles.n_real as f64;
        let lagging = lagging_rank(&times, step - self.ranged, left, cost[0], rounding);
        let early = lagging.is_some() && lagging == self.lagging;
        self.lagging = lagging;
        self.rebalances += u64::from(early);
        early
    }

    /// The ranges and the ranks' seconds on them that this full search balances its new
    /// ranges on (`balance_basis`), or `None` to keep the ranges and go on measuring them.
    fn measure(&mut self, short: bool, reordered: bool) -> Option<Measure> {
        let distributed = self.distributed();
        let (ranks, parts, busy) = (self.ranks, &self.parts, &mut self.busy);
        let fresh = || (parts.clone(), ranks.gather_each(std::mem::take(busy)));
        balance_basis(&mut self.measured, fresh, (short, reordered, distributed))
    }

    /// Seconds spent in the exchanges between ranks so far (0 on one rank).
    pub fn exchange_seconds(&self) -> f64 {
        self.exchanging
    }

    /// Where this rank's time has gone so far: see [`PhaseSeconds`].
    pub fn phase_seconds(&self) -> PhaseSeconds {
        PhaseSeconds {
            search: self.searching,
            passes: self.passing,
            exchanges: self.exchanging,
        }
    }

    /// The halos `count` ranks would exchange at the current state (see [`crate::ranks::Halo`]):
    /// the real particles put in the order of `curve` and split into `count` ranges balanced
    /// by neighbour count, as a distributed run splits them (it uses [`Curve::Cells`]), each
    /// range's halo read off this process's neighbour lists. The lists must be of every
    /// particle (one rank) and current (after a step); otherwise, or before the first step,
    /// there is nothing to count (empty).
    pub fn halo_census(&self, count: usize, curve: Curve) -> Vec<crate::ranks::Halo> {
        let p = &self.particles;
        let n = p.n_real;
        if self.ranks.size() > 1
            || self.neighbors.len() != n
            || self.rates.particles.range() != (0..n)
        {
            return Vec::new();
        }
        let order = match curve {
            Curve::Cells => NeighborList::default()
                .cell_order(&p.x[..n], &p.h[..n])
                .to_vec(),
            Curve::Morton => {
                let h_max = p.h[..n].iter().copied().fold(0.0_f64, f64::max);
                crate::ranks::morton_order(&p.x[..n], h_max)
            }
        };
        let rates = &self.rates.particles;
        let cost = |k: usize| f64::from(rates[order[k] as usize].neighbors) + 8.0;
        let parts = crate::ranks::split_by_cost(count, n, cost);
        crate::ranks::halos(&parts, Some(&order), None, |i, out| self.named(i, out))
    }

    /// This rank's halo under the ranks' current split (MPI; on one rank: none).
    pub fn own_halo(&self) -> crate::ranks::Halo {
        let parts = self.rank_ranges();
        let rank = self.ranks.rank();
        crate::ranks::halos(&parts, None, Some(rank), |i, out| self.named(i, out))[rank]
    }

    /// Under MPI: every particle of another rank that this rank's lists name (ghosts by their
    /// sources) comes from its owner, as the owner advanced it, and the ghosts then take their
    /// sources' states again. The plan changes with the lists (`need`: this step's search).
    ///
    /// After a full search the ranges may have changed: the state of each particle of this
    /// rank's new range and halo comes from the rank that advanced it last (the migration of
    /// the particles that changed ranks, and the new halo), which every rank knows from the
    /// old ranges and the reordering (`moved`).
    fn receive_halo(&mut self, need: Refresh) {
        if need != Refresh::Valid {
            // A partial rebuild changes only the rebuilt lists: their particles join the full
            // build's halo (a few too many until the next full build cost nothing).
            let owned = &self.parts[self.ranks.rank()];
            if need == Refresh::Full {
                self.halo = self.needed(owned, false);
                self.plan = self.ranks.plan(&self.parts, &self.halo);
                // What the refreshes until the next full search read: the displacements of
                // this rank's own particles and their ghosts, and the positions in the blocks
                // near them, which come from their owners after each step (`send_positions`).
                let n = self.particles.n_real;
                self.neighbors.own_ghosts(self.ghosts.mirroring(owned, n));
                let mut near: Vec<u32> = self
                    .neighbors
                    .near_members()
                    .map(|j| self.ghosts.real_source(j as usize, n))
                    .filter(|s| !owned.contains(s))
                    .map(|s| s as u32)
                    .collect();
                near.par_sort_unstable();
                near.dedup();
                self.positions = self.ranks.plan(&self.parts, &near);
            } else {
                let mut needed = self.needed(owned, true);
                needed.extend_from_slice(&self.halo);
                needed.par_sort_unstable();
                needed.dedup();
                self.plan = self.ranks.plan(&self.parts, &needed);
            }
        }
        let p = &mut self.particles;
        match (need, self.moved.take()) {
            (Refresh::Full, Some((old, order))) => {
                let rank = self.ranks.rank();
                let before = |i: u32| order.get(i as usize).map_or(i as usize, |&k| k);
                let was = |i: u32| old.partition_point(|r| r.end <= before(i));
                let mut wanted: Vec<u32> = self.parts[rank].clone().map(|i| i as u32).collect();
                wanted.extend_from_slice(&self.halo);
                wanted.par_sort_unstable();
                wanted.retain(|&i| was(i) != rank);
                let moving = self.ranks.plan_from(&wanted, was);
                self.ranks
                    .exchange(&moving, p, Particles::pack, Particles::unpack);
            }
            // The first search: every rank holds every particle's state.
            (Refresh::Full, None) => {}
            _ => self
                .ranks
                .exchange(&self.plan, p, Particles::pack, Particles::unpack),
        }
        self.ghosts.update(p, &self.symmetry);
    }

    /// Under MPI, after a step: the positions and smoothing lengths of this rank's particles
    /// to the ranks whose next neighbour refresh reads them, and theirs to this rank (the
    /// position plan of the last full search). The others' stay as they were: no pass reads
    /// them before the next full search gathers every particle's position.
    fn send_positions(&mut self) {
        let p = &mut self.particles;
        let (pack, unpack) = (Particles::pack_positions, Particles::unpack_positions);
        self.ranks.exchange(&self.positions, p, pack, unpack);
    }

    /// The particles of other ranks that this rank's passes read: those that the lists of its
    /// own particles `owned` name (ghosts by their sources), ascending; with `only_rebuilt`,
    /// those of the lists rebuilt since the last full build.
    fn needed(&self, owned: &Range<usize>, only_rebuilt: bool) -> Vec<u32> {
        let n = self.particles.n_real;
        let nl = &self.neighbors;
        let mut found: Vec<u32> = owned
            .clone()
            .into_par_iter()
            .filter(|&i| !only_rebuilt || nl.rebuilt_since_build(i))
            .fold(Vec::new, |mut found, i| {
                found.extend(
                    nl.list(i)
                        .map(|j| self.ghosts.real_source(j as usize, n))
                        .filter(|s| !owned.contains(s))
                        .map(|s| s as u32),
                );
                found
            })
            .reduce(Vec::new, |mut a, mut b| {
                a.append(&mut b);
                a
            });
        found.par_sort_unstable();
        found.dedup();
        found
    }

    /// The real particles that particle i's list names (ghosts by their sources).
    fn named(&self, i: usize, out: &mut Vec<usize>) {
        let n = self.particles.n_real;
        out.clear();
        out.extend(
            self.neighbors
                .list(i)
                .map(|j| self.ghosts.real_source(j as usize, n)),
        );
    }

    /// The state a checkpoint keeps: the real particles and the scalars. Neighbour lists and
    /// ghosts are left out: a resumed run rebuilds them, and as lists are summed in canonical
    /// order that changes no bit of the results.
    pub fn checkpoint_state(&self) -> (Particles<D>, SimState, SearchStats) {
        let mut particles = self.particles.clone();
        particles.truncate_to_real();
        (particles, self.state.clone(), self.stats)
    }

    /// Continue from a checkpoint's state (the case must be the one it was written for).
    pub fn restore(&mut self, particles: Particles<D>, state: SimState, stats: SearchStats) {
        self.particles = particles;
        self.state = state;
        self.stats = stats;
        self.neighbors = NeighborList::default();
        self.ghosts = boundary::Ghosts::default();
    }

    /// Advance one step, of at most `dt_max`. On instability the particles are left at t_n
    /// (the last good state) and the error names the particle, its body, place and cause.
    ///
    /// The step runs on a worker of the thread pool (`rayon::scope`; in place where the caller
    /// is one already, as `strike run`'s thread is), so that its twenty-odd parallel loops start
    /// from inside the pool. Called from outside, each loop would be handed to the pool with the
    /// caller asleep on a futex until it ended: for a step of a few thousand particles that
    /// costs as much as the arithmetic (the 2D bars of `tests/verification_contact.rs` spent
    /// 105 s in the kernel, sched_yield and futex, beside 121 s of user time, and ran 1.8×
    /// longer). Under an MPI that takes calls from the main thread only, the step stays on the
    /// calling thread (`ranks::steps_in_pool`). The arithmetic is the same either way.
    pub fn step(&mut self, dt_max: f64) -> Result<Diagnostics> {
        // Through the non-generic `step_2d` / `step_3d` (see `new_2d`).
        let sim: &mut dyn Any = self;
        if let Some(sim) = sim.downcast_mut::<Simulation<2>>() {
            return step_2d(sim, dt_max);
        }
        if let Some(sim) = sim.downcast_mut::<Simulation<3>>() {
            return step_3d(sim, dt_max);
        }
        Err(no_dimension(D))
    }

    fn step_here(&mut self, dt_max: f64) -> Result<Diagnostics> {
        if crate::ranks::steps_in_pool(self.ranks) {
            rayon::scope(|_| self.advance(dt_max))
        } else {
            self.advance(dt_max)
        }
    }

    fn advance(&mut self, dt_max: f64) -> Result<Diagnostics> {
        let unbalanced = self.unbalanced();
        let distributed = self.distributed();
        let p = &mut self.particles;
        // A rank predicts its own particles only: the others' come whole with the halo, or with
        // a full search's migration, from the rank that owned them at the step's start (until
        // 2026-12-02 every rank predicted every particle). Before the first search (a start or
        // a restart) every rank holds and predicts every particle's state.
        let predicted = if distributed {
            self.parts[self.ranks.rank()].clone()
        } else {
            0..p.n_real
        };
        integrate::predict_velocity(p, &self.model, self.state.dt_prev, predicted);
        // Ghosts and neighbour lists are rebuilt when the skin is used up (positions are those
        // of the real particles with the old ghosts refreshed), and every REORDER_EVERY steps
        // at the latest, when the real particles are also put back in cell order. Ranks that
        // advance a range each need only the ghosts' positions here: their state comes whole
        // after the halo (`receive_halo`), or with a full search's rebuild.
        if distributed {
            self.ghosts.update_positions(p, &self.symmetry);
        } else {
            self.ghosts.update(p, &self.symmetry);
        }
        let (search, exchanged) = (Instant::now(), self.exchanging);
        let wide = self.model.colour.is_some();
        let reorder = self.state.step >= self.state.last_reorder + REORDER_EVERY;
        let mut need = Refresh::Full;
        if !(reorder || unbalanced) {
            let h = search_radii(p, wide, &mut self.h_search);
            need = self.neighbors.refresh(&p.x, h, self.ranks);
            if need == Refresh::Partial {
                // Particles moved beyond the skin: the ghost layers must still reach 2 h_max
                // (each rank looks at its own particles and their ghosts).
                let reach = 2.0 * self.neighbors.h_max();
                let (ghosts, n) = (&self.ghosts, p.n_real);
                let covered = if distributed {
                    let own = &self.parts[self.ranks.rank()];
                    let mine = |i: usize| own.contains(&ghosts.real_source(i, n));
                    ghosts.cover(p, &self.symmetry, reach, mine)
                } else {
                    ghosts.cover(p, &self.symmetry, reach, |_| true)
                };
                if self.ranks.any(!covered) {
                    need = Refresh::Full;
                }
            }
            if need == Refresh::Partial {
                let start = Instant::now();
                if self.neighbors.rebuild_dirty(&p.x, h) {
                    self.neighbors.classify(&p.body, true);
                    self.stats.partial_searches += 1;
                } else {
                    // The last partial rebuild's lists still hold (the same on every rank).
                    need = Refresh::Valid;
                }
                self.busy += start.elapsed().as_secs_f64();
            }
        }
        let mut counts = Vec::new();
        let full = Instant::now();
        if need == Refresh::Full && distributed {
            // Each rank has advanced only its own range since the ranges were set: before they
            // change (and the order with them), every rank takes every particle's position and
            // smoothing length, which the order and the lists are made of, and the neighbour
            // counts of the last pass, which weigh the new ranges. The rest of the state goes
            // only where the new ranges need it (`receive_halo`).
            let lap = Instant::now();
            p.share_positions(self.ranks, &self.parts);
            counts = neighbour_counts(self.ranks, &self.rates.particles, &self.parts);
            self.exchanging += lap.elapsed().as_secs_f64();
        }
        if need == Refresh::Full {
            let reordered = reorder && self.state.step > 0;
            if reordered {
                // Cell order of the real particles' current positions: a function of the
                // state alone, so a resumed run reorders exactly as the uninterrupted one.
                p.truncate_to_real();
                self.order.clear();
                self.order.extend(
                    self.neighbors
                        .cell_order(&p.x, &p.h)
                        .iter()
                        .map(|&i| i as usize),
                );
                p.permute(&self.order);
                self.state.last_reorder = self.state.step;
            }
            let n = p.n_real;
            let window = self.state.step - self.ranged;
            let measured = self.measure(distributed && window < BALANCE_EVERY, reordered);
            let keep = measured.is_none();
            let parts = match measured {
                Some((ranges, times)) => {
                    let order = reordered.then_some(&self.order[..]);
                    rebalance(self.ranks, n, &counts, (&ranges, &times), order)
                }
                None => self.parts.clone(),
            };
            let p = &mut self.particles;
            let old = std::mem::replace(&mut self.parts, parts);
            // The permutation is needed by this step's halo under MPI (`moved`: who held each
            // particle), then not before the next reordering, 50 steps on: kept, it would hold
            // 8 bytes a particle through every step between.
            let order = std::mem::take(&mut self.order);
            if distributed {
                self.moved = Some((old, if reordered { order } else { Vec::new() }));
            }
            if self.ranks.size() > 1 {
                self.neighbors.own(self.parts[self.ranks.rank()].clone());
            }
            let h = search_radii(p, wide, &mut self.h_search);
            let h_max = h.iter().copied().fold(0.0_f64, f64::max);
            let skin = SKIN * h_max;
            self.ghosts.rebuild(p, &self.symmetry, 2.0 * h_max + skin);
            let h = search_radii(p, wide, &mut self.h_search);
            self.neighbors.build(&p.x, h, p.n_real, skin);
            self.neighbors.classify(&p.body, false);
            self.stats.searches += 1;
            if !keep {
                self.ranged = self.state.step;
                self.lagging = None;
            }
        }
        self.searching += search.elapsed().as_secs_f64() - (self.exchanging - exchanged);
        if self.ranks.size() > 1 {
            let lap = Instant::now();
            self.receive_halo(need);
            self.exchanging += lap.elapsed().as_secs_f64();
            if need == Refresh::Full {
                // The search with its exchanges, the migration and the new plans: what new
                // ranges cost.
                self.rebuild = full.elapsed().as_secs_f64();
            }
        }
        let p = &mut self.particles;
        // This rank's time on its share, without the waits in the exchanges.
        let mut lap = Instant::now();
        let (ranks, parts) = (self.ranks, &self.parts[..]);
        let owned = parts[ranks.rank()].clone();
        let owned = &owned;
        // CN-SPH: the gradient corrections, in their own pass before the rates.
        self.corr.clear();
        self.lambda.clear();
        let mut fallbacks = 0;
        let cn = self.model.formulation == Formulation::Corrected;
        if cn {
            let (nl, model, out) = (&self.neighbors, &self.model, &mut self.corrections);
            let own = match self.kernel {
                KernelKind::CubicSpline => {
                    physics::corrections(CubicSpline, p, nl, model, owned, out)
                }
                KernelKind::WendlandC2 => {
                    physics::corrections(WendlandC2, p, nl, model, owned, out)
                }
            };
            let t = lap.elapsed().as_secs_f64();
            (self.busy, self.passing) = (self.busy + t, self.passing + t);
            lap = Instant::now();
            // The halo's corrections from their ranks (what the rate pass reads of them: B,
            // and the surface indicator), and every rank's count of fallbacks.
            ranks.swap(&self.plan, out);
            fallbacks = ranks.sum(own as u64) as usize;
            self.exchanging += lap.elapsed().as_secs_f64();
            lap = Instant::now();
            self.stats.correction_fallbacks += fallbacks as u64;
            // B and the surface indicator out of the corrections in one pass.
            self.corrections
                .par_iter()
                .map(|c| (c.b, c.lambda_min))
                .unzip_into_vecs(&mut self.corr, &mut self.lambda);
            self.ghosts
                .extend_to_ghosts_with(&mut self.lambda, &self.symmetry, |l, _| l);
            // A ghost's B is its source's seen in the mirror: M B M, M = I − 2 e_a e_aᵀ.
            self.ghosts
                .extend_to_ghosts_with(&mut self.corr, &self.symmetry, |mut b, axis| {
                    for k in 0..D {
                        if k != axis {
                            b[(axis, k)] = -b[(axis, k)];
                            b[(k, axis)] = -b[(k, axis)];
                        }
                    }
                    b
                });
        }
        // The colour contact law (and CN-SPH's contact normal) needs every particle's colour
        // state first (the pass overwrites the real particles' entries of the last step, and
        // the ghosts' are appended anew).
        if physics::needs_colour_states(&self.model) {
            let (nl, model) = (&self.neighbors, &self.model);
            let surfaces = cn.then_some(colour::Surfaces {
                lambda: &self.lambda,
            });
            match self.kernel {
                KernelKind::CubicSpline => physics::colour_states(
                    CubicSpline,
                    p,
                    nl,
                    model,
                    (surfaces, owned),
                    &mut self.colour,
                ),
                KernelKind::WendlandC2 => physics::colour_states(
                    WendlandC2,
                    p,
                    nl,
                    model,
                    (surfaces, owned),
                    &mut self.colour,
                ),
            }
            let t = lap.elapsed().as_secs_f64();
            (self.busy, self.passing) = (self.busy + t, self.passing + t);
            lap = Instant::now();
            self.colour.swap(ranks, &self.plan);
            self.exchanging += lap.elapsed().as_secs_f64();
            lap = Instant::now();
            // A ghost's state is its source's, with the normal mirrored.
            self.colour.extend_to_ghosts(&self.ghosts, &self.symmetry);
        }
        let (nl, model) = (&self.neighbors, &self.model);
        // The corrections (and their supports) only where this step computed them.
        let marks = if cn { &self.corrections[..] } else { &[][..] };
        let fields = (&self.colour, &self.corr[..], marks);
        // The pass writes the contact forces into the particles' own array, lent to it.
        std::mem::swap(&mut self.rates.contact_force, &mut p.contact_force);
        match self.kernel {
            KernelKind::CubicSpline => {
                physics::compute_rates(CubicSpline, p, nl, model, fields, owned, &mut self.rates)
            }
            KernelKind::WendlandC2 => {
                physics::compute_rates(WendlandC2, p, nl, model, fields, owned, &mut self.rates)
            }
        }
        std::mem::swap(&mut self.rates.contact_force, &mut p.contact_force);
        let t = lap.elapsed().as_secs_f64();
        (self.busy, self.passing) = (self.busy + t, self.passing + t);
        // Each rank's rates stay its own: it advances only its own particles.
        let rates = &self.rates.particles;
        let near = |i: usize| rates[i].min_interbody_gap.is_finite();
        let (nl, spacing) = (&self.neighbors, &self.spacing);
        let mut mixing = match self.kernel {
            KernelKind::CubicSpline => mixing::mixing(CubicSpline, p, nl, near, spacing, owned),
            KernelKind::WendlandC2 => mixing::mixing(WendlandC2, p, nl, near, spacing, owned),
        };
        let lap = Instant::now();
        ranks.combine_mixing(&mut mixing);
        self.exchanging += lap.elapsed().as_secs_f64();
        let n = p.n_real;
        // The stable step, its growth limited to 25 % a step; the collapse check uses it before
        // it is shortened to land on an output time. (min and max are exact in any order.)
        let mut dt_stable = ranks.min(
            self.rates
                .particles
                .as_slice()
                .par_iter()
                .map(|r| r.dt)
                .reduce(|| f64::INFINITY, f64::min),
        );
        if self.state.dt_prev > 0.0 {
            dt_stable = dt_stable.min(1.25 * self.state.dt_prev);
        }
        let dt_first = *self.state.dt_first.get_or_insert(dt_stable);
        let dt = dt_stable.min(dt_max);
        self.check(dt, dt_stable, dt_first)?;

        let bodies = self.body_names.len();
        let p = &self.particles;
        let rates = &self.rates.particles;
        let g = self.model.gravity;
        let split = (self.ranks, &self.parts[..]);
        let old = block_sums(n, &mut self.sums_old, split, |range| {
            let mut s = Sums::default();
            for i in range {
                s.add_half_step(p, i);
                s.contact += rates[i].contact_energy;
                s.gravity -= p.m[i] * g.dot(&p.x[i]);
                s.max_pressure = s.max_pressure.max(p.p[i]);
                s.gap = s.gap.min(rates[i].min_interbody_gap);
                s.failed += usize::from(p.damage[i] >= 1.0);
            }
            s
        });
        // Contact force per body, by the same blocks.
        let per = bodies.max(1);
        self.body_force_blocks
            .resize(n.div_ceil(BLOCK) * per, [0.0; 3]);
        let blocks = blocks_of(&self.parts, per);
        let mine = blocks[self.ranks.rank()].clone();
        self.body_force_blocks[mine.clone()]
            .par_chunks_mut(per)
            .enumerate()
            .for_each(|(k, fb)| {
                let b = mine.start / per + k;
                fb.fill([0.0; 3]);
                for i in b * BLOCK..n.min((b + 1) * BLOCK) {
                    let f = to3(&p.contact_force[i]);
                    let fb = &mut fb[p.body[i] as usize];
                    for k in 0..3 {
                        fb[k] += f[k];
                    }
                }
            });
        self.ranks.share(&mut self.body_force_blocks, &blocks);
        let mut d = Diagnostics {
            time: self.state.time,
            dt,
            body_contact_force: vec![[0.0; 3]; bodies],
            interactions: self.ranks.sum(
                rates
                    .as_slice()
                    .par_iter()
                    .map(|r| u64::from(r.neighbors))
                    .sum(),
            ) as usize,
            contact: old.contact,
            gravity: old.gravity,
            max_pressure: old.max_pressure,
            min_interbody_distance: old.gap.is_finite().then_some(old.gap),
            mixing,
            correction_fallbacks: fallbacks,
            failed: old.failed,
            ..Default::default()
        };
        for block in self.body_force_blocks.chunks_exact(bodies.max(1)) {
            for (sum, f) in d.body_contact_force.iter_mut().zip(block) {
                for k in 0..3 {
                    sum[k] += f[k];
                }
            }
        }

        integrate::advance(
            &mut self.particles,
            &self.rates,
            &self.model,
            (dt, self.state.dt_prev),
            owned.clone(),
        );
        boundary::reflect_crossed(&mut self.particles, &self.symmetry, owned.clone());
        if self.ranks.size() > 1 {
            // Where the particles near each rank's are, and their reach: what the next step's
            // search reads.
            let lap = Instant::now();
            self.send_positions();
            self.exchanging += lap.elapsed().as_secs_f64();
        }

        let p = &self.particles;
        let split = (self.ranks, &self.parts[..]);
        let new = block_sums(n, &mut self.sums_new, split, |range| {
            let mut s = Sums::default();
            for i in range {
                s.add_half_step(p, i);
                s.momentum_scale += p.m[i] * p.vh[i].norm();
            }
            s
        });
        d.momentum_scale = new.momentum_scale;
        // Whole-step values are the means of the half-step ones; the first step starts from
        // v^0 and e^0 themselves.
        if self.state.step == 0 {
            d.kinetic = old.kinetic;
            d.internal = old.internal;
            d.momentum = old.momentum;
        } else {
            d.kinetic = 0.5 * (old.kinetic + new.kinetic);
            d.internal = 0.5 * (old.internal + new.internal);
            d.momentum = [0, 1, 2].map(|k| 0.5 * (old.momentum[k] + new.momentum[k]));
        }
        d.total = d.kinetic + d.internal + d.contact + d.gravity;
        self.state.time += dt;
        self.state.step += 1;
        self.state.dt_prev = dt;
        Ok(d)
    }

    /// The rates at t_n must be finite, the density must stay positive over the step, no
    /// particle may exceed the speed limit and the step must not collapse.
    ///
    /// Under MPI each rank looks at its own particles; where any finds one, or the step fails,
    /// every rank takes every particle's state and rates and looks again at all of them, so
    /// that every rank names the particle one process would.
    fn check(&mut self, dt: f64, dt_stable: f64, dt_first: f64) -> Result<()> {
        let n = self.particles.n_real;
        let parts = self.rank_ranges();
        let mut bad = self.first_bad(parts[self.ranks.rank()].clone(), dt);
        let stalled = !(dt.is_finite() && dt > 0.0) || self.state.time + dt == self.state.time;
        let collapsed = dt_stable < 1e-6 * dt_first || dt_stable.is_nan();
        if self.ranks.size() > 1 && (self.ranks.any(bad.is_some()) || stalled || collapsed) {
            self.particles.share_real(self.ranks, &parts);
            // Each rank holds the rates of its own range only.
            let mut all = vec![physics::ParticleRates::default(); n];
            let held = self.rates.particles.range();
            all[held].copy_from_slice(self.rates.particles.as_slice());
            self.ranks.share(&mut all, &parts);
            self.rates.particles = physics::OwnRates::whole(all);
            bad = self.first_bad(0..n, dt);
        }
        let p = &self.particles;
        let r = &self.rates.particles;
        let (i, cause) = match bad {
            Some(b) => b,
            None if stalled => {
                let i = (0..p.n_real)
                    .min_by(|&a, &b| r[a].dt.total_cmp(&r[b].dt))
                    .unwrap_or(0);
                (
                    i,
                    format!(
                        "the time step {dt:.4e} s does not advance the time {:.6e} s (speed {:.4e} m/s, sound speed {:.4e} m/s, h {:.4e} m); this particle sets it",
                        self.state.time, p.v[i].norm(), p.c[i], p.h[i]
                    ),
                )
            }
            None if collapsed => {
                let i = (0..p.n_real)
                    .min_by(|&a, &b| r[a].dt.total_cmp(&r[b].dt))
                    .unwrap_or(0);
                (
                    i,
                    format!("time step collapsed to {dt_stable:.4e} s, below 1e-6 of the first ({dt_first:.4e} s); this particle sets it"),
                )
            }
            None => return Ok(()),
        };
        let pos: Vec<String> = to3(&p.x[i]).iter().map(|c| format!("{c:.6e}")).collect();
        Err(Error::Unstable {
            step: self.state.step,
            time: self.state.time,
            cause: format!(
                "particle {} of body '{}' at ({}) m: {cause}",
                p.id[i],
                self.body_names[p.body[i] as usize],
                pos.join(", ")
            ),
        })
    }

    /// The first of the particles `range` whose state or rates are not fit for a step of `dt`,
    /// and why.
    fn first_bad(&self, range: Range<usize>, dt: f64) -> Option<(usize, String)> {
        let p = &self.particles;
        let r = &self.rates.particles;
        // The state first (a bad particle spoils its neighbours' rates), then the rates.
        let state = range.clone().into_par_iter().find_map_first(|i| {
            let finite = p.x[i].iter().all(|c| c.is_finite())
                && p.v[i].iter().all(|c| c.is_finite())
                && p.rho[i].is_finite()
                && p.e[i].is_finite()
                && p.p[i].is_finite()
                && p.s[i].is_finite();
            if !finite {
                Some((i, "position, velocity, density, energy or stress is not finite (NaN/inf)".to_string()))
            } else if p.v[i].norm() > self.state.speed_limit {
                Some((i, format!(
                    "speed {:.4e} m/s exceeds 10× the fastest initial speed or sound speed ({:.4e} m/s)",
                    p.v[i].norm(),
                    self.state.speed_limit
                )))
            } else {
                None
            }
        });
        state.or_else(|| {
            range.into_par_iter().find_map_first(|i| {
                if !(r[i].acc.iter().all(|c| c.is_finite())
                    && r[i].drho.is_finite()
                    && r[i].de.is_finite()
                    && r[i].grad_v.iter().all(|c| c.is_finite()))
                {
                    Some((
                        i,
                        "acceleration or strain rate is not finite (NaN/inf)".to_string(),
                    ))
                } else if integrate::next_density(
                    self.model.material_of(p.body[i]),
                    p.rho[i],
                    dt * r[i].drho,
                    p.e[i],
                    p.damage[i] >= 1.0,
                )
                .partial_cmp(&0.0)
                    != Some(std::cmp::Ordering::Greater)
                {
                    Some((
                        i,
                        format!(
                            "density would fall to {:.4e} kg/m³ (from {:.4e})",
                            p.rho[i] + dt * r[i].drho,
                            p.rho[i]
                        ),
                    ))
                } else {
                    None
                }
            })
        })
    }
}

/// Every real particle's neighbour count at the last pass (zero where its rank evaluated none
/// yet), by index: each rank's own from its rates, all-gathered over the ranges `parts` (4 bytes
/// a particle, where the rates are 152 in 3D).
fn neighbour_counts<const D: usize>(
    ranks: Ranks,
    rates: &physics::OwnRates<D>,
    parts: &[Range<usize>],
) -> Vec<u32> {
    let n = parts.last().map_or(0, |r| r.end);
    let mut counts = vec![0u32; n];
    let own = parts[ranks.rank()].clone();
    if rates.range() == own {
        for (c, r) in counts[own].iter_mut().zip(rates.as_slice()) {
            *c = r.neighbors;
        }
    }
    ranks.share(&mut counts, parts);
    counts
}

/// Ranges with each rank's seconds on its own share over them: what new ranges are balanced
/// on (see `rebalance`).
type Measure = (Vec<Range<usize>>, Vec<f64>);

/// What a full search balances the new ranges on: the ranges and the ranks' seconds over the
/// steps since they were set (`fresh`, which gathers them from every rank), or `None` to keep
/// the ranges and go on measuring. A measure over fewer than `BALANCE_EVERY` steps (`short`: a
/// full search for the lists' sake, or the reordering, just after another) is not taken: the
/// step after a full search has no partial rebuilds, so its times leave out what the impact
/// zone's rebuilds cost its rank. Until 2026-12-02 it was: in a trace of the sphere–plate demo
/// on 2 ranks, a full search at step 99 balanced on 49 steps set 0..16 128 | 16 128..47 812,
/// the reordering at step 100 set 0..22 272 on the times of that one step (0.022 against
/// 0.036 s), and the early rebalance took to step 110 to undo it; late in the demo full
/// searches come every 2–4 steps, each balanced on as few. The last measure over
/// `BALANCE_EVERY` steps or more (`last`) is taken instead while the particles keep the order
/// it was made in (a full search that does not reorder keeps it); after a reordering there is
/// none, and a short measure keeps the ranges, unless this search reorders too (then the short
/// measure is all there is). Every rank decides alike: the steps and reorderings are the same
/// on all. Nothing is kept on one process (`distributed` false).
fn balance_basis(
    last: &mut Option<Measure>,
    fresh: impl FnOnce() -> Measure,
    (short, reordered, distributed): (bool, bool, bool),
) -> Option<Measure> {
    if short && !reordered && last.is_none() {
        return None;
    }
    let fresh = fresh();
    let chosen = match last.take() {
        Some(kept) if short => kept,
        _ => fresh,
    };
    if distributed && !reordered {
        *last = Some(chosen.clone());
    }
    Some(chosen)
}

/// The ranks' ranges of the `n` real particles until the next full build (before it: the
/// lists are built for them). Each particle weighs its neighbour count in the last pass
/// (`counts`, by old index: the pass's cost) times the seconds per neighbour its rank took since the `old`
/// ranges were set (`old.1`: each rank's time), so that costs the count does not see (a fast
/// particle's search at every step) move work away from the rank that had them. `order`: the
/// old index of each particle, where they were reordered since. Every rank computes the same
/// ranges (from the exchanged times); the results do not depend on them.
fn rebalance(
    ranks: Ranks,
    n: usize,
    counts: &[u32],
    (old, times): (&[Range<usize>], &[f64]),
    order: Option<&[usize]>,
) -> Vec<Range<usize>> {
    if ranks.size() == 1 {
        return ranks.split(n, |_| 0.0);
    }
    let base = |k: usize| counts.get(k).map_or(0.0, |&c| f64::from(c)) + 8.0;
    // Seconds per unit of weight of each old range (1 where nothing was measured yet).
    let per: Vec<f64> = old
        .iter()
        .zip(times)
        .map(|(r, &t)| {
            let w: f64 = r.clone().map(base).sum();
            if t > 0.0 && w > 0.0 {
                t / w
            } else {
                1.0
            }
        })
        .collect();
    let cost = |i: usize| {
        let k = order.map_or(i, |o| o[i]);
        let owner = old.partition_point(|r| r.end <= k);
        base(k) * per.get(owner).copied().unwrap_or(1.0)
    };
    // Each range starts at a multiple of BLOCK, so that each rank sums whole blocks of its own
    // (`block_sums`): every boundary is moved to the nearest one.
    let mut parts = ranks.split(n, cost);
    let mut start = 0;
    let last = parts.len() - 1;
    for (r, range) in parts.iter_mut().enumerate() {
        let end = if r == last {
            n
        } else {
            ((range.end + BLOCK / 2) / BLOCK * BLOCK).clamp(start, n)
        };
        *range = start..end;
        start = end;
    }
    parts
}

/// The slowest rank, where new ranges would pay for the full search that makes them. The
/// ranks wait for the slowest at each step's exchanges, so ranges balanced on the measured
/// loads would save about (t_max − t_mean (1 + r)) / `steps` a step, `times` being each rank's
/// seconds on its own share over the `steps` since the ranges were set and r the fraction of
/// a rank's load by which its new range may still miss the balance (`rounding`: the ranges
/// start at whole blocks); they would do so for the `left` steps until the next reordering
/// sets new ranges anyway (at most: a full search for the lists' own sake may come sooner),
/// against `cost`, the seconds of the slowest rank's last full search with its exchanges.
/// Besides paying, the imbalance must pass `IMBALANCE`, above the times' scatter. The renewal
/// rule again (see `neighbors::NeighborList::refresh`): a balance is worth
/// buying when it earns back its price before it would come free. Until 2026-12-02 every
/// imbalance past 1.1 forced a full search, however few steps were left before the next.
fn lagging_rank(times: &[f64], steps: u64, left: u64, cost: f64, rounding: f64) -> Option<usize> {
    if times.is_empty() || steps == 0 {
        return None;
    }
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    // The first of the slowest, so that ties name the same rank on every rank.
    let (rank, slowest) = times
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
    let saving = (slowest - mean * (1.0 + rounding)) / steps as f64 * left as f64;
    (slowest > IMBALANCE * mean && saving > cost).then_some(rank)
}

/// The neighbour search radius of each particle (ghosts included): its smoothing length, or
/// max(h, h0) when the colour contact law, which acts over the reference support, is in use
/// (`colour`; the radii are then written into `out` and returned from it). Without the colour
/// law the radii are `p.h` itself: a copy would cost 8 bytes a particle for nothing.
fn search_radii<'a, const D: usize>(
    p: &'a Particles<D>,
    colour: bool,
    out: &'a mut Vec<f64>,
) -> &'a [f64] {
    out.clear();
    if colour {
        out.par_extend(p.h.par_iter().zip(&p.h0).map(|(&h, &h0)| h.max(h0)));
        out
    } else {
        &p.h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// New ranges are bought only when the time the imbalance loses before the next reordering
    /// pays for the full search, and never for an imbalance within the times' scatter.
    #[test]
    fn rebalancing_pays_for_its_search() {
        // 2 ranks, 1.0 and 1.3 s over 10 steps: 0.15 s lost a step against the mean.
        let times = [1.0, 1.3];
        assert_eq!(
            lagging_rank(&times, 10, 40, 0.5, 0.0),
            Some(1),
            "0.6 s saved for 0.5"
        );
        assert_eq!(
            lagging_rank(&times, 10, 20, 0.5, 0.0),
            None,
            "0.3 s saved for 0.5"
        );
        assert_eq!(
            lagging_rank(&times, 10, 0, 0.0, 0.0),
            None,
            "nothing left to save"
        );
        let long = lagging_rank(&times, 40, 40, 0.5, 0.0);
        assert_eq!(long, None, "the same loss over 40 steps");
        // Whole blocks may leave 10 % of a rank's load: 0.0035 s a step to gain, 0.14 s over
        // 40 steps, 0.7 s over 200.
        assert_eq!(lagging_rank(&times, 10, 40, 0.5, 0.1), None);
        assert_eq!(lagging_rank(&times, 10, 200, 0.5, 0.1), Some(1));
        // 3 % over the mean: within the scatter, however cheap the search.
        assert_eq!(lagging_rank(&[1.0, 1.06], 10, 50, 0.0, 0.0), None);
        let three = [1.5, 1.0, 1.0];
        assert_eq!(
            lagging_rank(&three, 5, 45, 0.7, 0.0),
            Some(0),
            "1.5 / 1.167 over 5 steps"
        );
        let two = [1.0, 1.5, 1.5];
        assert_eq!(
            lagging_rank(&two, 5, 45, 0.1, 0.0),
            Some(1),
            "the first of two"
        );
        assert_eq!(lagging_rank(&[], 5, 45, 0.0, 0.0), None);
        assert_eq!(lagging_rank(&times, 0, 45, 0.0, 0.0), None);
    }

    /// A full search just after another does not balance on the one or few steps between
    /// them: it takes the last measure over `BALANCE_EVERY` steps or more while the order it
    /// was made in holds, and otherwise keeps the ranges (not even gathering the times),
    /// unless it reorders itself. On one process nothing is kept.
    #[test]
    fn a_short_measure_does_not_set_the_ranges() {
        let long: Measure = (vec![0..100, 100..300], vec![4.0, 2.0]);
        let one_step: Measure = (vec![0..150, 150..300], vec![0.022, 0.036]);
        let mut last = None;
        let taken = || panic!("a kept range gathers no times");
        // A full search at the end of 49 steps: its own measure, kept.
        let basis = balance_basis(&mut last, || long.clone(), (false, false, true));
        assert_eq!(basis.as_ref(), Some(&long));
        assert_eq!(last.as_ref(), Some(&long));
        // One step on, another (the lists') that does not reorder: the long one again.
        let basis = balance_basis(&mut last, || one_step.clone(), (true, false, true));
        assert_eq!(
            basis.as_ref(),
            Some(&long),
            "one step's times would swing the ranges"
        );
        assert_eq!(last.as_ref(), Some(&long));
        // The reordering one step on: still the long one, then nothing (a new order).
        let basis = balance_basis(&mut last, || one_step.clone(), (true, true, true));
        assert_eq!(basis.as_ref(), Some(&long));
        assert_eq!(last, None);
        // A short measure in the new order: the ranges stay, and the times go on adding up.
        assert_eq!(balance_basis(&mut last, taken, (true, false, true)), None);
        assert_eq!(last, None);
        // ... until a reordering, where the short measure is all there is.
        let basis = balance_basis(&mut last, || one_step.clone(), (true, true, true));
        assert_eq!(basis.as_ref(), Some(&one_step));
        assert_eq!(last, None);
        // A long measure after a reordering is kept again; on one process never.
        let basis = balance_basis(&mut last, || one_step.clone(), (false, false, true));
        assert_eq!(
            (basis.as_ref(), last.as_ref()),
            (Some(&one_step), Some(&one_step))
        );
        let mut serial = None;
        let basis = balance_basis(&mut serial, || long.clone(), (false, false, false));
        assert_eq!((basis.as_ref(), serial), (Some(&long), None));
    }

    /// The ranks' ranges start at multiples of the sums' block, nearest the balanced split, so
    /// that each rank sums whole blocks of its own; a range too short for a block is empty.
    #[test]
    fn ranges_start_at_whole_blocks() {
        let none: (&[Range<usize>], &[f64]) = (&[], &[]);
        let parts = rebalance(Ranks::pretend(0, 3), 1000, &[], none, None);
        assert_eq!(parts, vec![0..256, 256..768, 768..1000]);
        assert_eq!(blocks_of(&parts, 2), vec![0..2, 2..6, 6..8]);
        let parts = rebalance(Ranks::pretend(1, 3), 300, &[], none, None);
        assert_eq!(parts, vec![0..0, 0..256, 256..300]);
        assert_eq!(blocks_of(&parts, 1), vec![0..0, 0..1, 1..2]);
    }

    /// The halos of a cube of 20³ particles split in two: the ranges are the two halves along
    /// the first axis (the slowest of the cell order), and each needs the other's two layers
    /// nearest to it (the lists reach 2.52 Δp: h = 1.2 Δp and the skin), 800 particles; in
    /// four, the inner quarters need layers either side. Before the first step nothing is
    /// counted, and on one rank its own halo is empty.
    #[test]
    fn a_cube_split_in_slabs_needs_two_layers_of_each_neighbour() {
        let case = crate::deck::parse(&crate::bench::cube_deck(20), "cube.toml").unwrap();
        let mut sim = Simulation::<3>::new(&case).unwrap();
        assert!(sim.halo_census(2, Curve::Cells).is_empty());
        sim.step(f64::INFINITY).unwrap();
        let halo = |own, halo, neighbour_ranks| crate::ranks::Halo {
            own,
            halo,
            neighbour_ranks,
        };
        assert_eq!(sim.halo_census(1, Curve::Cells), vec![halo(8000, 0, 0)]);
        assert_eq!(
            sim.halo_census(2, Curve::Cells),
            vec![halo(4000, 800, 1); 2]
        );
        // Split in four by cost, the outer slabs (cheaper surface particles) are wider and
        // the cuts fall within layers: each side then needs from two to three layers.
        let four = sim.halo_census(4, Curve::Cells);
        assert_eq!(four.iter().map(|h| h.own).sum::<usize>(), 8000);
        for (r, h) in four.iter().enumerate() {
            let sides = if r == 0 || r == 3 { 1 } else { 2 };
            assert_eq!(h.neighbour_ranks, sides, "{four:?}");
            assert!((800 * sides..=1200 * sides).contains(&h.halo), "{four:?}");
        }
        // Morton's curve cuts the cube into two halves as well.
        assert_eq!(
            sim.halo_census(2, Curve::Morton),
            vec![halo(4000, 800, 1); 2]
        );
        assert_eq!(sim.own_halo(), halo(8000, 0, 0));
    }

    /// The rate pass holds the neighbour records that `check`'s memory estimate counts
    /// (`physics::record_bytes`): a ring of a window's, and every particle's once one failed.
    #[test]
    fn the_records_held_are_those_check_estimates() {
        // A cube of 25³ particles (one window: its ring holds every record, rounded up to a
        // power of two) and of 50³ (a window and the slabs beside it).
        for edge in [25, 50] {
            let n = edge * edge * edge;
            let case = crate::deck::parse(&crate::bench::cube_deck(edge), "cube.toml").unwrap();
            let mut sim = Simulation::<3>::new(&case).unwrap();
            sim.step(f64::INFINITY).unwrap();
            let held = sim.rates.record_bytes_held() as f64;
            let estimate = crate::physics::record_bytes(n, 3, false);
            // The padding record beside the ring.
            assert!(
                (held / estimate - 1.0).abs() < 1e-3,
                "{edge}³: {held} for {estimate}"
            );
            // Once a particle has failed, every particle's record (and the padding's).
            sim.particles.damage[0] = 1.0;
            sim.step(f64::INFINITY).unwrap();
            let held = sim.rates.record_bytes_held() as f64;
            let estimate = crate::physics::record_bytes(n, 3, true);
            assert!(
                held <= estimate * (1.0 + 1e-3),
                "{edge}³: {held} for {estimate}"
            );
            assert!(held >= (n * 200) as f64, "{edge}³: {held}");
        }
    }

    /// A step too small to advance the time (here: one particle's sound speed made absurd)
    /// stops the run with the particle that sets it, instead of stepping forever.
    #[test]
    fn a_step_that_does_not_advance_time_stops_the_run() {
        let deck = r#"
[simulation]
dimension = 2
end_time = 2.0
[materials.al]
density = 2700.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }
[[body]]
name = "block"
material = "al"
spacing = 1.0e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [5.0e-3, 5.0e-3] }
"#;
        let case = crate::deck::parse(deck, "stall.toml").unwrap();
        let mut sim = Simulation::<2>::new(&case).unwrap();
        sim.step(f64::INFINITY).unwrap();
        sim.state.time = 1.0;
        sim.particles.c[7] = 1e300;
        let Err(Error::Unstable { cause, .. }) = sim.step(f64::INFINITY) else {
            panic!("the run went on");
        };
        assert!(cause.contains("does not advance the time"), "{cause}");
        assert!(
            cause.contains(&format!("particle {}", sim.particles.id[7])),
            "{cause}"
        );
    }
}
