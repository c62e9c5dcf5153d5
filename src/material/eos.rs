//! Equations of state p(ρ, e): linear and Mie–Grüneisen here, and
//! [`super::tillotson::Tillotson`].

use super::params::{Param, Valid};

/// An equation of state: pressure from density and specific internal energy.
pub trait Eos: Send + Sync + std::fmt::Debug {
    /// p(ρ, e) (Pa).
    fn pressure(&self, rho: f64, e: f64) -> f64;
    /// Isentropic bulk modulus K_s = ρ (∂p/∂ρ)_s = ρ (∂p/∂ρ)_e + (p/ρ)(∂p/∂e)_ρ (Pa).
    fn bulk_modulus(&self, rho: f64, e: f64) -> f64;
}

/// Linear EOS p = K (ρ/ρ0 − 1), for elastic test problems.
#[derive(Debug, Clone, Copy)]
pub struct LinearEos {
    pub rho0: f64,
    pub bulk_modulus: f64,
}

impl LinearEos {
    pub const PARAMS: &'static [Param] = &[Param::required(
        "bulk_modulus",
        "the bulk modulus K in Pa, e.g. 76e9 for aluminium",
        Valid::Positive,
    )];
}

impl Eos for LinearEos {
    fn pressure(&self, rho: f64, _e: f64) -> f64 {
        self.bulk_modulus * (rho / self.rho0 - 1.0)
    }

    fn bulk_modulus(&self, rho: f64, _e: f64) -> f64 {
        self.bulk_modulus * rho / self.rho0
    }
}

/// Mie–Grüneisen EOS referenced to the Hugoniot, in LS-DYNA's EOS_GRUNEISEN form, with
/// μ = ρ/ρ0 − 1 and E = ρ0 e (energy per reference volume):
///
/// compression (μ > 0):
///   p = ρ0 C² μ [1 + (1 − γ0/2) μ − (a/2) μ²] / [1 − (S1 − 1) μ − S2 μ²/(μ+1) − S3 μ³/(μ+1)²]²
///       + (γ0 + a μ) E
/// tension (μ ≤ 0): p = ρ0 C² μ + (γ0 + a μ) E.
///
/// Its cold Hugoniot is the linear U_s = C + S1 u_p shock (S2 = S3 = 0): along it the
/// Rankine–Hugoniot jump p = ρ0 U_s u_p holds exactly (tested below).
#[derive(Debug, Clone, Copy)]
pub struct MieGruneisen {
    pub rho0: f64,
    pub c0: f64,
    pub s1: f64,
    pub s2: f64,
    pub s3: f64,
    pub gamma0: f64,
    pub a: f64,
}

/// Where the compressed branch's denominator falls to this, the reference curve goes on along
/// its tangent. The linear U_s = C + S1 u_p fit is singular where the denominator vanishes, at
/// μ = 1/(S1 − 1) (u_p → ∞), and past it the formula's pressure falls again: nylon 6/6's S1 =
/// 1.849 puts that at ρ = 2.18 ρ0 (ε = 0.541), inside the 60 % of compression that the colour
/// contact's curve tabulates (`contact::colour::UniaxialCurve`), whose stiffness spiked there.
/// A nylon sphere at 7 or 10 km/s on aluminium (the demo's shapes, Δp = 30 µm) stopped at 3.7
/// ns as unstable until 2026-12-02: the backstop's look-ahead (`physics`, `BACKSTOP_STEP`),
/// taken where a bulk step would carry a pair 0.64 Δp apart closing at 4.6 km/s, landed on the
/// spike and halved the step every 70 steps down to 5e-16 s. At 0.1 the Hugoniot pressure is
/// 100 ρ0 C² η (η = 1 − ρ0/ρ; 365 GPa for nylon, whose 10 km/s impact on aluminium reaches
/// η ≈ 0.46), far past the states the fits are made from: the tangent changes no state a
/// fit describes (aluminium reaches it at 3.66 ρ0, copper at 2.84 ρ0; of the library only
/// nylon, from 1.96 ρ0, and Armco iron, S1 = 1.92, from 1.98 ρ0, come near it in an impact).
const DEN_MIN: f64 = 0.1;

