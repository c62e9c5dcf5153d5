//! The colour form of eq. (5): the contact potential of a particle is a function of the *other*
//! body's colour at it, c_i = Σ_{j∈C_i} V_j W_ij — the paper's φ(x_i) = Σ_j V_j K (W_ij/W0)^n
//! with the power taken of the sum rather than of each term — offset so that it vanishes for
//! bodies that merely touch, and sized by the material's own stiffness. See the module doc of
//! [`crate::contact`] for why; here are the pieces:
//!
//! - **Strain.** For a particle facing a flat lattice of the other body, the colour is a
//!   monotone function c(d) of the gap d to the facing layer ([`LatticeColour`], a lattice sum
//!   for the dimension, kernel and h/Δp in use). Its inverse reads a colour as the interface
//!   strain ε = 1 − d/Δp: 0 for bodies touching at the natural spacing Δp (c = c0), positive
//!   when they are pressed together. The colour is taken with each neighbour's reference volume
//!   m/ρ0 and the reference smoothing length h0, so that it measures geometry only and the
//!   potential is a function of the positions alone (energy is conserved).
//! - **Potential.** Φ_i = ½ V0_i Σ_u(ε_i), with Σ_u(ε) = ∫₀^ε σ_u the work of the material's
//!   uniaxial-strain compression curve σ_u(ε) = p(ρ0/(1 − ε), e = 0) + min(4G/3 ε, 2Y0/3)
//!   ([`UniaxialCurve`]). Two facing layers pressed to a strain ε then carry the traction
//!   σ_u(ε), as a layer of the material itself would: the contact is as stiff as the bodies, at
//!   any pressure (hypervelocity shocks included), and follows the load the contact carries.
//! - **Force.** −∇Φ pairs up as f_c,i = −Σ_j V0_i V0_j (P_i + P_j) ∇_i W_ij (h0), with
//!   P = ½ σ_u(ε) dε/dc: eq. (5)'s shape with the pair factor K n (W_ij/W0)^(n−1) replaced by
//!   the two particles' colour derivatives. Each pair's force is split along the contact
//!   normal n̂_ij (from the two bodies' own outward normals, [`normal`]): the normal part acts
//!   in full and never pulls; of the tangential part — for a pair mostly the lattice
//!   corrugation of the other body's surface — all is kept while the interface is pressed
//!   lightly, and only [`TANGENTIAL`] of it where it is pressed hard ([`tangential_share`], by
//!   the pair's interface strain). With all of it at every load the two lattices of a 7 km/s
//!   planar impact slide into each other's gaps at Δp = 0.05 mm (penetration 2.1 Δp when the
//!   share was chosen; with the damping since, the interface roughens to 0.73 Δp, against
//!   1e-4 Δp with half); with none of it particles sliding sideways past each other at a jet's
//!   edge are not kept apart. Half at every load (until 2026-11-29) kept the planar interface
//!   flat but made the contact a drag wherever a body slides along a curved one, since the
//!   work of a force that is not −∇Φ departs from the potential: the ogive projectile of
//!   `examples/ogive_plate.toml` at 167 m/s lost 12 % of the energy in 80 µs, and came out at
//!   7.5 m/s against 31.5 m/s with all of −∇Φ; a Hertz impact's energy strayed by 0.83 %.
//!   Below [`PRESSED`] the force is −∇Φ and energy is kept (4e-5 and 2e-4). Linear momentum is
//!   conserved exactly (every pair force is antisymmetric); where the share falls below one,
//!   angular momentum and energy are not: a 1 mm aluminium sphere into an aluminium block at
//!   6 km/s (`examples/crater.toml`) loses 4.5 % of the energy in its first 0.25 µs (CN-SPH,
//!   whose contact acts along the normal only, 5.1 %), the same at a third of the step.
//! - **Damping.** The interface of a shock is part of the shock: [`damping`] gives contact
//!   pairs the bulk's quadratic viscosity on their normal closing speed (without it the first
//!   layers of a 7 km/s impact closed to 0.44 Δp and rang back; with it 0.58 Δp, and the peak
//!   pressure is +6 % of the Hugoniot's at both resolutions).
//! - **Backstop.** A sparse neighbourhood (a debris filament) can stay below touching colour
//!   however close the other body comes; [`backstop`] is a pair potential from the same
//!   compression curves, idle beyond 0.6 Δp, that keeps such particles apart.

use crate::kernel::Kernel;
use crate::material::Material;
use crate::neighbors::NeighborList;
use crate::particles::{Particles, Tensor};
use crate::physics::correction::{self, plane_normal, LAMBDA_SURFACE};
use rayon::prelude::*;
use std::ops::Range;

