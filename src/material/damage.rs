//! Damage D ∈ [0, 1] (DESIGN.md §7). A failed particle (D = 1) is a fluid that cannot be
//! pulled: it keeps its mass, momentum and energy, carries no tension and no deviator, and
//! pushes on its neighbours only in compression. Before it fails, what D does depends on the
//! model ([`Damage::degrades`], [`crate::material::Material::carried`]):
//! - the spall model's D is the share of the particle its cracks have crossed: the particle
//!   carries (1 − D) of its tension and of its yield stress (Benz & Asphaug 1994);
//! - Johnson–Cook's D is a fracture indicator, the share of the failure strain used up: the
//!   particle keeps its whole strength until D = 1 (Johnson & Cook 1985: "fracture occurs when
//!   D = 1.0"; LS-DYNA's MAT_015 and AUTODYN do the same). The hardening curve A + B εp^n is
//!   the material's own up to fracture, so scaling it by (1 − D) as well would count the
//!   damage twice: strike did so until 2026-11-26 (DESIGN.md §7 reads that way), and the
//!   core of a 2024-T3 block squeezed between frictionless platens then fell to 43 % of the
//!   Johnson–Cook flow stress and failed at εp = 0.34 against ε_f = 0.44
//!   (`examples/jc_failure_compression.toml`). A material with both models uses the indicator
//!   reading for both: the spall's cracks cross a particle in a few nanoseconds, so that its
//!   tension then falls at once rather than over those nanoseconds.
//!
//! **Fragments do not stick back together, and a crack stays a crack.** A pair with a failed
//! member passes on only the compressive pressures of its two particles (`physics::tension_cut`:
//! the tension and the deviator of the intact side are taken out of the pair's stress terms;
//! the cut is the pair's, the same from either side, so momentum is exact). So does a pair of
//! intact particles with a failed particle between them (`physics::CrackLists::severs`: within
//! ¾ of its spacing of the segment that joins them), so that a crack one particle wide cuts the
//! bodies on either side apart at once. Where the crack is open (its failed particle at no
//! pressure), the intact particles also leave the pair out of their continuity and their
//! velocity gradient: the crack's opening is not their own expansion or strain. Until
//! 2026-11-27 they read it as theirs, went into 2–4 GPa of tension beside the crack, flowed and
//! failed in turn, and a failed zone grew from every crack: every particle of the strip of
//! `examples/jc_failure_tension.toml` failed, where now two cracks of 16 particles cross it.
//! Where the failed particle is compressed, the rubble carries the load and deforms with its
//! neighbours, and the pair stays in their kinematics. This is the "failed neighbours meet only
//! in compression" choice, which needs no new contact sets and no change to the neighbour
//! search; a fragment of undamaged particles keeps its own cohesion. A failed particle keeps all
//! its pairs in its own continuity and velocity gradient: its density follows its neighbours
//! apart as well as together. (Dropping separating pairs altogether, as strike first did, let
//! the density ratchet up through every rebound, to 1.4 ρ0 and 65 GPa in fragments at rest,
//! and the pairs' switching made energy: +10 % in `examples/ogive_plate.toml`, 0.67 % then.)
//!
//! Three models, each optional per material (the first two are alternatives; either goes with
//! the third, whose deck table names the spall's constants: [`JOHNSON_COOK_WITH_SPALL`]):
//! - [`Spall`]: deterministic activation at the spall strength σ_s, then crack growth at the
//!   Grady–Kipp speed c_g = 0.4 c_L (Grady & Kipp 1980, Int. J. Rock Mech. 17, 147; as used in
//!   SPH by Benz & Asphaug 1994, Icarus 107, 98, eq. 11): while the largest principal stress
//!   of the particle exceeds σ_s, d(D^⅓)/dt = c_g/R_s with R_s half the particle's spacing. A
//!   crack crosses a particle in R_s/c_g = 1.25 Δp/c_L, so the spall plane opens in a few
//!   particle transit times and the tension it held falls to zero behind it.
//! - [`TulerButcher`] (Tuler & Butcher 1968, Int. J. Fract. Mech. 4, 431): a spall strength
//!   that depends on how fast the tension rises. D = (1/K_f) ∫ (σ1 − σ0)^λ dt over the time the
//!   largest principal stress σ1 exceeds the threshold σ0; the particle fails at D = 1 and
//!   keeps its whole strength until then (a fracture indicator, as LS-DYNA's
//!   `*MAT_ADD_EROSION` uses the criterion). Under tension rising at σ̇ from σ0 it fails at
//!   σ0 + ((λ + 1) σ̇ K_f)^(1/(λ+1)): the faster the load, the higher the stress it carries.
//!   Unlike [`Spall`], whose crack crosses a particle in a time proportional to its spacing,
//!   nothing in it depends on the lattice.
//! - [`JohnsonCookFailure`] (Johnson & Cook 1985, Eng. Fract. Mech. 21, 31, eq. 1):
//!   D += Δεp/ε_f, ε_f = (D1 + D2 exp(D3 σ*))(1 + D4 ln ε̇*)(1 + D5 T*), σ* = −p/σ_eq, ε̇*
//!   taken as 1 below the reference rate.

