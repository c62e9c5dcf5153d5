//! Tillotson EOS (Tillotson 1962, General Atomics GA-3216; in the form of Melosh 1989, "Impact
//! Cratering", §AII, and Benz & Asphaug 1999, Icarus 142, eqs. 17–19), with η = ρ/ρ0,
//! μ = η − 1, z = 1/η − 1 and ω = e/(E0 η²) + 1:
//!
//! - compressed (μ ≥ 0), and cold expanded (μ < 0, e ≤ E_iv):
//!   p_c = (a + b/ω) ρ e + A μ + B μ²;
//! - hot expanded (μ < 0, e ≥ E_cv):
//!   p_e = a ρ e + [b ρ e/ω + A μ exp(−β z)] exp(−α z²);
//! - between E_iv and E_cv (μ < 0), linear in e: p = [(e − E_iv) p_e + (E_cv − e) p_c]/(E_cv − E_iv).
//!
//! The isentropic bulk modulus is exact for each branch and their blend,
//! K_s = ρ ∂p/∂ρ|_e + (p/ρ) ∂p/∂e|_ρ (DESIGN.md §7); the material floors it (see
//! [`super::Material::sound_speed`]), which Tillotson needs in the expanded states where K_s
//! can fall to or below zero.

use super::eos::Eos;
use super::params::{Param, ParamError, Valid};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tillotson {
    pub rho0: f64,
    pub a: f64,
    pub b: f64,
    pub big_a: f64,
    pub big_b: f64,
    pub e0: f64,
    pub alpha: f64,
    pub beta: f64,
    pub e_iv: f64,
    pub e_cv: f64,
}

impl Tillotson {
    /// The parameters other than ρ0 (which is the material's density): their order in
    /// [`Tillotson::from_values`] is this list's, after ρ0.
    pub const PARAMS: &'static [Param] = &[
        Param::required(
            "a",
            "Tillotson a (dimensionless), e.g. 0.5",
            Valid::NonNegative,
        ),
        Param::required(
            "b",
            "Tillotson b (dimensionless), e.g. 1.63",
            Valid::NonNegative,
        ),
        Param::required(
            "A",
            "Tillotson A in Pa (the bulk modulus at ρ0), e.g. 75.2e9",
            Valid::Positive,
        ),
        Param::required("B", "Tillotson B in Pa, e.g. 65.0e9", Valid::Any),
        Param::required("e0", "Tillotson E0 in J/kg, e.g. 5.0e6", Valid::Positive),
        Param::required("alpha", "Tillotson α, e.g. 5", Valid::NonNegative),
        Param::required("beta", "Tillotson β, e.g. 5", Valid::NonNegative),
        Param::required(
            "e_iv",
            "energy of incipient vaporisation E_iv in J/kg, e.g. 2.7e6",
            Valid::Positive,
        ),
        Param::required(
            "e_cv",
            "energy of complete vaporisation E_cv in J/kg, e.g. 14.1e6",
            Valid::Positive,
        ),
    ];

    /// From ρ0 and the values of [`Tillotson::PARAMS`] in order.
    pub fn from_values(rho0: f64, v: &[f64]) -> Result<Self, ParamError> {
        let t = Tillotson {
            rho0,
            a: v[0],
            b: v[1],
            big_a: v[2],
            big_b: v[3],
            e0: v[4],
            alpha: v[5],
            beta: v[6],
            e_iv: v[7],
            e_cv: v[8],
        };
        if t.e_cv <= t.e_iv {
            return Err(ParamError::new(
                "e_cv",
                format!(
                    "E_cv = {} J/kg is not above E_iv = {} J/kg",
                    t.e_cv, t.e_iv
                ),
                "complete vaporisation needs more energy than incipient: e.g. E_iv = 2.7e6, E_cv = 14.1e6 for aluminium",
            ));
        }
        Ok(t)
    }

    /// From ρ0 and (key, value) pairs, for a library: panics on a missing or invalid value, a
    /// bug in the library's table.
    pub fn from_pairs(rho0: f64, pairs: &[(&str, f64)]) -> Self {
        let v = super::params::values_from_pairs("tillotson", Self::PARAMS, pairs);
        Self::from_values(rho0, &v).unwrap_or_else(|e| panic!("tillotson: {}", e.message))
    }

    pub fn values(&self) -> Vec<f64> {
        vec![
            self.a, self.b, self.big_a, self.big_b, self.e0, self.alpha, self.beta, self.e_iv,
            self.e_cv,
        ]
    }

    /// Compressed (and cold expanded) branch: (p, ∂p/∂ρ|_e, ∂p/∂e|_ρ).
    fn compressed(&self, rho: f64, e: f64) -> (f64, f64, f64) {
        let eta = rho / self.rho0;
        let mu = eta - 1.0;
        let omega = e / (self.e0 * eta * eta) + 1.0;
        let domega_drho = -2.0 * e / (self.e0 * eta * eta * eta * self.rho0);
        let domega_de = 1.0 / (self.e0 * eta * eta);
        let g = self.a + self.b / omega;
        let p = g * rho * e + self.big_a * mu + self.big_b * mu * mu;
        let dp_drho = g * e - self.b / (omega * omega) * domega_drho * rho * e
            + (self.big_a + 2.0 * self.big_b * mu) / self.rho0;
        let dp_de = g * rho - self.b / (omega * omega) * domega_de * rho * e;
        (p, dp_drho, dp_de)
    }

    /// Hot expanded branch: (p, ∂p/∂ρ|_e, ∂p/∂e|_ρ).
    fn expanded(&self, rho: f64, e: f64) -> (f64, f64, f64) {
        let eta = rho / self.rho0;
        let mu = eta - 1.0;
        let z = 1.0 / eta - 1.0;
        let dz_drho = -1.0 / (self.rho0 * eta * eta);
        let omega = e / (self.e0 * eta * eta) + 1.0;
        let domega_drho = -2.0 * e / (self.e0 * eta * eta * eta * self.rho0);
        let domega_de = 1.0 / (self.e0 * eta * eta);
        let decay = (-self.beta * z).exp();
        let q = self.b * rho * e / omega + self.big_a * mu * decay;
        let f = (-self.alpha * z * z).exp();
        let dq_drho = self.b * e / omega - self.b * rho * e / (omega * omega) * domega_drho
            + self.big_a / self.rho0 * decay
            - self.big_a * mu * decay * self.beta * dz_drho;
        let df_drho = -f * 2.0 * self.alpha * z * dz_drho;
        let dq_de = self.b * rho / omega - self.b * rho * e / (omega * omega) * domega_de;
        let p = self.a * rho * e + q * f;
        let dp_drho = self.a * e + dq_drho * f + q * df_drho;
        let dp_de = self.a * rho + dq_de * f;
        (p, dp_drho, dp_de)
    }

    /// (p, ∂p/∂ρ|_e, ∂p/∂e|_ρ) on the branch (or blend) of the state.
    fn state(&self, rho: f64, e: f64) -> (f64, f64, f64) {
        let rho = rho.max(1e-6 * self.rho0);
        if rho >= self.rho0 || e <= self.e_iv {
            return self.compressed(rho, e);
        }
        if e >= self.e_cv {
            return self.expanded(rho, e);
        }
        let (pc, dc_rho, dc_e) = self.compressed(rho, e);
        let (pe, de_rho, de_e) = self.expanded(rho, e);
        let span = self.e_cv - self.e_iv;
        let x = (e - self.e_iv) / span;
        (
            x * pe + (1.0 - x) * pc,
            x * de_rho + (1.0 - x) * dc_rho,
            x * de_e + (1.0 - x) * dc_e + (pe - pc) / span,
        )
    }
}

