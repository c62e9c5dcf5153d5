//! Reading `[materials.NAME]`: density, the EOS, the strength and damage models, options. Each
//! model's keys, defaults, valid ranges and cross-checks are the model's own
//! (`material::params`); this file only matches a table against them and turns what is wrong
//! into an error at the key.

use std::ops::Range;

use super::raw::{self, Entry, S};
use super::{did_you_mean, leaf, list, Ctx};
use crate::case::{DamageSpec, EosSpec, MaterialSpec, StrengthSpec};
use crate::error::Result;
use crate::material::params::{Param, ParamError};
use crate::material::{params_of, DAMAGE_MODELS, ELASTIC_CONSTANTS, EOS_MODELS, STRENGTH_MODELS};

use super::library::{library_material, library_names};

/// A model family: how errors name it, its models, an example table.
struct Family {
    what: &'static str,
    models: &'static [(&'static str, &'static [Param])],
    example: &'static str,
}

const STRENGTH: Family = Family {
    what: "strength model",
    models: &STRENGTH_MODELS,
    example: "e.g. `strength = { type = \"von_mises\", shear_modulus = 26e9, yield_stress = 0.3e9 }` or `{ type = \"hydrodynamic\" }`",
};

const EOS: Family = Family {
    what: "EOS",
    models: &EOS_MODELS,
    example: "e.g. `eos = { type = \"mie_gruneisen\", c0 = 5328.0, s1 = 1.338, gamma0 = 2.0 }` or `{ type = \"linear\", bulk_modulus = 76e9 }`",
};

const DAMAGE: Family = Family {
    what: "damage model",
    models: &DAMAGE_MODELS,
    example:
        "e.g. `damage = { type = \"spall\", spall_strength = 1.2e9 }` or `{ type = \"none\" }`",
};

/// What [`Ctx::model`] read.
struct Read {
    kind: &'static str,
    values: Vec<f64>,
    /// Where errors about the model as a whole point (its `type`, or the material).
    at: Range<usize>,
}