/// The colour of a flat square (2D) or simple-cubic (3D) lattice of spacing Δp seen by a
/// particle whose facing layer is d away (head-on), tabulated for d ∈ [D_MIN, 1] Δp and read
/// backwards as the strain ε = 1 − d/Δp.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeColour {
    /// Colours, increasing (d decreasing), and the strains they mean.
    colour: Vec<f64>,
    strain: Vec<f64>,
}

/// The table's smallest gap (Δp): beyond it the strain is extrapolated.
const D_MIN: f64 = 0.05;
const TABLE: usize = 400;

impl LatticeColour {
    pub fn new<const D: usize, K: Kernel>(kernel: K, smoothing_ratio: f64) -> Self {
        let h = smoothing_ratio;
        let reach = (2.0 * h).ceil() as i64 + 1;
        let lateral = if D == 3 { reach } else { 0 };
        let colour_at = |d: f64| {
            let mut c = 0.0;
            for a in 0..=reach {
                let z = d + a as f64;
                for k in -reach..=reach {
                    for l in -lateral..=lateral {
                        let r = ((k * k + l * l) as f64 + z * z).sqrt();
                        c += kernel.w::<D>(r, h);
                    }
                }
            }
            c
        };
        let (mut colour, mut strain) = (Vec::new(), Vec::new());
        for k in 0..=TABLE {
            let d = 1.0 - (1.0 - D_MIN) * k as f64 / TABLE as f64;
            colour.push(colour_at(d));
            strain.push(1.0 - d);
        }
        LatticeColour { colour, strain }
    }

    /// c0: the colour of touching at the natural spacing, where the potential starts.
    pub fn touching(&self) -> f64 {
        self.colour[0]
    }

    /// (ε, dε/dc) for a colour c ≥ c0.
    pub fn strain(&self, c: f64) -> (f64, f64) {
        let n = self.colour.len();
        let k = self.colour.partition_point(|&x| x <= c).clamp(1, n - 1);
        let (c0, c1) = (self.colour[k - 1], self.colour[k]);
        let (e0, e1) = (self.strain[k - 1], self.strain[k]);
        let slope = (e1 - e0) / (c1 - c0);
        (e0 + (c - c0) * slope, slope)
    }
}

/// How far past the colour of touching, relatively, a particle's colour must be for the
/// contact to act on it. Bodies laid out touching at the natural spacing (every deck that
/// places one on another) start with colours equal to [`LatticeColour::touching`] in exact
/// arithmetic, and the round-off of each particle's sum put some over it and some under: the
/// pairs over it took the interface's [`damping`] of their whole closing speed at once, their
/// mirror images none. Two identical Taylor rods meeting (R0/Δp = 8, CN-SPH) were out of
/// mirror symmetry by 5e-6 Δp after the first step and 2.5e-3 Δp at 36 µs (2026-12-03); with
/// the tie broken, within 3e-10 Δp to 68 µs. (At R0/Δp = 16 one particle near the axis still
/// ends 0.2 Δp past the plane between them: whatever grows there, it is not this seed.) A
/// strain of 1e-10 of a spacing is no physical contact.
pub const TOUCHING_TIE: f64 = 1e-10;

/// A material's uniaxial-strain compression curve at zero internal energy, and its work.
#[derive(Debug, Clone, PartialEq)]
pub struct UniaxialCurve {
    /// Σ_u at ε = k ΔE, k = 0..=N.
    work: Vec<f64>,
    /// σ_u and dσ_u/dε at the table's end, for ε beyond it.
    end: (f64, f64),
}

/// The table step and end: beyond CAP the curve continues with its slope there (compression
/// beyond 60 % is far past any Hugoniot state of a solid).
const DE: f64 = 1e-3;
const CAP: f64 = 0.6;

impl UniaxialCurve {
    pub fn new(m: &Material) -> Self {
        let n = (CAP / DE).round() as usize;
        let mut work = vec![0.0];
        for k in 0..n {
            // Simpson's rule over each step.
            let (a, b) = (k as f64 * DE, (k + 1) as f64 * DE);
            let s = (stress(m, a) + 4.0 * stress(m, 0.5 * (a + b)) + stress(m, b)) * DE / 6.0;
            work.push(work[k] + s);
        }
        let d = 1e-6;
        let end = (stress(m, CAP), (stress(m, CAP) - stress(m, CAP - d)) / d);
        UniaxialCurve { work, end }
    }

