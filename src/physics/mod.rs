//! The SPH equations of solid dynamics (updated Lagrangian, conventional SPH), evaluated in one
//! gather pass over each real particle's neighbours. Per pair, with x_ij = x_i − x_j,
//! v_ij = v_i − v_j, h_ij = (h_i + h_j)/2 and ∇_i W_ij = (dW/dr) x_ij/r_ij:
//!
//! - continuity: dρ_i/dt = Σ_{j∈N_i} m_j w_ij·∇_i W_ij (CN-SPH: see below)
//! - velocity gradient: L_i = −Σ_{j∈N_i} V_j w_ij ⊗ ∇_i W_ij, w = v + dv the velocity at the
//!   step's middle (`integrate`, "Staggered material update"; every other term takes v)
//! - momentum: dv_i/dt = Σ_{j∈N_i} m_j T_ij ∇_i W_ij + f_c,i/m_i + g,
//!   T_ij = σ_i/ρ_i² + σ_j/ρ_j² − Π_ij I + A_ij, Π_ij the viscosity on the pair's limited
//!   velocity jump ([`viscosity`])
//! - energy: de_i/dt = −½ Σ_{j∈N_i} m_j v_ij·(T_ij ∇_i W_ij), the pairwise form whose sum
//!   Σ m_i de_i/dt is exactly minus the power of the internal forces, so total energy is
//!   conserved by the spatial discretisation (DESIGN.md §2 allows it in place of σ:D/ρ);
//!   plus the lagged correction −½ Σ m_j (u_i − u_j)·(T_ij ∇_i W_ij) (see `integrate`).
//!
//! - density diffusion (`density_diffusion` = δ, default 0): dρ_i/dt += δ Σ_{j∈N_i} h_ij c_ij
//!   ψ_ij·∇_i W_ij V_j, ψ_ij = 2 (ρ_j − ρ_i) x_ji/|x_ji|² (Molteni & Colagrossi 2009, Comput.
//!   Phys. Commun. 180, 861; [`diffusion_term`]), on the plain ∇W in both formulations, as the
//!   viscosity is: it damps the density noise of heavy plastic flow, whose tensile tail a
//!   failure model would read as tension (README, "Failure in heavy plastic flow")
//! - tensor smoothing (`smoothing_shape = "tensor"`): ∇_i W_ij is the ellipsoidal kernel's of
//!   [`asph`], h_ij the pair's h along x_ij (the viscosity's), and the step follows the
//!   ellipsoid's shortest axis
//!
//! N_i are neighbours of the same body or of a `welded` body, and a wall's images of these
//! while pressed against them ([`PairRule::Wall`], see `boundary`); C_i, neighbours of a body
//! in `contact`, enter only through [`crate::contact`] (the paper's W = 0 across bodies).
//!
//! **CN-SPH** (`formulation = "corrected"`): with the corrections B_i of [`correction`], i's
//! continuity and velocity gradient use ∇̃_i W_ij = B_i ∇_i W_ij (so a linear velocity field
//! gives its exact L, at a surface too), and the stresses' pair force is built from both sides,
//! (σ_i/ρ_i²) B_i ∇_i W_ij + (σ_j/ρ_j²) B_j ∇_i W_ij, antisymmetric in i and j: linear momentum
//! is conserved to round-off (3e-15 in the elastic impact), and the pairwise energy equation on
//! the same force keeps the total energy's discretisation error to the time integration's
//! (0.81 % drift in the elastic impact at CFL 0.3, conventional 0.73 %). The pair's work is
//! split so that each particle keeps its own correction's: i takes
//! m_j v_ij·[½ (σ_i/ρ_i² + σ_j/ρ_j²) ∇W + (σ_i/ρ_i²)(B_i − I) ∇W − ½ Π_ij ∇W] and j the
//! rest, so the total is still exactly conservative, and the split is conventional SPH's where
//! B = I. Split in halves, a surface particle's large (σ_j/ρ_j²) B_j ∇W went half to its
//! neighbour: beside the 7 km/s demo's contact rim at Δp = 10 µm it drained neighbours to
//! −2 × 10⁹ J/kg, and a particle ran away at step 689. (Each particle's energy from its own
//! corrected stress alone, the σ_i : D_i/ρ_i of DESIGN.md §2, does that too, but it moved the
//! heat of the plastic strip of `tests/verification_materials.rs` between neighbours and
//! widened its cracks from 24 to 36 failed particles of 300; this split keeps 24.)
//! CN-SPH's continuity is dρ_i/dt = ρ_i Σ_j V_j v_ij·∇̃_i W_ij = −ρ_i tr L_i: the density
//! follows the same consistent velocity gradient as the stress (ρ̇ = −ρ ∇·v exactly for a
//! linear velocity field, also where the density varies). Conventional SPH's mass-weighted
//! Σ m_j v_ij·∇_i W_ij, the derivative of the summation density, weighs each neighbour's
//! velocity by ρ_j/ρ_i; with B's gain on top, a particle expanding among denser neighbours (the
//! 7 km/s demo's jet at Δp = 10 µm) had its expansion rate multiplied by its own rarefaction
//! and ran away to 0.014 ρ0 (step 350). B_i, the same for all of i's pairs, is applied once to
//! the sum, L_i = −(Σ_j V_j v_ij ⊗ ∇_i W_ij) B_iᵀ. The viscosity keeps the plain ∇_i W_ij: it
//! is a dissipation, not a consistency term, and a pair's B_j would cost the pass nine more
//! loads. (σ/ρ²) B is formed once per particle, so that a pair costs CN-SPH nine more products
//! than conventional SPH (the energy split's); and the correction pass, which tests every
//! entry of a particle's list against the support anyway, hands the rate pass the entries
//! inside ([`correction::Support`]), so that CN-SPH's rate pass skips the filter that is 30 %
//! of the conventional one. Angular momentum is not conserved exactly in either formulation.
//! The contact acts along the contact normal from the boundary particles (see
//! [`colour::states`]), with either contact law.

pub mod artificial_stress;
pub mod asph;
pub mod correction;
pub mod viscosity;

use crate::case::Formulation;
use crate::contact::colour::{self, ColourLaw, ColourStates};
use crate::contact::{self, ContactLaw, ContactParams};
use crate::kernel::Kernel;
use crate::material::Material;
use crate::neighbors::{NeighborList, PAGE};
use crate::particles::{Particles, Tensor, Vector};
use rayon::prelude::*;
use std::ops::Range;

/// How particles of two bodies interact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairRule {
    /// Through the conservation equations (same body, or welded bodies).
    Conserve,
    /// Through the contact force only.
    Contact(ContactParams),
    /// A body and a wall's image of itself or of a body welded to it (`boundary`): through the
    /// conservation equations while the pair is pressed together, not at all while it pulls
    /// apart.
    Wall,
}

/// The rule for every ordered pair of bodies (symmetric).
#[derive(Debug, Clone, Default)]
pub struct PairTable {
    n: usize,
    rules: Vec<PairRule>,
}

impl PairTable {
    /// All distinct bodies in contact with `params(a, b)`, each body conserving with itself.
    pub fn new(n: usize, mut params: impl FnMut(usize, usize) -> PairRule) -> Self {
        let mut rules = vec![PairRule::Conserve; n * n];
        for a in 0..n {
            for b in a + 1..n {
                let r = params(a, b);
                rules[a * n + b] = r;
                rules[b * n + a] = r;
            }
        }
        PairTable { n, rules }
    }

    #[inline(always)]
    pub fn rule(&self, a: u32, b: u32) -> &PairRule {
        &self.rules[a as usize * self.n + b as usize]
    }

    pub fn bodies(&self) -> usize {
        self.n
    }

    /// Whether any pair of distinct bodies has a rule satisfying `f`.
    pub fn any(&self, f: impl Fn(&PairRule) -> bool) -> bool {
        (0..self.n).any(|a| (0..self.n).any(|b| a != b && f(&self.rules[a * self.n + b])))
    }
}

/// Everything the equations need that is not particle state.
#[derive(Debug)]
pub struct Model<const D: usize> {
    pub materials: Vec<Material>,
    /// Material index of each body.
    pub body_material: Vec<usize>,
    /// Prescribed velocity of each body (None: free).
    pub body_prescribed: Vec<Option<Vector<D>>>,
    pub pairs: PairTable,
    pub alpha: f64,
    pub beta: f64,
    /// The viscosity's limiter κ ([`viscosity::limited`]; 0: off).
    pub limiter: f64,
    pub gravity: Vector<D>,
    pub cfl: f64,
    /// h0 / Δp.
    pub smoothing_ratio: f64,
    pub h_min_ratio: f64,
    pub h_max_ratio: f64,
    /// The most h grows with the material's stretch (see `integrate::smoothing_length`).
    pub smoothing_stretch: f64,
    /// δ of the density diffusion (module doc; 0: none).
    pub density_diffusion: f64,
    /// Whether the kernel follows the stretch as an ellipsoid ([`asph`]). Conventional SPH
    /// only, which the deck checks: the pass takes the round kernel in CN-SPH.
    pub tensor_smoothing: bool,
    /// The colour contact law's tables, where a pair of bodies uses it.
    pub colour: Option<ColourLaw>,
    /// Conventional SPH, or CN-SPH's corrected gradients.
    pub formulation: Formulation,
    /// The planes that meet some body as a rigid wall (their pairs' share:
    /// [`crate::boundary::wall_share`]).
    pub walls: Vec<crate::boundary::Plane>,
}

impl<const D: usize> Model<D> {
    pub fn material_of(&self, body: u32) -> &Material {
        &self.materials[self.body_material[body as usize]]
    }
}

/// The share of the pair of i and a wall's image j the pass counts
/// ([`crate::boundary::wall_share`]).
#[inline]
fn wall_share<const D: usize>(model: &Model<D>, gi: &Gather<D>, gj: &Gather<D>) -> f64 {
    crate::boundary::wall_share(&model.walls, gj.body, (&gi.x, gi.dp), (&gj.x, gj.dp))
}

/// How the bodies of a model meet, as the colour law asks.
struct BodyPairs<'a, const D: usize>(&'a Model<D>);

impl<const D: usize> colour::Meeting for BodyPairs<'_, D> {
    fn colour(&self, a: u32, b: u32) -> bool {
        matches!(self.0.pairs.rule(a, b), PairRule::Contact(c) if c.law == ContactLaw::Colour)
    }

    fn contact(&self, a: u32, b: u32) -> bool {
        matches!(self.0.pairs.rule(a, b), PairRule::Contact(_))
    }

    fn welded(&self, a: u32, b: u32) -> bool {
        matches!(self.0.pairs.rule(a, b), PairRule::Conserve)
    }

    fn material(&self, b: u32) -> (usize, &Material) {
        let k = self.0.body_material[b as usize];
        (k, &self.0.materials[k])
    }
}

/// Whether the pass needs [`colour_states`]: where a pair of bodies uses the colour law, and
/// in CN-SPH where any pair of bodies is in contact (its contact acts along their normals).
pub fn needs_colour_states<const D: usize>(model: &Model<D>) -> bool {
    model.colour.is_some()
        || (model.formulation == Formulation::Corrected
            && model.pairs.any(|r| matches!(r, PairRule::Contact(_))))
}

/// The colour-law state of the real particles in `owned` (`out[i]`, see [`colour::states`]);
/// nothing where [`needs_colour_states`] says so. `surfaces`: CN-SPH's surface indicator and
/// corrections of every particle, ghosts included. Ghosts take their sources' (see `boundary`).
pub fn colour_states<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    (surfaces, owned): (Option<colour::Surfaces<D>>, &Range<usize>),
    out: &mut ColourStates,
) {
    if needs_colour_states(model) {
        let law = model.colour.as_ref();
        colour::states(
            kernel,
            p,
            nl,
            &BodyPairs(model),
            (law, surfaces),
            owned,
            out,
        );
    } else {
        out.clear();
    }
}

/// CN-SPH's gradient correction of the real particles in `owned` (`out[i]`, see
/// [`correction`]), over its own body and the bodies welded to it, and B at a face in contact
/// through the colour law over the facing body too ([`correction::Counts::Facing`]); returns
/// how many of them kept the uncorrected gradient.
pub fn corrections<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    owned: &Range<usize>,
    out: &mut Vec<correction::Correction<D>>,
) -> usize {
    use correction::Counts;
    // A wall's image counts as the body's own while it and i are pressed together, as a
    // symmetry plane's ghost does; once the face lifts off, the rate pass leaves the image out
    // ([`pressed`], on the same records), and so does B: B's moments are then the free
    // surface's, and the corrected gradient stays exact for a linear field there.
    let ratio = model.smoothing_ratio;
    let counts = |i: usize, j: usize| {
        let (a, b) = (p.body[i], p.body[j]);
        if a == b {
            return Counts::Body;
        }
        match model.pairs.rule(a, b) {
            PairRule::Conserve => Counts::Body,
            PairRule::Wall => {
                let (gi, gj) = (Gather::of(p, i, ratio), Gather::of(p, j, ratio));
                let xij: [f64; D] = std::array::from_fn(|k| gi.x[k] - gj.x[k]);
                match pressed(&gi, &gj, &xij).then(|| wall_share(model, &gi, &gj)) {
                    Some(1.0) => Counts::Body,
                    Some(share) if share > 0.0 => Counts::Share(share),
                    _ => Counts::Not,
                }
            }
            // The colour law's traction stands in for the facing body's missing neighbours
            // (see `Counts::Facing`); the paper's form keeps the paper's CN-SPH, W = 0
            // across bodies in B too.
            PairRule::Contact(c) if c.law == ContactLaw::Colour => Counts::Facing,
            PairRule::Contact(_) => Counts::Not,
        }
    };
    // The tensor smoothing length's metrics, as the rate pass takes them ([`asph`]).
    let metric: Vec<asph::Metric> = if model.tensor_smoothing {
        let s = model.smoothing_stretch;
        (0..p.len())
            .into_par_iter()
            .map(|i| asph::Metric::of(&p.stretch[i], p.h[i], s))
            .collect()
    } else {
        Vec::new()
    };
    correction::corrections(kernel, p, nl, counts, owned, out, &metric)
}

/// Rates of change and per-particle diagnostics of one real particle, from one pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleRates<const D: usize> {
    /// dv/dt (m/s²), contact and gravity included.
    pub acc: Vector<D>,
    /// dρ/dt.
    pub drho: f64,
    /// de/dt.
    pub de: f64,
    /// Lagged energy correction of the last step (J/kg), added to e as it is.
    pub de_lag: f64,
    /// Velocity gradient L = ∂v/∂x.
    pub grad_v: Tensor<D>,
    /// Half the contact potential of each of the particle's contact pairs (J): the sum over
    /// particles is Φ.
    pub contact_energy: f64,
    /// Stable time step of the particle (s).
    pub dt: f64,
    /// Smallest r_ij/Δp_avg to a neighbour of another body, in contact or welded (∞ if none):
    /// the no-mixing diagnostic.
    pub min_interbody_gap: f64,
    /// Neighbours within the support (the list may hold more, see `neighbors`).
    pub neighbors: u32,
}

/// A placeholder, for the particles another rank evaluates (see `ranks`).
impl<const D: usize> Default for ParticleRates<D> {
    fn default() -> Self {
        ParticleRates {
            acc: Vector::zeros(),
            drho: 0.0,
            de: 0.0,
            de_lag: 0.0,
            grad_v: Tensor::zeros(),
            contact_energy: 0.0,
            dt: f64::INFINITY,
            min_interbody_gap: f64::INFINITY,
            neighbors: 0,
        }
    }
}

/// The rates of the real particles a pass evaluated, indexed by particle (`rates[i]` for `i` in
/// [`OwnRates::range`]): every real particle on one process, an MPI rank's own range under
/// MPI, which keeps no record of the particles the other ranks advance (152 bytes a particle
/// in 3D; until 2026-12-01 every rank held every particle's, and all-gathered them at each
/// full search for the neighbour counts that weigh the ranges).
#[derive(Debug, Default, Clone)]
pub struct OwnRates<const D: usize> {
    first: usize,
    rates: Vec<ParticleRates<D>>,
}

impl<const D: usize> OwnRates<D> {
    /// Every real particle's rates, `rates[i]` for particle `i`.
    pub fn whole(rates: Vec<ParticleRates<D>>) -> Self {
        OwnRates { first: 0, rates }
    }

    /// The particles whose rates are held.
    pub fn range(&self) -> Range<usize> {
        self.first..self.first + self.rates.len()
    }

    /// The rates held, in particle order from `range().start`.
    pub fn as_slice(&self) -> &[ParticleRates<D>] {
        &self.rates
    }

    /// Hold the rates of `range` (their values are the next pass's to write).
    fn hold(&mut self, range: Range<usize>) {
        self.first = range.start;
        self.rates.resize(range.len(), ParticleRates::default());
    }

    /// The rates of the particles `range` (within [`OwnRates::range`]).
    fn slice_mut(&mut self, range: Range<usize>) -> &mut [ParticleRates<D>] {
        &mut self.rates[range.start - self.first..range.end - self.first]
    }
}

impl<const D: usize> std::ops::Index<usize> for OwnRates<D> {
    type Output = ParticleRates<D>;

    #[inline]
    fn index(&self, i: usize) -> &ParticleRates<D> {
        &self.rates[i - self.first]
    }
}

