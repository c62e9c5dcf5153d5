//! Equations of state p(ρ, e): linear and Mie–Grüneisen here, and
//! [`super::tillotson::Tillotson`].

use super::params::{Param, Valid};

/// An equation of state: pressure from density and specific internal energy.
pub trait Eos: Send + Sync + std::fmt::Debug {
    /// p(ρ, e) (Pa).
    fn pressure(&self, rho: f64, e: f64) -> f64;
    /// Isentropic bulk modulus K_s = ρ (∂p/∂ρ)_s = ρ (∂p/∂ρ)_e + (p/ρ)(∂p/∂e)_ρ (Pa).
    fn bulk_modulus(&self, rho: f64, e: f64) -> f64;
    /// The compression μ = ρ/ρ0 − 1 at which the EOS's reference curve is singular, where it
    /// has one (none by default).
    fn singular_compression(&self) -> Option<f64> {
        None
    }
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

    /// (p, dp/dμ at constant E) for the given μ and E.
    fn p_and_slope(&self, mu: f64, big_e: f64) -> (f64, f64) {
        let k = self.rho0 * self.c0 * self.c0;
        let gamma = self.gamma0 + self.a * mu;
        if mu > 0.0 {
            let num = k * mu * (1.0 + (1.0 - 0.5 * self.gamma0) * mu - 0.5 * self.a * mu * mu);
            let dnum = k * (1.0 + 2.0 * (1.0 - 0.5 * self.gamma0) * mu - 1.5 * self.a * mu * mu);
            let mp1 = mu + 1.0;
            let den = 1.0
                - (self.s1 - 1.0) * mu
                - self.s2 * mu * mu / mp1
                - self.s3 * mu * mu * mu / (mp1 * mp1);
            let dden = -(self.s1 - 1.0)
                - self.s2 * mu * (mu + 2.0) / (mp1 * mp1)
                - self.s3 * mu * mu * (mu + 3.0) / (mp1 * mp1 * mp1);
            let p = num / (den * den) + gamma * big_e;
            let slope = dnum / (den * den) - 2.0 * num * dden / (den * den * den) + self.a * big_e;
            (p, slope)
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

    /// The smallest μ > 0 at which the denominator 1 − (S1 − 1) μ − S2 μ²/(μ+1) − S3 μ³/(μ+1)²
    /// vanishes: the U_s = C + S1 u_p line's u_p → ∞ (μ = 1/(S1 − 1) for the linear fit; 1.18,
    /// ρ = 2.18 ρ0, for nylon 6/6's S1 = 1.849). The fit means nothing near it. Found by a scan
    /// in steps of 0.01 up to μ = 100 and bisection within the step where the sign changes.
    fn singular_compression(&self) -> Option<f64> {
        let den = |mu: f64| {
            let mp1 = mu + 1.0;
            1.0 - (self.s1 - 1.0) * mu
                - self.s2 * mu * mu / mp1
                - self.s3 * mu * mu * mu / (mp1 * mp1)
        };
        let step = 0.01;
        let k = (1..=10_000).find(|&k| den(k as f64 * step) <= 0.0)?;
        let (mut lo, mut hi) = ((k - 1) as f64 * step, k as f64 * step);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if den(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(lo)
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

    /// The linear fit's singular compression is 1/(S1 − 1); with S2 the root of the quadratic.
    #[test]
    fn singular_compression_is_where_the_denominator_vanishes() {
        let nylon = MieGruneisen {
            rho0: 1140.0,
            c0: 2570.0,
            s1: 1.849,
            ..al2024()
        };
        let mu = nylon.singular_compression().unwrap();
        assert_relative_eq!(mu, 1.0 / 0.849, max_relative = 1e-12);
        let quadratic = MieGruneisen {
            s2: 0.5,
            ..al2024()
        };
        let mu = quadratic.singular_compression().unwrap();
        let den = 1.0 - 0.338 * mu - 0.5 * mu * mu / (mu + 1.0);
        assert!(den.abs() < 1e-12, "{den}");
        // S1 ≤ 1 with no S2, S3: no singularity.
        let flat = MieGruneisen {
            s1: 0.9,
            ..al2024()
        };
        assert_eq!(flat.singular_compression(), None);
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
