//! Monaghan–Gingold artificial viscosity (Monaghan & Gingold 1983; Monaghan 1992):
//! for approaching pairs (v_ij·x_ij < 0), μ_ij = h_ij v_ij·x_ij / (r_ij² + 0.01 h_ij²) and
//! Π_ij = (−α c̄_ij μ_ij + β μ_ij²)/ρ̄_ij; Π_ij = 0 for separating pairs.
//!
//! v_ij·x_ij is the pair's jump less what the particles' own strain rates predict of it, where
//! the flow is smooth and the jump weak ([`limited`]): α = 1 damps every compression, not only
//! shocks, and an elastic wave lost a tenth of its energy along 200 spacings. The pair terms
//! stay symmetric in i and j, so momentum and energy are conserved as before, and the
//! viscosity's heat is never negative.

/// The limiter's default κ: pairs closing at up to κ c̄ have their jump reconstructed.
pub const LIMITER: f64 = 0.003;

/// The closing v_ij·x_ij that the viscosity acts on: the pair's velocity jump, less what each
/// particle's own strain rate predicts of it, where the flow is smooth and the jump weak.
///
/// q_i = x_ij·D_i·x_ij is the jump v_ij·x_ij that particle i's strain rate D_i predicts over
/// the pair (the skew part of L drops out of the quadratic form). The jump reconstructed to
/// the pair's midpoint, limited, is v_ij·x_ij − H(q_i, q_j), H = 2 q_i q_j/(q_i + q_j) where
/// q_i and q_j have the same sign and 0 otherwise: the harmonic mean of the two one-sided
/// slopes, which is van Leer's limiter (van Leer 1974; for SPH's pair viscosity, Christensen
/// 1990's reconstruction as in Frontiere, Raskin & Owen 2017, J. Comput. Phys. 332, 160,
/// and Spheral's limited Monaghan–Gingold viscosity). In a linear velocity field H is the
/// whole jump and the viscosity vanishes; where the strain rate changes sign from particle to
/// particle (the lattice's shortest waves, ringing behind a front) H = 0 and the viscosity
/// acts in full. The result is bounded to [v_ij·x_ij, 0]: it never adds compression, nor acts
/// on a separating pair.
///
/// The reconstruction fades out linearly as the pair's closing speed |v_ij·x̂_ij| rises to
/// `limit` / r = κ c̄ (`limit` = κ c̄ r_ij): shocks keep the plain viscosity. A limiter alone
/// smooths nothing inside a shock front, whose particles all compress alike; with κ = ∞ the
/// 14 GPa shock of `shocked_strength` rang behind its front until its flow stress read −81 %
/// of the Rayleigh line's, the spall pull-back read 0.38 GPa for a set 1.0 GPa and the
/// 7 km/s planar peak rose +26 % (conventional) and +39 % (CN-SPH) over the Hugoniot's. At
/// κ = 0.01 the first two still failed (−18 %, 0.28 GPa); at κ = 0.003 (`LIMITER`, a jump of
/// 18 m/s in aluminium, an elastic wave of 0.3 % strain) they pass. What it spares are the
/// weak waves the plain viscosity damped along their whole path: two elastic bars meeting at
/// ±10 m/s part 2.7 % slow at L/Δp = 100 (CN-SPH 3.2 %) instead of 5.3 % (5.9 %), measured
/// with the mid-step material update of `integrate`, which it needs (less viscosity otherwise
/// lets the whole-step update's negative damping grow: the same bars blew up once apart, 10×
/// their energy).
///
/// **Elastic material only.** A particle that has flowed plastically (εp > 0) offers no
/// prediction: its strain rate is stored as zero (`integrate::advance`), so its pairs keep
/// the plain viscosity. In the large plastic flow of a Taylor rod's foot, where pairs close
/// slowly, the limiter took the viscosity's stress off the flow and the footprint widened
/// with refinement: the 42CrMo4 bar's face read +5.3 % of the finite-element results at
/// R0/Δp = 16 (+3.9 % with the plain viscosity, 5 % held) and Johnson & Cook's 130 m/s copper
/// rod's +10.5 % of the test's (+9.1 %, 10 % held). The limiter is meant for the waves an
/// elastic solid carries; whether strike's plastic flow needs the viscosity's stress, or
/// hides another error behind it, is open (README, "Not yet").
#[inline(always)]
pub fn limited(vdotx: f64, (qi, qj): (f64, f64), limit: f64) -> f64 {
    // fade × H = (limit − |v_ij·x_ij|)/limit × 2 q_i q_j/(q_i + q_j), in one division (the
    // pair loop's costliest operation); zero where the slopes differ in sign or the jump
    // passes the limit (the division's value, of any kind, is then not taken).
    let room = limit - vdotx.abs();
    let product = qi * qj;
    let reconstructed = if product > 0.0 && room > 0.0 {
        2.0 * room * product / (limit * (qi + qj))
    } else {
        0.0
    };
    (vdotx - reconstructed).max(vdotx.min(0.0)).min(0.0)
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

    /// A weak jump that both particles' strain rates predict (a linear velocity field) gets
    /// no viscosity; one they disagree on in sign (the lattice's shortest wave) gets it all;
    /// a strong one (a shock) keeps it; and whatever the slopes, the result lies in
    /// [v_ij·x_ij, 0], the same from either side.
    #[test]
    fn limiter_spares_smooth_weak_jumps_only() {
        let limit = 1.0;
        // Linear field, compressing: q_i = q_j = v_ij·x_ij; a tenth of the limit keeps a tenth.
        assert!(limited(-0.1, (-0.1, -0.1), 1e9).abs() < 1e-10);
        assert!((limited(-0.1, (-0.1, -0.1), limit) + 0.01).abs() < 1e-15);
        // The harmonic mean of unequal slopes: 2 (0.05)(0.2)/0.25 = 0.08 of the 0.1.
        let got = limited(-0.1, (-0.05, -0.2), limit);
        assert!((got - (-0.1 + 0.9 * 0.08)).abs() < 1e-15, "{got}");
        // Slopes of opposite sign, or one flat: the plain jump.
        assert_eq!(limited(-0.1, (-0.1, 0.1), limit), -0.1);
        assert_eq!(limited(-0.1, (0.0, -0.1), limit), -0.1);
        // A shock (closing at the limit or faster): the plain jump.
        assert_eq!(limited(-1.0, (-1.0, -1.0), limit), -1.0);
        assert_eq!(limited(-3.0, (-3.0, -3.0), limit), -3.0);
        // Separating pairs get nothing; no limit (κ = 0) is the plain viscosity.
        assert_eq!(limited(0.1, (0.1, 0.1), limit), 0.0);
        assert_eq!(limited(-0.1, (-0.1, -0.1), 0.0), -0.1);
        let values = [-2.0, -0.5, -0.1, -1e-3, 0.0, 1e-3, 0.1, 0.5, 2.0];
        for &v in &values {
            for &a in &values {
                for &b in &values {
                    let got = limited(v, (a, b), limit);
                    assert!(got <= 0.0 && got >= v.min(0.0), "{v} {a} {b}: {got}");
                    assert_eq!(got, limited(v, (b, a), limit));
                }
            }
        }
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
