//! Materials: an equation of state and a strength model behind traits, so that Tillotson,
//! Johnson–Cook and others can be added without touching the solver. The paper's material is
//! the "elastic-plastic hydrodynamic" model with a Mie–Grüneisen EOS (LS-DYNA MAT_010 +
//! EOS_GRUNEISEN).

pub mod damage;
pub mod eos;
pub mod johnson_cook;
pub mod params;
pub mod steinberg_guinan;
pub mod strength;
pub mod tillotson;

use crate::case::{EosSpec, MaterialSpec, StrengthSpec};
pub use damage::{Damage, DamageState, Damaged, JohnsonCookFailure, Spall, TulerButcher};
pub use eos::{Eos, LinearEos, MieGruneisen};
pub use johnson_cook::JohnsonCook;
use params::{Param, ParamError, Parameters};
pub use steinberg_guinan::SteinbergGuinan;
pub use strength::{radial_return, Strength, StrengthState, VonMises};
pub use tillotson::Tillotson;

/// A material as the solver sees it.
#[derive(Debug)]
pub struct Material {
    pub name: String,
    /// Reference density ρ0 (kg/m³).
    pub rho0: f64,
    pub eos: Box<dyn Eos>,
    pub strength: Box<dyn Strength>,
    /// Pressure cut-off p_min (Pa): p = max(p, p_min); −∞ when off.
    pub p_min: f64,
    /// Artificial stress ε (Monaghan 2000), None when off.
    pub artificial_stress: Option<f64>,
    /// Damage models, applied in this order (empty: never fails).
    pub damage: Vec<Box<dyn Damage>>,
    /// Whether damage below 1 weakens the particle: every damage model [`Damage::degrades`]
    /// (see `damage`'s module doc).
    pub damage_degrades: bool,
    /// Whether the material flows plastically (a shear modulus and a finite yield stress): its
    /// particles' h follows their stretch (`integrate::smoothing_length`).
    pub flows: bool,
}

impl Material {
    /// Build from a validated spec.
    pub fn from_spec(spec: &MaterialSpec) -> Self {
        let rho0 = spec.density;
        let eos: Box<dyn Eos> = match spec.eos {
            EosSpec::Linear { bulk_modulus } => Box::new(LinearEos { rho0, bulk_modulus }),
            EosSpec::MieGruneisen {
                c0,
                s1,
                s2,
                s3,
                gamma0,
                a,
            } => Box::new(MieGruneisen {
                rho0,
                c0,
                s1,
                s2,
                s3,
                gamma0,
                a,
            }),
            EosSpec::Tillotson(t) => Box::new(Tillotson { rho0, ..t }),
        };
        let strength: Box<dyn Strength> = match spec.strength {
            StrengthSpec::Hydrodynamic => Box::new(VonMises {
                shear_modulus: 0.0,
                yield_stress: 0.0,
                hardening_modulus: 0.0,
            }),
            StrengthSpec::Elastic { shear_modulus } => Box::new(VonMises {
                shear_modulus,
                yield_stress: f64::INFINITY,
                hardening_modulus: 0.0,
            }),
            StrengthSpec::VonMises {
                shear_modulus,
                yield_stress,
                hardening_modulus,
            } => Box::new(VonMises {
                shear_modulus,
                yield_stress,
                hardening_modulus,
            }),
            StrengthSpec::JohnsonCook(jc) => Box::new(jc),
            StrengthSpec::SteinbergGuinan(sg) => Box::new(sg),
        };
        let mut damage: Vec<Box<dyn Damage>> = Vec::new();
        if let Some(s) = spec.damage.spall {
            damage.push(Box::new(s));
        }
        if let Some(t) = spec.damage.tuler_butcher {
            damage.push(Box::new(t));
        }
        if let Some(f) = spec.damage.johnson_cook {
            damage.push(Box::new(f));
        }
        let damage_degrades = !damage.is_empty() && damage.iter().all(|m| m.degrades());
        let flows = strength.reference_shear_modulus() > 0.0
            && strength.reference_yield_stress().is_finite();
        Material {
            name: spec.name.clone(),
            rho0,
            eos,
            flows,
            strength,
            p_min: spec.pressure_cutoff.unwrap_or(f64::NEG_INFINITY),
            artificial_stress: spec.artificial_stress,
            damage,
            damage_degrades,
        }
    }