/// The pass's output (one record per real particle evaluated) and its work buffers.
#[derive(Debug, Default, Clone)]
pub struct Rates<const D: usize> {
    pub particles: OwnRates<D>,
    /// The contact force f_c (N) on each real particle (at least; the pass writes the first
    /// `n_real`). The simulation lends the particles' own array
    /// ([`crate::particles::Particles::contact_force`]) here for the pass and takes it back
    /// after, so that the force is kept once (24 bytes a particle in 3D), not in both.
    pub contact_force: Vec<Vector<D>>,
    /// What the pass reads of each neighbour, packed into one record so that a neighbour costs
    /// few cache lines: the records of the real particles the window in hand needs (see
    /// [`Records`]).
    gather: Vec<Gather<D>>,
    /// The records of the ghosts and the padding ([`Records`]).
    tail: Vec<Gather<D>>,
    /// Per-particle artificial stress R (an entry for every particle, ghosts included, and a
    /// zero at the end for the padding; current for the particles the pass reads, see
    /// [`fill_read`]; empty when no material uses it).
    art: Vec<Tensor<D>>,
    /// (σ/ρ²) B per particle (CN-SPH; ghosts included, and a zero for the padding, current for
    /// the particles the pass reads as `art`; empty in conventional SPH): the particle's side
    /// of the pair force,
    /// (σ_i/ρ_i²) B_i ∇W + (σ_j/ρ_j²) B_j ∇W. Apart from B, which only the particle itself
    /// reads (from the caller's array), so that a neighbour costs 9 numbers, not 18.
    sb: Vec<Matrix<D>>,
    /// Each particle's kernel metric ([`asph`]; ghosts included and the padding's, current for
    /// the particles the pass reads as `art`; empty with the round kernel).
    metric: Vec<asph::Metric>,
    /// The failed particles that may sever each particle's pairs (empty where none has failed).
    cracks: CrackLists<D>,
}

impl<const D: usize> Rates<D> {
    /// Bytes of neighbour records the last pass held (the window's ring and the records by
    /// index), what [`record_bytes`] estimates.
    pub fn record_bytes_held(&self) -> usize {
        (self.gather.capacity() + self.tail.capacity()) * std::mem::size_of::<Gather<D>>()
    }
}

/// A D × D matrix in plain arrays (row-major), as the pass reads it.
type Matrix<const D: usize> = [[f64; D]; D];

fn matrix<const D: usize>(m: &Tensor<D>) -> Matrix<D> {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

/// The pass goes over the real particles this many pages ([`PAGE`] particles) at a time at
/// least, in at most [`WINDOWS`] windows, with the neighbour records of only the particles a
/// window's lists name in memory (see [`Records`]): 200 bytes a particle in 3D for all of
/// them, a sixth of a run's memory, against those of a window and of the slabs of cells
/// either side of it (the particles are in cell order, the last axis fastest, so that a
/// neighbour lies at most two slabs away: `neighbors`). A record is built once a pass and
/// kept while the next window still needs it.
const WINDOW_PAGES: usize = 128;
/// See [`WINDOW_PAGES`].
const WINDOWS: usize = 64;

/// The neighbour records of the pass, by particle index: those of the real particles
/// `lo..lo + len` (the range the window in hand needs, see [`WINDOW_PAGES`]), record k in
/// entry k mod `ring.len()` of a ring (a power of two at least `len` long, so that the next
/// window keeps the records it shares with this one where they are), and those of the ghosts
/// from `split` (the number of real particles) on, with the [`Gather::padding`] record one
/// past the last ghost. The records are the same however many are held, so the pass's results
/// do not depend on the windows. Finding a record costs a subtraction and a mask more than
/// indexing one array of all of them (the comparison is the bounds check's; ghosts are few
/// and the branch predictable), and the pass finds each neighbour's once. Over 42 steps of two
/// cubes of 1728 particles on 1 thread (cachegrind, 2026-11-30) that came to 0.7 % fewer
/// instructions than one array of all the records in conventional SPH and 3.4 % more in
/// CN-SPH (whose marked supports had found each record once already); a page table (a slot
/// per 256 particles) cost 5 % more, and the queue's loops written over indices instead of
/// `step_by` 6 % more: the pass's code generation is that sensitive.
#[derive(Clone, Copy)]
struct Records<'a, const D: usize> {
    ring: &'a [Gather<D>],
    lo: usize,
    len: usize,
    split: usize,
    tail: &'a [Gather<D>],
}

impl<'a, const D: usize> Records<'a, D> {
    /// Records `lo..lo + len` held in `ring` (of a power-of-two length at least `len`), and
    /// from `split` on in `tail`.
    fn new(
        ring: &'a [Gather<D>],
        (lo, len): (usize, usize),
        split: usize,
        tail: &'a [Gather<D>],
    ) -> Self {
        assert!(len == 0 || (ring.len().is_power_of_two() && len <= ring.len()));
        Records {
            ring,
            lo,
            len,
            split,
            tail,
        }
    }

    /// The records of particles 0, 1, … in one slice.
    #[cfg(test)]
    fn whole(records: &'a [Gather<D>]) -> Self {
        Records {
            ring: &[],
            lo: 0,
            len: 0,
            split: 0,
            tail: records,
        }
    }
}

impl<const D: usize> std::ops::Index<usize> for Records<'_, D> {
    type Output = Gather<D>;

    #[inline(always)]
    fn index(&self, k: usize) -> &Gather<D> {
        // One comparison finds a held real record (below `lo` the difference wraps past
        // every length); anything else must be a ghost's or the padding's.
        if k.wrapping_sub(self.lo) < self.len {
            // SAFETY: where any record is held in the ring, its length is a power of two
            // (`Records::new`).
            unsafe { self.ring.get_unchecked(k & (self.ring.len() - 1)) }
        } else {
            &self.tail[k.wrapping_sub(self.split)]
        }
    }
}

/// Build the records of particles `range` into `out` (one each, in order), the padding
/// record at index `p.len()`.
fn build_records<const D: usize>(
    p: &Particles<D>,
    ratio: f64,
    range: Range<usize>,
    out: &mut [Gather<D>],
) {
    debug_assert_eq!(range.len(), out.len());
    let all = p.len();
    out.par_iter_mut()
        .zip(range.into_par_iter())
        .with_min_len(64)
        .for_each(|(record, k)| {
            *record = if k < all {
                Gather::of(p, k, ratio)
            } else {
                Gather::padding()
            };
        });
}

/// Build the records of real particles `range` into their places in `ring` (record k in entry
/// k mod its power-of-two length, see [`Records`]).
fn build_ring<const D: usize>(
    p: &Particles<D>,
    ratio: f64,
    range: Range<usize>,
    ring: &mut [Gather<D>],
) {
    if range.is_empty() {
        return;
    }
    let cap = ring.len();
    debug_assert!(range.len() <= cap);
    let at = range.start & (cap - 1);
    // Up to the ring's end, then on from its start.
    let first = range.len().min(cap - at);
    let (wrapped, from_at) = ring.split_at_mut(at);
    build_records(
        p,
        ratio,
        range.start..range.start + first,
        &mut from_at[..first],
    );
    let rest = range.start + first..range.end;
    build_records(p, ratio, rest, &mut wrapped[..range.len() - first]);
}

/// What the pass reads besides the particle's own neighbour list.
#[derive(Clone, Copy)]
struct Pass<'a, const D: usize> {
    gather: Records<'a, D>,
    /// The index of the [`Gather::padding`] record (the number of particles).
    padding: u32,
    cracks: &'a CrackLists<D>,
    art: &'a [Tensor<D>],
    /// The kernel metrics ([`asph`]; empty with the round kernel).
    metric: &'a [asph::Metric],
    /// CN-SPH's B of every particle, ghosts included (empty: conventional SPH).
    corr: &'a [Tensor<D>],
    sb: &'a [Matrix<D>],
    /// CN-SPH: each real particle's correction, whose [`correction::Support`] marks the list entries in
    /// its support (may be empty).
    marks: &'a [correction::Correction<D>],
    /// Whether any particle is fully damaged (pairs with one, or severed by one
    /// ([`CrackLists::severs`]), need [`tension_cut`]).
    any_failed: bool,
    colour: &'a ColourStates,
    /// Pressures (ghosts included): what a pair with a failed member passes on.
    pressure: &'a [f64],
    model: &'a Model<D>,
}

/// Neighbours go through the conservation equations this many at a time, one lane each: the
/// sums are written lane by lane over fixed-size arrays with no branches, which the compiler
/// turns into vector instructions (see [`compute_rates`]). The lane count is fixed, not taken
/// from the machine, so that every machine adds the same numbers in the same order.
const LANES: usize = 4;

/// The step bound of the colour law's backstop, Δt ≤ C · BACKSTOP_STEP · √(m/k), with k the
/// backstop's stiffness now or at where a bulk step would take the pair: two lone particles
/// meeting head-on then part within 0.6 % (±1 km/s) and 0.8 % (±3.5 km/s) of their speed. With
/// the contact springs' factor 2 they lost 4 %, without the look-ahead 8 %.
const BACKSTOP_STEP: f64 = 1.0;

/// `values[i] = of(i)` for the real particles in `read` and the ghosts `n..all`, and `pad` at
/// `all` (the padding record's); `values` is resized to `all + 1` first where it is not that
/// long, and its other entries keep what they held.
fn fill_read<T: Copy + Send + Sync>(
    values: &mut Vec<T>,
    all: usize,
    (read, n): (&Range<usize>, usize),
    of: impl Fn(usize) -> T + Sync,
    pad: T,
) {
    if values.len() != all + 1 {
        values.clear();
        values.reserve_exact(all + 1);
        values.resize(all + 1, pad);
    }
    let (real, ghosts) = values.split_at_mut(n);
    let read = read.start.min(n)..read.end.min(n);
    real[read.clone()]
        .par_iter_mut()
        .zip(read)
        .for_each(|(v, i)| *v = of(i));
    ghosts[..all - n]
        .par_iter_mut()
        .enumerate()
        .for_each(|(k, v)| *v = of(n + k));
    values[all] = pad;
}

/// The bytes of neighbour records the rate pass holds for a store of `n` real particles in
/// cell order, each slab of cells holding n^((D−1)/D) of them (a cube's): while no particle has
/// failed, the ring of one window and the two slabs either side of it, its length a power of
/// two (see `WINDOW_PAGES`); once one has (`failed`), every particle's record. For a few
/// tens of thousands of particles the ring holds them all, rounded up: 210–290 bytes a
/// particle, against 26 at a million in 3D, most of why `check`, with one figure a particle,
/// read the small cases of `strike bench` 17–44 % short (2026-12-02).
pub fn record_bytes(n: usize, dimension: usize, failed: bool) -> f64 {
    let (size, d) = (record_size(dimension), dimension.clamp(2, 3) as f64);
    let window = WINDOW_PAGES.max(n.div_ceil(PAGE).div_ceil(WINDOWS)) * PAGE;
    let slab = (n as f64).powf((d - 1.0) / d) as usize;
    let span = if n <= window {
        n
    } else {
        n.min(window + 4 * slab)
    };
    let ring = span.max(1).next_power_of_two();
    let held = if failed { ring.max(n + 1) } else { ring };
    (held * size) as f64
}

/// Bytes of one particle's neighbour record in the rate pass (200 in 3D, 176 in 2D).
pub fn record_size(dimension: usize) -> usize {
    match dimension {
        2 => std::mem::size_of::<Gather<2>>(),
        _ => std::mem::size_of::<Gather<3>>(),
    }
}

/// In-support neighbours are collected in batches of this many (a multiple of `LANES`) before
/// their sums, on the stack.
const BATCH: usize = 64;

/// A particle as its neighbours see it in the pass, in plain arrays: the pair loop is the
/// hot spot of the code, and fixed-size loops over `D` compile to straight-line arithmetic.
/// What the neighbour filter reads (x, h, body) comes first, in one cache line.
#[derive(Debug, Clone, Copy)]
struct Gather<const D: usize> {
    x: [f64; D],
    h: f64,
    body: u32,
    /// Damage 1: it meets its neighbours only in compression (see below).
    failed: bool,
    /// Initial spacing Δp = h0/ratio.
    dp: f64,
    v: [f64; D],
    /// The lagged energy correction's displacement ([`Particles::u`]), in single precision as
    /// dv and D: all three are corrections, and the record is 200 bytes in 3D (176 before
    /// dv and D; with u in double precision the conventional cubes ran about 5 % slower).
    u: [f32; D],
    m: f64,
    /// V = m/ρ.
    vol: f64,
    rho: f64,
    c: f64,
    /// σ/ρ², its symmetric components in [`SYM`] order (6 loads a neighbour instead of 9).
    sr2: [f64; 6],
    /// v + dv is the velocity of the continuity equation and the velocity gradient
    /// ([`Particles::dv`]).
    dv: [f32; D],
    /// The last step's strain rate D, in [`SYM`] order ([`Particles::strain_rate`]).
    d: [f32; 6],
}

impl<const D: usize> Gather<D> {
    /// Particle i's record (`ratio`: the model's h0/Δp).
    #[inline]
    fn of(p: &Particles<D>, i: usize, ratio: f64) -> Self {
        let sr2 = p.stress(i) / (p.rho[i] * p.rho[i]);
        Gather {
            x: arr(&p.x[i]),
            h: p.h[i],
            body: p.body[i],
            failed: p.damage[i] >= 1.0,
            dp: p.h0[i] / ratio,
            v: arr(&p.v[i]),
            u: std::array::from_fn(|k| p.u[i][k]),
            m: p.m[i],
            vol: p.m[i] / p.rho[i],
            rho: p.rho[i],
            c: p.c[i],
            sr2: std::array::from_fn(|k| {
                let (a, b) = SYM[k];
                if a < D && b < D {
                    sr2[(a, b)]
                } else {
                    0.0
                }
            }),
            dv: std::array::from_fn(|k| p.dv[i][k]),
            d: std::array::from_fn(|k| {
                let (a, b) = SYM[k];
                if a < D && b < D {
                    p.strain_rate[i].get(a, b)
                } else {
                    0.0
                }
            }),
        }
    }

    /// The neighbour that fills the unused lanes of the last chunk: massless, at rest and far
    /// beyond every support, so that all its terms are exactly zero (and finite).
    fn padding() -> Self {
        Gather {
            x: [1e100; D],
            h: 0.0,
            body: u32::MAX,
            failed: false,
            // So that the artificial stress's W(Δp_avg) with any particle is positive (Δp_avg
            // is half the particle's own spacing) and f_ij = W_ij/W(Δp_avg) = 0.
            dp: 0.0,
            v: [0.0; D],
            u: [0.0; D],
            m: 0.0,
            vol: 0.0,
            rho: 1.0,
            c: 0.0,
            sr2: [0.0; 6],
            dv: [0.0; D],
            d: [0.0; 6],
        }
    }
}

/// The components of a symmetric tensor kept in [`Gather::sr2`]: the diagonal, then xy, xz, yz
/// (2D uses xx, yy, xy).
const SYM: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// Where component (a, b) of a symmetric tensor sits in [`SYM`].
#[inline(always)]
const fn sym(a: usize, b: usize) -> usize {
    if a == b {
        a
    } else {
        a + b + 2
    }
}

#[inline(always)]
fn arr<const D: usize>(v: &Vector<D>) -> [f64; D] {
    std::array::from_fn(|k| v[k])
}

#[inline(always)]
fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut s = 0.0;
    for k in 0..D {
        s += a[k] * b[k];
    }
    s
}

/// Evaluate the rates of the real particles in `owned` (`out.particles[i]`) at the particles'
/// current state (positions, velocities `p.v`, stress).
///
/// `fields`: see [`PassFields`] (the colour states come from [`colour::states`], B and the
/// supports from [`correction`]).
pub fn compute_rates<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    fields: PassFields<D>,
    owned: &Range<usize>,
    out: &mut Rates<D>,
) {
    compute_rates_on(
        kernel,
        p,
        nl,
        model,
        fields,
        owned,
        out,
        wide_lanes(),
        WINDOW_PAGES,
    );
}

/// What [`compute_rates`] reads besides the particles: the colour-law state of every particle,
/// ghosts included (empty where no pair of bodies uses the colour law), CN-SPH's B of every
/// particle, ghosts included (empty: conventional SPH), and CN-SPH's corrections of the real
/// particles from the correction pass of the same step, for their [`correction::Support`] (may be empty:
/// the pass then tests the whole list).
pub type PassFields<'a, const D: usize> = (
    &'a ColourStates,
    &'a [Tensor<D>],
    &'a [correction::Correction<D>],
);