impl MieGruneisen {
    pub const PARAMS: &'static [Param] = &[
        Param::required(
            "c0",
            "the bulk sound speed C in m/s, e.g. 5328 for Al 2024-T4",
            Valid::Positive,
        ),
        Param::required(
            "s1",
            "the slope S1 of the Us–up Hugoniot, e.g. 1.338",
            Valid::NonNegative,
        ),
        Param::optional("s2", "the Hugoniot's S2, usually 0", Valid::Any, 0.0),
        Param::optional("s3", "the Hugoniot's S3, usually 0", Valid::Any, 0.0),
        Param::required(
            "gamma0",
            "the Grüneisen coefficient γ0, e.g. 2.0",
            Valid::NonNegative,
        ),
        Param::optional(
            "a",
            "the first-order volume correction a to γ0, usually 0",
            Valid::Any,
            0.0,
        ),
    ];

    /// The denominator 1 − (S1 − 1) μ − S2 μ²/(μ+1) − S3 μ³/(μ+1)² of the compressed branch.
    fn den(&self, mu: f64) -> f64 {
        let mp1 = mu + 1.0;
        1.0 - (self.s1 - 1.0) * mu - self.s2 * mu * mu / mp1 - self.s3 * mu * mu * mu / (mp1 * mp1)
    }

    /// The compressed branch's reference part num/den² and its slope d/dμ, for μ > 0.
    fn reference(&self, mu: f64) -> (f64, f64) {
        let k = self.rho0 * self.c0 * self.c0;
        let num = k * mu * (1.0 + (1.0 - 0.5 * self.gamma0) * mu - 0.5 * self.a * mu * mu);
        let dnum = k * (1.0 + 2.0 * (1.0 - 0.5 * self.gamma0) * mu - 1.5 * self.a * mu * mu);
        let mp1 = mu + 1.0;
        let den = self.den(mu);
        let dden = -(self.s1 - 1.0)
            - self.s2 * mu * (mu + 2.0) / (mp1 * mp1)
            - self.s3 * mu * mu * (mu + 3.0) / (mp1 * mp1 * mp1);
        (
            num / (den * den),
            dnum / (den * den) - 2.0 * num * dden / (den * den * den),
        )
    }

    /// (p, dp/dμ at constant E) for the given μ and E.
    fn p_and_slope(&self, mu: f64, big_e: f64) -> (f64, f64) {
        let k = self.rho0 * self.c0 * self.c0;
        let gamma = self.gamma0 + self.a * mu;
        if mu > 0.0 {
            let (reference, slope) = if self.den(mu) >= DEN_MIN {
                self.reference(mu)
            } else {
                // Past the fit's end: along its tangent at μ_l, where the denominator is
                // DEN_MIN (in (0, μ): the denominator is 1 at 0).
                let (mut lo, mut hi) = (0.0, mu);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if self.den(mid) >= DEN_MIN {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let (p, s) = self.reference(lo);
                (p + s * (mu - lo), s)
            };
            (reference + gamma * big_e, slope + self.a * big_e)
        } else {
            (k * mu + gamma * big_e, k + self.a * big_e)
        }
    }
}

impl Eos for MieGruneisen {
    fn pressure(&self, rho: f64, e: f64) -> f64 {
        self.p_and_slope(rho / self.rho0 - 1.0, self.rho0 * e).0
    }

