//! Central-difference (leapfrog) time integration.
//!
//! Velocities and the specific internal energy live at half steps, positions and the rest of
//! the material state at whole steps:
//!
//!   v^{n+½} = v^{n−½} + k_n a^n,   e^{n+½} = e^{n−½} + k_n ė^n,   k_n = ½ (Δt_{n−1} + Δt_n),
//!   x^{n+1} = x^n + Δt_n v^{n+½},  ρ^{n+1} = ρ^n + Δt_n ρ̇^n,  S^{n+1} = return(S^n + Δt_n Ṡ^n).
//!
//! Kicking e with the same weight k_n as v makes the kinetic and internal energies exchange
//! exactly the same work each step (a left-point e^{n+1} = e^n + Δt ė^n gains half a step of
//! stress power that the kinetic energy never lost: 2–3 % at an impulsive start). The EOS uses
//! e predicted to the whole step, e^{n+1} = e^{n+½} + ½ Δt_n ė^n.
//!
//! The rates at t_n (forces, contact, strain rate) are evaluated in one pass with the velocity
//! predicted to the whole step, v^n = v^{n−½} + ½ Δt_{n−1} a^{n−1} (the predictor of LAMMPS'
//! SMD and of Monaghan's leapfrog), so a step costs one neighbour pass. The stress rate is the
//! Jaumann rate dS/dt = 2G (D − ⅓ tr D I) + Ω S − S Ω with D = sym L, Ω = skew L.
//!
//! **Lagged energy correction.** The leapfrog changes the kinetic energy by the work of the
//! forces at the time-centred velocity v̄^n = ½ (v^{n−½} + v^{n+½}), but the energy equation
//! used the predicted v^n. The two differ at first order where accelerations jump (an impact
//! starting with a velocity discontinuity lost 5 % of its energy this way at C_cfl = 0.3). The
//! energy rate is linear in the velocities, de_i = −½ Σ m_j v_ij·(T_ij ∇W), so each step stores
//! u = (v̄ − v_pred) k_n and the next pass adds −½ Σ m_j (u_i − u_j)·(T_ij ∇W) to e: internal
//! and kinetic energy then exchange the same work to second order, at the cost of one dot
//! product per pair and no extra neighbour pass.
//!
//! **Staggered material update.** The central difference advances the material (ρ, S, b)
//! over the step with the velocity at its middle, v^{n+½} (DESIGN.md §2: the constitutive
//! update at t_{n+½}). Advanced with the whole-step v^n instead, the stress lags the motion by
//! half a step, and for an oscillation of frequency ω that lag is a negative damping: each
//! step multiplies its amplitude by about 1 + (ωΔt)²/4 (1.025 at ωΔt = 0.3). Only the
//! artificial viscosity held it: with the viscosity spared in smooth flow (its limiter,
//! `physics::viscosity`), the elastic bars of `examples/bars_contact.toml` blew up once apart,
//! to 10× their energy within 20 µs. One pass cannot know v^{n+½}, since it computes the
//! step's accelerations, so continuity and the velocity gradient take it extrapolated from the
//! last two, w = v + dv = v^{n−½} + Δt (2aⁿ⁻¹ − aⁿ⁻²) (`Particles::dv`, carried in the pass's
//! neighbour record in single precision): for a single oscillator (s' = w, a = −ω² s) its
//! amplification per step stays at or below 1 up to ωΔt ≈ 0.71 (0.9996 at 0.3, 0.97 at 0.5),
//! so it damps only the shortest waves; extrapolating aⁿ⁻¹ alone (dv = ½ Δt aⁿ⁻¹) gives
//! 1.005 at 0.3, a minmod-limited slope lets the oscillation grow at 0.5, and with either the
//! viscosity-free bar below blew up (tried 2026-11-28, against the tension strip's failed
//! bands: `tests/verification_materials.rs`). The forces, the viscosity, the contact and the
//! energy equation keep v, so that the energy exchange stays second order as above (with w
//! there too, the lagged energy correction is first order: 20 % of the energy of an elastic
//! impact lost). An elastic bar with no viscosity at all keeps its energy within 1 % over 40 µs
//! (`tests/verification_engine.rs`). The idea and the measurements are those of a branch of
//! 2026-11-24 (`git show fe10977`), where the update was an option and the plain viscosity
//! made it lose more than it gained.