    /// (σ_u(ε), dσ_u/dε, Σ_u(ε)) for ε ≥ 0, with `m` the material the curve was made for.
    pub fn at(&self, m: &Material, eps: f64) -> (f64, f64, f64) {
        if eps >= CAP {
            let x = eps - CAP;
            let (s, ds) = self.end;
            let w = self.work[self.work.len() - 1] + s * x + 0.5 * ds * x * x;
            return (s + ds * x, ds, w);
        }
        let s = stress(m, eps);
        let d = 1e-7;
        let ds = (stress(m, eps + d) - s) / d;
        let k = (eps / DE).floor() as usize;
        let e0 = k as f64 * DE;
        // Simpson from the tabulated point: its derivative is σ_u(ε) to second order in the
        // step (a trapezoid's was off by ½σ_u'(ε)(ε − e0), 1 % at ε = 0.45 for aluminium), so
        // the force and the potential it derives from agree.
        let mid = stress(m, 0.5 * (e0 + eps));
        let w = self.work[k] + (stress(m, e0) + 4.0 * mid + s) * (eps - e0) / 6.0;
        (s, ds, w)
    }
}

/// σ_u(ε) = p(ρ0/(1 − ε), 0) + min(4G/3 ε, 2Y0/3): the stress of a uniaxial compression ε.
pub fn stress(m: &Material, eps: f64) -> f64 {
    let p = m.pressure(m.rho0 / (1.0 - eps), 0.0).max(0.0);
    let g = m.strength.reference_shear_modulus();
    let y = m.strength.reference_yield_stress();
    p + (4.0 / 3.0 * g * eps).min(2.0 / 3.0 * y)
}

/// The colour law of a case: the lattice table and each material's curve.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourLaw {
    pub lattice: LatticeColour,
    /// Indexed like the case's materials.
    pub curves: Vec<UniaxialCurve>,
}

impl ColourLaw {
    pub fn new<const D: usize, K: Kernel>(
        kernel: K,
        smoothing_ratio: f64,
        materials: &[Material],
    ) -> Self {
        ColourLaw {
            lattice: LatticeColour::new::<D, K>(kernel, smoothing_ratio),
            curves: materials.iter().map(UniaxialCurve::new).collect(),
        }
    }
}

/// What the pass needs of a particle that meets another body through the colour law.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ColourState {
    /// P = ½ σ_u(ε) dε/dc (Pa): the particle's share of each pair coefficient.
    pub coef: f64,
    /// ½ dσ_u/dε (dε/dc)² (Pa), for the time step.
    pub curvature: f64,
    /// Its potential Φ_i = ½ V0 Σ_u(ε) (J).
    pub energy: f64,
    /// Σ_j V0_j |∇_i W_ij| over its contact neighbours (1/m), for the time step.
    pub grad_sum: f64,
    /// Outward normal of its own body (welded bodies included), −Σ_k V0_k ∇_i W_ik over its own
    /// neighbours, unnormalised (≈ 1/h at a face, ≈ 0 inside).
    pub normal: [f64; 3],
    /// The interface strain ε its colour reads (0 where it is not pressed).
    pub strain: f64,
    /// CN-SPH: how far its body's surface particles within its support are from a plane
    /// ([`correction::plane_normal`]: 0 on a face, up to 1 at an edge or a corner), which
    /// weighs `normal` in a pair's ([`normal`]); 0 in conventional SPH.
    pub roughness: f64,
}

/// How two bodies meet, as the colour states need it.
pub trait Meeting: Sync {
    /// Whether bodies a ≠ b meet through the colour law.
    fn colour(&self, a: u32, b: u32) -> bool;
    /// Whether bodies a ≠ b meet through a contact law (either).
    fn contact(&self, a: u32, b: u32) -> bool;
    /// Whether bodies a ≠ b are welded (one body for the normal).
    fn welded(&self, a: u32, b: u32) -> bool;
    /// The material of body b.
    fn material(&self, b: u32) -> (usize, &Material);
}

/// CN-SPH's view of the bodies' surfaces, for the contact normal: the surface indicator λ_min
/// of every particle, ghosts included (see [`crate::physics::correction`]).
#[derive(Clone, Copy)]
pub struct Surfaces<'a, const D: usize> {
    pub lambda: &'a [f64],
}