use super::params::{Param, ParamError, Parameters, Valid};

/// What the damage models read of a particle after its stress update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamageState {
    /// Largest principal stress of −p I + S with the EOS's undamaged pressure (tension > 0).
    /// Where every model is [`Damage::idle`] at Gershgorin's upper bound of it (with no plastic
    /// strain), that bound instead: no model's growth then depends on the value.
    pub sigma_1: f64,
    /// Undamaged pressure (Pa).
    pub p: f64,
    /// von Mises stress of the deviator (Pa).
    pub sigma_eq: f64,
    /// Plastic strain gained this step.
    pub d_eps_p: f64,
    /// Equivalent strain rate (1/s).
    pub rate: f64,
    /// Homologous temperature T* ∈ [0, 1] (from the strength model).
    pub t_star: f64,
    /// Longitudinal sound speed (m/s).
    pub c: f64,
    /// The particle's volume V (m³; m² in 2D).
    pub volume: f64,
    /// The number of dimensions D.
    pub dimension: usize,
}

impl DamageState {
    /// The particle's spacing V^(1/D) (m).
    pub fn size(&self) -> f64 {
        if self.dimension == 2 {
            self.volume.sqrt()
        } else {
            self.volume.cbrt()
        }
    }
}

/// A damage model: the damage after a step of dt from damage d.
pub trait Damage: Send + Sync + std::fmt::Debug {
    fn grow(&self, st: &DamageState, d: f64, dt: f64) -> f64;

    /// Whether [`Damage::grow`] surely leaves the damage as it is for a particle whose largest
    /// principal stress is at most `sigma_1_bound` and which gained `d_eps_p` of plastic strain:
    /// then the step need not build its [`DamageState`] (an eigenvalue, a cube root, the
    /// temperature), which most particles in an impact do not need at most steps.
    fn idle(&self, sigma_1_bound: f64, d_eps_p: f64) -> bool;

    /// Whether the particle carries only (1 − D) of its tension and yield stress before it
    /// fails (true), or all of them until D = 1, D being a fracture indicator (false).
    fn degrades(&self) -> bool;
}

/// Spall: see the module doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spall {
    /// σ_s (Pa): the tension at which cracks start to grow.
    pub strength: f64,
}

/// The crack speed as a fraction of the longitudinal sound speed (Grady & Kipp 1980).
pub const CRACK_SPEED: f64 = 0.4;

impl Spall {
    pub const PARAMS: &'static [Param] = &[Param::required(
        "spall_strength",
        "the spall strength σ_s in Pa, e.g. 1.2e9 for aluminium",
        Valid::Positive,
    )];
}

