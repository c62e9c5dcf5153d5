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

/// Rates of change and per-particle diagnostics from one pass (indices of real particles).
#[derive(Debug, Default, Clone)]
pub struct Rates<const D: usize> {
    /// dv/dt (m/s²), contact and gravity included.
    pub acc: Vec<Vector<D>>,
    /// dρ/dt.
    pub drho: Vec<f64>,
    /// de/dt.
    pub de: Vec<f64>,
    /// Lagged energy correction of the last step (J/kg), added to e as it is.
    pub de_lag: Vec<f64>,
    /// Velocity gradient L = ∂v/∂x.
    pub grad_v: Vec<Tensor<D>>,
    /// Contact force f_c (N).
    pub contact_force: Vec<Vector<D>>,
    /// Half the contact potential of each of the particle's contact pairs (J): the sum over
    /// particles is Φ.
    pub contact_energy: Vec<f64>,
    /// Stable time step of the particle (s).
    pub dt: Vec<f64>,
    /// Neighbours within the support (the list may hold more, see `neighbors`).
    pub neighbors: Vec<u32>,
    /// Smallest r_ij/Δp_avg to a neighbour of another body, in contact or welded (∞ if none):
    /// the no-mixing diagnostic.
    pub min_interbody_gap: Vec<f64>,
    /// What the pass reads of each neighbour (all particles, ghosts included), packed into one
    /// record so that a neighbour costs one bounds check and few cache lines.
    gather: Vec<Gather<D>>,
    /// Per-particle artificial stress R (all particles, ghosts included).
    art: Vec<Tensor<D>>,
}