/// [`compute_rates`], on 256-bit vectors (`wide`, where [`wide_lanes`]) or portable code, in
/// windows of at least `window` pages (see [`WINDOW_PAGES`]).
#[allow(clippy::too_many_arguments)]
fn compute_rates_on<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    (colour, corr, marks): PassFields<D>,
    owned: &Range<usize>,
    out: &mut Rates<D>,
    wide: bool,
    window: usize,
) {
    let all = p.len();
    let ratio = model.smoothing_ratio;
    let any_art = model
        .materials
        .iter()
        .any(|m| m.artificial_stress.is_some());
    // Whether any pair may need cutting (`cut_pair`), and which failed particles may sever
    // each particle's pairs.
    let any_failed = p.damage.par_iter().any(|&d| d >= 1.0);
    assert!(
        !wide || wide_lanes(),
        "AVX2 pass asked for on a CPU without AVX2"
    );
    // The windows: runs of pages of the real particles evaluated here, and the range of real
    // particles each needs (its own and those its lists name). Where a particle has failed,
    // the crack lists read records by index: one window, every record its lists can name
    // held in `tail` (below).
    let n = p.n_real;
    let range = owned.start.min(n)..owned.end.min(n);
    let (first, last) = (range.start / PAGE, range.end.div_ceil(PAGE));
    let width = if any_failed {
        usize::MAX
    } else {
        window.max((last - first).div_ceil(WINDOWS)).max(1)
    };
    let windows: Vec<Range<usize>> = (first..last)
        .step_by(width.min(last - first).max(1))
        .map(|c| c..c.saturating_add(width).min(last))
        .collect();
    let needs: Vec<Range<usize>> = windows
        .par_iter()
        .map(|w| {
            let (mut lo, mut hi) = (w.start * PAGE, (w.end * PAGE).min(n));
            for c in w.clone() {
                let named = nl.named(c);
                if !named.is_empty() {
                    (lo, hi) = (lo.min(named.start), hi.max(named.end));
                }
            }
            lo..hi
        })
        .collect();
    // The (σ/ρ²) B and artificial stresses of the particles the pass reads: the real ones its
    // windows need (their own and those their lists name) and the ghosts, and a zero for the
    // padding. Under MPI the rest of each array keeps what it held, which nothing reads; until
    // 2026-12-02 every rank built both for every particle at each pass.
    let read = needs
        .iter()
        .fold(range.clone(), |a, r| a.start.min(r.start)..a.end.max(r.end));
    let cn = !corr.is_empty();
    if cn {
        assert_eq!(
            corr.len(),
            all,
            "a correction for every particle, ghosts included"
        );
        let sb_of = |i: usize| matrix(&(p.stress(i) / (p.rho[i] * p.rho[i]) * corr[i]));
        fill_read(
            &mut out.sb,
            all,
            (&read, n),
            sb_of,
            matrix(&Tensor::<D>::zeros()),
        );
    } else {
        out.sb.clear();
    }
    if any_art {
        // In CN-SPH the artificial stress's side of the pair force is R B, as the stress's.
        let art_of = |i: usize| {
            let r = match model.material_of(p.body[i]).artificial_stress {
                Some(eps) => artificial_stress::tensor(&p.stress(i), p.rho[i], eps),
                None => Tensor::<D>::zeros(),
            };
            if cn {
                r * corr[i]
            } else {
                r
            }
        };
        fill_read(&mut out.art, all, (&read, n), art_of, Tensor::<D>::zeros());
    } else {
        out.art.clear();
    }
    if model.tensor_smoothing {
        let s = model.smoothing_stretch;
        let metric_of = |i: usize| asph::Metric::of(&p.stretch[i], p.h[i], s);
        fill_read(
            &mut out.metric,
            all,
            (&read, n),
            metric_of,
            asph::Metric::NONE,
        );
    } else {
        out.metric.clear();
    }
    // Where a particle has failed, there is one window: its need's records go to `tail`, and
    // it holds none in the ring.
    let in_tail = if any_failed {
        needs.first().cloned().unwrap_or(0..0)
    } else {
        0..0
    };
    let span = needs.iter().map(|r| r.len()).max().unwrap_or(0);
    let Rates {
        particles,
        contact_force,
        gather,
        tail,
        art,
        sb,
        metric,
        cracks,
    } = out;
    // The ring keeps its size from pass to pass while the need does not change much (what it
    // holds is built again at every pass). Where a particle has failed, every record is in
    // `tail` instead, by index.
    let split = if any_failed { 0 } else { n };
    let cap = if any_failed {
        0
    } else {
        span.next_power_of_two()
    };
    if gather.len() != cap {
        *gather = Vec::new();
        gather.reserve_exact(cap);
        gather.resize(cap, Gather::padding());
    }
    if tail.len() != all + 1 - split {
        tail.clear();
        tail.reserve_exact(all + 1 - split);
        tail.resize(all + 1 - split, Gather::padding());
    }
    if any_failed {
        // Only the records the evaluated lists can name: the pass and the crack lists read
        // those of i and of the particles its list names, never another's. Under MPI that is a
        // rank's own range and the span its lists reach (`named`), with the ghosts; the rest
        // of `tail` keeps whatever it held, which nothing reads. Until 2026-12-02 every rank
        // built every particle's record at each pass once one had failed.
        build_records(p, ratio, in_tail.clone(), &mut tail[in_tail]);
        build_records(p, ratio, n..all + 1, &mut tail[n..]);
    } else {
        build_records(p, ratio, split..all + 1, tail);
    }
    particles.hold(range.clone());
    if contact_force.len() < n {
        contact_force.resize(n, Vector::zeros());
    }
    if !any_failed {
        *cracks = CrackLists::default();
    }
    // The real records held.
    let mut held = 0..0;
    for (w, need) in windows.iter().zip(&needs) {
        let need = if any_failed { 0..0 } else { need.clone() };
        // What the last window held and this one needs stays where it is; the rest is built.
        if need.start >= held.start && need.start < held.end {
            build_ring(p, ratio, held.end.max(need.start)..need.end, gather);
        } else {
            build_ring(p, ratio, need.clone(), gather);
        }
        held = need.clone();
        let records = Records::new(gather, (need.start, need.len()), split, tail);
        if any_failed {
            // One window, every record in `tail`.
            debug_assert_eq!(windows.len(), 1);
            cracks.build(n, records, &p.damage, &p.p, nl, model, wide);
        }
        let pass = Pass {
            gather: records,
            padding: all as u32,
            cracks,
            art,
            metric,
            corr,
            sb,
            marks,
            any_failed,
            colour,
            pressure: &p.p,
            model,
        };
        let evaluated = (w.start * PAGE).max(range.start)..(w.end * PAGE).min(range.end);
        let start = evaluated.start;
        // One monomorphised pass per (artificial stress, CN-SPH, density diffusion)
        // combination, on AVX2 or portable: switched off, the diffusion costs the pass nothing
        // (computed in every build it added 5 % of the instructions of a Taylor rod's step).
        macro_rules! run {
            ($art:literal, $cn:literal, $diff:literal, $ell:literal) => {
                particles
                    .slice_mut(evaluated.clone())
                    .par_iter_mut()
                    .zip(&mut contact_force[evaluated.clone()])
                    .enumerate()
                    .for_each_init(Vec::new, |list, (k, (o, f))| {
                        // The thread's own copy of the pass's slices, read at every
                        // neighbour: the shared one sits in the calling thread's stack, whose
                        // lines that thread keeps writing (false sharing cost the 2-thread
                        // cubes 20 % in some builds).
                        let pass = pass;
                        let i = start + k;
                        // The list unpacked into the job's own buffer.
                        nl.list(i).unpack_into(list);
                        #[cfg(target_arch = "x86_64")]
                        if wide {
                            // SAFETY: the CPU has AVX2 (asserted above).
                            unsafe {
                                particle_rates_avx2::<D, K, $art, $cn, $diff, $ell>(
                                    kernel,
                                    i,
                                    list,
                                    &pass,
                                    (o, f),
                                )
                            };
                            return;
                        }
                        particle_rates::<D, K, $art, $cn, $diff, $ell>(
                            kernel,
                            i,
                            list,
                            &pass,
                            (o, f),
                        )
                    })
            };
        }
        match (
            any_art,
            cn,
            model.density_diffusion > 0.0,
            model.tensor_smoothing,
        ) {
            (false, false, false, false) => run!(false, false, false, false),
            (true, false, false, false) => run!(true, false, false, false),
            (false, true, false, false) => run!(false, true, false, false),
            (true, true, false, false) => run!(true, true, false, false),
            (false, false, true, false) => run!(false, false, true, false),
            (true, false, true, false) => run!(true, false, true, false),
            (false, true, true, false) => run!(false, true, true, false),
            (true, true, true, false) => run!(true, true, true, false),
            (false, false, false, true) => run!(false, false, false, true),
            (true, false, false, true) => run!(true, false, false, true),
            (false, false, true, true) => run!(false, false, true, true),
            (false, true, false, true) => run!(false, true, false, true),
            (true, true, false, true) => run!(true, true, false, true),
            (false, true, true, true) => run!(false, true, true, true),
            (true, false, true, true) => run!(true, false, true, true),
            (true, true, true, true) => run!(true, true, true, true),
        }
    }
}

/// Whether the CPU has 256-bit vectors (AVX2), so that the pass can run its `LANES` lanes in
/// one register instead of two. Both builds add the same numbers in the same order (no fused
/// multiply-adds: Rust never contracts a·b + c), so the results are bit-identical.
pub(crate) fn wide_lanes() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// [`particle_rates`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn particle_rates_avx2<
    const D: usize,
    K: Kernel,
    const ART: bool,
    const CN: bool,
    const DIFF: bool,
    const ELL: bool,
>(
    kernel: K,
    i: usize,
    neighbors: &[u32],
    pass: &Pass<D>,
    out: (&mut ParticleRates<D>, &mut Vector<D>),
) {
    particle_rates::<D, K, ART, CN, DIFF, ELL>(kernel, i, neighbors, pass, out)
}

/// The conservation sums of one particle, one accumulator per lane (added up in lane order at
/// the end).
struct LaneSums<const D: usize> {
    acc: [[f64; LANES]; D],
    grad_v: [[[f64; LANES]; D]; D],
    drho: [f64; LANES],
    /// The density diffusion's sum (before δ).
    diff: [f64; LANES],
    de: [f64; LANES],
    de_lag: [f64; LANES],
    mu_max: [f64; LANES],
    v2_max: [f64; LANES],
}

impl<const D: usize> LaneSums<D> {
    fn new() -> Self {
        LaneSums {
            acc: [[0.0; LANES]; D],
            grad_v: [[[0.0; LANES]; D]; D],
            drho: [0.0; LANES],
            diff: [0.0; LANES],
            de: [0.0; LANES],
            de_lag: [0.0; LANES],
            mu_max: [0.0; LANES],
            v2_max: [0.0; LANES],
        }
    }
}

#[inline(always)]
fn lane_sum(a: &[f64; LANES]) -> f64 {
    a.iter().sum()
}

#[inline(always)]
fn lane_max(a: &[f64; LANES]) -> f64 {
    a.iter().copied().fold(0.0, f64::max)
}

/// One real particle's sums over its neighbours (see the module doc for the equations).
///
/// A first loop sorts the neighbour list: those beyond the support are dropped, those in
/// contact get eq. (5) at once (few: only at interfaces), and the rest are queued, without a
/// branch, for the conservation equations, which [`conserve_chunk`] evaluates `LANES` at a
/// time. The last chunk is filled up with the padding record. The rates are written into `out`,
/// the contact force into `contact_force` (the particle's entry of the array the simulation
/// lends the pass, see [`Rates::contact_force`]).
#[inline(always)]
fn particle_rates<
    const D: usize,
    K: Kernel,
    const ART: bool,
    const CN: bool,
    const DIFF: bool,
    const ELL: bool,
>(
    kernel: K,
    i: usize,
    neighbors: &[u32],
    pass: &Pass<D>,
    (out, contact_force): (&mut ParticleRates<D>, &mut Vector<D>),
) {
    let Pass {
        gather,
        colour,
        model,
        ..
    } = *pass;
    let gi = &gather[i];
    let (xi, hi, bi) = (gi.x, gi.h, gi.body);
    let padding = pass.padding;

    let mut sums = LaneSums::<D>::new();
    let mut fc = [0.0; D];
    let mut phi = 0.0;
    let mut k_contact = 0.0;
    let mut v2_contact = 0.0_f64;
    let mut gap = f64::INFINITY;
    let (mut de_contact, mut de_lag_contact, mut mu_contact) = (0.0, 0.0, 0.0_f64);
    let (mut k_backstop, mut k_ahead) = (0.0, 0.0_f64);
    let mut count = 0u32;
    let mut queue = [padding; BATCH];
    // The queued neighbours' records, found once (finding one costs: see `Records`).
    let pad = &gather[padding as usize];
    let mut records = [pad; BATCH];
    let mut queued = 0;

    // Neighbour j (record gj) into the queue (where `inside`), and the queue through the sums
    // when full.
    macro_rules! queue {
        ($j:expr, $gj:expr, $inside:expr) => {
            queue[queued] = $j;
            records[queued] = $gj;
            queued += $inside as usize;
            if queued == BATCH {
                for c in (0..BATCH).step_by(LANES) {
                    let (js, gs) = (&queue[c..c + LANES], &records[c..c + LANES]);
                    conserve_chunk::<D, K, ART, CN, DIFF, ELL>(
                        kernel,
                        (i, gi),
                        (js, gs),
                        pass,
                        &mut sums,
                    );
                }
                count += BATCH as u32;
                queued = 0;
            }
        };
    }
    // Pairs with a failed member, or severed by one, and what they take out of i's sums
    // ([`cut_pair`]; only where any particle has failed). A pair of two failed particles has
    // nothing to cut: neither carries tension or a deviator, so each side's σ/ρ² + max(p, 0)/ρ²
    // is zero to the bit, and neither is intact to lose its kinematics; only the artificial
    // stress, where it is on, is left to take out.
    let mut cuts = Cut::<D>::default();
    let cuttable = |gj: &Gather<D>| {
        if gi.failed {
            !gj.failed || ART
        } else {
            gj.failed
        }
    };
    // The pairs with a failed member to cut, queued without a branch on whether j is in the
    // support or has failed; and an intact i's severed pairs, found before the pass
    // ([`CrackLists::severed`]). Both are cut in list order, which is the neighbours' index
    // order (the same sums as cutting each at once).
    let severed = pass.cracks.severed(i);
    let mut met = 0;
    let mut cut_queue = [0u32; BATCH];
    let mut cut_queued = 0;
    // The queued pairs, and the severed pairs with a neighbour below `upto`.
    macro_rules! cut_before {
        ($upto:expr) => {
            cut_in_order::<D, K, CN, ELL>(
                kernel,
                i,
                (&cut_queue[..cut_queued], severed, &mut met, $upto),
                pass,
                &mut cuts,
            )
        };
    }

    // Neighbour j (record gj) into the queue of pairs to cut, where it is one (`inside`).
    macro_rules! cut_queue {
        ($j:expr, $gj:expr, $inside:expr) => {
            if pass.any_failed {
                cut_queue[cut_queued] = $j;
                cut_queued += ($inside & cuttable($gj)) as usize;
                if cut_queued == BATCH {
                    cut_before!($j + 1);
                    cut_queued = 0;
                }
            }
        };
    }

    // CN-SPH: the correction pass has marked the list's entries in the support (a particle
    // with neighbours of its own body only): they are queued in list order, as the filter
    // below would queue them, with no test.
    let marked = if CN {
        pass.marks.get(i).and_then(|c| c.support)
    } else {
        None
    };
    if let Some(mask) = marked {
        for (w, &word) in mask.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let j = neighbors[64 * w + bits.trailing_zeros() as usize];
                bits &= bits - 1;
                cut_queue!(j, &gather[j as usize], true);
                queue!(j, &gather[j as usize], true);
            }
        }
    }
    // Otherwise the whole list, skin included, through the filter.
    let unmarked = if marked.is_some() { &[][..] } else { neighbors };
    for &j in unmarked {
        let gj = &gather[j as usize];
        let xij: [f64; D] = std::array::from_fn(|k| xi[k] - gj.x[k]);
        let r2 = dot(&xij, &xij);
        let support = hi + gj.h;
        let inside = r2 < support * support && r2 > 0.0;
        if gj.body != bi {
            let rule = model.pairs.rule(bi, gj.body);
            if let PairRule::Wall = rule {
                // A wall's image: a neighbour of the same body while pressed (see `pressed`),
                // from when the pair touches the wall (`boundary::wall_share`).
                if !(inside && pressed(gi, gj, &xij)) {
                    continue;
                }
                let share = wall_share(model, gi, gj);
                if share == 0.0 {
                    continue;
                }
                if share < 1.0 {
                    // Coming into touch: summed at once (rare), and cut as any pair is.
                    cut_queue!(j, gj, inside);
                    wall_pair::<D, K, ART, CN, DIFF, ELL>(
                        kernel,
                        (i, gi),
                        (j, gj),
                        share,
                        pass,
                        &mut sums,
                    );
                    count += 1;
                    continue;
                }
            } else if inside {
                gap = gap.min(r2.sqrt() / (0.5 * (gi.dp + gj.dp)));
            }
            if let PairRule::Contact(params) = rule {
                let vij: [f64; D] = std::array::from_fn(|k| gi.v[k] - gj.v[k]);
                match params.law {
                    ContactLaw::Paper => {
                        if !inside {
                            continue;
                        }
                        let r = r2.sqrt();
                        let hij = 0.5 * support;
                        let gf = kernel.grad_factor::<D>(r, hij);
                        let (coef, pot, k) =
                            contact::pair::<D, K>(kernel, params, gi.vol, gj.vol, r, hij, gf * r);
                        let f: [f64; D] = std::array::from_fn(|a| xij[a] * gf * coef);
                        if CN {
                            // CN-SPH: along the contact normal (n̂ from i's body into j's),
                            // pushing i back into its body or not at all.
                            let n = colour::normal(&colour[i], &colour[j as usize], &xij, r, hij);
                            let push = dot(&f, &n).min(0.0);
                            for a in 0..D {
                                fc[a] += push * n[a];
                            }
                        } else {
                            for a in 0..D {
                                fc[a] += f[a];
                            }
                        }
                        phi += 0.5 * pot;
                        k_contact += k;
                    }
                    ContactLaw::Colour => {
                        // The colour law acts over the reference support 2 h0_ij.
                        let h0 = 0.5 * model.smoothing_ratio * (gi.dp + gj.dp);
                        if r2 >= 4.0 * h0 * h0 || r2 == 0.0 {
                            continue;
                        }
                        let r = r2.sqrt();
                        let vol0 = (
                            gi.m / model.material_of(bi).rho0,
                            gj.m / model.material_of(gj.body).rho0,
                        );
                        // The pair's states, found once (each a slot and an entry).
                        let (si, sj) = (&colour[i], &colour[j as usize]);
                        let (f, k) = colour::pair::<D, K>(
                            kernel,
                            si,
                            sj,
                            &xij,
                            r,
                            vol0,
                            h0,
                            // CN-SPH: along the contact normal only (frictionless).
                            if CN {
                                0.0
                            } else {
                                colour::tangential_share(si, sj)
                            },
                        );
                        for a in 0..D {
                            fc[a] += f[a];
                        }
                        k_contact += k;
                        if let Some(law) = &model.colour {
                            let (ka, kb) = (
                                model.body_material[bi as usize],
                                model.body_material[gj.body as usize],
                            );
                            let backstop = |r: f64| {
                                colour::backstop(
                                    (&law.curves[ka], &law.curves[kb]),
                                    (&model.materials[ka], &model.materials[kb]),
                                    vol0,
                                    r,
                                    0.5 * (gi.dp + gj.dp),
                                )
                            };
                            let (f, pot, k) = backstop(r);
                            for a in 0..D {
                                fc[a] += f * xij[a] / r;
                            }
                            phi += 0.5 * pot;
                            k_backstop += k;
                            // The backstop stiffens steeply from zero: a pair closing on it
                            // would enter in one step taken at its outside stiffness, so the
                            // step is also bounded by the stiffness at where a bulk step would
                            // take it (see BACKSTOP_STEP).
                            let closing = -dot(&vij, &xij) / r;
                            if closing > 0.0 {
                                let ahead = r - closing * model.cfl * hi / (gi.c + closing);
                                k_ahead = k_ahead.max(backstop(ahead.max(0.0)).2);
                            }
                        }
                        let (t, mu) = colour::damping::<D, K>(
                            kernel,
                            si,
                            sj,
                            &xij,
                            r,
                            h0,
                            &vij,
                            (0.5 * (gi.c + gj.c), 0.5 * (gi.rho + gj.rho)),
                            model.beta,
                        );
                        let (mut vt, mut ut) = (0.0, 0.0);
                        for a in 0..D {
                            fc[a] += gi.m * gj.m * t[a];
                            vt += vij[a] * t[a];
                            ut += (f64::from(gi.u[a]) - f64::from(gj.u[a])) * t[a];
                        }
                        de_contact -= 0.5 * gj.m * vt;
                        de_lag_contact -= 0.5 * gj.m * ut;
                        mu_contact = mu_contact.max(-mu);
                    }
                }
                count += inside as u32;
                // Bodies closing on each other bound the step like any neighbour (below).
                if inside {
                    v2_contact = v2_contact.max(dot(&vij, &vij));
                }
                continue;
            }
            if !inside {
                continue;
            }
        }
        cut_queue!(j, gj, inside);
        // The ellipsoid's pairs beyond its support add nothing ([`asph::within`]).
        let inside = if ELL {
            inside && asph::within(&pass.metric[i].a, &pass.metric[j as usize].a, &xij)
        } else {
            inside
        };
        queue!(j, gj, inside);
    }
    if pass.any_failed {
        cut_before!(u32::MAX);
        debug_assert_eq!(met, severed.len(), "particle {i} cut every severed pair");
    }
    count += queued as u32;
    let used = queued.div_ceil(LANES) * LANES;
    queue[queued..used].fill(padding);
    records[queued..used].fill(pad);
    for c in (0..used).step_by(LANES) {
        let (js, gs) = (&queue[c..c + LANES], &records[c..c + LANES]);
        conserve_chunk::<D, K, ART, CN, DIFF, ELL>(kernel, (i, gi), (js, gs), pass, &mut sums);
    }

    if let Some(own) = colour.get(i) {
        phi += own.energy;
        k_contact +=
            own.curvature * (gi.m / model.material_of(bi).rho0) * own.grad_sum * own.grad_sum;
    }
    let mi = gi.m;
    let ci = gi.c;
    let (alpha, beta) = (model.alpha, model.beta);
    let fc = Vector::<D>::from_fn(|k, _| fc[k]);
    // Time step Δt_i = C h_i / (c_i + max_j |v_ij| + 0.6 (α c_i + β max_j |μ_ij|)) (Monaghan
    // 1992), and the contact springs (ω² = Σk/m, leapfrog stable for ω Δt < 2). DESIGN.md's
    // |v_i| is taken as the largest speed relative to a neighbour, its Galilean-invariant form:
    // a body flying at 7 km/s in one piece needs no shorter step, two meeting at 7 km/s do.
    let v_max = lane_max(&sums.v2_max).max(v2_contact).sqrt();
    let signal = ci + v_max + 0.6 * (alpha * ci + beta * lane_max(&sums.mu_max).max(mu_contact));
    // The ellipsoid's shortest half-axis bounds the step ([`asph`]).
    let h_step = if ELL { pass.metric[i].h_min } else { hi };
    let mut dt = model.cfl * h_step / signal;
    if k_contact > 0.0 {
        dt = dt.min(model.cfl * 2.0 * (mi / k_contact).sqrt());
    }
    let k_backstop = k_backstop.max(k_ahead);
    if k_backstop > 0.0 {
        dt = dt.min(model.cfl * BACKSTOP_STEP * (mi / k_backstop).sqrt());
    }
    let acc = Vector::<D>::from_fn(|k, _| lane_sum(&sums.acc[k]) + cuts.acc[k]);
    let grad_v = Tensor::<D>::from_fn(|a, b| lane_sum(&sums.grad_v[a][b]) + cuts.grad_v[a][b]);
    let (drho, grad_v) = if CN {
        finish_corrected(&pass.corr[i], gi.rho, &grad_v)
    } else {
        (lane_sum(&sums.drho) + cuts.drho, grad_v)
    };
    let drho = if DIFF {
        drho + model.density_diffusion * (lane_sum(&sums.diff) + cuts.diff)
    } else {
        drho
    };
    *contact_force = fc;
    *out = ParticleRates {
        acc: acc + fc / mi + model.gravity,
        drho,
        de: lane_sum(&sums.de) + de_contact + cuts.de,
        de_lag: lane_sum(&sums.de_lag) + de_lag_contact + cuts.de_lag,
        grad_v,
        contact_energy: phi,
        dt,
        min_interbody_gap: gap,
        neighbors: count,
    };
}