/// The colour state of the real particles in `owned` (`out[i]`; `out` holds one for every real
/// particle, the default for those outside `owned` until [`ColourStates::share`]), from its
/// neighbours within the support.
///
/// The outward normal is −Σ_k V0_k ∇_i W_ik over its own body in conventional SPH. With
/// CN-SPH's `surfaces`, where the body's boundary is its boundary particles, it is the normal of
/// the plane through the surface particles (λ_min < [`LAMBDA_SURFACE`]) of its own body within
/// its support, weighted by W and oriented outwards, with the same length; where they do not
/// lie on a plane (an edge, a corner, a filament), the corrected gradient's B_i Σ_k V0_k ∇_i W_ik
/// gives its direction. That B_i is over the particle's own body (and welded bodies), summed
/// here: the rate pass's B counts a facing body's particles too
/// ([`crate::physics::correction::Counts::Facing`]), and with the normal from that B the
/// CN-SPH slider of `strike validate --case sliding` lost 1.03 % of its speed at Δp = 0.05 m
/// (0.73 % before the facing body counted, 0.79 % with this B). On the face of a lattice
/// perturbed by up to ±0.1 Δp the uncorrected sum strays up to 7.5° from the face's normal and
/// the corrected one 3.7°; the plane is exact. How far the surface particles are from that
/// plane (their roughness) weighs the normal against the other side's in the pair's
/// ([`normal`]). Every contact pair (of either law) then gets a state, for its normal.
pub fn states<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    meeting: &impl Meeting,
    (law, surfaces): (Option<&ColourLaw>, Option<Surfaces<D>>),
    owned: &Range<usize>,
    out: &mut ColourStates,
) {
    let state = |i: usize| {
        let bi = p.body[i];
        // Most particles have no neighbour of another body (see `NeighborList::classify`).
        if !nl.mixed.get(i).copied().unwrap_or(true) {
            return ColourState::default();
        }
        let (mut c, mut g) = (0.0, 0.0);
        let mut own = [0.0; 3];
        let mut near = false;
        // CN-SPH: the moments of the surface particles about x_i, weighted by W, and A_i over
        // the own body for the corrected gradient (as `physics::correction` sums it).
        let (mut count, mut w, mut m1, mut m2) = (0, 0.0, [0.0; D], Tensor::<D>::zeros());
        let mut a_own = Tensor::<D>::zeros();
        let h0i = p.h0[i];
        if let Some(s) = surfaces {
            if s.lambda[i] < LAMBDA_SURFACE {
                count = 1;
                w = kernel.w::<D>(0.0, h0i);
            }
        }
        for j in nl.list(i) {
            let j = j as usize;
            let bj = p.body[j];
            let r = (p.x[i] - p.x[j]).norm();
            if r >= p.h[i] + p.h[j] {
                continue;
            }
            let same = bj == bi || meeting.welded(bi, bj);
            let colour = !same && meeting.colour(bi, bj);
            let cn_contact = surfaces.is_some() && meeting.contact(bi, bj);
            if !(same || colour || cn_contact) {
                continue;
            }
            let h0 = 0.5 * (h0i + p.h0[j]);
            let vol0 = p.m[j] / meeting.material(bj).1.rho0;
            let dw = kernel.dw::<D>(r, h0);
            if same {
                if r > 0.0 {
                    for (a, o) in own.iter_mut().enumerate().take(D) {
                        *o -= vol0 * dw * (p.x[i][a] - p.x[j][a]) / r;
                    }
                }
                if let Some(s) = surfaces {
                    if r > 0.0 {
                        let hij = 0.5 * (p.h[i] + p.h[j]);
                        let f = -p.volume(j) * kernel.dw::<D>(r, hij) / r;
                        for a in 0..D {
                            for b in 0..D {
                                a_own[(a, b)] +=
                                    f * (p.x[i][a] - p.x[j][a]) * (p.x[i][b] - p.x[j][b]);
                            }
                        }
                    }
                    if s.lambda[j] < LAMBDA_SURFACE {
                        let wk = kernel.w::<D>(r, h0);
                        let d: [f64; D] = std::array::from_fn(|a| p.x[j][a] - p.x[i][a]);
                        count += 1;
                        w += wk;
                        for a in 0..D {
                            m1[a] += wk * d[a];
                            for b in 0..D {
                                m2[(a, b)] += wk * d[a] * d[b];
                            }
                        }
                    }
                }
            } else {
                near = true;
                if colour {
                    c += vol0 * kernel.w::<D>(r, h0);
                    g += vol0 * dw.abs();
                }
            }
        }
        if !near {
            return ColourState::default();
        }
        let mut rough = 0.0;
        if surfaces.is_some() {
            let length = own.iter().map(|x| x * x).sum::<f64>().sqrt();
            let b = correction::invert(&a_own, correction::surface_indicator(&a_own))
                .unwrap_or_else(Tensor::<D>::identity);
            let corrected: [f64; D] =
                std::array::from_fn(|a| (0..D).map(|k| b[(a, k)] * own[k]).sum());
            let (plane, r) = plane_normal(count, w, &m1, &m2);
            rough = r;
            let dir: [f64; D] = plane
                .map(|n| {
                    // Outwards: the side the (corrected) gradient points to.
                    let side: f64 = (0..D).map(|a| n[a] * corrected[a]).sum();
                    std::array::from_fn(|a| if side < 0.0 { -n[a] } else { n[a] })
                })
                .unwrap_or_else(|| {
                    let l = corrected.iter().map(|x| x * x).sum::<f64>().sqrt();
                    std::array::from_fn(|a| if l > 0.0 { corrected[a] / l } else { 0.0 })
                });
            own = [0.0; 3];
            for a in 0..D {
                own[a] = dir[a] * length;
            }
        }
        let mut s = ColourState {
            grad_sum: g,
            normal: own,
            roughness: rough,
            ..Default::default()
        };
        if let Some(law) = law.filter(|law| c > law.lattice.touching() * (1.0 + TOUCHING_TIE)) {
            let (eps, deps) = law.lattice.strain(c);
            let (k, mat) = meeting.material(bi);
            let (sigma, stiff, work) = law.curves[k].at(mat, eps.max(0.0));
            let vol0 = p.m[i] / mat.rho0;
            s.coef = 0.5 * sigma * deps;
            s.curvature = 0.5 * stiff * deps * deps;
            s.energy = 0.5 * vol0 * work;
            s.strain = eps.max(0.0);
        }
        s
    };
    // Only the particles near another body have a state other than the default: kept in
    // particle order, whatever the thread count.
    let found: Vec<(u32, ColourState)> = owned
        .clone()
        .into_par_iter()
        .filter_map(|i| {
            let s = state(i);
            (s != ColourState::default()).then_some((i as u32, s))
        })
        .collect();
    out.slot.clear();
    out.slot.resize(p.n_real, 0);
    out.states.clear();
    out.states.push(ColourState::default());
    for (i, s) in found {
        out.slot[i as usize] = out.states.len() as u32;
        out.states.push(s);
    }
}

