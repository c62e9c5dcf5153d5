//! Johnson–Cook strength (Johnson & Cook 1983, 7th Int. Symp. on Ballistics, eq. 1):
//!
//!   Y = (A + B εp^n) (1 + C ln ε̇*) (1 − T*^m),
//!
//! ε̇* = ε̇/ε̇0 with ε̇ the equivalent total strain rate, taken as 1 below the reference rate
//! (the rate term never softens, as in Abaqus), and T* = (T − T_room)/(T_melt − T_room) clamped
//! to [0, 1]; at T* = 1 the material is molten and carries no deviatoric stress.
//!
//! **Temperature** comes from the plastic work through the specific heat, adiabatically:
//! T = T_room + χ w_p/c_p, w_p = Σ σ_eq Δεp/ρ the plastic work per unit mass and χ the
//! Taylor–Quinney factor (the fraction of plastic work that becomes heat, 0.9 by default), as
//! in the finite-element references of the Taylor test. Not DESIGN.md §7's T = T0 + e/c_v:
//! in SPH the internal energy also holds the artificial viscosity's heat, which in a Taylor
//! rod's mushroom is numerical (42CrMo4 at 287 m/s, Δp = 0.4 mm: e reached 400 kJ/kg where the
//! plastic work was about 280 kJ/kg, a temperature rise of 870 K instead of about 540 K, and
//! the footprint came out 8 % wide). Shock heating is left out with it; it is small below
//! about 10 GPa, and under hypervelocity impact the plastic work alone melts the material
//! that flows.

use super::params::{Param, ParamError, Parameters, Valid};
use super::strength::{Strength, StrengthState};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCook {
    pub shear_modulus: f64,
    pub a: f64,
    pub b: f64,
    pub n: f64,
    pub c: f64,
    pub m: f64,
    pub reference_strain_rate: f64,
    pub room_temperature: f64,
    pub melt_temperature: f64,
    pub specific_heat: f64,
    pub taylor_quinney: f64,
}

impl Parameters for JohnsonCook {
    const NAME: &'static str = "johnson_cook";
    const PARAMS: &'static [Param] = &[
        Param::required(
            "shear_modulus",
            "shear modulus G in Pa, e.g. 26e9",
            Valid::Positive,
        ),
        Param::required(
            "a",
            "initial yield stress A in Pa, e.g. 806e6",
            Valid::NonNegative,
        ),
        Param::required(
            "b",
            "hardening modulus B in Pa, e.g. 614e6",
            Valid::NonNegative,
        ),
        Param::required("n", "hardening exponent n, e.g. 0.168", Valid::Positive),
        Param::optional(
            "c",
            "strain-rate constant C, e.g. 0.0089",
            Valid::NonNegative,
            0.0,
        ),
        Param::optional(
            "m",
            "thermal-softening exponent m, e.g. 1.1",
            Valid::Positive,
            1.0,
        ),
        Param::optional(
            "reference_strain_rate",
            "reference strain rate ε̇0 in 1/s, e.g. 1.0",
            Valid::Positive,
            1.0,
        ),
        Param::optional(
            "room_temperature",
            "room temperature T_room in K, e.g. 293.15",
            Valid::Positive,
            293.15,
        ),
        Param::required(
            "melt_temperature",
            "melting temperature T_melt in K, e.g. 1813",
            Valid::Positive,
        ),
        Param::required(
            "specific_heat",
            "specific heat c_p in J/(kg K), e.g. 460",
            Valid::Positive,
        ),
        Param::optional(
            "taylor_quinney",
            "Taylor–Quinney factor χ: the fraction of plastic work that heats, e.g. 0.9",
            Valid::Closed(0.0, 1.0),
            0.9,
        ),
    ];

    fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let jc = JohnsonCook {
            shear_modulus: v[0],
            a: v[1],
            b: v[2],
            n: v[3],
            c: v[4],
            m: v[5],
            reference_strain_rate: v[6],
            room_temperature: v[7],
            melt_temperature: v[8],
            specific_heat: v[9],
            taylor_quinney: v[10],
        };
        if jc.melt_temperature <= jc.room_temperature {
            return Err(ParamError::new(
                "melt_temperature",
                format!(
                    "the melting temperature {} K is not above the room temperature {} K",
                    jc.melt_temperature, jc.room_temperature
                ),
                "temperatures are in kelvin: e.g. 1813 for steel, 1356 for copper",
            ));
        }
        if jc.a + jc.b <= 0.0 {
            return Err(ParamError::new(
                "a",
                "A and B are both zero: the material has no strength",
                "give the initial yield stress A (Pa), or use `type = \"hydrodynamic\"`",
            ));
        }
        Ok(jc)
    }

    fn values(&self) -> Vec<f64> {
        vec![
            self.shear_modulus,
            self.a,
            self.b,
            self.n,
            self.c,
            self.m,
            self.reference_strain_rate,
            self.room_temperature,
            self.melt_temperature,
            self.specific_heat,
            self.taylor_quinney,
        ]
    }
}