/// The conservation terms of particle i with `LANES` neighbours `js`, one per lane, added to
/// the lane sums. Straight-line arithmetic with selects only (the kernel gradient is 0 beyond
/// the support, which zeroes every term of the padding record), so that it vectorises.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops over lanes and axes read as the equations
fn conserve_chunk<
    const D: usize,
    K: Kernel,
    const ART: bool,
    const CN: bool,
    const DIFF: bool,
    const ELL: bool,
>(
    kernel: K,
    (i, gi): (usize, &Gather<D>),
    (js, gs): (&[u32], &[&Gather<D>]),
    pass: &Pass<D>,
    s: &mut LaneSums<D>,
) {
    let Pass { art, sb, model, .. } = *pass;
    // CN-SPH: i's (σ/ρ²) B, and each lane's neighbour's, read out (with their bounds checks)
    // before the lanes' arithmetic, which then vectorises. The neighbours' are read component
    // by component across the lanes, as x is: copied out matrix by matrix, they went through
    // the stack in 8-byte stores read back 32 bytes at a time, a stalled store forward that
    // cost CN-SPH's cubes 5 %.
    let zero = [[0.0; D]; D];
    let sbi = if CN { sb[i] } else { zero };
    // CN-SPH's energy split (module doc), doubled: i's side of the pair's stress work counts
    // 2 (σ_i/ρ_i²) B_i − σ_i/ρ_i², the neighbour's σ_j/ρ_j² (added per pair), and the sum is
    // halved with the rest's.
    let ei: Matrix<D> = if CN {
        std::array::from_fn(|a| std::array::from_fn(|b| 2.0 * sbi[a][b] - gi.sr2[sym(a, b)]))
    } else {
        zero
    };
    let sbj: [[[f64; LANES]; D]; D] = if CN {
        let rows: [&[[f64; D]; D]; LANES] = std::array::from_fn(|l| &sb[js[l] as usize]);
        std::array::from_fn(|a| std::array::from_fn(|b| std::array::from_fn(|l| rows[l][a][b])))
    } else {
        [[[0.0; LANES]; D]; D]
    };
    let g: [&Gather<D>; LANES] = std::array::from_fn(|l| gs[l]);
    // CN-SPH's energy split reads the neighbours' plain σ/ρ², likewise across the lanes.
    let srj: [[f64; LANES]; 6] = if CN {
        std::array::from_fn(|k| std::array::from_fn(|l| g[l].sr2[k]))
    } else {
        [[0.0; LANES]; 6]
    };
    let (alpha, beta, limiter) = (model.alpha, model.beta, model.limiter);
    let di: [f64; 6] = std::array::from_fn(|k| f64::from(gi.d[k]));
    for l in 0..LANES {
        let gj = g[l];
        let xij: [f64; D] = std::array::from_fn(|k| gi.x[k] - gj.x[k]);
        let r2 = dot(&xij, &xij);
        let r = r2.sqrt();
        // The pair's h (along its line for the ellipsoid, which the viscosity takes), the
        // gradient's factor along x_ij (the density diffusion's ψ·∇W) and ∇_i W_ij; the
        // ellipsoid's isotropic h for the artificial stress's W(Δp) ([`pair_kernel`]). The
        // round kernel is spelled out here, on this lane's r: through `pair_kernel`, which
        // takes the root of r² again, LLVM left every build of the lanes scalar
        // (`tests/vectorised.rs`; 2026-12-05). The same numbers.
        let (hij, gf, grad, h_iso) = if ELL {
            pair_kernel::<D, K, ELL>(kernel, pass, (i, gi), (js[l] as usize, gj), &xij, r2)
        } else {
            let hij = 0.5 * (gi.h + gj.h);
            let gf = kernel.grad_factor::<D>(r, hij);
            let grad: [f64; D] = std::array::from_fn(|k| xij[k] * gf);
            (hij, gf, grad, hij)
        };
        let vij: [f64; D] = std::array::from_fn(|k| gi.v[k] - gj.v[k]);
        let near = r < 2.0 * hij;
        let v2 = if near { dot(&vij, &vij) } else { 0.0 };
        s.v2_max[l] = s.v2_max[l].max(v2);
        let mj = gj.m;
        // CN-SPH's continuity and velocity gradient use ∇̃_i W_ij = B_i ∇_i W_ij: B_i is the
        // same for every pair of i, so the sum is taken on the plain ∇W and B_i applied once
        // at the end, L_i = −(Σ_j V_j v_ij ⊗ ∇_i W_ij) B_iᵀ and dρ_i/dt = −ρ_i tr L_i
        // ([`finish_corrected`]).
        // The material's rates take the velocity at the step's middle, w = v + dv
        // (`integrate`, "Staggered material update"); the forces take v.
        let wij: [f64; D] =
            std::array::from_fn(|k| vij[k] + (f64::from(gi.dv[k]) - f64::from(gj.dv[k])));
        if !CN {
            s.drho[l] += mj * dot(&wij, &grad);
        }
        if DIFF {
            s.diff[l] += diffusion_term(hij, 0.5 * (gi.c + gj.c), gj.rho - gi.rho, gf, gj.vol);
        }
        for a in 0..D {
            let va = wij[a] * gj.vol;
            for b in 0..D {
                s.grad_v[a][b][l] -= va * grad[b];
            }
        }
        // Each side's prediction of the pair's jump from its own strain rate, x_ij·D·x_ij.
        let (mut qi, mut qj) = (0.0, 0.0);
        for a in 0..D {
            for b in a..D {
                let k = sym(a, b);
                let xx = if a == b { 1.0 } else { 2.0 } * xij[a] * xij[b];
                qi += xx * di[k];
                qj += xx * f64::from(gj.d[k]);
            }
        }
        let c_mean = 0.5 * (gi.c + gj.c);
        let (pi, mu) = viscosity::monaghan_gingold(
            viscosity::limited(dot(&vij, &xij), (qi, qj), limiter * c_mean * r),
            r2,
            hij,
            c_mean,
            0.5 * (gi.rho + gj.rho),
            alpha,
            beta,
        );
        let mu = if near { mu } else { 0.0 };
        s.mu_max[l] = s.mu_max[l].max(-mu);
        // T_ij ∇W = (σ_i/ρ_i² + σ_j/ρ_j²) ∇W − Π_ij ∇W (+ A_ij ∇W); in CN-SPH the stresses'
        // part is built from both sides, (σ_i/ρ_i²) B_i ∇W + (σ_j/ρ_j²) B_j ∇W (the artificial
        // stress's likewise), and the viscosity stays on the plain ∇W.
        let mut tg: [f64; D] = std::array::from_fn(|a| {
            let mut t = -pi * grad[a];
            for b in 0..D {
                t += if CN {
                    (sbi[a][b] + sbj[a][b][l]) * grad[b]
                } else {
                    (gi.sr2[sym(a, b)] + gj.sr2[sym(a, b)]) * grad[b]
                };
            }
            t
        });
        // The part of T_ij ∇W that is not the stresses' (CN-SPH's energy split).
        let mut rest: [f64; D] = std::array::from_fn(|a| -pi * grad[a]);
        if ART {
            let (ri, rj) = (&art[i], &art[js[l] as usize]);
            let dp = 0.5 * (gi.dp + gj.dp);
            // f_ij = W_ij/W(Δp): for the ellipsoid, Δp in its own coordinates (the lattice
            // it sees is the initial one), both at h = 1.
            let fa = stress_factor::<D, K, ELL>(kernel, r, dp, (hij, h_iso));
            for a in 0..D {
                for b in 0..D {
                    let t = (ri[(a, b)] + rj[(a, b)]) * fa * grad[b];
                    tg[a] += t;
                    rest[a] += t;
                }
            }
        }
        // i's share of the pair's work is half of eg: eg = T_ij ∇W; in CN-SPH the plain
        // stresses' and the rest's, and twice i's own correction's, (σ_i/ρ_i²)(B_i − I) ∇W.
        let eg: [f64; D] = if CN {
            std::array::from_fn(|a| {
                let mut t = rest[a];
                for b in 0..D {
                    t += (ei[a][b] + srj[sym(a, b)][l]) * grad[b];
                }
                t
            })
        } else {
            tg
        };
        let mut veg = 0.0;
        let mut ueg = 0.0;
        for a in 0..D {
            s.acc[a][l] += tg[a] * mj;
            veg += vij[a] * eg[a];
            ueg += (f64::from(gi.u[a]) - f64::from(gj.u[a])) * eg[a];
        }
        s.de[l] -= 0.5 * mj * veg;
        s.de_lag[l] -= 0.5 * mj * ueg;
    }
}

/// The pair's kernel: (h_ij, gf, ∇_i W_ij, h_iso). The round kernel's ∇_i W_ij = x_ij gf at
/// h_ij = ½ (h_i + h_j), h_iso = h_ij; the ellipsoid's ([`asph::pair_gradient`]) with h_ij its h
/// along the pair's line (which the viscosity takes), gf = x_ij·∇_i W_ij/r² (the factor along
/// x_ij, which the density diffusion's ψ·∇W takes) and h_iso the mean metric's isotropic h.
#[inline(always)]
fn pair_kernel<const D: usize, K: Kernel, const ELL: bool>(
    kernel: K,
    pass: &Pass<D>,
    (i, gi): (usize, &Gather<D>),
    (j, gj): (usize, &Gather<D>),
    xij: &[f64; D],
    r2: f64,
) -> (f64, f64, [f64; D], f64) {
    if ELL {
        let (mi, mj) = (&pass.metric[i].a, &pass.metric[j].a);
        let (grad, h_line, h_iso) = asph::pair_gradient(kernel, mi, mj, xij);
        let along = if r2 > 0.0 { dot(xij, &grad) / r2 } else { 0.0 };
        (h_line, along, grad, h_iso)
    } else {
        let hij = 0.5 * (gi.h + gj.h);
        let gf = kernel.grad_factor::<D>(r2.sqrt(), hij);
        let grad: [f64; D] = std::array::from_fn(|k| xij[k] * gf);
        (hij, gf, grad, hij)
    }
}

/// The artificial stress's (W_ij/W(Δp))^n (Monaghan 2000) at distance r, (h_ij, h_iso) from
/// [`pair_kernel`]: for the ellipsoid both in its own coordinates (the lattice it sees is the
/// initial one), at h = 1.
#[inline(always)]
fn stress_factor<const D: usize, K: Kernel, const ELL: bool>(
    kernel: K,
    r: f64,
    dp: f64,
    (hij, h_iso): (f64, f64),
) -> f64 {
    let f = if ELL {
        kernel.w::<D>(r / hij, 1.0) / kernel.w::<D>(dp / h_iso, 1.0)
    } else {
        kernel.w::<D>(r, hij) / kernel.w::<D>(dp, hij)
    };
    f.powi(artificial_stress::EXPONENT)
}

/// A wall's image pair counted in part, `share` of it ([`crate::boundary::wall_share`]): every
/// term of a pair in [`conserve_chunk`] is linear in the neighbour's mass or volume, so the
/// pair's share is the pair with j's record carrying `share` of both. Summed at once in the
/// first lane (rare: only while a face comes into touch with a wall).
#[cold]
#[inline(never)]
fn wall_pair<
    const D: usize,
    K: Kernel,
    const ART: bool,
    const CN: bool,
    const DIFF: bool,
    const ELL: bool,
>(
    kernel: K,
    (i, gi): (usize, &Gather<D>),
    (j, gj): (u32, &Gather<D>),
    share: f64,
    pass: &Pass<D>,
    sums: &mut LaneSums<D>,
) {
    let part = Gather {
        m: share * gj.m,
        vol: share * gj.vol,
        ..*gj
    };
    let pad = &pass.gather[pass.padding as usize];
    let mut js = [pass.padding; LANES];
    let mut gs = [pad; LANES];
    js[0] = j;
    gs[0] = &part;
    conserve_chunk::<D, K, ART, CN, DIFF, ELL>(kernel, (i, gi), (&js, &gs), pass, sums);
}

/// CN-SPH's velocity gradient and density rate from the plain sum G_i = −Σ_j V_j v_ij ⊗ ∇_i W_ij
/// and the correction B_i: L_i = G_i B_iᵀ (so that L_i = −Σ_j V_j v_ij ⊗ B_i ∇_i W_ij) and
/// dρ_i/dt = −ρ_i tr L_i.
fn finish_corrected<const D: usize>(b: &Tensor<D>, rho: f64, g: &Tensor<D>) -> (f64, Tensor<D>) {
    let l = g * b.transpose();
    (-rho * l.trace(), l)
}

/// Cuts the pairs of i with a failed member, `members` (neighbours in increasing index), and
/// its severed pairs from the `met`-th on whose neighbour is below `upto`, merged in the
/// neighbours' order ([`cut_pair`]); `met` moves past the severed pairs cut.
#[inline(never)]
fn cut_in_order<const D: usize, K: Kernel, const CN: bool, const ELL: bool>(
    kernel: K,
    i: usize,
    (members, severed, met, upto): (&[u32], &[(u32, bool)], &mut usize, u32),
    pass: &Pass<D>,
    cuts: &mut Cut<D>,
) {
    let gather = pass.gather;
    let xi = gather[i].x;
    let mut q = 0;
    loop {
        let member = members.get(q).copied().unwrap_or(u32::MAX);
        let sever = match severed.get(*met) {
            Some(&(j, _)) if j < upto => j,
            _ => u32::MAX,
        };
        if member == u32::MAX && sever == u32::MAX {
            break;
        }
        let (j, kind) = if sever < member {
            *met += 1;
            (sever as usize, CutKind::severed(severed[*met - 1].1))
        } else {
            q += 1;
            (member as usize, CutKind::Member)
        };
        let xij: [f64; D] = std::array::from_fn(|k| xi[k] - gather[j].x[k]);
        cut_pair::<D, K, CN, ELL>(kernel, (i, j), &xij, kind, pass, cuts);
    }
}

