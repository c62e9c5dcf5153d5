//! Monaghan–Gingold artificial viscosity (Monaghan & Gingold 1983; Monaghan 1992):
//! for approaching pairs (v_ij·x_ij < 0), μ_ij = h_ij v_ij·x_ij / (r_ij² + 0.01 h_ij²) and
//! Π_ij = (−α_ij c̄_ij μ_ij + β_ij μ_ij²)/ρ̄_ij; Π_ij = 0 for separating pairs.
//!
//! **Switch** (Morris & Monaghan 1997, J. Comput. Phys. 136, 41). A fixed α = 1 damps every
//! compression, not only shocks: two elastic bars meeting at ±10 m/s
//! (`examples/bars_contact.toml`, L/Δp = 100) were heated along the whole length their wave ran
//! and parted 5.3 % slow (CN-SPH 5.9 %) with the mid-step material update (4.0 and 5.3 % with
//! the whole-step one, whose negative damping offsets part of the loss), a loss that shrinks
//! only as about (Δp/L)^½. Each
//! particle therefore carries its own α_i between the deck's `alpha_min` and `alpha`, raised by
//! compression and decaying back:
//!
//!   dα_i/dt = −(α_i − α_min)/τ_i + max(−∇·v_i, 0) (α − α_i),   τ_i = h_i/(ℓ c_i), ℓ = 0.1,
//!
//! integrated implicitly over a step ([`relax`]), so α_i stays in [α_min, α] at any step. A
//! pair takes the mean strength s_ij = (α_i + α_j)/(2α), and both terms follow it: α_ij = α s_ij,
//! β_ij = β s_ij (Morris & Monaghan keep β = 2α). Particles start at α, since impacts start
//! with a jump in velocity; α_min = α switches it off.
//!
//! **Off unless asked for** (`alpha_min` defaults to `alpha`). Morris & Monaghan's floor, 0.1,
//! chosen for gas dynamics, let the lattice ring behind release waves in solids: the spall
//! test's target failed early (its pull-back read 0.42 GPa for a set 1.0 GPa), CN-SPH's 7 km/s
//! planar peak rose to +33 % of the Hugoniot pressure and the rubber rings drifted 2.7 %
//! (CN-SPH 7.2 %) in energy. At 0.5, with `material_update = "mid_step"`, every case of
//! `strike validate` that passed before passes at the CI's resolution, the ±10 m/s bars part
//! 4.1 % slow (CN-SPH 4.7 %) and the Taylor bar's face is −1.6 % of the
//! finite-element results at R0/Δp = 8 (−8.5 % with α = 1). But at R0/Δp = 16 that face reads
//! +7.9 % (−0.2 % with α = 1): with less viscosity it moves away from the reference as the
//! lattice is refined, and CN-SPH's sphere–plate at 20 µm mixes to 0.12 Δp (0.1 allowed). So
//! the switch is there to be used where waves matter more than heavy plastic flow (elastic
//! impacts, wave propagation), and is not the default.
//!
//! The switch needs a material update that does not feed energy into the lattice's shortest
//! waves: the whole-step one does, and only α near 1 holds it (see `integrate`, "Staggered
//! material update").

/// ℓ of the decay time τ = h/(ℓ c): about ten sound crossings of h (Morris & Monaghan 1997).
pub const DECAY: f64 = 0.1;

/// A particle's α after a step of dt (s), from α_i (`alpha`), the deck's α_min and α
/// (`bounds`), the velocity divergence ∇·v (1/s), h (m) and c (m/s): the switch's equation,
/// backward Euler, (α_i + dt (α_min/τ + S α)) / (1 + dt (1/τ + S)) with S = max(−∇·v, 0): a
/// weighted mean of α_i, α_min and α, so it never leaves [α_min, α] (but for rounding, which
/// the bounds take off).
pub fn relax(
    alpha: f64,
    (alpha_min, alpha_max): (f64, f64),
    div_v: f64,
    h: f64,
    c: f64,
    dt: f64,
) -> f64 {
    let decay = DECAY * c / h;
    let source = (-div_v).max(0.0);
    let mean =
        (alpha + dt * (alpha_min * decay + source * alpha_max)) / (1.0 + dt * (decay + source));
    mean.max(alpha_min).min(alpha_max)
}

/// The strength α_i/α a particle passes to the pairs (1 where the deck's α is 0, so that β
/// alone still acts).
#[inline(always)]
pub fn strength(alpha_i: f64, alpha: f64) -> f64 {
    if alpha > 0.0 {
        alpha_i / alpha
    } else {
        1.0
    }
}

/// Returns (Π_ij, μ_ij) with μ_ij ≤ 0 (0 when the pair separates).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn monaghan_gingold(
    vdotx: f64,
    r2: f64,
    h: f64,
    c_mean: f64,
    rho_mean: f64,
    alpha: f64,
    beta: f64,
) -> (f64, f64) {
    // Branch-free: μ = 0 for separating pairs gives Π = 0 (the sign of v_ij·x_ij is close to
    // random from pair to pair, and a mispredicted branch costs more than the arithmetic).
    // One division: with d = 1/(den ρ̄), μ = h (v·x) ρ̄ d and 1/ρ̄ = den d.
    let den = r2 + 0.01 * h * h;
    let d = 1.0 / (den * rho_mean);
    let mu = h * vdotx.min(0.0) * rho_mean * d;
    ((-alpha * c_mean * mu + beta * mu * mu) * (den * d), mu)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The switch stays in [α_min, α] at any step, decays to α_min with the time constant
    /// τ = h/(ℓ c) where nothing compresses, and rises toward α under compression.
    #[test]
    fn switch_is_bounded_decays_and_rises() {
        let (h, c) = (1e-3, 5000.0);
        let tau = h / (DECAY * c);
        for dt in [1e-12, 1e-9, 1e-6, 1.0] {
            for div in [-1e12, -1e4, 0.0, 1e8] {
                for a0 in [0.1, 0.5, 1.0] {
                    let a = relax(a0, (0.1, 1.0), div, h, c, dt);
                    assert!(
                        (0.1..=1.0).contains(&a),
                        "{a} from {a0}, ∇·v {div}, dt {dt}"
                    );
                }
            }
        }
        // Free decay over τ in small steps: α − α_min falls by e.
        let mut a = 1.0;
        let steps = 10_000;
        for _ in 0..steps {
            a = relax(a, (0.1, 1.0), 0.0, h, c, tau / steps as f64);
        }
        assert!(((a - 0.1) / 0.9 - (-1.0f64).exp()).abs() < 1e-4, "{a}");
        // A shock's compression (−∇·v ≫ 1/τ) drives it to α within a few of its own times.
        let mut a = 0.1;
        for _ in 0..50 {
            a = relax(a, (0.1, 1.0), -100.0 / tau, h, c, tau / 100.0);
        }
        assert!(a > 0.95, "{a}");
        // α_min = α: constant.
        assert_eq!(relax(0.7, (0.7, 0.7), -1e9, h, c, 1e-6), 0.7);
    }

    #[test]
    fn only_for_approaching_pairs_and_positive() {
        assert_eq!(
            monaghan_gingold(1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0),
            (0.0, 0.0)
        );
        let (pi, mu) = monaghan_gingold(-2.0, 1.0, 1.0, 3.0, 2.0, 1.0, 2.0);
        let m = -2.0 / 1.01;
        assert_eq!(mu, m);
        assert!((pi - (-3.0 * m + 2.0 * m * m) / 2.0).abs() < 1e-15 && pi > 0.0);
    }
}