impl Damage for Spall {
    fn grow(&self, st: &DamageState, d: f64, dt: f64) -> f64 {
        if st.sigma_1 <= self.strength || d >= 1.0 {
            return d;
        }
        let r = d.cbrt() + CRACK_SPEED * st.c * dt / (0.5 * st.size());
        r.min(1.0).powi(3)
    }

    fn idle(&self, sigma_1_bound: f64, _d_eps_p: f64) -> bool {
        sigma_1_bound <= self.strength
    }

    fn degrades(&self) -> bool {
        true
    }
}

/// Tuler–Butcher's cumulative stress criterion: see the module doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TulerButcher {
    /// σ0 (Pa): the tension below which nothing accumulates.
    pub threshold: f64,
    /// λ: the exponent of the excess stress (1: an impulse; 2: an energy).
    pub exponent: f64,
    /// K_f (Pa^λ s): the integral at which the particle fails.
    pub impulse: f64,
}

impl Parameters for TulerButcher {
    const NAME: &'static str = "tuler_butcher";
    const PARAMS: &'static [Param] = &[
        Param::required(
            "threshold",
            "the threshold stress σ0 in Pa, e.g. 0.7e9",
            Valid::Positive,
        ),
        Param::optional(
            "exponent",
            "the exponent λ of the excess stress, e.g. 2",
            Valid::Closed(1.0, 10.0),
            2.0,
        ),
        Param::required(
            "impulse",
            "the damage integral K_f at failure in Pa^λ s, e.g. 1e9 for λ = 2",
            Valid::Positive,
        ),
    ];

    fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        Ok(TulerButcher {
            threshold: v[0],
            exponent: v[1],
            impulse: v[2],
        })
    }

    fn values(&self) -> Vec<f64> {
        vec![self.threshold, self.exponent, self.impulse]
    }
}

impl TulerButcher {
    /// The stress at which a particle fails under tension rising at `rate` (Pa/s) from σ0:
    /// σ0 + ((λ + 1) σ̇ K_f)^(1/(λ+1)), from ∫0^t (σ̇ s)^λ ds = K_f.
    pub fn failure_stress_at_rate(&self, rate: f64) -> f64 {
        let l1 = self.exponent + 1.0;
        self.threshold + (l1 * rate * self.impulse).powf(1.0 / l1)
    }
}

impl Damage for TulerButcher {
    fn grow(&self, st: &DamageState, d: f64, dt: f64) -> f64 {
        if st.sigma_1 <= self.threshold || d >= 1.0 {
            return d;
        }
        let excess = st.sigma_1 - self.threshold;
        (d + excess.powf(self.exponent) * dt / self.impulse).min(1.0)
    }

    fn idle(&self, sigma_1_bound: f64, _d_eps_p: f64) -> bool {
        sigma_1_bound <= self.threshold
    }

    fn degrades(&self) -> bool {
        false
    }
}

/// Johnson–Cook failure: see the module doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCookFailure {
    pub d: [f64; 5],
    pub reference_strain_rate: f64,
}

/// The smallest failure strain used: a floor for very high triaxiality where D1 + D2 e^(D3 σ*)
/// would fall to zero or below (as LS-DYNA's MAT_015 does with its own floor).
pub const MIN_FAILURE_STRAIN: f64 = 1e-3;

impl Parameters for JohnsonCookFailure {
    const NAME: &'static str = "johnson_cook";
    const PARAMS: &'static [Param] = &[
        Param::required("d1", "D1, e.g. 0.05", Valid::Any),
        Param::required("d2", "D2, e.g. 3.44", Valid::Any),
        Param::required("d3", "D3, e.g. -2.12", Valid::Any),
        Param::optional("d4", "D4 (strain rate), e.g. 0.002", Valid::Any, 0.0),
        Param::optional("d5", "D5 (temperature), e.g. 0.61", Valid::Any, 0.0),
        Param::optional(
            "reference_strain_rate",
            "reference strain rate ε̇0 in 1/s, e.g. 1.0",
            Valid::Positive,
            1.0,
        ),
    ];

    fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let f = JohnsonCookFailure {
            d: [v[0], v[1], v[2], v[3], v[4]],
            reference_strain_rate: v[5],
        };
        if f.d[0] + f.d[1] <= 0.0 {
            return Err(ParamError::new(
                "d1",
                format!(
                    "D1 + D2 = {} : the failure strain at zero triaxiality is not positive",
                    f.d[0] + f.d[1]
                ),
                "e.g. D1 = 0.05, D2 = 3.44 for 4340 steel",
            ));
        }
        Ok(f)
    }

    fn values(&self) -> Vec<f64> {
        let mut v = self.d.to_vec();
        v.push(self.reference_strain_rate);
        v
    }
}