impl JohnsonCook {
    /// Temperature T = T_room + χ w_p/c_p (K).
    pub fn temperature(&self, w_p: f64) -> f64 {
        self.room_temperature + self.taylor_quinney * w_p / self.specific_heat
    }

    /// The rate and thermal factors (1 + C ln ε̇*)(1 − T*^m).
    fn factors(&self, st: &StrengthState) -> f64 {
        let rate = (st.rate / self.reference_strain_rate).max(1.0);
        let t = self.homologous_temperature(st);
        (1.0 + self.c * rate.ln()) * (1.0 - t.powf(self.m))
    }
}

impl Strength for JohnsonCook {
    fn shear_modulus(&self, _st: &StrengthState) -> f64 {
        self.shear_modulus
    }

    fn yield_stress(&self, st: &StrengthState) -> f64 {
        self.yield_and_slope_scaled(st, self.factors(st)).0
    }

    fn hardening_modulus(&self, st: &StrengthState) -> f64 {
        self.yield_and_slope_scaled(st, self.factors(st)).1
    }

    fn state_factor(&self, st: &StrengthState) -> f64 {
        self.factors(st)
    }

    /// Y = k (A + B εpⁿ), and ∂Y/∂εp = k B n εpⁿ/εp from the same power.
    fn yield_and_slope_scaled(&self, st: &StrengthState, k: f64) -> (f64, f64) {
        let eps = st.eps_p.max(0.0);
        let power = eps.powf(self.n);
        let y = ((self.a + self.b * power) * k).max(0.0);
        let slope = if eps > 0.0 {
            self.b * self.n * power / eps
        } else if self.n < 1.0 && self.b > 0.0 {
            f64::INFINITY
        } else if self.n == 1.0 {
            self.b
        } else {
            0.0
        };
        (y, slope * k.max(0.0))
    }

    /// A (1 − T*) where m ≥ 1, A (1 − √T*) where m ≥ ½ (T*^m below either, T* in [0, 1]), and
    /// 0 below: the rate factor is at least 1 (C ≥ 0, ε̇* ≥ 1) and B εpⁿ ≥ 0.
    fn yield_floor(&self, st: &StrengthState) -> f64 {
        let t = self.homologous_temperature(st);
        let thermal = if self.m >= 1.0 {
            1.0 - t
        } else if self.m >= 0.5 {
            1.0 - t.sqrt()
        } else {
            0.0
        };
        self.a * thermal
    }