use crate::material::{radial_return, DamageState, Damaged};
use crate::particles::{Particles, Tensor, Vector};
use crate::physics::{Model, Rates};
use crate::tensor::{
    equivalent_strain_rate, max_principal, max_principal_bound, out_of_plane, von_mises, Sym,
};
use nalgebra::SVector;
use rayon::prelude::*;

/// Predict v^n = v^{n−½} + ½ Δt_{n−1} a^{n−1} for the real particles in `range` (prescribed
/// bodies keep their velocity): all of them in one process, an MPI rank's own (the others'
/// come from their ranks with the halo, predicted there).
pub fn predict_velocity<const D: usize>(
    p: &mut Particles<D>,
    model: &Model<D>,
    dt_prev: f64,
    range: std::ops::Range<usize>,
) {
    let n = p.n_real;
    let range = range.start.min(n)..range.end.min(n);
    let start = range.start;
    let (v, rest) = (
        &mut p.v[range.clone()],
        (&p.vh[..n], &p.a[..n], &p.body[..n]),
    );
    v.par_iter_mut().enumerate().for_each(|(k, vi)| {
        let i = start + k;
        *vi = match model.body_prescribed[rest.2[i] as usize] {
            Some(v0) => v0,
            None => rest.0[i] + rest.1[i] * (0.5 * dt_prev),
        };
    });
}

/// The density after a step's change dρ. A failed particle (`material::damage`) cannot be
/// pulled, so it does not expand into tension: where its neighbours draw away and the EOS
/// pressure at the lower density would be negative, the gap that opens is a crack, and the
/// particle keeps its density (its pressure is zero there, so holding ρ changes no work term).
/// Hot rubble still expands while its pressure is positive. Without the hold, rubble of the
/// 7 km/s demo in CN-SPH thinned to 1e-4 ρ0 and its density went negative.
pub fn next_density(
    mat: &crate::material::Material,
    rho: f64,
    d_rho: f64,
    e: f64,
    failed: bool,
) -> f64 {
    let next = rho + d_rho;
    if failed && d_rho < 0.0 && (next <= 0.0 || mat.eos.pressure(next, e) < 0.0) {
        rho
    } else {
        next
    }
}

/// The smoothing length: h = h0 (ρ0/ρ)^(1/D) min(max(λ_max, 1), s_max), within
/// [h_min, h_max] × h0, λ_max the particle's largest stretch (the square root of b's largest
/// eigenvalue). Only materials that flow plastically stretch (b stays 1 otherwise): a fluid's
/// particles re-sort freely, and an elastic solid's strains stay small.
///
/// The density factor keeps the number of neighbours as the material compresses or expands
/// (DESIGN.md §2). Plastic flow keeps the volume but stretches a particle's neighbourhood: in
/// uniaxial compression by εp its lateral spacing grows by e^(εp/2), at the foot of a Taylor
/// rod (εp ≈ 2) by almost three. With h following the density alone, the cubic spline at
/// 1.2 Δp then sums the stress divergence across the stretched direction from too few
/// neighbours: in the 42CrMo4 Taylor rod at R0/Δp = 16 the hoop moment Σ_j V_j x_ji ⊗ ∇_i W_ij
/// read 0.63–0.73 instead of 1 where εp > 1, and the foot spread more the finer the lattice
/// (face diameter +4.7 % at R0/Δp = 8, +15 % at 16, against the finite-element results). So h
/// also follows the largest stretch, up to s_max (`simulation.smoothing_stretch`, 1.25 by
/// default: h0 = 1.2 Δp grows to 1.5 Δp, the support usual for 3D solid SPH). Uniaxial strain
/// (a plate impact) stretches nothing and keeps the density rule alone. Measured on the Taylor
/// rods with it: README, validation.
#[inline]
pub fn smoothing_length<const D: usize>(
    h0: f64,
    rho0_over_rho: f64,
    lambda_max: f64,
    model: &Model<D>,
) -> f64 {
    let density = if D == 2 {
        rho0_over_rho.sqrt()
    } else {
        rho0_over_rho.cbrt()
    };
    let stretch = lambda_max.clamp(1.0, model.smoothing_stretch);
    (h0 * density * stretch).clamp(model.h_min_ratio * h0, model.h_max_ratio * h0)
}