/// A pair's kernel as [`cut_pair`] takes it ([`pair_kernel`]; a wall's image's share in gf and
/// ∇W): distance r, gf, ∇_i W_ij, h_ij and h_iso.
struct PairTerms<const D: usize> {
    r: f64,
    gf: f64,
    grad: [f64; D],
    hij: f64,
    h_iso: f64,
}

/// Why a pair is cut ([`cut_pair`]): a failed member, or a failed particle between two intact
/// ones with the crack closed or open ([`CrackLists::severs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum CutKind {
    Member,
    Closed,
    Open,
}

impl CutKind {
    fn severed(open: bool) -> Self {
        if open {
            CutKind::Open
        } else {
            CutKind::Closed
        }
    }
}

/// What the cut pairs of a particle take out of its sums (see [`cut_pair`]).
struct Cut<const D: usize> {
    acc: [f64; D],
    de: f64,
    de_lag: f64,
    drho: f64,
    /// The density diffusion's terms taken out (before δ).
    diff: f64,
    grad_v: [[f64; D]; D],
}

impl<const D: usize> Default for Cut<D> {
    fn default() -> Self {
        Cut {
            acc: [0.0; D],
            de: 0.0,
            de_lag: 0.0,
            drho: 0.0,
            diff: 0.0,
            grad_v: [[0.0; D]; D],
        }
    }
}

/// What [`CrackLists::severs`] reads of one particle's candidates, one array per number: the
/// position, the smoothing length, the reach² ((¾ Δp)², see [`CrackLists::severs`]) and the
/// pressure ([`CrackLists::candidates`]).
#[derive(Debug, Clone)]
struct Candidates<const D: usize> {
    x: [Vec<f64>; D],
    h: Vec<f64>,
    reach2: Vec<f64>,
    p: Vec<f64>,
}

impl<const D: usize> Default for Candidates<D> {
    fn default() -> Self {
        Candidates {
            x: std::array::from_fn(|_| Vec::new()),
            h: Vec::new(),
            reach2: Vec::new(),
            p: Vec::new(),
        }
    }
}

/// For every real particle with a list here, the failed particles in its support of bodies
/// that meet its own through the conservation equations, in list order: the only particles
/// that may sever one of its pairs ([`CrackLists::severs`]). Built once a pass, where any
/// particle has failed, so that a particle's pairs test a handful of candidates each instead
/// of its whole list (in `strike bench`'s shocked steel cubes, 12 % of their particles failed,
/// scanning the list for every pair made Johnson–Cook with damage cost 70 % more a step than
/// von Mises). What the test reads of a particle's candidates is copied into arrays beside
/// each other, one per number ([`Candidates`]), so that the test runs over them in vector
/// lanes (on AVX2 where the CPU has it) without gathering their 200-byte records; the copies
/// are made a block of particles at a time as their pairs are tested, into each thread's own
/// arrays, and only the candidates' indices are kept (4 bytes each; the copies of every
/// candidate, kept until 2026-12-02, took 48 more in 3D: in `strike bench`'s shocked steel
/// cubes, at 1.7 candidates a particle with 6.5 % of them failed, the peak fell by 110 bytes a
/// particle, at the same speed and to the same bits). By `perf`, the test was 9 % of a step of those
/// cubes, 5 % since (a pair asks it of 7 candidates on average, and 90 % of the pairs asked
/// are not severed). Since 2026-11-28 each pair is asked once, before the pass, and the pass
/// cuts each particle's few severed pairs in list order ([`CrackLists::find_severed`]): in a
/// window of those cubes (steps 100–160, one thread, `perf` at 2 kHz) the test fell from 233
/// to 127 samples, and the pass, which no longer called [`cut_pair`] for every pair beside a
/// crack to be told "not severed", from 2048 to 1711, against 177 for the new search. Kept out of
/// the pass's own frame: with the candidates in an array there (of 32 entries, or even of
/// one), the conventional cubes, where nothing fails, ran about 15 % slower.
#[derive(Debug, Clone)]
struct CrackLists<const D: usize> {
    /// ends[i]: where particle i's candidates end (they start at ends[i − 1]).
    ends: Vec<u32>,
    /// Each candidate's index.
    items: Vec<u32>,
    /// Every particle's (ghosts included): intact, with candidates, or with no list here
    /// (ghosts and another rank's particles, whose pairs then take the test in full). A pair
    /// of intact particles can be severed only where both are.
    cracked: Vec<bool>,
    /// How many particles before each have failed (the build's, kept for its allocation).
    failed_before: Vec<u32>,
    /// The severed pairs of each particle with a list here ([`CrackLists::severed`]):
    /// `severed_ends[i]` ends i's entries in `severed`, each the other particle and whether the
    /// crack is open.
    severed_ends: Vec<u32>,
    severed: Vec<(u32, bool)>,
    /// Whether [`CrackLists::severs`] runs on 256-bit vectors ([`wide_lanes`]).
    wide: bool,
}

impl<const D: usize> Default for CrackLists<D> {
    fn default() -> Self {
        CrackLists {
            ends: Vec::new(),
            items: Vec::new(),
            cracked: Vec::new(),
            failed_before: Vec::new(),
            severed_ends: Vec::new(),
            severed: Vec::new(),
            wide: false,
        }
    }
}

impl<const D: usize> CrackLists<D> {
    /// Where particle i's candidates lie in the arrays (none where none was built).
    fn range(&self, i: usize) -> std::ops::Range<usize> {
        match self.ends.get(i) {
            Some(&end) => {
                let start = if i == 0 { 0 } else { self.ends[i - 1] };
                start as usize..end as usize
            }
            None => 0..0,
        }
    }

    /// The lists of the `n` real particles, and which particles are `cracked`. Whether a
    /// particle has failed is read from `damage` (D ≥ 1, as [`Gather::of`] sets `failed`; every
    /// particle's, ghosts included, so that its length is the padding record's index), 8
    /// bytes a particle, so that only a failed neighbour's 200-byte record is read. The build
    /// was 3.8 % of a step of `strike bench`'s shocked steel cubes by `perf`, 2.4 % since.
    /// `pressure`: the pass's (ghosts included). `wide`: the test on 256-bit vectors (the CPU
    /// has AVX2).
    #[allow(clippy::too_many_arguments)]
    fn build(
        &mut self,
        n: usize,
        gather: Records<D>,
        damage: &[f64],
        pressure: &[f64],
        nl: &NeighborList,
        model: &Model<D>,
        wide: bool,
    ) {
        assert!(
            !wide || wide_lanes(),
            "AVX2 asked for on a CPU without AVX2"
        );
        self.wide = wide;
        // The padding record past the particles has not failed.
        let failed = |k: usize| damage.get(k).is_some_and(|&d| d >= 1.0);
        // before[k]: how many of the particles before k have failed. A list's segment whose
        // index range holds none of them is skipped whole: where failure is local, most are
        // (in `strike bench`'s shocked steel cubes the scan of every entry cost as many
        // instructions as the severing test and the cuts together).
        let before = &mut self.failed_before;
        before.clear();
        before.push(0);
        let mut count = 0u32;
        before.extend(damage.iter().map(|&d| {
            count += u32::from(d >= 1.0);
            count
        }));
        let before = &*before;
        let none_within = |lo: usize, last: usize| {
            let hi = (last + 1).min(damage.len());
            lo >= hi || before[hi] == before[lo]
        };
        const BLOCK: usize = 4096;
        let g = gather;
        let blocks: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .map(|b| {
                let (mut items, mut counts) = (Vec::new(), Vec::new());
                for i in b * BLOCK..((b + 1) * BLOCK).min(n) {
                    let gi = &g[i];
                    let before = items.len();
                    if !failed(i) && nl.listed(i) {
                        // A plain loop: as `extend` over a `filter`, the test was a call per
                        // entry that the compiler did not inline.
                        for (base, offsets) in nl.list(i).segments() {
                            let base = base as usize;
                            let last = base + offsets.last().map_or(0, |&o| usize::from(o));
                            if none_within(base, last) {
                                continue;
                            }
                            for &o in offsets {
                                let k = base + usize::from(o);
                                if failed(k) {
                                    let gk = &g[k];
                                    if joined(model, gi.body, gk.body) && within_support(gi, gk) {
                                        items.push(k as u32);
                                    }
                                }
                            }
                        }
                    }
                    counts.push((items.len() - before) as u32);
                }
                (items, counts)
            })
            .collect();
        self.ends.clear();
        self.items.clear();
        let mut end = 0u32;
        for (items, counts) in blocks {
            self.items.extend_from_slice(&items);
            for c in counts {
                end += c;
                self.ends.push(end);
            }
        }
        let mut cracked = std::mem::take(&mut self.cracked);
        cracked.clear();
        cracked.par_extend(
            (0..damage.len() + 1)
                .into_par_iter()
                .map(|i| !failed(i) && (i >= n || !nl.listed(i) || !self.range(i).is_empty())),
        );
        self.cracked = cracked;
        self.find_severed(n, gather, pressure, nl, model);
    }

    /// Particle i's severed pairs: the neighbours (in increasing index, the list's order) that
    /// are intact, met through the conservation equations in the pass ([`meets_in_pass`]) and
    /// severed ([`CrackLists::severs`]), with whether the crack is open. Empty for a failed
    /// particle.
    #[inline]
    fn severed(&self, i: usize) -> &[(u32, bool)] {
        match self.severed_ends.get(i) {
            Some(&end) => {
                let start = if i == 0 { 0 } else { self.severed_ends[i - 1] };
                &self.severed[start as usize..end as usize]
            }
            None => &[],
        }
    }

    /// Every severed pair of intact particles, tested once: from its lower index's side, or
    /// from the side that has a list where the other has none here (a ghost, another rank's
    /// particle), and entered in the lists of both (of each that has one). The pass used to
    /// test each pair from both sides as it met it; both answer the same
    /// ([`CrackLists::severs`]), and nine pairs in ten were not severed. The results are
    /// those of testing in the pass, to the bit: the same answers, cut in the same order.
    fn find_severed(
        &mut self,
        n: usize,
        gather: Records<D>,
        pressure: &[f64],
        nl: &NeighborList,
        model: &Model<D>,
    ) {
        const BLOCK: usize = 4096;
        let has_list = |k: usize| k < n && nl.listed(k);
        let joined = |a: u32, b: u32| joined(model, a, b);
        let this = &*self;
        // (i, j, open), in order of i and then of j.
        let blocks: Vec<Vec<(u32, u32, bool)>> = (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .map_init(Candidates::default, |candidates, b| {
                let mut hits = Vec::new();
                let block = b * BLOCK..((b + 1) * BLOCK).min(n);
                // The block's candidates, copied together.
                let first = this.range(block.start).start;
                let last = this.range(block.end - 1).end;
                this.candidates(first..last, gather, pressure, candidates);
                for i in block {
                    // A particle with candidates is intact and has its list here.
                    let range = this.range(i);
                    if range.is_empty() {
                        continue;
                    }
                    let mine = (&*candidates, range.start - first..range.end - first);
                    let gi = &gather[i];
                    for j in nl.list(i) {
                        let ju = j as usize;
                        if (ju < i && has_list(ju)) || !this.cracked[ju] {
                            continue;
                        }
                        if !meets_in_pass(model, gi, &gather[ju]) {
                            continue;
                        }
                        if let Some(open) = this.severs((i, ju), gather, joined, mine.clone()) {
                            hits.push((i as u32, j, open));
                        }
                    }
                }
                hits
            })
            .collect();
        // Each hit in the entries of both.
        let mut entries: Vec<(u32, u32, bool)> = Vec::new();
        for &(i, j, open) in blocks.iter().flatten() {
            entries.push((i, j, open));
            if has_list(j as usize) {
                entries.push((j, i, open));
            }
        }
        entries.sort_unstable_by_key(|&(k, other, _)| (k, other));
        self.severed_ends.clear();
        self.severed.clear();
        let mut e = entries.iter().peekable();
        for k in 0..n as u32 {
            while let Some(&(_, other, open)) = e.next_if(|x| x.0 == k) {
                self.severed.push((other, open));
            }
            self.severed_ends.push(self.severed.len() as u32);
        }
    }

    /// What [`CrackLists::severs`] reads of the candidates `span` (of [`CrackLists::items`]),
    /// into `out`.
    fn candidates(
        &self,
        span: std::ops::Range<usize>,
        gather: Records<D>,
        pressure: &[f64],
        out: &mut Candidates<D>,
    ) {
        let items = &self.items[span];
        for a in 0..D {
            out.x[a].clear();
            out.x[a].extend(items.iter().map(|&k| gather[k as usize].x[a]));
        }
        out.h.clear();
        out.h.extend(items.iter().map(|&k| gather[k as usize].h));
        out.reach2.clear();
        out.reach2.extend(items.iter().map(|&k| {
            let reach = 0.75 * gather[k as usize].dp;
            reach * reach
        }));
        out.p.clear();
        out.p.extend(items.iter().map(|&k| pressure[k as usize]));
    }

    /// Whether the pair (i, j) of intact particles is severed: a failed particle k, in the
    /// supports of both and of a body that meets both through the conservation equations
    /// (`joined`), lies between them, within ¾ of its spacing of the segment x_i x_j (its
    /// closest point strictly inside it). Such a pair meets as a pair with a failed member does
    /// ([`tension_cut`]); the crack is open (`Some(true)`) where a failed particle that severs
    /// the pair is at no pressure (it carries no tension), closed (`Some(false)`) where all of
    /// them are compressed. `None`: not severed. Only i's candidates can: they are the failed
    /// particles in i's support of bodies that meet i's, and k is in j's support too.
    ///
    /// A crack of failed particles one particle wide then cuts the bodies on either side apart
    /// at once, where before their intact particles pulled each other across it until it was a
    /// support wide. Evaluated with the lower index first, so that both sides of the pair get
    /// the same answer to the bit (k is in both supports, and the answer does not depend on the
    /// order k comes in). ¾ Δp: a crack across a lattice passes within Δp/√2 of one of its
    /// particles; the intact particles along the crack's face, a spacing off it, keep their
    /// pairs. The idea is the visibility criterion of the element-free Galerkin method
    /// (Belytschko, Lu & Gu 1994, IJNME 37, 229) and Spheral's three-point damaged coupling
    /// (Owen, LLNL), where a damaged point between two points cuts what passes between them.
    ///
    /// `candidates`: copies of some of the candidates ([`CrackLists::candidates`]) and where
    /// i's lie in them.
    fn severs(
        &self,
        ij: (usize, usize),
        gather: Records<D>,
        joined: impl Fn(u32, u32) -> bool,
        candidates: (&Candidates<D>, Range<usize>),
    ) -> Option<bool> {
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: the CPU has AVX2 (asserted in `build`).
            return unsafe { self.severs_avx2(ij, gather, joined, candidates) };
        }
        self.severs_in_lanes(ij, gather, joined, candidates)
    }

    /// [`CrackLists::severs`] compiled for AVX2: four candidates at a time instead of two
    /// (the same comparisons of the same numbers, so the same answers).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn severs_avx2(
        &self,
        ij: (usize, usize),
        gather: Records<D>,
        joined: impl Fn(u32, u32) -> bool,
        candidates: (&Candidates<D>, Range<usize>),
    ) -> Option<bool> {
        self.severs_in_lanes(ij, gather, joined, candidates)
    }

    /// The body of [`CrackLists::severs`].
    #[inline(always)]
    fn severs_in_lanes(
        &self,
        (i, j): (usize, usize),
        gather: Records<D>,
        joined: impl Fn(u32, u32) -> bool,
        (candidates, at): (&Candidates<D>, Range<usize>),
    ) -> Option<bool> {
        let range = self.range(i);
        debug_assert_eq!(at.len(), range.len(), "i's candidates");
        let (ga, gb) = (&gather[i.min(j)], &gather[i.max(j)]);
        let e: [f64; D] = std::array::from_fn(|a| gb.x[a] - ga.x[a]);
        let ee = dot(&e, &e);
        let (gi, gj) = (&gather[i], &gather[j]);
        debug_assert!(!gi.failed && !gj.failed);
        let x: [&[f64]; D] = std::array::from_fn(|a| &candidates.x[a][at.clone()]);
        let (h, reach2, p) = (
            &candidates.h[at.clone()],
            &candidates.reach2[at.clone()],
            &candidates.p[at],
        );
        // Candidate c between the two, but for its body. A zero ee gives t = NaN: no cut.
        // (A function, not a closure: the compiler did not inline the closure.)
        #[inline(always)]
        #[allow(clippy::needless_range_loop)] // index loops over axes read as the equations
        fn between<const D: usize>(
            (xa, e, ee): (&[f64; D], &[f64; D], f64),
            gj: &Gather<D>,
            xk: [f64; D],
            hk: f64,
            reach2: f64,
        ) -> bool {
            let w: [f64; D] = std::array::from_fn(|a| xk[a] - xa[a]);
            let t = dot(&w, e) / ee;
            let off: [f64; D] = std::array::from_fn(|a| w[a] - t * e[a]);
            // k within j's support, r² as the filter computes it ([`within_support`]).
            let mut r2 = 0.0;
            for a in 0..D {
                let d = gj.x[a] - xk[a];
                r2 += d * d;
            }
            let support = gj.h + hk;
            (r2 < support * support) & (t > 0.0) & (t < 1.0) & (dot(&off, &off) < reach2)
        }
        let segment = (&ga.x, &e, ee);
        let xk = |c: usize| std::array::from_fn(|a| x[a][c]);
        // Every candidate tested, with no branch on the outcome (which varies from one
        // candidate to the next as no predictor could follow).
        let (mut cut, mut open) = (false, false);
        for c in 0..h.len() {
            let b = between(segment, gj, xk(c), h[c], reach2[c]);
            cut |= b;
            open |= b & (p[c] <= 0.0);
        }
        // The candidates meet i's body; where j is of another (welded) body, the ones between
        // the two must meet j's as well (the rare case).
        if cut && gi.body != gj.body {
            (cut, open) = (false, false);
            for (c, &k) in self.items[range].iter().enumerate() {
                let b = between(segment, gj, xk(c), h[c], reach2[c])
                    && joined(gj.body, gather[k as usize].body);
                cut |= b;
                open |= b & (p[c] <= 0.0);
            }
        }
        cut.then_some(open)
    }
}