    fn homologous_temperature(&self, st: &StrengthState) -> f64 {
        ((self.temperature(st.w_p) - self.room_temperature)
            / (self.melt_temperature - self.room_temperature))
            .clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::strength::radial_return;
    use crate::particles::Tensor;
    use crate::tensor::von_mises;
    use approx::assert_relative_eq;

    /// 42CrMo4 (VALIDATION.md §F).
    pub(crate) fn steel() -> JohnsonCook {
        JohnsonCook::from_pairs(&[
            ("shear_modulus", 206.9e9 / 2.6),
            ("a", 806e6),
            ("b", 614e6),
            ("n", 0.168),
            ("c", 0.0089),
            ("m", 1.1),
            ("room_temperature", 293.15),
            ("melt_temperature", 1813.15),
            ("specific_heat", 460.0),
        ])
    }

    /// The return's factored calls give the model's own numbers, bit for bit.
    #[test]
    fn factored_calls_are_the_same_numbers() {
        let jc = steel();
        for (eps_p, rate, w_p) in [(0.0, 0.0, 0.0), (0.3, 1e4, 1e5), (1.2, 0.5, 3e5)] {
            let st = StrengthState {
                eps_p,
                rate,
                w_p,
                ..StrengthState::REFERENCE
            };
            let k = jc.state_factor(&st);
            assert_eq!(
                jc.yield_and_slope_scaled(&st, k),
                (jc.yield_stress(&st), jc.hardening_modulus(&st))
            );
        }
    }

    #[test]
    fn yield_stress_by_hand() {
        let jc = steel();
        // w_p is given as the heat it makes: 0.9 w_p/c_p kelvin.
        let st = |eps_p: f64, rate: f64, heat: f64| StrengthState {
            eps_p,
            rate,
            w_p: heat / 0.9,
            ..StrengthState::REFERENCE
        };
        assert_relative_eq!(
            jc.yield_stress(&st(0.0, 0.0, 0.0)),
            806e6,
            max_relative = 1e-14
        );
        // εp = 0.5, ε̇ = 1000/s, 200 K above room: by hand.
        let e = 200.0 * 460.0;
        let by_hand = (806e6 + 614e6 * 0.5f64.powf(0.168))
            * (1.0 + 0.0089 * 1000f64.ln())
            * (1.0 - (200.0f64 / 1520.0).powf(1.1));
        assert_relative_eq!(
            jc.yield_stress(&st(0.5, 1000.0, e)),
            by_hand,
            max_relative = 1e-14
        );
        // Below the reference rate the rate term is 1; at the melting point Y = 0.
        assert_relative_eq!(
            jc.yield_stress(&st(0.0, 1e-3, 0.0)),
            806e6,
            max_relative = 1e-14
        );
        assert_eq!(jc.yield_stress(&st(0.3, 0.0, 1520.0 * 460.0)), 0.0);
        assert_eq!(
            jc.homologous_temperature(&st(0.0, 0.0, 2000.0 * 460.0)),
            1.0
        );
        // The slope matches a difference quotient.
        let s = st(0.2, 1e4, 5e4);
        let d = 1e-7;
        let fd = (jc.yield_stress(&st(0.2 + d, 1e4, 5e4))
            - jc.yield_stress(&st(0.2 - d, 1e4, 5e4)))
            / (2.0 * d);
        assert_relative_eq!(jc.hardening_modulus(&s), fd, max_relative = 1e-6);
        assert!(jc.hardening_modulus(&st(0.0, 0.0, 0.0)).is_infinite());
    }

    /// The return lands on the hardened surface σ_eq = Y(εp + Δεp) with σ_eq* − 3G Δεp = Y,
    /// also from εp = 0 where the power law's slope is infinite.
    #[test]
    fn return_on_the_power_law_surface() {
        let jc = steel();
        let g = jc.shear_modulus;
        let s = Tensor::<3>::new(2e9, 3e8, 0.0, 3e8, -0.5e9, 1e8, 0.0, 1e8, -1.5e9);
        for eps0 in [0.0, 0.05, 1.0] {
            let st = StrengthState {
                eps_p: eps0,
                rate: 3e3,
                w_p: 1e5,
                ..StrengthState::REFERENCE
            };
            let (out, d) = radial_return(&s, &st, &jc);
            assert!(d > 0.0);
            let y = jc.yield_stress(&StrengthState {
                eps_p: eps0 + d,
                ..st
            });
            assert_relative_eq!(von_mises(&out), y, max_relative = 1e-10);
            assert_relative_eq!(von_mises(&s) - 3.0 * g * d, y, max_relative = 1e-10);
        }
    }

    /// Johnson–Cook's floor of Y is never above Y (any m, rate, temperature and εp), and is Y
    /// itself at εp = 0, at the reference rate, for m = 1.
    #[test]
    fn yield_floor_is_below_the_yield_stress() {
        for m in [0.3, 0.7, 1.0, 1.1, 1.7] {
            let jc = JohnsonCook { m, ..steel() };
            for eps_p in [0.0, 1e-6, 0.2, 2.0] {
                for rate in [0.0, 1.0, 1e5] {
                    for heat in [0.0, 1.0, 300.0, 1500.0] {
                        let st = StrengthState {
                            eps_p,
                            rate,
                            w_p: heat * 460.0 / 0.9,
                            ..StrengthState::REFERENCE
                        };
                        let (floor, y) = (jc.yield_floor(&st), jc.yield_stress(&st));
                        assert!(floor <= y, "m = {m}, {st:?}: {floor} > {y}");
                        assert!(floor >= 0.0);
                    }
                }
            }
        }
        let jc = JohnsonCook { m: 1.0, ..steel() };
        let st = StrengthState {
            w_p: 300.0 * 460.0 / 0.9,
            ..StrengthState::REFERENCE
        };
        assert_eq!(jc.yield_floor(&st), jc.yield_stress(&st));
        assert_eq!(JohnsonCook { m: 0.3, ..steel() }.yield_floor(&st), 0.0);
    }

    /// Counts the return's evaluations of Y.
    #[derive(Debug)]
    struct Counting<'a> {
        inner: &'a dyn Strength,
        calls: std::sync::atomic::AtomicUsize,
    }