/// The largest principal stretch λ_max = √(largest eigenvalue of b) (in 2D, plane strain: the
/// out-of-plane stretch is 1).
#[inline]
pub fn largest_stretch<const D: usize>(b: &Tensor<D>) -> f64 {
    max_principal(b, 1.0).sqrt()
}

/// b after a step of velocity gradient L: b ← ΔF b ΔFᵀ with the incremental deformation
/// gradient ΔF = (I − ½Δt L)⁻¹ (I + ½Δt L) (the midpoint rule: exactly orthogonal for a
/// rigid spin, so a rotating body's b stays put).
#[inline]
pub fn stretch_step<const D: usize>(b: &Tensor<D>, l: &Tensor<D>, dt: f64) -> Tensor<D> {
    let half = l * (0.5 * dt);
    let id = Tensor::<D>::identity();
    let df = match (id - half).try_inverse() {
        Some(inv) => inv * (id + half),
        None => id + l * dt,
    };
    df * b * df.transpose()
}

/// Jaumann rate of the deviatoric stress, dS/dt = 2G (D − ⅓ tr D I) + Ω S − S Ω
/// (the ⅓ is that of 3D also in plane strain, where D_zz = 0 and S_zz = −tr S follows).
pub fn jaumann_rate<const D: usize>(s: &Tensor<D>, l: &Tensor<D>, g: f64) -> Tensor<D> {
    let d = (l + l.transpose()) * 0.5;
    let w = (l - l.transpose()) * 0.5;
    (d - Tensor::<D>::identity() * (d.trace() / 3.0)) * (2.0 * g) + w * s - s * w
}