    fn bulk_modulus(&self, rho: f64, e: f64) -> f64 {
        let mu = rho / self.rho0 - 1.0;
        let (p, slope) = self.p_and_slope(mu, self.rho0 * e);
        // (∂p/∂ρ)_e = slope/ρ0 ; (∂p/∂e)_ρ = (γ0 + a μ) ρ0.
        rho * slope / self.rho0 + p / rho * (self.gamma0 + self.a * mu) * self.rho0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn al2024() -> MieGruneisen {
        MieGruneisen {
            rho0: 2785.0,
            c0: 5328.0,
            s1: 1.338,
            s2: 0.0,
            s3: 0.0,
            gamma0: 2.0,
            a: 0.0,
        }
    }

    /// On the Hugoniot of a shock with particle velocity u: U_s = C + S1 u,
    /// ρ = ρ0 U_s/(U_s − u), e = u²/2, p_H = ρ0 U_s u. The EOS must return p_H.
    #[test]
    fn hugoniot_jump() {
        let m = al2024();
        for u in [100.0, 1000.0, 3500.0] {
            let us = m.c0 + m.s1 * u;
            let rho = m.rho0 * us / (us - u);
            let p = m.pressure(rho, 0.5 * u * u);
            assert_relative_eq!(p, m.rho0 * us * u, max_relative = 1e-12);
        }
    }

    #[test]
    fn reference_state_and_sound_speed() {
        let m = al2024();
        assert_eq!(m.pressure(m.rho0, 0.0), 0.0);
        assert_relative_eq!(
            m.bulk_modulus(m.rho0, 0.0),
            m.rho0 * m.c0 * m.c0,
            max_relative = 1e-14
        );
        assert_relative_eq!(
            m.pressure(0.9 * m.rho0, 0.0),
            -0.1 * m.rho0 * m.c0 * m.c0,
            max_relative = 1e-14
        );
    }

    /// Past the linear fit's end the pressure goes on along the tangent: continuous, rising,
    /// finite through the fit's singularity at 1/(S1 − 1) (nylon 6/6's, ρ = 2.18 ρ0) and
    /// beyond it, where the formula's own pressure fell again; before the end, the formula's.
    #[test]
    fn past_the_fits_end_the_pressure_rises_along_its_tangent() {
        let nylon = MieGruneisen {
            rho0: 1140.0,
            c0: 2570.0,
            s1: 1.849,
            gamma0: 0.87,
            ..al2024()
        };
        let end = 1.0 + 0.9 / 0.849; // ρ/ρ0 where the denominator is 0.1
        let p = |x: f64| nylon.pressure(x * nylon.rho0, 1e6);
        // Continuous at the end, and the formula's before it.
        assert_relative_eq!(
            p(end * (1.0 - 1e-9)),
            p(end * (1.0 + 1e-9)),
            max_relative = 1e-6
        );
        let mu = 0.8;
        let formula = nylon.rho0 * 2570.0_f64.powi(2) * mu * (1.0 + (1.0 - 0.435) * mu)
            / (1.0 - 0.849 * mu).powi(2)
            + 0.87 * nylon.rho0 * 1e6;
        assert_relative_eq!(p(1.0 + mu), formula, max_relative = 1e-12);
        // Rising and finite through the singularity and past it.
        let mut last = p(end);
        for k in 1..=200 {
            let x = end + 0.01 * k as f64;
            let (next, k_s) = (p(x), nylon.bulk_modulus(x * nylon.rho0, 1e6));
            assert!(
                next.is_finite() && next > last && k_s > 0.0,
                "ρ/ρ0 = {x}: {next}"
            );
            last = next;
        }
    }

    #[test]
    fn bulk_modulus_matches_isentropic_derivative() {
        // K_s = ρ dp/dρ along de = p/ρ² dρ.
        let m = MieGruneisen {
            a: 0.5,
            s2: 0.3,
            s3: 0.1,
            ..al2024()
        };
        for (rho, e) in [(3200.0, 2e5), (2500.0, 1e4), (4000.0, 3e6)] {
            let d = rho * 1e-7;
            let p = m.pressure(rho, e);
            let de = p / (rho * rho) * d;
            let fd = rho * (m.pressure(rho + d, e + de) - m.pressure(rho - d, e - de)) / (2.0 * d);
            assert_relative_eq!(m.bulk_modulus(rho, e), fd, max_relative = 1e-6);
        }
    }
}
