//! Monaghan–Gingold artificial viscosity (Monaghan & Gingold 1983; Monaghan 1992):
//! for approaching pairs (v_ij·x_ij < 0), μ_ij = h_ij v_ij·x_ij / (r_ij² + 0.01 h_ij²) and
//! Π_ij = (−α c̄_ij μ_ij + β μ_ij²)/ρ̄_ij; Π_ij = 0 for separating pairs.

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