/// One leapfrog update of the real particles `range` (all of them on one rank; under MPI the
/// rank's own) from the rates at t_n: kick, drift, and the material update (density, energy,
/// stress, plastic strain, h, pressure, sound speed). `dt`: (Δt_n, Δt_{n−1}).
pub fn advance<const D: usize>(
    p: &mut Particles<D>,
    rates: &Rates<D>,
    model: &Model<D>,
    (dt, dt_prev): (f64, f64),
    range: std::ops::Range<usize>,
) {
    let n = p.n_real;
    let r = range.start.min(n)..range.end.min(n);
    let kick = 0.5 * (dt_prev + dt);
    let body = &p.body[..n];
    let h0 = &p.h0[..n];
    let v_pred = &p.v[..n];
    let m_body = &model.body_prescribed;
    let m = &p.m[..n];

    p.vh[r.clone()]
        .par_iter_mut()
        .zip(p.a[r.clone()].par_iter_mut())
        .zip(p.x[r.clone()].par_iter_mut())
        .zip(p.rho[r.clone()].par_iter_mut())
        .zip(p.e[r.clone()].par_iter_mut())
        .zip(p.s[r.clone()].par_iter_mut())
        .zip(p.eps_p[r.clone()].par_iter_mut())
        .zip(p.h[r.clone()].par_iter_mut())
        .zip(p.p[r.clone()].par_iter_mut())
        .zip(p.c[r.clone()].par_iter_mut())
        .zip(p.u[r.clone()].par_iter_mut())
        .zip(p.eh[r.clone()].par_iter_mut())
        .zip(p.damage[r.clone()].par_iter_mut())
        .zip(p.plastic_work[r.clone()].par_iter_mut())
        .zip(p.stretch[r.clone()].par_iter_mut())
        .zip(
            p.strain_rate[r.clone()]
                .par_iter_mut()
                .zip(p.dv[r.clone()].par_iter_mut()),
        )
        .enumerate()
        .for_each(
            |(
                k,
                (
                    (
                        (
                            (
                                (((((((((((vh, a), x), rho), e), s), eps_p), h), pr), c), u), eh),
                                dmg,
                            ),
                            w_p,
                        ),
                        bb,
                    ),
                    (sr, dv),
                ),
            )| {
                let i = r.start + k;
                let b = body[i] as usize;
                let mat = model.material_of(body[i]);
                let v_old = *vh;
                match m_body[b] {
                    Some(v0) => {
                        *a = Vector::<D>::zeros();
                        *vh = v0;
                        *dv = SVector::<f32, D>::zeros();
                    }
                    None => {
                        let a_old = *a;
                        *a = rates.particles[i].acc;
                        *vh += *a * kick;
                        // The next step's v + dv = v^{n+½} + Δt (2 aⁿ − aⁿ⁻¹), its predictor
                        // being v = v^{n+½} + ½ Δt aⁿ (module doc, "Staggered material
                        // update"). Δt is this step's: the next one is not known yet.
                        *dv = ((*a * 1.5 - a_old) * dt).cast::<f32>();
                    }
                }
                *u = (((v_old + *vh) * 0.5 - v_pred[i]) * kick).cast::<f32>();
                *x += *vh * dt;
                *eh += rates.particles[i].de * kick + rates.particles[i].de_lag;
                *e = *eh + rates.particles[i].de * (0.5 * dt);
                *rho = next_density(mat, *rho, rates.particles[i].drho * dt, *e, *dmg >= 1.0);
                let p_eos = mat.eos.pressure(*rho, *e);
                let grad_v = &rates.particles[i].grad_v;
                let rate = equivalent_strain_rate(grad_v);
                let mut d_eps = 0.0;
                if mat.strength.reference_shear_modulus() > 0.0 {
                    let st = mat.strength_state(*rho, *e, (*eps_p, *w_p), rate, p_eos);
                    let g = mat.strength.shear_modulus(&st);
                    let s_old = s.full();
                    let trial = s_old + jaumann_rate(&s_old, grad_v, g) * dt;
                    let damaged = Damaged {
                        inner: mat.strength.as_ref(),
                        keep: mat.carried(*dmg),
                    };
                    let (s_new, d) = radial_return(&trial, &st, &damaged);
                    *s = Sym::from_full(&s_new);
                    d_eps = d;
                    *eps_p += d;
                    // The work of the flow stress on the plastic strain (the return ends on the
                    // yield surface: σ_eq = Y).
                    *w_p += von_mises(&s_new) * d / *rho;
                }
                // What the viscosity's limiter reads of the particle's flow: its strain rate,
                // or none once it has flowed plastically, so that its pairs keep the plain
                // viscosity (`physics::viscosity::limited`, "Elastic material only").
                *sr = if *eps_p > 0.0 {
                    Sym::zeros()
                } else {
                    Sym::from_full(&((grad_v + grad_v.transpose()) * 0.5).cast::<f32>())
                };
                // Most particles at most steps grow no damage: they are told by a bound of σ1,
                // before the eigenvalue and the temperature are computed; and where only the
                // plastic strain's models act, σ1 is left at its bound (see `DamageState`).
                if !mat.damage.is_empty() && *dmg < 1.0 {
                    let s_full = s.full();
                    let sigma = s_full - Tensor::<D>::identity() * p_eos;
                    let zz = out_of_plane(&s_full) - p_eos;
                    let bound = max_principal_bound(&sigma, zz);
                    let idle = |b: f64, d: f64| mat.damage.iter().all(|model| model.idle(b, d));
                    if !idle(bound, d_eps) {
                        let st = mat.strength_state(*rho, *e, (*eps_p, *w_p), rate, p_eos);
                        let state = DamageState {
                            sigma_1: if idle(bound, 0.0) {
                                bound
                            } else {
                                max_principal(&sigma, zz)
                            },
                            p: p_eos,
                            sigma_eq: von_mises(&s_full),
                            d_eps_p: d_eps,
                            rate,
                            t_star: mat.strength.homologous_temperature(&st),
                            c: *c,
                            volume: m[i] / *rho,
                            dimension: D,
                        };
                        for model in &mat.damage {
                            *dmg = model.grow(&state, *dmg, dt);
                        }
                        if *dmg >= 1.0 {
                            *s = Sym::zeros();
                        }
                    }
                }
                // b stays the identity (λ_max = 1) in a material that does not flow.
                let lambda_max = if mat.flows {
                    let b_new = stretch_step(&bb.full(), grad_v, dt);
                    *bb = Sym::from_full(&b_new);
                    largest_stretch(&bb.full())
                } else {
                    1.0
                };
                *h = smoothing_length::<D>(h0[i], mat.rho0 / *rho, lambda_max, model);
                *pr = mat.damaged_pressure(p_eos, *dmg);
                *c = mat.sound_speed_at(*rho, *e, p_eos);
            },
        );
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn jaumann_rate_of_uniaxial_strain_and_pure_rotation() {
        // Uniaxial strain rate ε̇ along x: Ṡ_xx = 4/3 G ε̇, Ṡ_yy = −2/3 G ε̇ (and S_zz alike).
        let l = Tensor::<2>::new(1.0, 0.0, 0.0, 0.0);
        let r = jaumann_rate(&Tensor::<2>::zeros(), &l, 3.0);
        assert_relative_eq!(r[(0, 0)], 4.0, epsilon = 1e-14);
        assert_relative_eq!(r[(1, 1)], -2.0, epsilon = 1e-14);
        // A pure spin ω (L = [[0, −ω], [ω, 0]]) rotates S = diag(1, −1) rigidly.
        let w = 0.7;
        let l = Tensor::<2>::new(0.0, -w, w, 0.0);
        let s = Tensor::<2>::new(1.0, 0.0, 0.0, -1.0);
        let r = jaumann_rate(&s, &l, 5.0);
        // Exact: S(t) = R(ωt) S Rᵀ(ωt) → Ṡ_xy = ω (S_xx − S_yy) = 2ω, diagonal unchanged.
        assert_relative_eq!(r[(0, 1)], 2.0 * w, epsilon = 1e-14);
        assert_relative_eq!(r[(0, 0)], 0.0, epsilon = 1e-14);
    }

    /// b integrated over a constant velocity gradient L for a time t (n steps).
    fn stretch_after(l: Tensor<3>, t: f64, n: usize) -> Tensor<3> {
        let mut b = Tensor::<3>::identity();
        for _ in 0..n {
            b = stretch_step(&b, &l, t / n as f64);
        }
        b
    }

    #[test]
    fn stretch_follows_the_deformation_and_ignores_a_spin() {
        let steps = 200;
        // Uniaxial stress compression, isochoric (a Taylor rod's foot): L = ε̇ diag(½, ½, −1)
        // for ε̇ t = 1 stretches sideways by e^(1/2).
        let l = Tensor::<3>::from_diagonal(&Vector::<3>::new(0.5, 0.5, -1.0));
        let b = stretch_after(l, 1.0, steps);
        assert_relative_eq!(largest_stretch(&b), 0.5_f64.exp(), max_relative = 1e-5);
        assert_relative_eq!(b.determinant(), 1.0, max_relative = 1e-5);
        // Uniaxial strain compression (a plate impact): nothing stretches.
        let l = Tensor::<3>::from_diagonal(&Vector::<3>::new(-1.0, 0.0, 0.0));
        assert_relative_eq!(
            largest_stretch(&stretch_after(l, 0.3, steps)),
            1.0,
            epsilon = 1e-14
        );
        // A rigid spin of 10 radians leaves b the identity.
        let l = Tensor::<3>::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = stretch_after(l, 10.0, 1000);
        assert!((b - Tensor::<3>::identity()).norm() < 1e-12, "{b}");
        // Simple shear γ = 2: λ_max = γ/2 + √(1 + γ²/4) = 1 + √2.
        let l = Tensor::<3>::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = stretch_after(l, 2.0, steps);
        assert_relative_eq!(
            largest_stretch(&b),
            1.0 + 2.0_f64.sqrt(),
            max_relative = 1e-5
        );
    }
}