    /// Pressure with the cut-off applied.
    pub fn pressure(&self, rho: f64, e: f64) -> f64 {
        self.eos.pressure(rho, e).max(self.p_min)
    }

    /// The share of its tension and yield stress that a particle with damage D carries: 0 once
    /// failed (D ≥ 1); before, 1 − D where the damage degrades the material (spall) and 1 where
    /// it is a fracture indicator (Johnson–Cook; see `damage`'s module doc).
    pub fn carried(&self, d: f64) -> f64 {
        if d >= 1.0 {
            0.0
        } else if self.damage_degrades {
            1.0 - d
        } else {
            1.0
        }
    }

    /// Pressure carried with damage D, from the EOS's pressure p_eos: the cut-off, and the
    /// [`Material::carried`] share of any tension.
    pub fn damaged_pressure(&self, p_eos: f64, d: f64) -> f64 {
        let p = p_eos.max(self.p_min);
        if p < 0.0 {
            p * self.carried(d)
        } else {
            p
        }
    }

    /// The strength model's state at (ρ, e) with plastic strain εp, plastic work w_p, strain
    /// rate and pressure p.
    pub fn strength_state(
        &self,
        rho: f64,
        e: f64,
        (eps_p, w_p): (f64, f64),
        rate: f64,
        p: f64,
    ) -> StrengthState {
        StrengthState {
            eps_p,
            rate,
            e,
            w_p,
            eta: rho / self.rho0,
            p,
        }
    }

    /// Sound speed c = √((K_s + 4G/3)/ρ), the longitudinal wave speed used for the time step and
    /// the viscosity, with G at the state (it grows with pressure in Steinberg–Guinan). K_s is
    /// floored at 1 % of its reference value so that a particle in deep tension (or a
    /// Tillotson vapour) still has a finite signal speed.
    pub fn sound_speed(&self, rho: f64, e: f64) -> f64 {
        self.sound_speed_at(rho, e, self.eos.pressure(rho, e))
    }

    /// [`Material::sound_speed`] where the EOS's pressure p at (ρ, e) is known already.
    pub fn sound_speed_at(&self, rho: f64, e: f64, p: f64) -> f64 {
        let k0 = self.eos.bulk_modulus(self.rho0, 0.0);
        let ks = self.eos.bulk_modulus(rho, e).max(0.01 * k0);
        let g = self.strength.reference_shear_modulus();
        let g = if g > 0.0 {
            self.strength
                .shear_modulus(&self.strength_state(rho, e, (0.0, 0.0), 0.0, p))
        } else {
            0.0
        };
        ((ks + 4.0 / 3.0 * g) / rho).sqrt()
    }

    /// Reference bulk modulus K0 = ρ0 c0².
    pub fn bulk_modulus0(&self) -> f64 {
        self.eos.bulk_modulus(self.rho0, 0.0)
    }

    /// Reference longitudinal sound speed.
    pub fn sound_speed0(&self) -> f64 {
        self.sound_speed(self.rho0, 0.0)
    }
}

/// The keys of the strength models that have a shear modulus can also be given as Young's
/// modulus and Poisson's ratio (the deck derives G, and K for a linear EOS).
pub const ELASTIC_CONSTANTS: [&str; 2] = ["youngs_modulus", "poissons_ratio"];

/// The strength models a deck can name (`type`), each with its parameters.
pub const STRENGTH_MODELS: [(&str, &[Param]); 5] = [
    ("hydrodynamic", &[]),
    ("elastic", strength::ELASTIC_PARAMS),
    ("von_mises", VonMises::PARAMS),
    (JohnsonCook::NAME, JohnsonCook::PARAMS),
    (SteinbergGuinan::NAME, SteinbergGuinan::PARAMS),
];

/// The equations of state a deck can name, each with its parameters (ρ0 is the material's).
pub const EOS_MODELS: [(&str, &[Param]); 3] = [
    ("linear", LinearEos::PARAMS),
    ("mie_gruneisen", MieGruneisen::PARAMS),
    ("tillotson", Tillotson::PARAMS),
];