/// Whether the pass meets the pair (i, j) of intact particles through the conservation
/// equations: j within i's support (r² and the support as [`particle_rates`] computes them, the
/// same bits from either side), of i's body or welded to it, or a wall's image pressed against
/// i ([`pressed`]); not a pair in contact.
fn meets_in_pass<const D: usize>(model: &Model<D>, gi: &Gather<D>, gj: &Gather<D>) -> bool {
    let xij: [f64; D] = std::array::from_fn(|k| gi.x[k] - gj.x[k]);
    let r2 = dot(&xij, &xij);
    let support = gi.h + gj.h;
    if !(r2 < support * support && r2 > 0.0) {
        return false;
    }
    if gi.body == gj.body {
        return true;
    }
    match model.pairs.rule(gi.body, gj.body) {
        PairRule::Conserve => true,
        PairRule::Contact(_) => false,
        PairRule::Wall => pressed(gi, gj, &xij) && wall_share(model, gi, gj) > 0.0,
    }
}

/// Whether a particle and a wall's image of a particle are pressed together: the pair closes
/// (v_ij·x_ij < 0), or its stress along the line between them, x̂_ij·(σ_i + σ_j)·x̂_ij, is
/// compressive. The same answer from either side, and for the mirrored pair (j, image of i).
#[inline]
fn pressed<const D: usize>(gi: &Gather<D>, gj: &Gather<D>, xij: &[f64; D]) -> bool {
    let mut closing = 0.0;
    let mut normal = 0.0;
    for a in 0..D {
        closing += (gi.v[a] - gj.v[a]) * xij[a];
        for b in 0..D {
            let k = sym(a, b);
            normal += xij[a] * (gi.sr2[k] * gi.rho * gi.rho + gj.sr2[k] * gj.rho * gj.rho) * xij[b];
        }
    }
    closing < 0.0 || normal < 0.0
}

/// Whether bodies a and b meet through the conservation equations (the same body, or welded).
fn joined<const D: usize>(model: &Model<D>, a: u32, b: u32) -> bool {
    a == b || matches!(model.pairs.rule(a, b), PairRule::Conserve)
}

/// A pair with a failed member, or severed by a failed particle between its two
/// ([`CrackLists::severs`]), passes on only compression (`material::damage`): its stress terms
/// lose the tension and the deviator of either side ([`tension_cut`]). The cut is the pair's, the same from either
/// side: momentum is kept. Where the crack between them is open (the failed particle at no
/// pressure), an intact i also takes the pair out of its continuity and its velocity gradient
/// (the pass queued it in full; its terms are taken back out here): the opening of a crack is
/// not the particle's own strain. Where the failed particle is compressed, the rubble carries
/// the load and deforms with its neighbours, and the pair stays in both. A failed particle
/// keeps its pairs in both, so that its density follows its neighbours apart as well as
/// together. Adds to `cuts` what the pair takes out of i's sums; `kind`: why it is cut.
#[inline(never)]
#[allow(clippy::needless_range_loop)] // index loops over axes read as the equations
fn cut_pair<const D: usize, K: Kernel, const CN: bool, const ELL: bool>(
    kernel: K,
    (i, j): (usize, usize),
    xij: &[f64; D],
    kind: CutKind,
    pass: &Pass<D>,
    cuts: &mut Cut<D>,
) {
    let (gi, gj) = (&pass.gather[i], &pass.gather[j]);
    debug_assert!(gi.failed || gj.failed || kind != CutKind::Member);
    let open = match kind {
        CutKind::Member => !gi.failed && gj.failed && pass.pressure[j] <= 0.0,
        CutKind::Closed => false,
        CutKind::Open => true,
    };
    // The pair's kernel ([`pair_kernel`]), shared by the two terms, and by a wall's image
    // pair only its share (every term is linear in it; see `wall_pair`).
    let r2 = dot(xij, xij);
    let r = r2.sqrt();
    let share = match pass.model.pairs.rule(gi.body, gj.body) {
        PairRule::Wall => wall_share(pass.model, gi, gj),
        _ => 1.0,
    };
    let (hij, gf, grad, h_iso) = pair_kernel::<D, K, ELL>(kernel, pass, (i, gi), (j, gj), xij, r2);
    let gf = share * gf;
    // The round kernel's x_ij gf as the pass's, the share in gf.
    let grad: [f64; D] = std::array::from_fn(|k| if ELL { share * grad[k] } else { xij[k] * gf });
    let terms = PairTerms {
        r,
        gf,
        grad,
        hij,
        h_iso,
    };
    let (cut, share) = tension_cut::<D, K, CN, ELL>(kernel, (i, j), xij, &terms, pass);
    let mj = gj.m;
    for a in 0..D {
        cuts.acc[a] -= cut[a] * mj;
        cuts.de += mj * (gi.v[a] - gj.v[a]) * share[a];
        cuts.de_lag += mj * (f64::from(gi.u[a]) - f64::from(gj.u[a])) * share[a];
    }
    if open {
        let (drho, grad_v) = kinematic_terms::<D, CN>((i, j), &grad, pass);
        cuts.drho -= drho;
        cuts.diff -= diffusion_term(hij, 0.5 * (gi.c + gj.c), gj.rho - gi.rho, gf, gj.vol);
        for a in 0..D {
            for b in 0..D {
                cuts.grad_v[a][b] -= grad_v[a][b];
            }
        }
    }
}

/// Whether k lies within i's support, r_ik < h_i + h_k, with r² as the filter computes it
/// (the same bits from either particle's side).
#[inline]
fn within_support<const D: usize>(gi: &Gather<D>, gk: &Gather<D>) -> bool {
    let mut r2 = 0.0;
    for a in 0..D {
        let d = gi.x[a] - gk.x[a];
        r2 += d * d;
    }
    let support = gi.h + gk.h;
    r2 < support * support
}

/// The pair's term in i's density diffusion before δ (module doc): −2 h_ij c_ij (ρ_j − ρ_i)
/// V_j gf, gf the kernel's gradient factor (∇_i W_ij = x_ij gf, gf ≤ 0), which is
/// ψ_ij·∇_i W_ij V_j h_ij c_ij with Molteni & Colagrossi's ψ_ij = 2 (ρ_j − ρ_i) x_ji/|x_ji|².
/// Symmetric in all but ρ_j − ρ_i, so that Σ_i V_i dρ_i/dt gains nothing from it.
#[inline(always)]
fn diffusion_term(hij: f64, cij: f64, drho_ji: f64, gf: f64, vol_j: f64) -> f64 {
    -2.0 * hij * cij * drho_ji * gf * vol_j
}

/// The pair's terms in i's continuity and velocity gradient, as the pass adds them:
/// (m_j w_ij · ∇̃_i W_ij, −V_j w_ij ⊗ ∇̃_i W_ij) with w = v + dv the velocity at the step's
/// middle, ∇̃ = B_i ∇ in CN-SPH, whose continuity term is V_j w_ij · ∇̃_i W_ij (times ρ_i with
/// the rest of the sum). `grad`: the plain ∇_i W_ij ([`pair_kernel`]).
fn kinematic_terms<const D: usize, const CN: bool>(
    (i, j): (usize, usize),
    grad: &[f64; D],
    pass: &Pass<D>,
) -> (f64, [[f64; D]; D]) {
    let (gi, gj) = (&pass.gather[i], &pass.gather[j]);
    let vij: [f64; D] =
        std::array::from_fn(|k| gi.v[k] - gj.v[k] + (f64::from(gi.dv[k]) - f64::from(gj.dv[k])));
    // CN-SPH: on the plain ∇W, as the pass's sums (B_i comes at the end, `finish_corrected`);
    // its density rate follows from L.
    let drho = if CN { 0.0 } else { gj.m * dot(&vij, grad) };
    let grad_v = std::array::from_fn(|a| std::array::from_fn(|b| -(vij[a] * gj.vol) * grad[b]));
    (drho, grad_v)
}