/// The colour states of all particles, ghosts included, kept only for the particles that have
/// one other than the default (those near another body): `slot[i]` indexes `states`, whose
/// first entry is the default state that every other particle reads. Kept for every particle, a
/// state took 64 bytes of each in 3D, the largest share of a contact run's memory after the
/// particles' own state and their lists; few particles are near another body.
#[derive(Debug, Clone, Default)]
pub struct ColourStates {
    slot: Vec<u32>,
    states: Vec<ColourState>,
}

impl std::ops::Index<usize> for ColourStates {
    type Output = ColourState;

    #[inline]
    fn index(&self, i: usize) -> &ColourState {
        &self.states[self.slot[i] as usize]
    }
}

impl ColourStates {
    /// Particle i's state, if the states reach it.
    #[inline]
    pub fn get(&self, i: usize) -> Option<&ColourState> {
        self.slot.get(i).map(|&k| &self.states[k as usize])
    }

    /// No states (no pair of bodies uses them).
    pub fn clear(&mut self) {
        self.slot.clear();
        self.states.clear();
    }

    /// The states other than the default, in particle order.
    pub fn kept(&self) -> &[ColourState] {
        self.states.get(1..).unwrap_or(&[])
    }

    /// Under MPI, after each rank has found the states of its own range: the states of its
    /// halo's particles from their ranks (over the halo's `plan`), each joining `states` after
    /// this rank's own, its particle's slot with it. Only states other than the default
    /// travel (few particles are near another body); the slots of the particles outside the
    /// range and the halo stay at the default, and no pass reads them.
    pub fn swap(&mut self, ranks: crate::ranks::Ranks, plan: &crate::ranks::Plan) {
        let pack = |c: &Self, idx: &[u32], out: &mut Vec<(u64, ColourState)>| {
            let kept = idx.iter().filter(|&&i| c.slot[i as usize] != 0);
            out.extend(kept.map(|&i| (u64::from(i), c[i as usize])));
        };
        ranks.exchange(plan, self, pack, |c, _, got| {
            for &(i, state) in got {
                c.slot[i as usize] = c.states.len() as u32;
                c.states.push(state);
            }
        });
    }