/// The damage choices a deck can name: none, spall alone, Tuler–Butcher's rate-dependent spall
/// alone, or Johnson–Cook failure with an optional spall: a spall strength or Tuler–Butcher's
/// criterion (0: none).
pub const DAMAGE_MODELS: [(&str, &[Param]); 4] = [
    ("none", &[]),
    ("spall", Spall::PARAMS),
    (TulerButcher::NAME, TulerButcher::PARAMS),
    ("johnson_cook", damage::JOHNSON_COOK_WITH_SPALL),
];

/// The parameters of model `kind` in `models`.
pub fn params_of(models: &[(&'static str, &'static [Param])], kind: &str) -> &'static [Param] {
    models
        .iter()
        .find(|(k, _)| *k == kind)
        .map_or(&[], |(_, p)| p)
}

impl StrengthSpec {
    /// Its `type` in a deck.
    pub fn kind(&self) -> &'static str {
        match self {
            StrengthSpec::Hydrodynamic => "hydrodynamic",
            StrengthSpec::Elastic { .. } => "elastic",
            StrengthSpec::VonMises { .. } => "von_mises",
            StrengthSpec::JohnsonCook(_) => JohnsonCook::NAME,
            StrengthSpec::SteinbergGuinan(_) => SteinbergGuinan::NAME,
        }
    }

    /// Its parameter values, in the order of its model's list.
    pub fn values(&self) -> Vec<f64> {
        match self {
            StrengthSpec::Hydrodynamic => vec![],
            StrengthSpec::Elastic { shear_modulus } => vec![*shear_modulus],
            StrengthSpec::VonMises {
                shear_modulus,
                yield_stress,
                hardening_modulus,
            } => vec![*shear_modulus, *yield_stress, *hardening_modulus],
            StrengthSpec::JohnsonCook(m) => m.values(),
            StrengthSpec::SteinbergGuinan(m) => m.values(),
        }
    }

    /// Model `kind` from its parameter values (each already valid by itself).
    pub fn from_values(kind: &str, v: &[f64]) -> Result<Self, ParamError> {
        Ok(match kind {
            "hydrodynamic" => StrengthSpec::Hydrodynamic,
            "elastic" => StrengthSpec::Elastic {
                shear_modulus: v[0],
            },
            "von_mises" => StrengthSpec::VonMises {
                shear_modulus: v[0],
                yield_stress: v[1],
                hardening_modulus: v[2],
            },
            "johnson_cook" => StrengthSpec::JohnsonCook(JohnsonCook::from_values(v)?),
            _ => StrengthSpec::SteinbergGuinan(SteinbergGuinan::from_values(v)?),
        })
    }

    /// Reference shear modulus (0 for a fluid).
    pub fn shear_modulus(&self) -> f64 {
        self.values().first().copied().unwrap_or(0.0)
    }
}

impl EosSpec {
    pub fn kind(&self) -> &'static str {
        match self {
            EosSpec::Linear { .. } => "linear",
            EosSpec::MieGruneisen { .. } => "mie_gruneisen",
            EosSpec::Tillotson(_) => "tillotson",
        }
    }

    pub fn values(&self) -> Vec<f64> {
        match self {
            EosSpec::Linear { bulk_modulus } => vec![*bulk_modulus],
            EosSpec::MieGruneisen {
                c0,
                s1,
                s2,
                s3,
                gamma0,
                a,
            } => vec![*c0, *s1, *s2, *s3, *gamma0, *a],
            EosSpec::Tillotson(t) => t.values(),
        }
    }

    /// Model `kind` from ρ0 and its parameter values.
    pub fn from_values(kind: &str, rho0: f64, v: &[f64]) -> Result<Self, ParamError> {
        Ok(match kind {
            "linear" => EosSpec::Linear { bulk_modulus: v[0] },
            "mie_gruneisen" => EosSpec::MieGruneisen {
                c0: v[0],
                s1: v[1],
                s2: v[2],
                s3: v[3],
                gamma0: v[4],
                a: v[5],
            },
            _ => EosSpec::Tillotson(Tillotson::from_values(rho0, v)?),
        })
    }

    /// Reference bulk modulus K0 = ρ0 (∂p/∂ρ) at ρ0, e = 0.
    pub fn bulk_modulus(&self, rho0: f64) -> f64 {
        match self {
            EosSpec::Linear { bulk_modulus } => *bulk_modulus,
            EosSpec::MieGruneisen { c0, .. } => rho0 * c0 * c0,
            EosSpec::Tillotson(t) => t.big_a,
        }
    }
}