impl Eos for Tillotson {
    fn pressure(&self, rho: f64, e: f64) -> f64 {
        self.state(rho, e).0
    }

    fn bulk_modulus(&self, rho: f64, e: f64) -> f64 {
        let (p, dp_drho, dp_de) = self.state(rho, e);
        rho * dp_drho + p / rho * dp_de
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Aluminium (VALIDATION.md §F; Melosh 1989 Table AII.3).
    fn al() -> Tillotson {
        Tillotson::from_values(
            2700.0,
            &[0.5, 1.63, 75.2e9, 65.0e9, 5.0e6, 5.0, 5.0, 2.7e6, 14.1e6],
        )
        .unwrap()
    }

    #[test]
    fn reference_state() {
        let t = al();
        assert_eq!(t.pressure(2700.0, 0.0), 0.0);
        // K = ρ ∂p/∂ρ = A at ρ0, e = 0.
        assert_relative_eq!(t.bulk_modulus(2700.0, 0.0), 75.2e9, max_relative = 1e-14);
        // Compressed by hand: η = 1.2, e = 1 MJ/kg.
        let (rho, e) = (3240.0, 1e6);
        let omega = e / (5e6 * 1.44) + 1.0;
        let by_hand = (0.5 + 1.63 / omega) * rho * e + 75.2e9 * 0.2 + 65e9 * 0.04;
        assert_relative_eq!(t.pressure(rho, e), by_hand, max_relative = 1e-14);
    }

    /// The blend is continuous at E_iv and E_cv, and the expanded branch is what it says.
    #[test]
    fn branches_join() {
        let t = al();
        let rho = 0.7 * 2700.0;
        for e_edge in [2.7e6, 14.1e6] {
            let below = t.pressure(rho, e_edge * (1.0 - 1e-12));
            let above = t.pressure(rho, e_edge * (1.0 + 1e-12));
            assert_relative_eq!(below, above, max_relative = 1e-9);
        }
        let e = 2e7;
        let (eta, z): (f64, f64) = (0.7, 1.0 / 0.7 - 1.0);
        let omega = e / (5e6 * eta * eta) + 1.0;
        let by_hand = 0.5 * rho * e
            + (1.63 * rho * e / omega + 75.2e9 * (eta - 1.0) * (-5.0 * z).exp())
                * (-5.0 * z * z).exp();
        assert_relative_eq!(t.pressure(rho, e), by_hand, max_relative = 1e-14);
    }

    /// K_s = ρ dp/dρ along an isentrope de = (p/ρ²) dρ, on every branch and in the blend.
    #[test]
    fn bulk_modulus_matches_isentropic_derivative() {
        let t = al();
        for (rho, e) in [
            (3500.0, 3e6),
            (2700.0, 1e5),
            (2000.0, 1e6),
            (2000.0, 8e6),
            (1500.0, 3e7),
        ] {
            let d = rho * 1e-7;
            let p = t.pressure(rho, e);
            let de = p / (rho * rho) * d;
            let fd = rho * (t.pressure(rho + d, e + de) - t.pressure(rho - d, e - de)) / (2.0 * d);
            assert_relative_eq!(t.bulk_modulus(rho, e), fd, max_relative = 1e-6);
        }
    }

    #[test]
    fn vaporisation_energies_in_order() {
        let err = Tillotson::from_values(
            2700.0,
            &[0.5, 1.63, 75.2e9, 65.0e9, 5.0e6, 5.0, 5.0, 2.7e6, 2.0e6],
        )
        .unwrap_err();
        assert_eq!(err.key, "e_cv");
    }
}
