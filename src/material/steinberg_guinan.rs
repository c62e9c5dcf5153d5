//! Steinberg–Guinan strength (Steinberg, Cochran & Guinan 1980, J. Appl. Phys. 51, 1498,
//! eqs. 1–3 and 7; constants in Steinberg 1996, LLNL UCRL-MA-106439):
//!
//!   G = G0 [1 + (G′_p/G0) p η^(−1/3) + (G′_T/G0)(T − 300)],
//!   Y = Y0 [1 + β(εp + εi)]^n [1 + (Y′_p/Y0) p η^(−1/3) + (G′_T/G0)(T − 300)],
//!   with Y0 [1 + β(εp + εi)]^n ≤ Y_max,
//!
//! η = ρ/ρ0, and both G and Y zero at or above the melting temperature
//! T_m = T_m0 exp(2a(1 − 1/η)) η^(2(γ0 − a − 1/3)) (the modified Lindemann law). Strain-rate
//! independent: the model's own argument is that above about 10⁵ /s rate effects saturate.
//! Temperature T = T0 + e/c_v from the specific internal energy (every joule counts as heat; see
//! [`super::johnson_cook`] for what that leaves out), with T0 = 300 K the model's reference.

use super::params::{Param, ParamError, Parameters, Valid};
use super::strength::{Strength, StrengthState};

/// The reference temperature of the model's constants (K).
const T_REF: f64 = 300.0;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteinbergGuinan {
    pub shear_modulus: f64,
    pub yield_stress: f64,
    pub max_yield_stress: f64,
    pub beta: f64,
    pub n: f64,
    pub initial_strain: f64,
    /// G′_p = ∂G/∂p (dimensionless).
    pub dg_dp: f64,
    /// G′_T = ∂G/∂T (Pa/K, negative).
    pub dg_dt: f64,
    /// Y′_p = ∂Y/∂p (dimensionless).
    pub dy_dp: f64,
    pub melt_temperature: f64,
    pub melt_a: f64,
    pub gamma0: f64,
    pub specific_heat: f64,
}

impl Parameters for SteinbergGuinan {
    const NAME: &'static str = "steinberg_guinan";
    const PARAMS: &'static [Param] = &[
        Param::required("shear_modulus", "G0 in Pa, e.g. 27.6e9", Valid::Positive),
        Param::required("yield_stress", "Y0 in Pa, e.g. 0.29e9", Valid::Positive),
        Param::required(
            "max_yield_stress",
            "Y_max in Pa, e.g. 0.68e9",
            Valid::Positive,
        ),
        Param::required("beta", "hardening constant β, e.g. 125", Valid::NonNegative),
        Param::required("n", "hardening exponent n, e.g. 0.1", Valid::NonNegative),
        Param::optional(
            "initial_strain",
            "initial plastic strain εi, e.g. 0",
            Valid::NonNegative,
            0.0,
        ),
        Param::required(
            "dg_dp",
            "G′_p = ∂G/∂p (dimensionless), e.g. 1.8",
            Valid::Any,
        ),
        Param::required("dg_dt", "G′_T = ∂G/∂T in Pa/K, e.g. -1.7e7", Valid::Any),
        Param::required(
            "dy_dp",
            "Y′_p = ∂Y/∂p (dimensionless), e.g. 0.0189",
            Valid::Any,
        ),
        Param::required("melt_temperature", "T_m0 in K, e.g. 1220", Valid::Positive),
        Param::required("melt_a", "a of the melting law, e.g. 1.5", Valid::Any),
        Param::required(
            "gamma0",
            "Grüneisen γ0 of the melting law, e.g. 1.97",
            Valid::Any,
        ),
        Param::required(
            "specific_heat",
            "specific heat c_v in J/(kg K), e.g. 885",
            Valid::Positive,
        ),
    ];

    fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let sg = SteinbergGuinan {
            shear_modulus: v[0],
            yield_stress: v[1],
            max_yield_stress: v[2],
            beta: v[3],
            n: v[4],
            initial_strain: v[5],
            dg_dp: v[6],
            dg_dt: v[7],
            dy_dp: v[8],
            melt_temperature: v[9],
            melt_a: v[10],
            gamma0: v[11],
            specific_heat: v[12],
        };
        if sg.max_yield_stress < sg.yield_stress {
            return Err(ParamError::new(
                "max_yield_stress",
                format!(
                    "Y_max = {} Pa is below Y0 = {} Pa",
                    sg.max_yield_stress, sg.yield_stress
                ),
                "Y_max caps the work-hardened yield stress: at least Y0",
            ));
        }
        if sg.melt_temperature <= T_REF {
            return Err(ParamError::new(
                "melt_temperature",
                format!("{} K is not above the model's 300 K", sg.melt_temperature),
                "the melting temperature at ρ0 in kelvin, e.g. 1220 for aluminium",
            ));
        }
        Ok(sg)
    }

    fn values(&self) -> Vec<f64> {
        vec![
            self.shear_modulus,
            self.yield_stress,
            self.max_yield_stress,
            self.beta,
            self.n,
            self.initial_strain,
            self.dg_dp,
            self.dg_dt,
            self.dy_dp,
            self.melt_temperature,
            self.melt_a,
            self.gamma0,
            self.specific_heat,
        ]
    }
}