    /// Extend the states to the ghosts, in ghost order: each ghost gets its source's state with
    /// the normal's component along its plane's axis reversed.
    pub fn extend_to_ghosts(
        &mut self,
        ghosts: &crate::boundary::Ghosts,
        planes: &[crate::boundary::Plane],
    ) {
        let states = &mut self.states;
        ghosts.extend_to_ghosts_with(&mut self.slot, planes, |k, axis| {
            if k == 0 {
                return 0;
            }
            let mut s = states[k as usize];
            s.normal[axis] = -s.normal[axis];
            states.push(s);
            (states.len() - 1) as u32
        });
    }
}

/// The roughness that even a flat face's normal is taken to have, in [`normal`]'s weights.
pub const ROUGHNESS_FLOOR: f64 = 1e-3;

/// The contact normal of a pair (i of body A, j of body B), pointing from A into B: the
/// difference of the two bodies' own outward normals, antisymmetric in i and j, or the line
/// of centres where both are negligible (two particles deep inside their bodies). `h` scales
/// the normals to numbers of order one; `xij` = x_i − x_j, `r` = |xij|.
///
/// In CN-SPH each side's normal is weighted by the inverse of its variance, 1/(roughness +
/// [`ROUGHNESS_FLOOR`]), as two estimates of one quantity are combined: two faces count alike,
/// and an edge or a corner (or a face near one, whose fitted plane tilts towards the edge)
/// against a flat face takes the face's normal, as a frictionless face pushes. With the plain
/// difference the diagonal normal of a rod's rim standing on a fixed block pushed the rim
/// inwards like a friction: the copper Taylor rod's face on a fixed block came out at 11.75 mm
/// against 12.54 on its twin and 13.01 on the wall (R0/Δp = 8; with the weights 12.67 mm, the
/// twin 12.49), and on a block pressed by a narrower one the force on the narrower one's
/// pressed layers tilted by up to 5.6° from the face's normal, at its edges by up to 41° (with
/// the weights 0.4° and 2.5°, `validate::blocks::contact_direction`).
#[inline(always)]
pub fn normal<const D: usize>(
    si: &ColourState,
    sj: &ColourState,
    xij: &[f64; D],
    r: f64,
    h: f64,
) -> [f64; D] {
    // Each side's normal weighted by the inverse of its variance (CN-SPH; conventional SPH's
    // roughness is 0 on both sides): an edge or a corner against a face meets the face.
    let (wi, wj) = (
        sj.roughness + ROUGHNESS_FLOOR,
        si.roughness + ROUGHNESS_FLOOR,
    );
    let scale = 2.0 * h / (wi + wj);
    let d: [f64; D] = std::array::from_fn(|a| (wi * si.normal[a] - wj * sj.normal[a]) * scale);
    let n2: f64 = d.iter().map(|x| x * x).sum();
    if n2 > 1e-6 {
        let n = n2.sqrt();
        std::array::from_fn(|a| d[a] / n)
    } else {
        std::array::from_fn(|a| -xij[a] / r)
    }
}

/// The share of the tangential part of each pair's force that the colour law keeps between
/// lattices pressed hard together (see the module doc and [`tangential_share`]).
pub const TANGENTIAL: f64 = 0.5;

/// The interface strains between which the tangential share falls from 1 (all of −∇Φ) to
/// [`TANGENTIAL`]: 0.05, about 5 GPa of interface stress in aluminium (a 1 km/s impact), and
/// 0.15, about 17 GPa (3 km/s). A 7 km/s impact presses its interface to ε ≈ 0.35.
pub const PRESSED: (f64, f64) = (0.05, 0.15);

/// The share of the tangential part of a pair's force that conventional SPH's colour law keeps
/// (the module doc's **Force**): all of it, so that the force is −∇Φ and the contact keeps the
/// energy, while the pair's interface strain ε = max(ε_i, ε_j) is below [`PRESSED`]`.0`;
/// [`TANGENTIAL`] beyond [`PRESSED`]`.1`, where the two lattices are pressed hard enough for the
/// corrugation to push them into each other's gaps; a smoothstep in ε between. Symmetric in i
/// and j, so every pair force stays antisymmetric.
pub fn tangential_share(si: &ColourState, sj: &ColourState) -> f64 {
    let (start, full) = PRESSED;
    let x = ((si.strain.max(sj.strain) - start) / (full - start)).clamp(0.0, 1.0);
    1.0 - (1.0 - TANGENTIAL) * x * x * (3.0 - 2.0 * x)
}

