//! The time loop of one run: neighbours → physics + contact + boundary → integration, with the
//! diagnostics of each step and the checks that stop an unstable run.

use crate::boundary;
use crate::boundary::Plane;
use crate::case::{Case, KernelKind};
use crate::error::{Error, Result};
use crate::integrate;
use crate::kernel::{CubicSpline, WendlandC2};
use crate::neighbors::NeighborList;
use crate::particles::{to3, Particles};
use crate::physics::{self, Model, Rates};
use crate::setup;

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
    /// Neighbour entries of the real particles this step (particle-neighbour interactions).
    pub interactions: usize,
}

/// A run in progress.
#[derive(Debug)]
pub struct Simulation<const D: usize> {
    pub particles: Particles<D>,
    pub model: Model<D>,
    pub kernel: KernelKind,
    pub symmetry: Vec<Plane>,
    pub body_names: Vec<String>,
    /// Time, step and the other scalars a checkpoint keeps.
    pub state: SimState,
    neighbors: NeighborList,
    ghosts: boundary::Ghosts,
    rates: Rates<D>,
    order: Vec<usize>,
    /// Search at the next step whatever the skin says (after a checkpoint, so that a resumed
    /// run, which must search first, stays bit-identical).
    force_search: bool,
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
    /// Neighbour searches made so far.
    pub searches: u64,
    /// Step of the last reordering into cell order.
    pub last_reorder: u64,
}

/// Real particles are put back in cell order at least this often (steps), for memory locality.
pub const REORDER_EVERY: u64 = 50;
/// Verlet skin of the neighbour lists, as a fraction of the largest smoothing length.
pub const SKIN: f64 = 0.1;