impl SteinbergGuinan {
    /// T = 300 K + e/c_v.
    pub fn temperature(&self, e: f64) -> f64 {
        T_REF + e / self.specific_heat
    }

    /// T_m(η) = T_m0 exp(2a(1 − 1/η)) η^(2(γ0 − a − 1/3)).
    pub fn melt_temperature_at(&self, eta: f64) -> f64 {
        let eta = eta.max(1e-3);
        self.melt_temperature
            * (2.0 * self.melt_a * (1.0 - 1.0 / eta)).exp()
            * eta.powf(2.0 * (self.gamma0 - self.melt_a - 1.0 / 3.0))
    }

    fn melted(&self, st: &StrengthState) -> bool {
        self.temperature(st.e) >= self.melt_temperature_at(st.eta)
    }

    /// The work-hardening part Y0 [1 + β(εp + εi)]^n, capped at Y_max, and its slope.
    fn hardening(&self, eps_p: f64) -> (f64, f64) {
        let base = 1.0 + self.beta * (eps_p.max(0.0) + self.initial_strain);
        let y = self.yield_stress * base.powf(self.n);
        if y >= self.max_yield_stress {
            (self.max_yield_stress, 0.0)
        } else {
            (
                y,
                self.yield_stress * self.n * self.beta * base.powf(self.n - 1.0),
            )
        }
    }

    /// The pressure and temperature factor, with ∂/∂p = `dp` (G′_p/G0 or Y′_p/Y0).
    fn factor(&self, st: &StrengthState, dp: f64) -> f64 {
        let t = self.temperature(st.e);
        (1.0 + dp * st.p * st.eta.max(1e-3).powf(-1.0 / 3.0)
            + self.dg_dt / self.shear_modulus * (t - T_REF))
            .max(0.0)
    }
}

impl Strength for SteinbergGuinan {
    fn shear_modulus(&self, st: &StrengthState) -> f64 {
        if self.melted(st) {
            return 0.0;
        }
        self.shear_modulus * self.factor(st, self.dg_dp / self.shear_modulus)
    }

    fn yield_stress(&self, st: &StrengthState) -> f64 {
        if self.melted(st) {
            return 0.0;
        }
        self.hardening(st.eps_p).0 * self.factor(st, self.dy_dp / self.yield_stress)
    }

    fn hardening_modulus(&self, st: &StrengthState) -> f64 {
        if self.melted(st) {
            return 0.0;
        }
        self.hardening(st.eps_p).1 * self.factor(st, self.dy_dp / self.yield_stress)
    }

    /// Both from one evaluation of the hardening and of the pressure and temperature factor
    /// (the same numbers as the two calls).
    fn yield_and_slope_scaled(&self, st: &StrengthState, _k: f64) -> (f64, f64) {
        if self.melted(st) {
            return (0.0, 0.0);
        }
        let (y, slope) = self.hardening(st.eps_p);
        let f = self.factor(st, self.dy_dp / self.yield_stress);
        (y * f, slope * f)
    }