impl Ctx<'_> {
    pub(super) fn material(&self, key: &S<String>, m: &raw::Material) -> Result<MaterialSpec> {
        let prefix = format!("materials.{}", super::key_seg(key.get_ref()));
        let anchor = key.span();
        let base = match &m.library {
            Some(lib) => Some(library_material(lib.get_ref()).ok_or_else(|| {
                self.fail(
                    lib.span(),
                    format!("{prefix}.library"),
                    format!("unknown library material `{}`", lib.get_ref()),
                    format!(
                        "{}the library materials are {}",
                        did_you_mean(lib.get_ref(), library_names().iter().copied()),
                        list(library_names())
                    ),
                )
            })?),
            None => None,
        };
        let density = match (&m.density, &base) {
            (Some(d), _) => self.positive(
                d,
                &format!("{prefix}.density"),
                "a density in kg/m³, e.g. 2700 for aluminium",
            )?,
            (None, Some(b)) => b.density,
            (None, None) => {
                return Err(self.missing(
                    &anchor,
                    &format!("{prefix}.density"),
                    "the reference density (kg/m³)",
                    "add e.g. `density = 2700.0`, or `library = \"al_2024_t4\"` to start from a library material",
                ))
            }
        };
        let (strength, elastic) = self.strength(
            m.strength.as_ref(),
            &format!("{prefix}.strength"),
            base.as_ref().map(|b| &b.strength),
            &anchor,
        )?;
        let eos = self.eos(
            m.eos.as_ref(),
            &format!("{prefix}.eos"),
            base.as_ref().map(|b| &b.eos),
            density,
            elastic,
            &anchor,
        )?;
        let damage = self.damage(
            m.damage.as_ref(),
            &format!("{prefix}.damage"),
            base.as_ref().map(|b| &b.damage),
            &anchor,
        )?;
        let pressure_cutoff = match &m.pressure_cutoff {
            Some(p) => Some(self.check(
                p,
                &format!("{prefix}.pressure_cutoff"),
                |x| x <= 0.0,
                "must be zero or negative",
                "the most tensile pressure allowed (spall), in Pa, e.g. -1.0e9",
            )?),
            None => base.as_ref().and_then(|b| b.pressure_cutoff),
        };
        let artificial_stress = match &m.artificial_stress {
            Some(a) => Some(self.check(
                a,
                &format!("{prefix}.artificial_stress"),
                |x| x > 0.0 && x <= 1.0,
                "must be in (0, 1]",
                "Monaghan's ε, usually 0.3; leave it out to switch artificial stress off",
            )?),
            None => base.as_ref().and_then(|b| b.artificial_stress),
        };
        Ok(MaterialSpec {
            name: key.get_ref().clone(),
            location: self.location(&anchor),
            density,
            eos,
            strength,
            pressure_cutoff,
            artificial_stress,
            damage,
        })
    }

    /// The strength model, and (E, ν) where the deck gave them.
    fn strength(
        &self,
        raw: Option<&raw::ModelTable>,
        prefix: &str,
        base: Option<&StrengthSpec>,
        anchor: &Range<usize>,
    ) -> Result<(StrengthSpec, Option<(f64, f64)>)> {
        let elastic = match raw {
            Some(r) => self.elastic_constants(r, prefix)?,
            None => None,
        };
        let shear = elastic.map(|(e, nu)| e / (2.0 * (1.0 + nu)));
        let Some(read) = self.model(
            raw,
            prefix,
            &STRENGTH,
            base.map(|b| (b.kind(), b.values())),
            &|kind| {
                if params_of(&STRENGTH_MODELS, kind)
                    .iter()
                    .any(|p| p.key == "shear_modulus")
                {
                    &ELASTIC_CONSTANTS
                } else {
                    &[]
                }
            },
            &|key| (key == "shear_modulus").then_some(shear).flatten(),
            &|key| {
                if key == "shear_modulus" {
                    " (or `youngs_modulus` and `poissons_ratio`)"
                } else {
                    ""
                }
            },
            anchor,
        )?
        else {
            unreachable!("a strength model is required")
        };
        if let (Some(r), Some(_)) = (raw, shear) {
            if let Some((k, _)) = r.get("shear_modulus") {
                return Err(self.fail(
                    k.span(),
                    format!("{prefix}.shear_modulus"),
                    "shear_modulus is given together with youngs_modulus and poissons_ratio",
                    "give either shear_modulus, or youngs_modulus and poissons_ratio, not both",
                ));
            }
        }
        let spec = StrengthSpec::from_values(read.kind, &read.values)
            .map_err(|e| self.param_error(raw, prefix, e, &read.at))?;
        let elastic = if read.kind == "hydrodynamic" {
            None
        } else {
            elastic
        };
        Ok((spec, elastic))
    }

    /// Young's modulus and Poisson's ratio, where both are given (one alone is an error).
    fn elastic_constants(&self, r: &raw::ModelTable, prefix: &str) -> Result<Option<(f64, f64)>> {
        let (e, nu) = (r.get("youngs_modulus"), r.get("poissons_ratio"));
        match (e, nu) {
            (Some((_, e)), Some((_, nu))) => {
                let e = self.number(e, &format!("{prefix}.youngs_modulus"))?;
                let nu = self.number(nu, &format!("{prefix}.poissons_ratio"))?;
                let e = self.positive(
                    &e,
                    &format!("{prefix}.youngs_modulus"),
                    "Young's modulus in Pa, e.g. 68.9e9 for aluminium",
                )?;
                let nu = self.check(
                    &nu,
                    &format!("{prefix}.poissons_ratio"),
                    |x| x > -1.0 && x < 0.5,
                    "must be in (-1, 0.5)",
                    "Poisson's ratio of a solid, e.g. 0.33 for aluminium",
                )?;
                Ok(Some((e, nu)))
            }
            (Some((k, _)), None) => Err(self.fail(
                k.span(),
                format!("{prefix}.poissons_ratio"),
                "youngs_modulus is given without poissons_ratio",
                "add `poissons_ratio` (e.g. 0.33), or give shear_modulus instead",
            )),
            (None, Some((k, _))) => Err(self.fail(
                k.span(),
                format!("{prefix}.youngs_modulus"),
                "poissons_ratio is given without youngs_modulus",
                "add `youngs_modulus` (Pa, e.g. 68.9e9), or give shear_modulus instead",
            )),
            (None, None) => Ok(None),
        }
    }

    fn eos(
        &self,
        raw: Option<&raw::ModelTable>,
        prefix: &str,
        base: Option<&EosSpec>,
        density: f64,
        elastic: Option<(f64, f64)>,
        anchor: &Range<usize>,
    ) -> Result<EosSpec> {
        let bulk = elastic.map(|(e, nu)| e / (3.0 * (1.0 - 2.0 * nu)));
        let Some(read) = self.model(
            raw,
            prefix,
            &EOS,
            base.map(|b| (b.kind(), b.values())),
            &|_| &[],
            &|key| (key == "bulk_modulus").then_some(bulk).flatten(),
            &|key| {
                if key == "bulk_modulus" {
                    " (or youngs_modulus and poissons_ratio in the elastic or von_mises strength table)"
                } else {
                    ""
                }
            },
            anchor,
        )?
        else {
            unreachable!("an EOS is required")
        };
        EosSpec::from_values(read.kind, density, &read.values)
            .map_err(|e| self.param_error(raw, prefix, e, &read.at))
    }

    /// The damage models: the deck's table, else the library material's, else none.
    fn damage(
        &self,
        raw: Option<&raw::ModelTable>,
        prefix: &str,
        base: Option<&DamageSpec>,
        anchor: &Range<usize>,
    ) -> Result<DamageSpec> {
        if raw.is_none() {
            return Ok(base.cloned().unwrap_or_default());
        }
        let Some(read) = self.model(
            raw,
            prefix,
            &DAMAGE,
            base.map(|b| (b.kind(), b.values())),
            &|_| &[],
            &|_| None,
            &|_| "",
            anchor,
        )?
        else {
            return Ok(DamageSpec::default());
        };
        DamageSpec::from_values(read.kind, &read.values)
            .map_err(|e| self.param_error(raw, prefix, e, &read.at))
    }

    /// A numeric entry of a model's table.
    fn number(&self, v: &S<Entry>, key: &str) -> Result<S<f64>> {
        match v.get_ref() {
            Entry::Number(x) => Ok(S::new(v.span(), *x)),
            other => Err(self.fail(
                v.span(),
                key,
                format!(
                    "wrong type: expected a number, found {}",
                    match other {
                        Entry::Text(t) => format!("string \"{t}\""),
                        _ => "another kind of value".to_string(),
                    }
                ),
                "write a number without quotes, e.g. 2.0e9",
            )),
        }
    }

    /// A model's table read against its family (see the module doc). The `type` is the
    /// table's, else the base's (a library material's); a key must be the model's or one of
    /// `extra(kind)` (read by the caller); a missing value is `derived(key)`, else the base's
    /// where the base is the same model, else the parameter's default, else an error (whose
    /// help adds `alternative(key)`). None where there is neither a table nor a base.
    #[allow(clippy::too_many_arguments)]
    fn model(
        &self,
        raw: Option<&raw::ModelTable>,
        prefix: &str,
        family: &Family,
        base: Option<(&'static str, Vec<f64>)>,
        extra: &dyn Fn(&str) -> &'static [&'static str],
        derived: &dyn Fn(&str) -> Option<f64>,
        alternative: &dyn Fn(&str) -> &'static str,
        anchor: &Range<usize>,
    ) -> Result<Option<Read>> {
        let kinds: Vec<&'static str> = family.models.iter().map(|(k, _)| *k).collect();
        let Some(r) = raw else {
            return match base {
                Some((kind, values)) => Ok(Some(Read {
                    kind,
                    values,
                    at: anchor.clone(),
                })),
                None => Err(self.missing(
                    anchor,
                    prefix,
                    &format!("the material's {} ({})", family.what, kinds.join(", ")),
                    &format!("add {}", family.example),
                )),
            };
        };
        let kind: &'static str = match &r.kind {
            Some(k) => self.choice(
                k,
                &format!("{prefix}.type"),
                &kinds,
                &format!("{} type", family.what),
            )?,
            None => match &base {
                Some((k, _)) => k,
                None => {
                    let at = r.values.first().map_or(anchor.clone(), |(k, _)| k.span());
                    return Err(self.missing(
                        &at,
                        &format!("{prefix}.type"),
                        &format!("which {}", family.what),
                        &format!(
                            "add `type = …`, one of {}; {}",
                            list(&kinds),
                            family.example
                        ),
                    ));
                }
            },
        };
        let at = r.kind.as_ref().map_or(anchor.clone(), |k| k.span());
        let params = params_of(family.models, kind);
        let extra = extra(kind);
        // Every key must be the model's.
        for (k, _) in &r.values {
            let name = k.get_ref().as_str();
            if !params.iter().any(|p| p.key == name) && !extra.contains(&name) {
                let mut keys: Vec<&str> = vec!["type"];
                keys.extend(params.iter().map(|p| p.key));
                keys.extend(extra.iter().copied());
                let what = format!("a {kind} {}", family.what);
                return Err(self.fail(
                    k.span(),
                    format!("{prefix}.{name}"),
                    format!("`{name}` is not a key of {what}"),
                    format!(
                        "{}{what} takes {}",
                        did_you_mean(name, keys.iter().copied()),
                        list(&keys)
                    ),
                ));
            }
        }
        let same_base = base.filter(|(k, _)| *k == kind).map(|(_, v)| v);
        let mut values = Vec::with_capacity(params.len());
        for (i, p) in params.iter().enumerate() {
            let key = format!("{prefix}.{}", p.key);
            let value = match r.get(p.key) {
                Some((_, v)) => {
                    let v = self.number(v, &key)?;
                    self.check(
                        &v,
                        &key,
                        |x| p.valid.accepts(x),
                        &p.valid.requirement(),
                        p.what,
                    )?
                }
                None => match (derived(p.key), &same_base, p.default) {
                    (Some(x), _, _) => x,
                    (None, Some(b), _) => b[i],
                    (None, None, Some(d)) => d,
                    (None, None, None) => {
                        return Err(self.missing(
                            &at,
                            &key,
                            &format!("{} of the {kind} {}", p.what, family.what),
                            &format!("add `{} = …`{}", p.key, alternative(p.key)),
                        ))
                    }
                },
            };
            values.push(value);
        }
        Ok(Some(Read { kind, values, at }))
    }

    /// A model's cross-check, as an error at the key it names (or the model's `type`).
    fn param_error(
        &self,
        raw: Option<&raw::ModelTable>,
        prefix: &str,
        e: ParamError,
        at: &Range<usize>,
    ) -> crate::error::Error {
        let span = raw
            .and_then(|r| r.get(e.key))
            .map_or(at.clone(), |(_, v)| v.span());
        let key = format!("{prefix}.{}", e.key);
        self.fail(
            span,
            key.clone(),
            format!("{}: {}", leaf(&key), e.message),
            e.help,
        )
    }
}