/// Johnson–Cook failure's parameters and, last, an optional spall: a spall strength (the
/// [`Spall`] model), or Tuler–Butcher's criterion (its three constants prefixed
/// `tuler_butcher_`), or neither (0: none). A particle with both grows one indicator D by the
/// sum of their increments and fails at D = 1 (Miner's linear rule, as a plastic strain and a
/// tension pulse that each use up part of the material's ductility add up).
pub const JOHNSON_COOK_WITH_SPALL: &[Param] = &[
    JohnsonCookFailure::PARAMS[0],
    JohnsonCookFailure::PARAMS[1],
    JohnsonCookFailure::PARAMS[2],
    JohnsonCookFailure::PARAMS[3],
    JohnsonCookFailure::PARAMS[4],
    JohnsonCookFailure::PARAMS[5],
    Param::optional(
        "spall_strength",
        "the spall strength σ_s in Pa (0: none), e.g. 1.2e9",
        Valid::NonNegative,
        0.0,
    ),
    Param::optional(
        "tuler_butcher_threshold",
        "Tuler–Butcher's threshold σ0 in Pa, instead of a spall strength (0: none), e.g. 0.7e9",
        Valid::NonNegative,
        0.0,
    ),
    Param::optional(
        "tuler_butcher_exponent",
        "Tuler–Butcher's exponent λ of the excess stress, e.g. 2",
        Valid::Closed(1.0, 10.0),
        2.0,
    ),
    Param::optional(
        "tuler_butcher_impulse",
        "Tuler–Butcher's damage integral K_f at failure in Pa^λ s, e.g. 1e9 for λ = 2",
        Valid::NonNegative,
        0.0,
    ),
];

impl JohnsonCookFailure {
    /// ε_f at triaxiality σ* = −p/σ_eq, strain rate and T*.
    pub fn failure_strain(&self, triaxiality: f64, rate: f64, t_star: f64) -> f64 {
        let [d1, d2, d3, d4, d5] = self.d;
        let rate = (rate / self.reference_strain_rate).max(1.0);
        ((d1 + d2 * (d3 * triaxiality).exp()) * (1.0 + d4 * rate.ln()) * (1.0 + d5 * t_star))
            .max(MIN_FAILURE_STRAIN)
    }
}

impl Damage for JohnsonCookFailure {
    fn grow(&self, st: &DamageState, d: f64, _dt: f64) -> f64 {
        if st.d_eps_p <= 0.0 || st.sigma_eq <= 0.0 {
            return d;
        }
        let eps_f = self.failure_strain(-st.p / st.sigma_eq, st.rate, st.t_star);
        (d + st.d_eps_p / eps_f).min(1.0)
    }

    fn idle(&self, _sigma_1_bound: f64, d_eps_p: f64) -> bool {
        d_eps_p <= 0.0
    }

    fn degrades(&self) -> bool {
        false
    }
}

/// Scales a strength model's yield stress by the share `keep` of it that a damaged particle
/// carries ([`crate::material::Material::carried`]).
#[derive(Debug)]
pub struct Damaged<'a> {
    pub inner: &'a dyn super::Strength,
    pub keep: f64,
}

impl Damaged<'_> {
    /// keep · x, and 0 for a failed particle whatever x is (not computed).
    fn share(&self, x: impl FnOnce() -> f64) -> f64 {
        if self.keep <= 0.0 {
            0.0
        } else {
            self.keep * x()
        }
    }
}

