//! The SPH equations of solid dynamics (updated Lagrangian, conventional SPH), evaluated in one
//! gather pass over each real particle's neighbours. Per pair, with x_ij = x_i − x_j,
//! v_ij = v_i − v_j, h_ij = (h_i + h_j)/2 and ∇_i W_ij = (dW/dr) x_ij/r_ij:
//!
//! - continuity: dρ_i/dt = Σ_{j∈N_i} m_j v_ij·∇_i W_ij
//! - velocity gradient: L_i = −Σ_{j∈N_i} V_j v_ij ⊗ ∇_i W_ij
//! - momentum: dv_i/dt = Σ_{j∈N_i} m_j T_ij ∇_i W_ij + f_c,i/m_i + g,
//!   T_ij = σ_i/ρ_i² + σ_j/ρ_j² − Π_ij I + A_ij
//! - energy: de_i/dt = −½ Σ_{j∈N_i} m_j v_ij·(T_ij ∇_i W_ij), the pairwise form whose sum
//!   Σ m_i de_i/dt is exactly minus the power of the internal forces, so total energy is
//!   conserved by the spatial discretisation (DESIGN.md §2 allows it in place of σ:D/ρ);
//!   plus the lagged correction −½ Σ m_j (u_i − u_j)·(T_ij ∇_i W_ij) (see `integrate`).
//!
//! N_i are neighbours of the same body or of a `welded` body; C_i, neighbours of a body in
//! `contact`, enter only through [`crate::contact`] (the paper's W = 0 across bodies).

pub mod artificial_stress;
pub mod viscosity;

use crate::contact::{self, ContactParams};
use crate::kernel::Kernel;
use crate::material::Material;
use crate::neighbors::NeighborList;
use crate::particles::{Particles, Tensor, Vector};
use rayon::prelude::*;

/// How particles of two bodies interact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairRule {
    /// Through the conservation equations (same body, or welded bodies).
    Conserve,
    /// Through the contact force only.
    Contact(ContactParams),
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
    pub gravity: Vector<D>,
    pub cfl: f64,
    /// h0 / Δp.
    pub smoothing_ratio: f64,
    pub h_min_ratio: f64,
    pub h_max_ratio: f64,
}