impl<const D: usize> Simulation<D> {
    /// Set up a case (the deck's dimension must be D).
    pub fn new(case: &Case) -> Result<Self> {
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
            state: SimState {
                time: 0.0,
                step: 0,
                dt_prev: 0.0,
                dt_first: None,
                // DESIGN.md: 10× the fastest initial speed. Bodies starting at rest (a block on
                // an incline) would trip that at once, so the sound speed bounds it from below.
                speed_limit: 10.0 * v0.max(c0),
                searches: 0,
                last_reorder: 0,
            },
            neighbors: NeighborList::default(),
            ghosts: boundary::Ghosts::default(),
            rates: Rates::default(),
            order: Vec::new(),
            force_search: false,
        })
    }

    /// The state a checkpoint keeps: the real particles and the scalars. Taking it makes the
    /// next step search afresh, as a run resumed from it will.
    pub fn checkpoint_state(&mut self) -> (Particles<D>, SimState) {
        self.force_search = true;
        let mut particles = self.particles.clone();
        particles.truncate_to_real();
        (particles, self.state.clone())
    }

    /// Continue from a checkpoint's state (the case must be the one it was written for).
    pub fn restore(&mut self, particles: Particles<D>, state: SimState) {
        self.particles = particles;
        self.state = state;
        self.force_search = true;
    }

    /// Advance one step, of at most `dt_max`. On instability the particles are left at t_n
    /// (the last good state) and the error names the particle, its body, place and cause.
    pub fn step(&mut self, dt_max: f64) -> Result<Diagnostics> {
        let p = &mut self.particles;
        integrate::predict_velocity(p, &self.model, self.state.dt_prev);
        // Ghosts and neighbour lists are rebuilt when the skin is used up (positions are those
        // of the real particles with the old ghosts refreshed), and every REORDER_EVERY steps
        // at the latest, when the real particles are also put back in cell order.
        self.ghosts.update(p, &self.symmetry);
        let reorder = self.state.step >= self.state.last_reorder + REORDER_EVERY;
        if reorder || self.force_search || self.neighbors.stale(&p.x, &p.h) {
            self.force_search = false;
            if reorder && self.state.step > 0 {
                let n = p.n_real;
                self.order.clear();
                self.order.extend(
                    self.neighbors
                        .cell_order()
                        .iter()
                        .map(|&i| i as usize)
                        .filter(|&i| i < n),
                );
                p.permute(&self.order);
                self.state.last_reorder = self.state.step;
            }
            let h_max = p.h.iter().copied().fold(0.0_f64, f64::max);
            let skin = SKIN * h_max;
            self.ghosts.rebuild(p, &self.symmetry, 2.0 * h_max + skin);
            self.neighbors.build(&p.x, &p.h, p.n_real, skin);
            self.state.searches += 1;
        }
        match self.kernel {
            KernelKind::CubicSpline => physics::compute_rates(
                CubicSpline,
                p,
                &self.neighbors,
                &self.model,
                &mut self.rates,
            ),
            KernelKind::WendlandC2 => {
                physics::compute_rates(WendlandC2, p, &self.neighbors, &self.model, &mut self.rates)
            }
        }
        let n = p.n_real;
        // The stable step, its growth limited to 25 % a step; the collapse check uses it before
        // it is shortened to land on an output time.
        let mut dt_stable = self
            .rates
            .particles
            .iter()
            .map(|r| r.dt)
            .fold(f64::INFINITY, f64::min);
        if self.state.dt_prev > 0.0 {
            dt_stable = dt_stable.min(1.25 * self.state.dt_prev);
        }
        let dt_first = *self.state.dt_first.get_or_insert(dt_stable);
        let dt = dt_stable.min(dt_max);
        self.check(dt, dt_stable, dt_first)?;

        let mut d = Diagnostics {
            time: self.state.time,
            dt,
            body_contact_force: vec![[0.0; 3]; self.body_names.len()],
            interactions: self
                .rates
                .particles
                .iter()
                .map(|r| r.neighbors as usize)
                .sum(),
            max_pressure: f64::NEG_INFINITY,
            ..Default::default()
        };
        let p = &self.particles;
        let g = self.model.gravity;
        let mut gap = f64::INFINITY;
        let (mut ke_old, mut ie_old, mut mom_old) = (0.0, 0.0, [0.0; 3]);
        for i in 0..n {
            ie_old += p.m[i] * p.eh[i];
            d.contact += self.rates.particles[i].contact_energy;
            d.gravity -= p.m[i] * g.dot(&p.x[i]);
            d.max_pressure = d.max_pressure.max(p.p[i]);
            gap = gap.min(self.rates.particles[i].min_interbody_gap);
            let f = to3(&self.rates.particles[i].contact_force);
            let fb = &mut d.body_contact_force[p.body[i] as usize];
            for k in 0..3 {
                fb[k] += f[k];
            }
            ke_old += 0.5 * p.m[i] * p.vh[i].norm_squared();
            let mv = to3(&(p.vh[i] * p.m[i]));
            for k in 0..3 {
                mom_old[k] += mv[k];
            }
        }
        d.min_interbody_distance = gap.is_finite().then_some(gap);

        integrate::advance(
            &mut self.particles,
            &self.rates,
            &self.model,
            dt,
            self.state.dt_prev,
        );
        boundary::reflect_crossed(&mut self.particles, &self.symmetry);

        let p = &self.particles;
        let (mut ke_new, mut ie_new, mut mom_new) = (0.0, 0.0, [0.0; 3]);
        for i in 0..n {
            ke_new += 0.5 * p.m[i] * p.vh[i].norm_squared();
            ie_new += p.m[i] * p.eh[i];
            let mv = to3(&(p.vh[i] * p.m[i]));
            for k in 0..3 {
                mom_new[k] += mv[k];
            }
            d.momentum_scale += p.m[i] * p.vh[i].norm();
        }
        // Whole-step values are the means of the half-step ones; the first step starts from
        // v^0 and e^0 themselves.
        if self.state.step == 0 {
            d.kinetic = ke_old;
            d.internal = ie_old;
            d.momentum = mom_old;
        } else {
            d.kinetic = 0.5 * (ke_old + ke_new);
            d.internal = 0.5 * (ie_old + ie_new);
            d.momentum = [0, 1, 2].map(|k| 0.5 * (mom_old[k] + mom_new[k]));
        }
        d.total = d.kinetic + d.internal + d.contact + d.gravity;
        self.state.time += dt;
        self.state.step += 1;
        self.state.dt_prev = dt;
        Ok(d)
    }

    /// The rates at t_n must be finite, the density must stay positive over the step, no
    /// particle may exceed the speed limit and the step must not collapse.
    fn check(&self, dt: f64, dt_stable: f64, dt_first: f64) -> Result<()> {
        let p = &self.particles;
        let r = &self.rates.particles;
        // The state first (a bad particle spoils its neighbours' rates), then the rates.
        let state = (0..p.n_real).find_map(|i| {
            let finite = p.x[i].iter().all(|c| c.is_finite())
                && p.v[i].iter().all(|c| c.is_finite())
                && p.rho[i].is_finite()
                && p.e[i].is_finite()
                && p.p[i].is_finite()
                && p.s[i].iter().all(|c| c.is_finite());
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
        let bad = state.or_else(|| {
            (0..p.n_real).find_map(|i| {
                if !(r[i].acc.iter().all(|c| c.is_finite())
                    && r[i].drho.is_finite()
                    && r[i].de.is_finite()
                    && r[i].grad_v.iter().all(|c| c.is_finite()))
                {
                    Some((
                        i,
                        "acceleration or strain rate is not finite (NaN/inf)".to_string(),
                    ))
                } else if p.rho[i] + dt * r[i].drho <= 0.0 || (p.rho[i] + dt * r[i].drho).is_nan() {
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
        });
        let (i, cause) = match bad {
            Some(b) => b,
            None if dt_stable < 1e-6 * dt_first || dt_stable.is_nan() => {
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
}