    impl Strength for Counting<'_> {
        fn shear_modulus(&self, st: &StrengthState) -> f64 {
            self.inner.shear_modulus(st)
        }
        fn yield_stress(&self, st: &StrengthState) -> f64 {
            self.inner.yield_stress(st)
        }
        fn hardening_modulus(&self, st: &StrengthState) -> f64 {
            self.inner.hardening_modulus(st)
        }
        fn state_factor(&self, st: &StrengthState) -> f64 {
            self.inner.state_factor(st)
        }
        fn yield_and_slope_scaled(&self, st: &StrengthState, k: f64) -> (f64, f64) {
            self.calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.inner.yield_and_slope_scaled(st, k)
        }
        fn yield_floor(&self, st: &StrengthState) -> f64 {
            self.inner.yield_floor(st)
        }
        fn homologous_temperature(&self, st: &StrengthState) -> f64 {
            self.inner.homologous_temperature(st)
        }
    }

    /// A step's plastic increment asks Y twice (at the start and after one Newton step, whose
    /// successor the curvature shows to be within the tolerance), and lands on the surface; a
    /// failed particle's return (Y = 0) ends at Δεp = σ_eq/3G after one step, where bisecting
    /// took 24; a trial under the floor asks nothing.
    #[test]
    fn return_asks_few_evaluations() {
        let jc = steel();
        let g = jc.shear_modulus;
        let st = StrengthState {
            eps_p: 0.2,
            rate: 3e3,
            w_p: 1e5,
            ..StrengthState::REFERENCE
        };
        let unit = Tensor::<3>::new(2.0, 0.3, 0.0, 0.3, -0.5, 0.1, 0.0, 0.1, -1.5);
        let unit = unit / von_mises(&unit);
        let count = |strength: &dyn Strength, sigma_eq: f64| {
            let counting = Counting {
                inner: strength,
                calls: 0.into(),
            };
            let (out, d) = radial_return(&(unit * sigma_eq), &st, &counting);
            (out, d, counting.calls.into_inner())
        };
        for increment in [1e-5, 1e-4, 1e-3] {
            let y0 = jc.yield_stress(&st);
            let (out, d, calls) = count(&jc, y0 + 3.0 * g * increment);
            let y = jc.yield_stress(&StrengthState {
                eps_p: st.eps_p + d,
                ..st
            });
            assert_relative_eq!(von_mises(&out), y, max_relative = 1e-12);
            assert_relative_eq!(
                y0 + 3.0 * g * increment - 3.0 * g * d,
                y,
                max_relative = 1e-12
            );
            assert_eq!(calls, 2, "increment {increment}");
        }
        let failed = crate::material::damage::Damaged {
            inner: &jc,
            keep: 0.0,
        };
        let (out, d, calls) = count(&failed, 1e9);
        assert_eq!(out, Tensor::<3>::zeros());
        assert_relative_eq!(d, 1e9 / (3.0 * g), max_relative = 1e-15);
        assert_eq!(calls, 2);
        let (out, d, calls) = count(&jc, 0.5 * jc.a);
        assert_eq!((out, d, calls), (unit * (0.5 * jc.a), 0.0, 0));
    }

    #[test]
    fn cross_checks() {
        let mut v = steel().values();
        v[8] = 200.0;
        let err = JohnsonCook::from_values(&v).unwrap_err();
        assert_eq!(err.key, "melt_temperature");
    }
}