impl<const D: usize> Model<D> {
    pub fn material_of(&self, body: u32) -> &Material {
        &self.materials[self.body_material[body as usize]]
    }
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
    /// Contact force f_c (N).
    pub contact_force: Vector<D>,
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

/// The pass's output (one record per real particle) and its work buffers.
#[derive(Debug, Default, Clone)]
pub struct Rates<const D: usize> {
    pub particles: Vec<ParticleRates<D>>,
    /// What the pass reads of each neighbour (all particles, ghosts included), packed into one
    /// record so that a neighbour costs one bounds check and few cache lines.
    gather: Vec<Gather<D>>,
    /// Per-particle artificial stress R (all particles, ghosts included; empty when no
    /// material uses it).
    art: Vec<Tensor<D>>,
}

/// A particle as its neighbours see it in the pass, in plain arrays: the pair loop is the
/// hot spot of the code, and fixed-size loops over `D` compile to straight-line arithmetic
/// (half the instructions of the same sums on nalgebra's generic small matrices).
#[derive(Debug, Clone, Copy)]
struct Gather<const D: usize> {
    /// σ/ρ², row by row.
    sr2: [[f64; D]; D],
    x: [f64; D],
    v: [f64; D],
    u: [f64; D],
    h: f64,
    m: f64,
    /// V = m/ρ.
    vol: f64,
    rho: f64,
    c: f64,
    /// Initial spacing Δp = h0/ratio.
    dp: f64,
    body: u32,
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

/// Evaluate all rates at the particles' current state (positions, velocities `p.v`, stress).
pub fn compute_rates<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    out: &mut Rates<D>,
) {
    let all = p.len();
    let ratio = model.smoothing_ratio;
    let any_art = model
        .materials
        .iter()
        .any(|m| m.artificial_stress.is_some());
    out.gather.clear();
    out.gather.par_extend((0..all).into_par_iter().map(|i| {
        let sr2 = p.stress(i) / (p.rho[i] * p.rho[i]);
        Gather {
            sr2: std::array::from_fn(|a| std::array::from_fn(|b| sr2[(a, b)])),
            x: arr(&p.x[i]),
            v: arr(&p.v[i]),
            u: arr(&p.u[i]),
            h: p.h[i],
            m: p.m[i],
            vol: p.m[i] / p.rho[i],
            rho: p.rho[i],
            c: p.c[i],
            dp: p.h0[i] / ratio,
            body: p.body[i],
        }
    }));
    out.art.clear();
    if any_art {
        out.art.par_extend((0..all).into_par_iter().map(|i| {
            match model.material_of(p.body[i]).artificial_stress {
                Some(eps) => artificial_stress::tensor(&p.stress(i), p.rho[i], eps),
                None => Tensor::<D>::zeros(),
            }
        }));
    }
    let (gather, art) = (&out.gather, &out.art);
    out.particles.clear();
    out.particles.par_extend(
        (0..p.n_real)
            .into_par_iter()
            .map(|i| particle_rates(kernel, i, &nl.lists[i], gather, art, model)),
    );
}

/// One real particle's sums over its neighbours (see the module doc for the equations).
#[inline(always)]
fn particle_rates<const D: usize, K: Kernel>(
    kernel: K,
    i: usize,
    neighbors: &[u32],
    gather: &[Gather<D>],
    art: &[Tensor<D>],
    model: &Model<D>,
) -> ParticleRates<D> {
    let gi = &gather[i];
    let (xi, vi, ui, hi, bi, rho_i, ci) = (gi.x, gi.v, gi.u, gi.h, gi.body, gi.rho, gi.c);
    let (alpha, beta) = (model.alpha, model.beta);
    let art_i = art.get(i).copied();

    let mut acc = [0.0; D];
    let mut fc = [0.0; D];
    let mut l = [[0.0; D]; D];
    let mut drho = 0.0;
    let mut de = 0.0;
    let mut de_lag = 0.0;
    let mut phi = 0.0;
    let mut k_contact = 0.0;
    let mut mu_max = 0.0_f64;
    let mut v2_max = 0.0_f64;
    let mut gap = f64::INFINITY;
    let mut count = 0u32;

    for &j in neighbors {
        let gj = &gather[j as usize];
        let xij: [f64; D] = std::array::from_fn(|k| xi[k] - gj.x[k]);
        let r2 = dot(&xij, &xij);
        let support = hi + gj.h;
        if r2 >= support * support || r2 == 0.0 {
            continue;
        }
        count += 1;
        let r = r2.sqrt();
        let hij = 0.5 * support;
        let gf = kernel.grad_factor::<D>(r, hij);
        let grad: [f64; D] = std::array::from_fn(|k| xij[k] * gf);
        let vij: [f64; D] = std::array::from_fn(|k| vi[k] - gj.v[k]);
        v2_max = v2_max.max(dot(&vij, &vij));
        if gj.body != bi {
            gap = gap.min(r / (0.5 * (gi.dp + gj.dp)));
        }
        match model.pairs.rule(bi, gj.body) {
            PairRule::Conserve => {
                let mj = gj.m;
                drho += mj * dot(&vij, &grad);
                for a in 0..D {
                    let va = vij[a] * gj.vol;
                    for b in 0..D {
                        l[a][b] -= va * grad[b];
                    }
                }
                let (pi, mu) = viscosity::monaghan_gingold(
                    dot(&vij, &xij),
                    r2,
                    hij,
                    0.5 * (ci + gj.c),
                    0.5 * (rho_i + gj.rho),
                    alpha,
                    beta,
                );
                mu_max = mu_max.max(-mu);
                // T_ij ∇W = (σ_i/ρ_i² + σ_j/ρ_j²) ∇W − Π_ij ∇W (+ A_ij ∇W).
                let mut tg: [f64; D] = std::array::from_fn(|a| {
                    let mut t = -pi * grad[a];
                    for (b, g) in grad.iter().enumerate() {
                        t += (gi.sr2[a][b] + gj.sr2[a][b]) * g;
                    }
                    t
                });
                if let Some(art_i) = art_i {
                    let r_ij = art_i + art[j as usize];
                    if r_ij != Tensor::<D>::zeros() {
                        let dp = 0.5 * (gi.dp + gj.dp);
                        let f = kernel.w::<D>(r, hij) / kernel.w::<D>(dp, hij);
                        let fa = f.powi(artificial_stress::EXPONENT);
                        for a in 0..D {
                            for b in 0..D {
                                tg[a] += r_ij[(a, b)] * fa * grad[b];
                            }
                        }
                    }
                }
                let mut vtg = 0.0;
                let mut utg = 0.0;
                for a in 0..D {
                    acc[a] += tg[a] * mj;
                    vtg += vij[a] * tg[a];
                    utg += (ui[a] - gj.u[a]) * tg[a];
                }
                de -= 0.5 * mj * vtg;
                de_lag -= 0.5 * mj * utg;
            }
            PairRule::Contact(params) => {
                let (coef, pot, k) =
                    contact::pair::<D, K>(kernel, params, gi.vol, gj.vol, r, hij, gf * r);
                for a in 0..D {
                    fc[a] += grad[a] * coef;
                }
                phi += 0.5 * pot;
                k_contact += k;
            }
        }
    }

    let mi = gi.m;
    let fc = Vector::<D>::from_fn(|k, _| fc[k]);
    // Time step Δt_i = C h_i / (c_i + max_j |v_ij| + 0.6 (α c_i + β max_j |μ_ij|)) (Monaghan
    // 1992), and the contact springs (ω² = Σk/m, leapfrog stable for ω Δt < 2). DESIGN.md's
    // |v_i| is taken as the largest speed relative to a neighbour, its Galilean-invariant form:
    // a body flying at 7 km/s in one piece needs no shorter step, two meeting at 7 km/s do.
    let signal = ci + v2_max.sqrt() + 0.6 * (alpha * ci + beta * mu_max);
    let mut dt = model.cfl * hi / signal;
    if k_contact > 0.0 {
        dt = dt.min(model.cfl * 2.0 * (mi / k_contact).sqrt());
    }
    ParticleRates {
        acc: Vector::<D>::from_fn(|k, _| acc[k]) + fc / mi + model.gravity,
        drho,
        de,
        de_lag,
        grad_v: Tensor::<D>::from_fn(|a, b| l[a][b]),
        contact_force: fc,
        contact_energy: phi,
        dt,
        min_interbody_gap: gap,
        neighbors: count,
    }
}