    fn homologous_temperature(&self, st: &StrengthState) -> f64 {
        let tm = self.melt_temperature_at(st.eta);
        ((self.temperature(st.e) - T_REF) / (tm - T_REF).max(1e-9)).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Al 6061-T6 (Steinberg 1996).
    fn al() -> SteinbergGuinan {
        SteinbergGuinan::from_pairs(&[
            ("shear_modulus", 27.6e9),
            ("yield_stress", 0.29e9),
            ("max_yield_stress", 0.68e9),
            ("beta", 125.0),
            ("n", 0.1),
            ("dg_dp", 1.8),
            ("dg_dt", -1.7e7),
            ("dy_dp", 0.018912),
            ("melt_temperature", 1220.0),
            ("melt_a", 1.5),
            ("gamma0", 1.97),
            ("specific_heat", 885.0),
        ])
    }

    #[test]
    fn modulus_and_yield_by_hand() {
        let sg = al();
        let r = StrengthState::REFERENCE;
        assert_relative_eq!(sg.shear_modulus(&r), 27.6e9, max_relative = 1e-14);
        assert_relative_eq!(sg.yield_stress(&r), 0.29e9, max_relative = 1e-14);
        // 20 GPa at η = 1.2, 200 K above 300 K, εp = 0.01.
        let st = StrengthState {
            eps_p: 0.01,
            rate: 0.0,
            e: 200.0 * 885.0,
            w_p: 0.0,
            eta: 1.2,
            p: 20e9,
        };
        let pf = 20e9 * 1.2f64.powf(-1.0 / 3.0);
        let tf = -1.7e7 / 27.6e9 * 200.0;
        assert_relative_eq!(
            sg.shear_modulus(&st),
            27.6e9 * (1.0 + 1.8 / 27.6e9 * pf + tf),
            max_relative = 1e-13
        );
        let hard = 0.29e9 * (1.0 + 125.0 * 0.01f64).powf(0.1);
        assert_relative_eq!(
            sg.yield_stress(&st),
            hard * (1.0 + 0.018912 / 0.29e9 * pf + tf),
            max_relative = 1e-13
        );
        // The cap: at large strain the hardening part is Y_max.
        let big = StrengthState { eps_p: 1e6, ..r };
        assert_relative_eq!(sg.yield_stress(&big), 0.68e9, max_relative = 1e-14);
        assert_eq!(sg.hardening_modulus(&big), 0.0);
        // The return's one call gives the two calls' numbers, bit for bit (melted included).
        let molten = StrengthState {
            e: 930.0 * 885.0,
            ..r
        };
        for s in [r, st, big, molten] {
            assert_eq!(
                sg.yield_and_slope_scaled(&s, 1.0),
                (sg.yield_stress(&s), sg.hardening_modulus(&s))
            );
        }
    }

    #[test]
    fn melts_by_the_lindemann_law() {
        let sg = al();
        // At η = 1 melting is at T_m0 = 1220 K: e = 920 K · c_v.
        let below = StrengthState {
            e: 910.0 * 885.0,
            ..StrengthState::REFERENCE
        };
        let above = StrengthState {
            e: 930.0 * 885.0,
            ..StrengthState::REFERENCE
        };
        assert!(sg.yield_stress(&below) > 0.0);
        assert_eq!(sg.yield_stress(&above), 0.0);
        assert_eq!(sg.shear_modulus(&above), 0.0);
        assert_eq!(sg.homologous_temperature(&above), 1.0);
        // Compression raises the melting point: exp(2a(1 − 1/η)) η^(2(γ0 − a − 1/3)).
        let eta: f64 = 1.3;
        let tm =
            1220.0 * (3.0 * (1.0 - 1.0 / eta)).exp() * eta.powf(2.0 * (1.97 - 1.5 - 1.0 / 3.0));
        assert_relative_eq!(sg.melt_temperature_at(eta), tm, max_relative = 1e-14);
        assert!(tm > 2000.0);
    }
}