/// The colour-law force on i from its contact neighbour j (i of body A, j of body B) at
/// distance r, with xij = x_i − x_j, reference volumes `vol0` and reference h0 = h0_ij: the
/// pair's part of −∇Φ, taken along the contact normal and never pulling, with the share
/// `tangential` of its tangential part ([`tangential_share`] in conventional SPH, none in
/// CN-SPH, whose contact acts along the surface normal); and the pair's stiffness for the time
/// step.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub fn pair<const D: usize, K: Kernel>(
    kernel: K,
    si: &ColourState,
    sj: &ColourState,
    xij: &[f64; D],
    r: f64,
    vol0: (f64, f64),
    h0: f64,
    tangential: f64,
) -> ([f64; D], f64) {
    let coef = si.coef + sj.coef;
    if coef <= 0.0 {
        return ([0.0; D], 0.0);
    }
    let n = normal(si, sj, xij, r, h0);
    let dw = kernel.dw::<D>(r, h0);
    // −V0_i V0_j (P_i + P_j) ∇_i W_ij is a repulsion of this magnitude along x̂_ij …
    let radial = -vol0.0 * vol0.1 * coef * dw;
    // … whose part along the normal pushes i back into its body (n̂ points from A into B).
    let along: f64 = -(0..D).map(|a| xij[a] * n[a]).sum::<f64>() / r;
    let push = radial * along.max(0.0);
    // The normal part in full, the tangential part (lattice corrugation) damped.
    let force = std::array::from_fn(|a| {
        let tangential_part = radial * (xij[a] / r + along * n[a]);
        -push * n[a] + tangential * tangential_part
    });
    let stiffness = vol0.0 * vol0.1 * coef * kernel.d2w::<D>(r, h0).abs()
        + sj.curvature * vol0.1 * vol0.0 * vol0.0 * dw * dw;
    (force, stiffness)
}

/// Where the pair term below starts, in Δp_avg.
pub const BACKSTOP: f64 = 0.6;

/// The pair term that keeps sparse particles apart: for r < r_s = [`BACKSTOP`] Δp_avg,
/// φ_ij = ½ V0_i Ŝ_A(ε) + ½ V0_j Ŝ_B(ε) with ε = 1 − r/Δp_avg and
/// Ŝ(ε) = Σ_u(ε) − Σ_u(ε_s) − σ_u(ε_s)(ε − ε_s): the work of each material's own compression
/// curve beyond ε_s, so that the force (along the line of centres, repulsive) starts from zero
/// at r_s and stiffens as the material does. Returns (force on i along x̂_ij, φ_ij, stiffness
/// |d²φ/dr²|), zero beyond r_s.
///
/// The colour of a sparse neighbourhood — a fragment of a debris cloud, a jet one particle
/// thick — can stay below that of touching however close the other body's particles come
/// (one particle's own kernel value, V W(0) ≈ 0.18 in 3D, is less than a face's 0.21), and
/// two such particles would pass through each other. Between bodies pressed together the
/// colour law holds the layers 0.65–1 Δp apart and this term stays idle.
pub fn backstop(
    curves: (&UniaxialCurve, &UniaxialCurve),
    materials: (&Material, &Material),
    vol0: (f64, f64),
    r: f64,
    dp: f64,
) -> (f64, f64, f64) {
    let rs = BACKSTOP * dp;
    if r >= rs {
        return (0.0, 0.0, 0.0);
    }
    let (eps, eps_s) = (1.0 - r / dp, 1.0 - BACKSTOP);
    let (mut force, mut phi, mut stiff) = (0.0, 0.0, 0.0);
    for (curve, m, v) in [
        (curves.0, materials.0, vol0.0),
        (curves.1, materials.1, vol0.1),
    ] {
        let (s, ds, w) = curve.at(m, eps);
        let (s0, _, w0) = curve.at(m, eps_s);
        force += 0.5 * v * (s - s0) / dp;
        phi += 0.5 * v * (w - w0 - s0 * (eps - eps_s));
        stiff += 0.5 * v * ds / (dp * dp);
    }
    (force, phi, stiff)
}