impl crate::case::DamageSpec {
    pub fn kind(&self) -> &'static str {
        match (self.spall, self.johnson_cook) {
            (_, Some(_)) => "johnson_cook",
            (Some(_), None) => "spall",
            (None, None) if self.tuler_butcher.is_some() => TulerButcher::NAME,
            (None, None) => "none",
        }
    }

    pub fn values(&self) -> Vec<f64> {
        let spall = self.spall.map_or(0.0, |s| s.strength);
        match (self.johnson_cook, self.tuler_butcher) {
            (Some(f), tb) => {
                let mut v = f.values();
                v.push(spall);
                // Tuler–Butcher's constants; none is the table's defaults (a threshold of 0).
                match tb {
                    Some(t) => v.extend(t.values()),
                    None => v.extend(
                        damage::JOHNSON_COOK_WITH_SPALL[v.len()..]
                            .iter()
                            .map(|p| p.default.unwrap_or(0.0)),
                    ),
                }
                v
            }
            (None, Some(t)) => t.values(),
            (None, None) if self.spall.is_some() => vec![spall],
            (None, None) => vec![],
        }
    }

    pub fn from_values(kind: &str, v: &[f64]) -> Result<Self, ParamError> {
        Ok(match kind {
            "none" => Self::default(),
            "spall" => Self {
                spall: Some(Spall { strength: v[0] }),
                ..Self::default()
            },
            TulerButcher::NAME => Self {
                tuler_butcher: Some(TulerButcher::from_values(v)?),
                ..Self::default()
            },
            _ => {
                // JOHNSON_COOK_WITH_SPALL: D1–D5 and the rate, the spall strength, then
                // Tuler–Butcher's threshold, exponent and impulse.
                let n = JohnsonCookFailure::PARAMS.len();
                let (strength, tb) = (v[n], &v[n + 1..n + 4]);
                let (threshold, impulse) = (tb[0], tb[2]);
                if strength > 0.0 && threshold > 0.0 {
                    return Err(ParamError::new(
                        "tuler_butcher_threshold",
                        "a spall strength and Tuler–Butcher's criterion are two spall models \
                         for one material",
                        "give either `spall_strength` or the `tuler_butcher_` constants, \
                         and set the other to 0",
                    ));
                }
                if (threshold > 0.0) != (impulse > 0.0) {
                    let (key, missing) = if threshold > 0.0 {
                        ("tuler_butcher_impulse", "its damage integral K_f")
                    } else {
                        ("tuler_butcher_threshold", "its threshold σ0")
                    };
                    return Err(ParamError::new(
                        key,
                        format!("Tuler–Butcher's criterion is missing {missing}"),
                        "give both `tuler_butcher_threshold` and `tuler_butcher_impulse` \
                         (positive), or neither",
                    ));
                }
                Self {
                    spall: (strength > 0.0).then_some(Spall { strength }),
                    johnson_cook: Some(JohnsonCookFailure::from_values(&v[..n])?),
                    tuler_butcher: if threshold > 0.0 {
                        Some(TulerButcher::from_values(tb)?)
                    } else {
                        None
                    },
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deck::library::library_material;

    /// Spall damage weakens a particle as it grows; Johnson–Cook's is a fracture indicator
    /// that takes nothing off until D = 1, alone or beside the spall criterion.
    #[test]
    fn what_a_damaged_particle_carries() {
        let spall_only = Material::from_spec(&library_material("al_6061_t6").unwrap());
        let with_jc = Material::from_spec(&library_material("al_2024_t3").unwrap());
        assert_eq!(spall_only.damage.len(), 1);
        assert_eq!(with_jc.damage.len(), 2);
        for d in [0.0, 0.3, 0.99] {
            assert_eq!(spall_only.carried(d), 1.0 - d);
            assert_eq!(spall_only.damaged_pressure(-1e9, d), -1e9 * (1.0 - d));
            assert_eq!(with_jc.carried(d), 1.0);
            assert_eq!(with_jc.damaged_pressure(-1e9, d), -1e9);
        }
        for m in [&spall_only, &with_jc] {
            assert_eq!(m.carried(1.0), 0.0);
            assert_eq!(m.damaged_pressure(-1e9, 1.0), 0.0);
            assert_eq!(m.damaged_pressure(2e9, 1.0), 2e9);
        }
    }
}