/// A particle as its neighbours see it in the pass.
#[derive(Debug, Clone, Copy)]
struct Gather<const D: usize> {
    /// σ/ρ².
    sr2: Tensor<D>,
    x: Vector<D>,
    v: Vector<D>,
    u: Vector<D>,
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

/// Evaluate all rates at the particles' current state (positions, velocities `p.v`, stress).
pub fn compute_rates<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    model: &Model<D>,
    out: &mut Rates<D>,
) {
    let n = p.n_real;
    let all = p.len();
    let ratio = model.smoothing_ratio;
    let any_art = model
        .materials
        .iter()
        .any(|m| m.artificial_stress.is_some());
    out.gather.clear();
    out.gather.par_extend((0..all).into_par_iter().map(|i| {
        let sigma = p.stress(i);
        Gather {
            sr2: sigma / (p.rho[i] * p.rho[i]),
            x: p.x[i],
            v: p.v[i],
            u: p.u[i],
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
    out.acc.resize(n, Vector::<D>::zeros());
    out.drho.resize(n, 0.0);
    out.de.resize(n, 0.0);
    out.de_lag.resize(n, 0.0);
    out.grad_v.resize(n, Tensor::<D>::zeros());
    out.contact_force.resize(n, Vector::<D>::zeros());
    out.contact_energy.resize(n, 0.0);
    out.dt.resize(n, 0.0);
    out.min_interbody_gap.resize(n, f64::INFINITY);
    out.neighbors.resize(n, 0);

    let gather = &out.gather;
    let art = &out.art;
    let (alpha, beta) = (model.alpha, model.beta);
    let gravity = model.gravity;
    let cfl = model.cfl;

    let per_particle = out
        .acc
        .par_iter_mut()
        .zip(out.drho.par_iter_mut())
        .zip(out.de.par_iter_mut())
        .zip(out.de_lag.par_iter_mut())
        .zip(out.grad_v.par_iter_mut())
        .zip(out.contact_force.par_iter_mut())
        .zip(out.contact_energy.par_iter_mut())
        .zip(out.dt.par_iter_mut())
        .zip(out.min_interbody_gap.par_iter_mut())
        .zip(out.neighbors.par_iter_mut())
        .enumerate();
    per_particle.for_each(
        |(
            i,
            (((((((((acc_o, drho_o), de_o), de_lag_o), l_o), fc_o), phi_o), dt_o), gap_o), count_o),
        )| {
            let gi = &gather[i];
            let (xi, vi, hi, bi, rho_i, ci) = (gi.x, gi.v, gi.h, gi.body, gi.rho, gi.c);
            let vol_i = gi.vol;
            let sr2_i = gi.sr2;
            let art_i = if any_art {
                art[i]
            } else {
                Tensor::<D>::zeros()
            };
            let u_i = gi.u;

            let mut acc = Vector::<D>::zeros();
            let mut fc = Vector::<D>::zeros();
            let mut l = Tensor::<D>::zeros();
            let mut drho = 0.0;
            let mut de = 0.0;
            let mut de_lag = 0.0;
            let mut phi = 0.0;
            let mut k_contact = 0.0;
            let mut mu_max = 0.0_f64;
            let mut v2_max = 0.0_f64;
            let mut gap = f64::INFINITY;
            let mut count = 0u32;

            for &j in &nl.lists[i] {
                let gj = &gather[j as usize];
                let xij = xi - gj.x;
                let r2 = xij.norm_squared();
                let support = hi + gj.h;
                if r2 >= support * support || r2 == 0.0 {
                    continue;
                }
                count += 1;
                let r = r2.sqrt();
                let hij = 0.5 * support;
                let gf = kernel.grad_factor::<D>(r, hij);
                let grad = xij * gf;
                let vij = vi - gj.v;
                v2_max = v2_max.max(vij.norm_squared());
                if gj.body != bi {
                    gap = gap.min(r / (0.5 * (gi.dp + gj.dp)));
                }
                match model.pairs.rule(bi, gj.body) {
                    PairRule::Conserve => {
                        let mj = gj.m;
                        let rho_j = gj.rho;
                        drho += mj * vij.dot(&grad);
                        l -= (vij * gj.vol) * grad.transpose();
                        let (pi, mu) = viscosity::monaghan_gingold(
                            vij.dot(&xij),
                            r2,
                            hij,
                            0.5 * (ci + gj.c),
                            0.5 * (rho_i + rho_j),
                            alpha,
                            beta,
                        );
                        mu_max = mu_max.max(-mu);
                        let mut t = sr2_i + gj.sr2;
                        if any_art {
                            let a = art_i + art[j as usize];
                            if a != Tensor::<D>::zeros() {
                                let dp = 0.5 * (gi.dp + gj.dp);
                                let f = kernel.w::<D>(r, hij) / kernel.w::<D>(dp, hij);
                                t += a * f.powi(artificial_stress::EXPONENT);
                            }
                        }
                        let tg = t * grad - grad * pi;
                        acc += tg * mj;
                        de -= 0.5 * mj * vij.dot(&tg);
                        de_lag -= 0.5 * mj * (u_i - gj.u).dot(&tg);
                    }
                    PairRule::Contact(params) => {
                        let (coef, pot, k) =
                            contact::pair::<D, K>(kernel, params, vol_i, gj.vol, r, hij, gf * r);
                        fc += grad * coef;
                        phi += 0.5 * pot;
                        k_contact += k;
                    }
                }
            }

            let mi = gi.m;
            *acc_o = acc + fc / mi + gravity;
            *drho_o = drho;
            *de_o = de;
            *de_lag_o = de_lag;
            *l_o = l;
            *fc_o = fc;
            *phi_o = phi;
            *gap_o = gap;
            *count_o = count;
            // Time step: sound, relative motion and viscosity (Monaghan 1992), and the contact
            // springs (ω² = Σk/m, leapfrog stable for ω Δt < 2).
            let signal = ci + v2_max.sqrt() + 0.6 * (alpha * ci + beta * mu_max);
            let mut dt = cfl * hi / signal;
            if k_contact > 0.0 {
                dt = dt.min(cfl * 2.0 * (mi / k_contact).sqrt());
            }
            *dt_o = dt;
        },
    );
}