impl super::Strength for Damaged<'_> {
    fn shear_modulus(&self, st: &super::StrengthState) -> f64 {
        self.inner.shear_modulus(st)
    }
    /// keep · Y, and 0 for a failed particle also where Y = ∞ (an elastic material).
    fn yield_stress(&self, st: &super::StrengthState) -> f64 {
        self.share(|| self.inner.yield_stress(st))
    }
    fn hardening_modulus(&self, st: &super::StrengthState) -> f64 {
        self.share(|| self.inner.hardening_modulus(st))
    }
    /// 1 for a failed particle (its yield is 0 whatever the factor: not computed).
    fn state_factor(&self, st: &super::StrengthState) -> f64 {
        if self.keep <= 0.0 {
            1.0
        } else {
            self.inner.state_factor(st)
        }
    }
    fn yield_floor(&self, st: &super::StrengthState) -> f64 {
        self.share(|| self.inner.yield_floor(st))
    }
    fn yield_and_slope_scaled(&self, st: &super::StrengthState, k: f64) -> (f64, f64) {
        if self.keep <= 0.0 {
            (0.0, 0.0)
        } else {
            let (y, slope) = self.inner.yield_and_slope_scaled(st, k);
            (self.keep * y, self.keep * slope)
        }
    }
    fn homologous_temperature(&self, st: &super::StrengthState) -> f64 {
        self.inner.homologous_temperature(st)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn state(sigma_1: f64) -> DamageState {
        DamageState {
            sigma_1,
            p: -sigma_1,
            sigma_eq: 0.0,
            d_eps_p: 0.0,
            rate: 0.0,
            t_star: 0.0,
            c: 5000.0,
            volume: 1e-12,
            dimension: 3,
        }
    }

    /// Below σ_s nothing; above it a crack crosses the particle's half spacing at 0.4 c.
    #[test]
    fn spall_grows_at_the_crack_speed() {
        let s = Spall { strength: 1e9 };
        assert_eq!(s.grow(&state(0.99e9), 0.0, 1e-9), 0.0);
        let crossing = 0.5 * 1e-4 / (0.4 * 5000.0);
        let half = s.grow(&state(1.5e9), 0.0, 0.5 * crossing);
        assert_relative_eq!(half, 0.125, max_relative = 1e-12);
        assert_eq!(s.grow(&state(1.5e9), half, 0.5 * crossing), 1.0);
        // Once grown it stays, also in compression.
        assert_eq!(s.grow(&state(-5e9), 0.3, 1e-6), 0.3);
    }

    /// A model that says it is idle leaves the damage as it is, whatever σ1 below the bound
    /// it was given; and each model is not idle where it acts (the shortcut can fire both ways).
    #[test]
    fn idle_models_grow_nothing() {
        let spall = Spall { strength: 1e9 };
        let jc = JohnsonCookFailure::from_pairs(&[("d1", 0.05), ("d2", 3.44), ("d3", -2.12)]);
        let tb = TulerButcher::from_pairs(&[("threshold", 1e9), ("impulse", 1e9)]);
        let models: [&dyn Damage; 3] = [&spall, &jc, &tb];
        for bound in [-2e9, 0.5e9, 1e9, 1.5e9] {
            for d_eps_p in [0.0, 0.01] {
                for model in models {
                    if !model.idle(bound, d_eps_p) {
                        continue;
                    }
                    for sigma_1 in [bound - 1e9, bound] {
                        let st = DamageState {
                            sigma_eq: 1e9,
                            d_eps_p,
                            ..state(sigma_1)
                        };
                        assert_eq!(model.grow(&st, 0.2, 1e-6), 0.2, "{model:?} at {bound}");
                    }
                }
            }
        }
        assert!(spall.idle(1e9, 1.0) && !spall.idle(1.01e9, 0.0));
        assert!(jc.idle(5e9, 0.0) && !jc.idle(-5e9, 1e-6));
        let st = DamageState {
            sigma_eq: 1e9,
            d_eps_p: 1e-3,
            ..state(0.0)
        };
        assert!(jc.grow(&st, 0.2, 1e-6) > 0.2);
        assert!(spall.grow(&state(1.01e9), 0.2, 1e-6) > 0.2);
        assert!(tb.grow(&state(1.01e9), 0.2, 1e-6) > 0.2);
    }

    /// Under a constant excess stress the integral reaches K_f at K_f/(σ − σ0)^λ; under tension
    /// rising at σ̇ it fails at σ0 + ((λ + 1) σ̇ K_f)^(1/(λ+1)), whatever the step (to the
    /// quadrature's first order), and eight times the rate doubles the excess for λ = 2.
    #[test]
    fn tuler_butcher_fails_at_its_rate_dependent_stress() {
        let tb = TulerButcher::from_pairs(&[("threshold", 0.7e9), ("impulse", 1e9)]);
        assert_eq!(tb.exponent, 2.0);
        assert_eq!(tb.grow(&state(0.7e9), 0.0, 1e-6), 0.0);
        // 0.3 GPa above σ0: K_f / (0.3e9)² = 11.1 ns.
        let t_f = 1e9 / (0.3e9f64).powi(2);
        let mut d = 0.0;
        for _ in 0..10 {
            d = tb.grow(&state(1.0e9), d, 0.1 * t_f);
        }
        assert_relative_eq!(d, 1.0, max_relative = 1e-12);
        assert_eq!(tb.grow(&state(1.0e9), d, 1e-9), 1.0);
        // Once grown it stays, also in compression.
        assert_eq!(tb.grow(&state(-5e9), 0.3, 1e-6), 0.3);
        for (rate, steps) in [(1e16, 4000), (8e16, 1000)] {
            let expected = tb.failure_stress_at_rate(rate);
            let dt = (expected - 0.7e9) / rate / steps as f64;
            let (mut d, mut t) = (0.0, 0.0);
            while d < 1.0 {
                t += dt;
                d = tb.grow(&state(0.7e9 + rate * t), d, dt);
            }
            assert_relative_eq!(0.7e9 + rate * t, expected, max_relative = 1e-3);
        }
        let excess = |rate| tb.failure_stress_at_rate(rate) - 0.7e9;
        assert_relative_eq!(excess(8e16) / excess(1e16), 2.0, max_relative = 1e-12);
        assert!(tb.idle(0.7e9, 1.0) && !tb.idle(0.71e9, 0.0));
        assert!(!tb.degrades());
    }

    #[test]
    fn johnson_cook_failure_strain() {
        // 4340 steel (Johnson & Cook 1985).
        let f = JohnsonCookFailure::from_pairs(&[
            ("d1", 0.05),
            ("d2", 3.44),
            ("d3", -2.12),
            ("d4", 0.002),
            ("d5", 0.61),
        ]);
        let by_hand = (0.05 + 3.44 * (-2.12f64 / 3.0).exp()) * (1.0 + 0.002 * 1e3f64.ln()) * 1.3;
        let eps_f = f.failure_strain(1.0 / 3.0, 1e3, 0.3 / 0.61);
        assert_relative_eq!(eps_f, by_hand, max_relative = 1e-12);
        // Uniaxial tension (σ* = 1/3): D reaches 1 at ε_f.
        let st = DamageState {
            sigma_1: 1e9,
            p: -1e9 / 3.0,
            sigma_eq: 1e9,
            d_eps_p: 0.25 * eps_f,
            rate: 1e3,
            t_star: 0.3 / 0.61,
            c: 5000.0,
            volume: 1e-12,
            dimension: 3,
        };
        let mut d = 0.0;
        for _ in 0..4 {
            d = f.grow(&st, d, 1e-9);
        }
        assert_relative_eq!(d, 1.0, max_relative = 1e-12);
    }
}