/// Shock dissipation across the interface: the quadratic (β) term of the bulk's
/// Monaghan–Gingold viscosity ([`crate::physics::viscosity`]) on the pair's closing speed along
/// the contact normal, acting along the normal, while the pair is in contact (the colour law
/// pushes). Returns T = −Π_ij (∇_i W_ij·n̂) n̂, which enters like the bulk's −Π_ij ∇_i W_ij
/// (force m_i m_j T, de_i/dt = −½ m_j v_ij·T ≥ 0, so the work it takes from the motion is the
/// heat it makes), and μ_ij for the time step.
///
/// Eq. (5) is conservative: two facing layers meeting at a shock's speed bounce off the
/// potential as off a spring, the surface layers alone storing the kinetic energy before the
/// bodies behind them feel the impact (at 7 km/s they closed to 0.44 Δp and rang back to
/// 0.97 Δp). In a body the same compression is a shock, made dissipative by the viscosity; the
/// interface is part of that shock and gets the same dissipation. Only the normal closing
/// speed counts, so sliding stays frictionless; and only the quadratic term, β ρ μ², which a
/// shock makes large and a slow contact negligible: the linear term α c μ acts at any speed,
/// and a slider riding over the other body's lattice corrugation lost 4 % of its velocity to it
/// (0.3 % without).
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub fn damping<const D: usize, K: Kernel>(
    kernel: K,
    si: &ColourState,
    sj: &ColourState,
    xij: &[f64; D],
    r: f64,
    h0: f64,
    vij: &[f64; D],
    (c_mean, rho_mean): (f64, f64),
    beta: f64,
) -> ([f64; D], f64) {
    if si.coef + sj.coef <= 0.0 {
        return ([0.0; D], 0.0);
    }
    let n = normal(si, sj, xij, r, h0);
    let vn: f64 = (0..D).map(|a| vij[a] * n[a]).sum();
    let xn: f64 = (0..D).map(|a| xij[a] * n[a]).sum();
    let (pi, mu) = crate::physics::viscosity::monaghan_gingold(
        vn * xn,
        r * r,
        h0,
        c_mean,
        rho_mean,
        0.0,
        beta,
    );
    let gn = kernel.dw::<D>(r, h0) * xn / r;
    (std::array::from_fn(|a| -pi * gn * n[a]), mu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CubicSpline;

    /// The table reads colours back as the strains they were made for, and the touching
    /// colour is that of a particle one spacing from a flat lattice (≈ 0.21 for the cubic
    /// spline at h = 1.2 Δp in 2D and 3D).
    #[test]
    fn lattice_colour_inverts_to_the_gap() {
        for (lat, d3) in [
            (LatticeColour::new::<2, _>(CubicSpline, 1.2), false),
            (LatticeColour::new::<3, _>(CubicSpline, 1.2), true),
        ] {
            let c0 = lat.touching();
            assert!((0.19..0.23).contains(&c0), "3D {d3}: c0 = {c0}");
            for k in [0, 37, 150, 399] {
                let (e, slope) = lat.strain(lat.colour[k]);
                assert!((e - lat.strain[k]).abs() < 1e-12, "{e}");
                assert!(slope > 0.0);
            }
            assert!(lat.colour.windows(2).all(|w| w[1] > w[0]), "monotone");
        }
    }

    /// The backstop is idle beyond 0.6 Δp, starts from zero force there, pushes apart and
    /// stiffens inward, and its force and stiffness are the derivatives of its potential.
    #[test]
    fn backstop_is_a_potential_that_starts_at_zero() {
        let spec = crate::deck::library::library_material("al_2024_t4").expect("library");
        let al = Material::from_spec(&spec);
        let curve = UniaxialCurve::new(&al);
        let (dp, v) = (1e-4, 1e-12);
        let at = |r: f64| backstop((&curve, &curve), (&al, &al), (v, v), r, dp);
        assert_eq!(at(BACKSTOP * dp), (0.0, 0.0, 0.0));
        assert_eq!(at(0.9 * dp), (0.0, 0.0, 0.0));
        let mut last = 0.0;
        for k in 1..12 {
            let r = (BACKSTOP - 0.05 * k as f64) * dp;
            let (f, phi, stiff) = at(r);
            assert!(
                f > last && phi > 0.0 && stiff > 0.0,
                "r = {r}: {f} {phi} {stiff}"
            );
            last = f;
            let d = 1e-6 * dp;
            let dphi = (at(r - d).1 - at(r + d).1) / (2.0 * d);
            assert!((dphi / f - 1.0).abs() < 1e-4, "−dφ/dr {dphi} vs f {f}");
            let dk = (at(r - d).0 - at(r + d).0) / (2.0 * d);
            assert!((dk / stiff - 1.0).abs() < 1e-3, "−df/dr {dk} vs k {stiff}");
        }
        let (f, _, _) = at((BACKSTOP - 1e-6) * dp);
        assert!(f.abs() < 1e-6 * last, "jump at r_s: {f}");
    }
}