/// What a pair with a failed member does not pass on: T_ij ∇W with each side's stress term
/// σ/ρ² (CN-SPH: (σ/ρ²) B) replaced by its tension and deviator, σ/ρ² + max(p, 0)/ρ² I, and
/// the artificial stress's term — the pair force less this keeps only the compressive
/// pressures. A failed particle carries no
/// tension and no deviator (`material::damage`), so its own part is zero. Returns the cut and
/// i's share of its work, split as the pair's (see `conserve_chunk`). `k`: the pair's kernel.
fn tension_cut<const D: usize, K: Kernel, const CN: bool, const ELL: bool>(
    kernel: K,
    (i, j): (usize, usize),
    xij: &[f64; D],
    k: &PairTerms<D>,
    pass: &Pass<D>,
) -> ([f64; D], [f64; D]) {
    let (gi, gj) = (&pass.gather[i], &pass.gather[j]);
    let squeeze = |k: usize, g: &Gather<D>| pass.pressure[k].max(0.0) / (g.rho * g.rho);
    // A side on the plain ∇W, σ/ρ² + max(p, 0)/ρ² I: conventional SPH's, and the plain sides
    // of CN-SPH's energy split.
    let plain = |k: usize, g: &Gather<D>| -> [[f64; D]; D] {
        let s = squeeze(k, g);
        std::array::from_fn(|a| {
            std::array::from_fn(|b| g.sr2[sym(a, b)] + if a == b { s } else { 0.0 })
        })
    };
    let side = |k: usize, g: &Gather<D>| -> [[f64; D]; D] {
        if CN {
            let s = squeeze(k, g);
            std::array::from_fn(|a| {
                std::array::from_fn(|b| pass.sb[k][a][b] + s * pass.corr[k][(a, b)])
            })
        } else {
            plain(k, g)
        }
    };
    let (ti, tj) = (side(i, gi), side(j, gj));
    let (plain_i, plain_j) = if CN {
        (plain(i, gi), plain(j, gj))
    } else {
        ([[0.0; D]; D], [[0.0; D]; D])
    };
    // The artificial stress (R_i + R_j) f^n exists only against the clumping of particles
    // held in tension: a pair that passes on no tension carries none of it either. (Kept, it
    // pushed rubble off the intact particles beside it, which held their tension and failed in
    // turn: a failed zone grew through the whole plate of `examples/ogive_plate.toml`.)
    let art = (!pass.art.is_empty()).then(|| {
        let dp = 0.5 * (gi.dp + gj.dp);
        (
            stress_factor::<D, K, ELL>(kernel, k.r, dp, (k.hij, k.h_iso)),
            &pass.art[i],
            &pass.art[j],
        )
    });
    // c ∇W along axis b: the round kernel's in the order its terms have always been summed
    // ((c x_b) gf), the ellipsoid's from its gradient.
    let along = |c: f64, b: usize| {
        if ELL {
            c * k.grad[b]
        } else {
            c * xij[b] * k.gf
        }
    };
    let mut cut = [0.0; D];
    let mut share = [0.0; D];
    for a in 0..D {
        let (mut t, mut rest, mut own) = (0.0, 0.0, 0.0);
        for b in 0..D {
            t += along(ti[a][b] + tj[a][b], b);
            own += along(ti[a][b] - 0.5 * plain_i[a][b] + 0.5 * plain_j[a][b], b);
            if let Some((fa, ri, rj)) = art {
                let r = along((ri[(a, b)] + rj[(a, b)]) * fa, b);
                t += r;
                rest += r;
            }
        }
        cut[a] = t;
        share[a] = if CN { own + 0.5 * rest } else { 0.5 * t };
    }
    (cut, share)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two passes' rates agree particle by particle (`what` prefixes the message).
    fn same_rates<const D: usize>(a: &OwnRates<D>, b: &OwnRates<D>, what: &str) {
        assert_eq!(a.range(), b.range(), "{what}the particles evaluated");
        for (i, (a, b)) in a.range().zip(a.as_slice().iter().zip(b.as_slice())) {
            assert_eq!(a, b, "{what}particle {i}");
        }
    }
    use crate::kernel::CubicSpline;
    use crate::particles::Tensor;
    use crate::tensor::Sym;

    /// The pass is bound by gathering its neighbours' records: their size is part of its
    /// speed (see [`Gather::u`]).
    #[test]
    fn the_neighbour_record_stays_small() {
        assert_eq!(std::mem::size_of::<Gather<3>>(), 200);
        assert_eq!(std::mem::size_of::<Gather<2>>(), 176);
    }

    /// The pass over all real particles, without the colour law (`b`: CN-SPH's corrections;
    /// empty: conventional SPH).
    fn all_rates<const D: usize>(
        p: &Particles<D>,
        nl: &NeighborList,
        model: &Model<D>,
        b: &[Tensor<D>],
    ) -> Rates<D> {
        let mut out = Rates::default();
        compute_rates(
            CubicSpline,
            p,
            nl,
            model,
            (&ColourStates::default(), b, &[]),
            &(0..p.n_real),
            &mut out,
        );
        out
    }

    /// Crack lists built by hand for the particles `g` (all real, each listing all), with
    /// `joined` the bodies that meet.
    fn cracks_by_hand<const D: usize>(
        g: &[Gather<D>],
        joined: impl Fn(u32, u32) -> bool,
    ) -> CrackLists<D> {
        let mut cracks = CrackLists::<D>::default();
        for gi in g {
            for (k, gk) in g.iter().enumerate() {
                if !gi.failed && gk.failed && joined(gi.body, gk.body) && within_support(gi, gk) {
                    cracks.items.push(k as u32);
                }
            }
            cracks.ends.push(cracks.items.len() as u32);
        }
        cracks.wide = wide_lanes();
        cracks
    }

    /// [`CrackLists::severs`] with i's candidates copied for it.
    fn severs_by_lists<const D: usize>(
        cracks: &CrackLists<D>,
        (i, j): (usize, usize),
        g: &[Gather<D>],
        pressure: &[f64],
        joined: impl Fn(u32, u32) -> bool,
    ) -> Option<bool> {
        let mut candidates = Candidates::default();
        let range = cracks.range(i);
        cracks.candidates(range.clone(), Records::whole(g), pressure, &mut candidates);
        cracks.severs(
            (i, j),
            Records::whole(g),
            joined,
            (&candidates, 0..range.len()),
        )
    }

    /// Severing by its definition ([`CrackLists::severs`]) over any list of particles that
    /// holds the candidates (i's whole neighbour list, say), each tested in full: failed, not j,
    /// in both supports, between the two within ¾ of its spacing, of a body that meets both.
    fn severed_by_definition<const D: usize>(
        (i, j): (usize, usize),
        candidates: &[u32],
        gather: &[Gather<D>],
        joined: impl Fn(u32, u32) -> bool,
        pressure: &[f64],
    ) -> Option<bool> {
        let (ga, gb) = (&gather[i.min(j)], &gather[i.max(j)]);
        let e: [f64; D] = std::array::from_fn(|a| gb.x[a] - ga.x[a]);
        let ee = dot(&e, &e);
        let (gi, gj) = (&gather[i], &gather[j]);
        // Every candidate tested, with no branch on the outcome (which varies from one candidate to
        // the next as no predictor could follow). A zero ee gives t = NaN: no cut. Bodies are
        // looked up only for a candidate between the two (the rare case).
        let (mut cut, mut open) = (false, false);
        for &k in candidates {
            let gk = &gather[k as usize];
            let w: [f64; D] = std::array::from_fn(|a| gk.x[a] - ga.x[a]);
            let t = dot(&w, &e) / ee;
            let off: [f64; D] = std::array::from_fn(|a| w[a] - t * e[a]);
            let reach = 0.75 * gk.dp;
            let between = gk.failed
                & (k as usize != j)
                & within_support(gi, gk)
                & within_support(gj, gk)
                & (t > 0.0)
                & (t < 1.0)
                & (dot(&off, &off) < reach * reach);
            let between = between && joined(gi.body, gk.body) && joined(gj.body, gk.body);
            cut |= between;
            open |= between & (pressure[k as usize] <= 0.0);
        }
        cut.then_some(open)
    }

    /// A failed particle between two intact ones severs their pair, with the same answer from
    /// either side; open at no pressure, closed when compressed. Off the segment by a spacing,
    /// beyond its ends, outside either support or of a body the pair does not meet, it does not.
    /// The crack lists' answer is the definition's.
    #[test]
    fn a_failed_particle_between_two_severs_their_pair() {
        let at = |x: [f64; 2], failed: bool, body: u32| Gather::<2> {
            x,
            h: 1.2,
            body,
            failed,
            dp: 1.0,
            ..Gather::padding()
        };
        // Bodies 0 and 1 are welded, and 0 and 2; 1 and 2 meet through the contact.
        let joined = |a: u32, b: u32| a == b || (a.min(b) == 0 && a.max(b) <= 2);
        let cut_between = |gi: Gather<2>, gj: Gather<2>, k: Gather<2>, p_k: f64| {
            let g = [gi, gj, k];
            let pressure = [0.0, 0.0, p_k];
            let (ij, ji) = (
                severed_by_definition((0, 1), &[1, 2], &g, joined, &pressure),
                severed_by_definition((1, 0), &[0, 2], &g, joined, &pressure),
            );
            assert_eq!(ij, ji);
            let cracks = cracks_by_hand(&g, joined);
            assert_eq!(severs_by_lists(&cracks, (0, 1), &g, &pressure, joined), ij);
            assert_eq!(severs_by_lists(&cracks, (1, 0), &g, &pressure, joined), ij);
            ij
        };
        let cut = |k: Gather<2>, p_k: f64| {
            cut_between(at([0.0, 0.0], false, 0), at([2.0, 0.1], false, 0), k, p_k)
        };
        // Across a weld: cut by a failed particle of either body, not by one of a body that
        // meets only one side through the conservation equations.
        let welded = |body_k: u32| {
            cut_between(
                at([0.0, 0.0], false, 0),
                at([2.0, 0.1], false, 1),
                at([1.0, 0.3], true, body_k),
                0.0,
            )
        };
        assert_eq!(welded(0), Some(true));
        assert_eq!(welded(1), Some(true));
        assert_eq!(welded(2), None);
        assert_eq!(cut(at([1.0, 0.3], true, 0), 0.0), Some(true));
        assert_eq!(cut(at([1.0, -0.5], true, 0), 0.0), Some(true));
        assert_eq!(cut(at([1.0, 0.3], true, 0), 1e8), Some(false));
        // A spacing off the segment: the crack's face, not across it.
        assert_eq!(cut(at([1.0, 1.05], true, 0), 0.0), None);
        // Beyond an end.
        assert_eq!(cut(at([-0.5, 0.0], true, 0), 0.0), None);
        // Near i, between the two, but outside j's support (a small h: 1.7 from j).
        let small = Gather {
            h: 0.5,
            ..at([0.2, 0.3], true, 0)
        };
        assert_eq!(cut(small, 0.0), None);
        assert_eq!(
            cut(
                Gather {
                    h: 0.5,
                    ..at([0.6, 0.3], true, 0)
                },
                0.0
            ),
            Some(true)
        );
        // Of another body (in contact, not welded).
        assert_eq!(cut(at([1.0, 0.3], true, 3), 0.0), None);
    }

    /// The crack candidates ([`CrackLists`]) sever exactly the pairs that the whole neighbour
    /// list does, and a pair of intact particles is severed only where both are `cracked`;
    /// a particle with no list here (another rank's) counts as cracked. Each particle's
    /// severed pairs found before the pass are exactly these, in the list's order.
    #[test]
    fn crack_candidates_sever_what_the_whole_list_does() {
        let (mut p, model) = elastic_block();
        let mut rnd = crate::validate::blocks::uniform(5);
        for i in 0..p.len() {
            for k in 0..2 {
                p.x[i][k] += 2e-4 * rnd();
            }
            if i % 5 == 0 {
                p.damage[i] = 1.0;
            }
        }
        let mut nl = NeighborList::default();
        let half = p.n_real / 2;
        nl.own(0..half);
        nl.build(&p.x, &p.h, p.n_real, 0.1 * p.h[0]);
        let gather: Vec<Gather<2>> = (0..p.len())
            .map(|i| Gather::of(&p, i, model.smoothing_ratio))
            .collect();
        let mut cracks = CrackLists::default();
        cracks.build(
            p.n_real,
            Records::whole(&gather),
            &p.damage,
            &p.p,
            &nl,
            &model,
            wide_lanes(),
        );
        let joined = |a: u32, b: u32| joined(&model, a, b);
        let (mut severed_pairs, mut listed) = (0, 0);
        for i in 0..p.n_real {
            assert_eq!(
                cracks.cracked[i],
                !gather[i].failed && (i >= half || !cracks.range(i).is_empty()),
                "{i}"
            );
            if !nl.listed(i) || gather[i].failed {
                continue;
            }
            listed += 1;
            // The pairs found before the pass ([`CrackLists::severed`]), found from either side
            // (or from i's alone where j has no list), in the list's order.
            let mut found = cracks.severed(i).iter();
            for j in nl.list(i) {
                let j = j as usize;
                if gather[j].failed || !within_support(&gather[i], &gather[j]) {
                    continue;
                }
                let whole = severed_by_definition(
                    (i, j),
                    &nl.list(i).collect::<Vec<_>>(),
                    &gather,
                    joined,
                    &p.p,
                );
                let few = severs_by_lists(&cracks, (i, j), &gather, &p.p, joined);
                assert_eq!(whole, few, "pair ({i}, {j})");
                if let Some(open) = whole {
                    severed_pairs += 1;
                    assert!(cracks.cracked[i] && cracks.cracked[j], "pair ({i}, {j})");
                    assert!(meets_in_pass(&model, &gather[i], &gather[j]));
                    assert_eq!(found.next(), Some(&(j as u32, open)), "pair ({i}, {j})");
                }
            }
            assert_eq!(found.next(), None, "{i}: no other pair is severed");
        }
        assert!(
            listed > 0 && severed_pairs > 20,
            "{severed_pairs} severed pairs"
        );
    }

    /// Two aluminium blocks in contact (a at 50 m/s onto b) and a third welded to b, on a
    /// lattice of `spacing`, the material's deck lines ending with `extra`.
    fn three_bodies(spacing: f64, extra: &str) -> String {
        let body = |name: &str, velocity: &str, min: &str, max: &str| {
            format!(
                "[[body]]\nname = \"{name}\"\nmaterial = \"al\"\nspacing = {spacing}\n{velocity}shape = {{ type = \"box\", min = [{min}], max = [{max}] }}\n"
            )
        };
        format!(
            "[simulation]\ndimension = 3\nend_time = 1.0\n[materials.al]\ndensity = 2700.0\neos = {{ type = \"linear\" }}\nstrength = {{ type = \"elastic\", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }}\n{extra}\n{}{}{}[[interaction]]\nbodies = [\"b\", \"c\"]\ntype = \"welded\"\n",
            body("a", "velocity = [50.0, 0.0, 0.0]\n", "-0.005, 0.0, 0.0", "0.0, 0.005, 0.005"),
            body("b", "", "0.0, 0.0, 0.0", "0.006, 0.005, 0.005"),
            body("c", "", "0.0, 0.006, 0.0", "0.006, 0.011, 0.005"),
        )
    }

    /// The AVX2 build of the pass adds the same numbers in the same order as the portable one,
    /// so a run gives the same bits on any x86-64 machine. Two bodies in contact with a welded
    /// third, artificial stress on, a seventh of the particles failed (their pairs cut, and the
    /// pairs between them severed), and a disordered state so that every term is non-zero.
    #[test]
    fn vector_and_portable_passes_agree_bit_for_bit() {
        if !wide_lanes() {
            eprintln!("no AVX2 on this CPU: only the portable pass exists");
            return;
        }
        let case = crate::deck::parse(
            &three_bodies(1.0e-3, "artificial_stress = 0.3"),
            "lanes.toml",
        )
        .unwrap();
        let (mut p, model) = crate::setup::build::<3>(&case).unwrap();
        let mut rnd = crate::validate::blocks::uniform(99);
        for i in 0..p.len() {
            for k in 0..3 {
                p.x[i][k] += 2e-4 * rnd();
                p.v[i][k] += 30.0 * rnd();
                p.u[i][k] = (0.1 * rnd()) as f32;
            }
            p.rho[i] *= 1.0 + 0.05 * rnd();
            p.p[i] = 1e8 * rnd();
            p.c[i] = 5000.0 * (1.0 + 0.1 * rnd());
            let s = Tensor::<3>::from_fn(|_, _| 1e8 * rnd());
            p.s[i] = Sym::from_full(&((s + s.transpose()) * 0.5));
            if i % 7 == 0 {
                p.damage[i] = 1.0;
            }
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.1 * p.h[0]);
        let (mut wide, mut portable) = (Rates::default(), Rates::default());
        let mut states = ColourStates::default();
        let all = 0..p.n_real;
        colour_states(CubicSpline, &p, &nl, &model, (None, &all), &mut states);
        assert!(
            states.kept().iter().any(|s| s.coef > 0.0),
            "the colour law is at work"
        );
        // The pass on AVX2 (`wide`) or portable, with CN-SPH's B (`b`, empty: conventional).
        let pass = |b: &[Tensor<3>], out: &mut Rates<3>, wide: bool| {
            compute_rates_on(
                CubicSpline,
                &p,
                &nl,
                &model,
                (&states, b, &[]),
                &all,
                out,
                wide,
                WINDOW_PAGES,
            );
        };
        pass(&[], &mut wide, true);
        pass(&[], &mut portable, false);
        assert!(wide.contact_force.iter().any(|f| f.norm() > 0.0));
        assert!(wide.cracks.wide && !portable.cracks.wide && !wide.cracks.items.is_empty());
        assert!(wide
            .particles
            .as_slice()
            .iter()
            .all(|r| r.acc.norm() > 0.0 && r.de != 0.0));
        same_rates(&wide.particles, &portable.particles, "");
        assert_eq!(wide.contact_force, portable.contact_force);
        // CN-SPH: the correction pass, then the rates with B.
        let bodies = p.body.clone();
        let joined = |i: usize, j: usize| {
            let (a, b) = (bodies[i], bodies[j]);
            match model.pairs.rule(a, b) {
                _ if a == b => correction::Counts::Body,
                PairRule::Conserve => correction::Counts::Body,
                _ => correction::Counts::Facing,
            }
        };
        let (mut cw, mut cp) = (Vec::new(), Vec::new());
        correction::corrections_on(CubicSpline, &p, &nl, joined, &all, &mut cw, (true, &[]));
        correction::corrections_on(CubicSpline, &p, &nl, joined, &all, &mut cp, (false, &[]));
        assert_eq!(cw, cp);
        assert!(cw
            .iter()
            .any(|c| !c.fallback && c.b != Tensor::<3>::identity()));
        let b: Vec<Tensor<3>> = cw.iter().map(|c| c.b).collect();
        pass(&b, &mut wide, true);
        pass(&b, &mut portable, false);
        same_rates(&wide.particles, &portable.particles, "CN-SPH, ");
        assert_eq!(wide.contact_force, portable.contact_force);
        // The supports the correction pass marks (once the lists are classified by body) give
        // the filter's rates to the bit, with failed particles among them.
        for i in (0..p.n_real).step_by(7) {
            p.damage[i] = 1.0;
        }
        nl.classify(&p.body, false);
        let mut marked = Vec::new();
        correction::corrections_on(CubicSpline, &p, &nl, joined, &all, &mut marked, (true, &[]));
        assert_eq!(marked.iter().map(|c| c.b).collect::<Vec<_>>(), b);
        let n_marked = marked.iter().filter(|c| c.support.is_some()).count();
        assert!(n_marked > p.n_real / 2, "{n_marked} of {}", p.n_real);
        for wide in [true, false] {
            let (mut filtered, mut with) = (Rates::default(), Rates::default());
            for (marks, out) in [(&[][..], &mut filtered), (&marked[..], &mut with)] {
                let fields = (&states, &b[..], marks);
                let w = WINDOW_PAGES;
                compute_rates_on(CubicSpline, &p, &nl, &model, fields, &all, out, wide, w);
            }
            assert!(filtered
                .particles
                .as_slice()
                .iter()
                .any(|r| r.acc.norm() > 0.0));
            let what = format!("CN-SPH, marked supports (wide: {wide}), ");
            same_rates(&filtered.particles, &with.particles, &what);
            assert_eq!(filtered.contact_force, with.contact_force);
        }
    }

    /// The pass in windows of one page, holding the records of only the real particles a
    /// window's lists name, gives the rates of one window holding them all to the bit: two bodies in contact
    /// with a welded third on a symmetry plane across the fastest axis of the cell order (so
    /// that every window needs ghosts), conventional and CN-SPH, over all particles and over
    /// a rank's share. And it holds fewer records than there are particles.
    #[test]
    fn windows_of_records_give_the_whole_passs_rates() {
        let case = crate::deck::parse(&three_bodies(0.5e-3, ""), "windows.toml").unwrap();
        let (mut p, model) = crate::setup::build::<3>(&case).unwrap();
        let mut rnd = crate::validate::blocks::uniform(7);
        for i in 0..p.n_real {
            for k in 0..3 {
                p.x[i][k] += 1e-4 * rnd();
                p.v[i][k] += 30.0 * rnd();
            }
            p.rho[i] *= 1.0 + 0.05 * rnd();
            p.p[i] = 1e8 * rnd();
        }
        // Cell order, as a run keeps it (the windows are runs of it).
        let mut nl = NeighborList::default();
        let order: Vec<usize> = nl
            .cell_order(&p.x, &p.h)
            .iter()
            .map(|&k| k as usize)
            .collect();
        p.permute(&order);
        let plane = [crate::boundary::Plane {
            axis: 2,
            position: 0.0,
            side: 1.0,
            wall: None,
        }];
        let mut ghosts = crate::boundary::Ghosts::default();
        let reach = 2.0 * p.h[0];
        ghosts.rebuild(&mut p, &plane, reach);
        assert!(p.len() > p.n_real && p.n_real > 12 * PAGE);
        nl.build(&p.x, &p.h, p.n_real, 0.1 * p.h[0]);
        // Colour states and B of the real particles, their ghosts' mirrored (as `simulation`).
        let mut states = ColourStates::default();
        let all = 0..p.n_real;
        colour_states(CubicSpline, &p, &nl, &model, (None, &all), &mut states);
        assert!(
            states.kept().iter().any(|s| s.coef > 0.0),
            "the colour law is at work"
        );
        states.extend_to_ghosts(&ghosts, &plane);
        let mut c = Vec::new();
        corrections(CubicSpline, &p, &nl, &model, &all, &mut c);
        let mut b: Vec<Tensor<3>> = c.iter().map(|c| c.b).collect();
        ghosts.extend_to_ghosts_with(&mut b, &plane, |mut b, axis| {
            for k in 0..3 {
                if k != axis {
                    b[(axis, k)] = -b[(axis, k)];
                    b[(k, axis)] = -b[(k, axis)];
                }
            }
            b
        });
        let share = 3 * PAGE + 17..p.n_real - 2 * PAGE;
        for (b, owned) in [(&[][..], &all), (&b[..], &all), (&[][..], &share)] {
            let (mut whole, mut paged) = (Rates::default(), Rates::default());
            for (out, window) in [(&mut whole, usize::MAX), (&mut paged, 1)] {
                let fields = (&states, b, &[][..]);
                compute_rates_on(
                    CubicSpline,
                    &p,
                    &nl,
                    &model,
                    fields,
                    owned,
                    out,
                    false,
                    window,
                );
            }
            // The ring holds fewer records than there are particles, the whole window's all
            // of them.
            let held = paged.gather.len();
            assert!(held < p.n_real, "{held} records");
            assert!(whole.gather.len() >= owned.len());
            assert_eq!(
                whole.particles.range(),
                owned.clone(),
                "only the rates evaluated are held"
            );
            assert!(whole
                .particles
                .as_slice()
                .iter()
                .all(|r| r.acc.norm() > 0.0));
            assert!(whole.contact_force.iter().any(|f| f.norm() > 0.0));
            for i in owned.clone() {
                assert_eq!(whole.particles[i], paged.particles[i], "particle {i}");
                assert_eq!(
                    whole.contact_force[i], paged.contact_force[i],
                    "particle {i}"
                );
            }
        }
    }

    /// The deck of [`elastic_block`].
    const ELASTIC_BLOCK: &str = r#"
[simulation]
dimension = 2
end_time = 1.0
[materials.al]
density = 2700.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }
[[body]]
name = "block"
material = "al"
spacing = 1.0e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [8.0e-3, 6.0e-3] }
"#;

    /// An elastic aluminium block of 8 × 6 mm on a 1 mm lattice (2D), as set up from a deck.
    fn elastic_block() -> (Particles<2>, Model<2>) {
        let case = crate::deck::parse(ELASTIC_BLOCK, "block.toml").unwrap();
        crate::setup::build::<2>(&case).unwrap()
    }

    /// The largest error of the pass's velocity gradient against G, relative to |G|.
    fn worst_gradient(r: &Rates<2>, g: &Tensor<2>) -> f64 {
        r.particles
            .as_slice()
            .iter()
            .map(|x| (x.grad_v - g).norm() / g.norm())
            .fold(0.0, f64::max)
    }

    /// The forces of the pass are antisymmetric: Σ m a = 0 to round-off of Σ |m a|.
    fn assert_no_net_force(p: &Particles<2>, r: &Rates<2>) {
        let force: Vector<2> = (0..p.n_real).map(|i| r.particles[i].acc * p.m[i]).sum();
        let scale: f64 = (0..p.n_real)
            .map(|i| (r.particles[i].acc * p.m[i]).norm())
            .sum();
        assert!(
            force.norm() < 1e-12 * scale,
            "net force {force:?} of {scale}"
        );
    }

    /// CN-SPH through the pass: a linear velocity field v = G x gives L = G to round-off at
    /// every particle of a block, faces and corners included, on a perturbed lattice; the
    /// conventional pass is off at the surface. Forces stay antisymmetric: Σ m a = 0.
    #[test]
    fn corrected_pass_reproduces_a_linear_velocity_field() {
        let (mut p, model) = elastic_block();
        let g = Tensor::<2>::new(30.0, -12.0, 7.0, -21.0);
        let mut seed = 7u64;
        for i in 0..p.n_real {
            for k in 0..2 {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                p.x[i][k] += 2e-4 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            }
            p.v[i] = g * p.x[i];
            p.p[i] = 1e6 * p.x[i][0];
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let mut c = Vec::new();
        assert_eq!(
            corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c),
            0
        );
        let b: Vec<Tensor<2>> = c.iter().map(|c| c.b).collect();
        let (cn, plain) = (
            all_rates(&p, &nl, &model, &b),
            all_rates(&p, &nl, &model, &[]),
        );
        let worst = |r: &Rates<2>| worst_gradient(r, &g);
        assert!(worst(&cn) < 1e-12, "CN-SPH: {}", worst(&cn));
        assert!(worst(&plain) > 0.3, "conventional: {}", worst(&plain));
        assert_no_net_force(&p, &cn);
    }

    /// CN-SPH with the tensor smoothing length: on a block deformed by F (a sheared stretch,
    /// every particle's b = F Fᵀ) and perturbed, a linear velocity field v = G x gives L = G to
    /// round-off at every particle, faces and corners included, with B inverting the
    /// ellipsoid's moments; B from the round kernel's moments with the ellipsoid's gradients
    /// in the pass misses it by more than 30 %. The surface indicator sees the deformed block
    /// as the undeformed one: its smallest real eigenvalue of A_i is the same within the
    /// perturbation's reach (A_i = F⁻ᵀ A_i⁰ Fᵀ on the unperturbed lattice), inside and on the
    /// faces.
    #[test]
    fn corrected_pass_with_the_ellipsoid_reproduces_a_linear_velocity_field() {
        let (mut p, mut model) = elastic_block();
        let (undeformed, _) = elastic_block();
        model.tensor_smoothing = true;
        model.smoothing_stretch = 2.0;
        let f = Tensor::<2>::new(1.5, 0.3, 0.1, 0.7);
        let b = Sym::from_full(&(f * f.transpose()));
        let g = Tensor::<2>::new(30.0, -12.0, 7.0, -21.0);
        let mut rnd = crate::validate::blocks::uniform(5);
        let longest = crate::integrate::largest_stretch(&b.full());
        for i in 0..p.n_real {
            p.x[i] = f * p.x[i];
            p.stretch[i] = b;
            // The ellipsoid's longest half-axis over 2 is h (`integrate::smoothing_length`).
            p.h[i] *= longest;
            for k in 0..2 {
                p.x[i][k] += 1e-4 * rnd();
            }
            p.v[i] = g * p.x[i];
            p.p[i] = 1e6 * p.x[i][0];
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let mut c = Vec::new();
        assert_eq!(
            corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c),
            0
        );
        let bs: Vec<Tensor<2>> = c.iter().map(|c| c.b).collect();
        let mut round = Vec::new();
        let same = correction::same_body(&p);
        correction::corrections(CubicSpline, &p, &nl, same, &(0..p.n_real), &mut round, &[]);
        let round: Vec<Tensor<2>> = round.iter().map(|c| c.b).collect();
        let worst = |r: &Rates<2>| worst_gradient(r, &g);
        let (ell, off) = (
            all_rates(&p, &nl, &model, &bs),
            all_rates(&p, &nl, &model, &round),
        );
        assert!(worst(&ell) < 1e-12, "ellipsoid: {}", worst(&ell));
        assert!(worst(&off) > 0.3, "round moments: {}", worst(&off));
        assert_no_net_force(&p, &ell);
        // The indicator against the undeformed block's, particle by particle.
        let mut nl0 = NeighborList::default();
        nl0.build(&undeformed.x, &undeformed.h, undeformed.n_real, 0.0);
        let mut c0 = Vec::new();
        let model0 = elastic_block().1;
        corrections(
            CubicSpline,
            &undeformed,
            &nl0,
            &model0,
            &(0..p.n_real),
            &mut c0,
        );
        for i in 0..p.n_real {
            let (l, l0) = (c[i].lambda_min, c0[i].lambda_min);
            assert!((l - l0).abs() < 0.1, "particle {i}: {l} against {l0}");
            assert_eq!(
                l < correction::LAMBDA_SURFACE,
                l0 < correction::LAMBDA_SURFACE,
                "particle {i}: {l} against {l0}"
            );
        }
    }

    /// CN-SPH beside a wall: B counts a wall's images only while they are pressed on the
    /// particle, as the rate pass does (`pressed`), and from when the face touches the wall, the
    /// share the rate pass counts (`boundary::wall_share`). A block on the wall y = 0 in a linear
    /// velocity field v = v0 ŷ + G x: lifting off (v0 > 0, unstressed), the face's B is the
    /// free surface's and the corrected L is G to round-off at every particle; pressed on
    /// (v0 < 0) but only touching (its face Δp/2 off the plane), the free surface's too; sunk
    /// 0.01 Δp into the wall's onset, neither; sunk past it (0.05 Δp), the symmetry plane's,
    /// images counted. Until 2026-11-27 B counted the images always, and a lifted face's L was
    /// off by the half of the support that the rate pass no longer summed.
    #[test]
    fn corrected_gradients_count_a_walls_images_only_while_pressed() {
        let deck = format!("{ELASTIC_BLOCK}[[wall]]\naxis = \"y\"\n");
        let case = crate::deck::parse(&deck, "wall.toml").unwrap();
        let (mut p, model) = crate::setup::build::<2>(&case).unwrap();
        let wall = [crate::boundary::Plane {
            axis: 1,
            position: 0.0,
            side: 1.0,
            wall: Some(crate::boundary::Walled::all(1)),
        }];
        let g = Tensor::<2>::new(30.0, 0.0, 0.0, 20.0);
        let face: Vec<usize> = (0..p.n_real).filter(|&i| p.x[i][1] < 1e-3).collect();
        assert_eq!(face.len(), 8);
        let x0 = p.x.clone();
        let dp = p.h0[0] / case.simulation.smoothing_ratio;
        for (v0, sink, met) in [
            (5.0, 0.0, Some(false)),
            (-5.0, 0.0, Some(false)),
            (-5.0, 0.01, None),
            (-5.0, 0.05, Some(true)),
        ] {
            let lifting = v0 > 0.0;
            p.truncate_to_real();
            for (i, x) in x0.iter().enumerate().take(p.n_real) {
                p.x[i] = x - Vector::<2>::new(0.0, sink * dp);
                p.v[i] = g * p.x[i] + Vector::<2>::new(0.0, v0);
            }
            crate::boundary::rebuild_ghosts(&mut p, &wall);
            assert!(p.len() > p.n_real);
            let mut nl = NeighborList::default();
            nl.build(&p.x, &p.h, p.n_real, 0.0);
            let (mut c, mut alone, mut mirrored) = (Vec::new(), Vec::new(), Vec::new());
            corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c);
            let all = 0..p.n_real;
            let body = &p.body;
            correction::corrections(
                CubicSpline,
                &p,
                &nl,
                |i, j| {
                    if body[i] == body[j] {
                        correction::Counts::Body
                    } else {
                        correction::Counts::Not
                    }
                },
                &all,
                &mut alone,
                &[],
            );
            correction::corrections(
                CubicSpline,
                &p,
                &nl,
                |_, _| correction::Counts::Body,
                &all,
                &mut mirrored,
                &[],
            );
            for &i in &face {
                assert_ne!(alone[i].b, mirrored[i].b, "particle {i}");
                match met {
                    Some(true) => assert_eq!(c[i].b, mirrored[i].b, "particle {i}, sunk {sink}"),
                    Some(false) => assert_eq!(c[i].b, alone[i].b, "particle {i}, v0 {v0}"),
                    None => {
                        let (a, m) = (
                            (c[i].b - alone[i].b).norm(),
                            (c[i].b - mirrored[i].b).norm(),
                        );
                        let gap = (alone[i].b - mirrored[i].b).norm();
                        assert!(
                            a > 1e-3 * gap && m > 1e-3 * gap,
                            "particle {i}: {a} {m} of {gap}"
                        );
                    }
                }
            }
            if lifting {
                let mut b: Vec<Tensor<2>> = c.iter().map(|c| c.b).collect();
                b.resize(p.len(), Tensor::identity());
                let worst = worst_gradient(&all_rates(&p, &nl, &model, &b), &g);
                assert!(worst < 1e-12, "L against G: {worst}");
            }
        }
    }

    /// CN-SPH's continuity, dρ_i/dt = ρ_i Σ_j V_j v_ij·∇̃_i W_ij = −ρ_i tr L_i: for a linear
    /// velocity field v = G x it gives −ρ_i tr G to round-off at every particle of a block whose
    /// density varies by half across it, faces and corners included. The mass-weighted sum,
    /// Σ_j m_j v_ij·∇̃_i W_ij (conventional SPH's form), weighs each neighbour by ρ_j/ρ_i and is
    /// off by percents there.
    #[test]
    #[allow(clippy::needless_range_loop)] // i indexes the particles' fields, b and the rates
    fn corrected_continuity_follows_the_velocity_gradient() {
        let (mut p, model) = elastic_block();
        let g = Tensor::<2>::new(30.0, -12.0, 7.0, -21.0);
        for i in 0..p.n_real {
            p.v[i] = g * p.x[i];
            p.rho[i] *= 1.0 + 60.0 * p.x[i][0];
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let mut c = Vec::new();
        corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c);
        let b: Vec<Tensor<2>> = c.iter().map(|c| c.b).collect();
        let rates = all_rates(&p, &nl, &model, &b);
        let mut worst = (0.0_f64, 0.0_f64);
        for i in 0..p.n_real {
            let want = -p.rho[i] * g.trace();
            let got = rates.particles[i].drho;
            // The mass-weighted sum over the same neighbours, by hand.
            let mut massed = 0.0;
            for j in nl.list(i) {
                let j = j as usize;
                let xij = p.x[i] - p.x[j];
                let r = xij.norm();
                if r == 0.0 || r >= p.h[i] + p.h[j] {
                    continue;
                }
                let grad = b[i] * xij * CubicSpline.grad_factor::<2>(r, 0.5 * (p.h[i] + p.h[j]));
                massed += p.m[j] * (p.v[i] - p.v[j]).dot(&grad);
            }
            worst.0 = worst.0.max((got / want - 1.0).abs());
            worst.1 = worst.1.max((massed / want - 1.0).abs());
        }
        eprintln!(
            "continuity against −ρ tr G: CN-SPH {:.1e}, mass-weighted {:.3}",
            worst.0, worst.1
        );
        assert!(worst.0 < 1e-12, "CN-SPH's continuity: {}", worst.0);
        assert!(worst.1 > 0.02, "the mass-weighted sum: {}", worst.1);
    }

    /// The density diffusion (module doc) is a diffusion: on a block at rest whose density
    /// alternates ±1 % from particle to particle like a checkerboard (every nearest neighbour
    /// the other sign), each denser particle loses density and each lighter one gains it,
    /// faces and corners included, while Σ V_i dρ_i/dt stays zero to round-off and δ = 0
    /// leaves the continuity as it was (zero at rest); a uniform density gets none.
    #[test]
    fn density_diffusion_smooths_a_checkerboard_and_keeps_the_volume_weighted_sum() {
        let (mut p, mut model) = elastic_block();
        let rho0 = p.rho[0];
        let sign = |x: &Vector<2>| {
            let k = (x[0] / 1e-3).floor() as i64 + (x[1] / 1e-3).floor() as i64;
            if k % 2 == 0 {
                1.0
            } else {
                -1.0
            }
        };
        for i in 0..p.n_real {
            p.rho[i] = rho0 * (1.0 + 0.01 * sign(&p.x[i]));
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let b = vec![Tensor::<2>::identity(); p.n_real];
        let off = all_rates(&p, &nl, &model, &b);
        assert!((0..p.n_real).all(|i| off.particles[i].drho == 0.0));
        model.density_diffusion = 0.1;
        let on = all_rates(&p, &nl, &model, &b);
        let (mut sum, mut scale) = (0.0, 0.0);
        for i in 0..p.n_real {
            let d = on.particles[i].drho;
            assert!(
                d * sign(&p.x[i]) < 0.0,
                "particle {i} at {:?}: dρ/dt {d}",
                p.x[i]
            );
            let v = p.m[i] / p.rho[i];
            sum += v * d;
            scale += v * d.abs();
        }
        assert!(
            sum.abs() < 1e-12 * scale,
            "Σ V dρ/dt = {sum:e} of {scale:e}"
        );
        p.rho.iter_mut().for_each(|r| *r = rho0);
        let uniform = all_rates(&p, &nl, &model, &b);
        assert!((0..p.n_real).all(|i| uniform.particles[i].drho == 0.0));
    }

    /// CN-SPH's energy split (module doc): a particle's energy rate does not take its
    /// neighbours' corrections B_j, only their plain stresses, so that a surface particle's
    /// large (σ_j/ρ_j²) B_j ∇W stays out of its neighbours' energy; and the pass still turns
    /// exactly the forces' power into heat, Σ m_i de_i/dt = −Σ m_i v_i·a_i. On a perturbed block
    /// under a varying stress and a random motion, scaling one corner's B changes no other
    /// particle's de/dt (with the pair's work split in halves it changes its neighbours').
    #[test]
    fn corrected_energy_keeps_each_correction_with_its_particle() {
        let (mut p, model) = elastic_block();
        let mut seed = 11u64;
        let mut random = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for i in 0..p.n_real {
            for k in 0..2 {
                p.x[i][k] += 2e-4 * random();
                p.v[i][k] = 20.0 * random();
            }
            p.p[i] = 1e8 * (1.0 + 200.0 * p.x[i][0]);
            p.s[i] = Sym::from_full(&(Tensor::<2>::new(1.0, 0.5, 0.5, -1.0) * (3e7 * random())));
        }
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let mut c = Vec::new();
        corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c);
        let mut b: Vec<Tensor<2>> = c.iter().map(|c| c.b).collect();
        let before = all_rates(&p, &nl, &model, &b);
        let (heat, work) = (0..p.n_real).fold((0.0, 0.0), |(h, w), i| {
            let r = &before.particles[i];
            (h + p.m[i] * r.de, w + p.m[i] * p.v[i].dot(&r.acc))
        });
        let scale: f64 = (0..p.n_real)
            .map(|i| p.m[i] * p.v[i].norm() * before.particles[i].acc.norm())
            .sum();
        assert!(
            (heat + work).abs() < 1e-12 * scale,
            "heat {heat} against work {work} (of {scale})"
        );
        let corner = (0..p.n_real)
            .min_by(|&i, &j| p.x[i].norm().total_cmp(&p.x[j].norm()))
            .unwrap();
        b[corner] *= 1.5;
        let after = all_rates(&p, &nl, &model, &b);
        let neighbours: Vec<usize> = nl.list(corner).map(|j| j as usize).collect();
        assert!(neighbours.len() > 3);
        for i in (0..p.n_real).filter(|&i| i != corner) {
            assert_eq!(
                before.particles[i].de,
                after.particles[i].de,
                "particle {i} (a neighbour of the corner: {})",
                neighbours.contains(&i)
            );
        }
        assert_ne!(before.particles[corner].de, after.particles[corner].de);
    }

    /// A failed particle's pairs are cut on the ellipsoid of the tensor smoothing length
    /// ([`asph`]): in a block under uniform tension (−100 MPa), at rest, on a perturbed
    /// lattice, with every particle stretched by the same sheared b, a failed particle inside
    /// it (carrying nothing itself) feels no force, since each of its pairs passes on only
    /// compression; and the forces stay antisymmetric, Σ m a = 0. Cut on the round kernel
    /// while the pass sums on the ellipsoid, it feels 5 % of one side's tension force.
    #[test]
    fn a_failed_particles_pairs_are_cut_on_the_ellipsoid() {
        let (mut p, mut model) = elastic_block();
        model.tensor_smoothing = true;
        model.smoothing_stretch = 2.0;
        let b = Sym::from_full(&Tensor::<2>::new(1.8, 0.4, 0.4, 0.7));
        let mut rnd = crate::validate::blocks::uniform(3);
        for i in 0..p.n_real {
            p.stretch[i] = b;
            p.p[i] = -1e8;
            // Off the lattice, so that the pairs' forces do not cancel by symmetry.
            for k in 0..2 {
                p.x[i][k] += 2e-4 * rnd();
            }
        }
        let failed = (0..p.n_real)
            .min_by(|&i, &j| {
                let d = |k: usize| (p.x[k] - Vector::<2>::new(4.5e-3, 3.5e-3)).norm();
                d(i).total_cmp(&d(j))
            })
            .unwrap();
        p.damage[failed] = 1.0;
        p.p[failed] = 0.0;
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let rates = all_rates(&p, &nl, &model, &[]);
        // What one side's tension alone gives the failed particle: Σ_j m_j |p_j|/ρ_j² |∇W|.
        let h = p.h[failed];
        let scale: f64 = nl
            .list(failed)
            .map(|j| j as usize)
            .map(|j| {
                let r = (p.x[failed] - p.x[j]).norm();
                p.m[j] * 1e8 / (p.rho[j] * p.rho[j])
                    * (r * CubicSpline.grad_factor::<2>(r, h)).abs()
            })
            .sum();
        assert!(scale > 0.0);
        let a = rates.particles[failed].acc.norm();
        assert!(a < 1e-12 * scale, "failed particle: |a| = {a} of {scale}");
        let intact = (0..p.n_real).find(|&i| i != failed).unwrap();
        assert!(rates.particles[intact].acc.norm() > 1e-3 * scale);
        let momentum: Vector<2> = (0..p.n_real).map(|i| p.m[i] * rates.particles[i].acc).sum();
        let total: f64 = (0..p.n_real)
            .map(|i| p.m[i] * rates.particles[i].acc.norm())
            .sum();
        assert!(
            momentum.norm() < 1e-12 * total,
            "Σ m a = {momentum:?} of {total}"
        );
    }

    /// Bodies closing on each other through the contact bound the time step by their relative
    /// speed, as neighbours of one body do: Δt = C h / (c + |v_ij| + 0.6 α c) for two particles
    /// of different bodies meeting at ±v (a soft contact, so that its springs do not set Δt).
    #[test]
    fn contact_pairs_bound_the_time_step_by_their_closing_speed() {
        let deck = r#"
[simulation]
name = "closing"
dimension = 2
end_time = 1.0
[materials.al]
density = 2700.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }
[[body]]
name = "a"
material = "al"
spacing = 1.0e-3
velocity = [500.0, 0.0]
shape = { type = "rectangle", min = [0.0, 0.0], max = [1.0e-3, 1.0e-3] }
[[body]]
name = "b"
material = "al"
spacing = 1.0e-3
velocity = [-500.0, 0.0]
shape = { type = "rectangle", min = [1.5e-3, 0.0], max = [2.5e-3, 1.0e-3] }
[[interaction]]
bodies = ["a", "b"]
type = "contact"
law = "paper"
stiffness = 1.0
"#;
        let case = crate::deck::parse(deck, "closing.toml").unwrap();
        let (p, model) = crate::setup::build::<2>(&case).unwrap();
        assert_eq!(p.n_real, 2);
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let rates = all_rates(&p, &nl, &model, &[]);
        let c = p.c[0];
        let expect = model.cfl * p.h[0] / (c + 1000.0 + 0.6 * model.alpha * c);
        assert!(rates.particles[0].neighbors == 1);
        assert!(
            (rates.particles[0].dt / expect - 1.0).abs() < 1e-12,
            "{} vs {expect}",
            rates.particles[0].dt
        );
    }
}
