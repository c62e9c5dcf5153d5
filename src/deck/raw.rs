//! The deck as written: serde structs mirroring the TOML, every value that gets validated kept
//! with its byte span. Nothing here is checked beyond TOML syntax, types and key names; `super`
//! turns these into a [`crate::case::Case`].

use std::ops::Range;

use serde::de::{Deserialize, Deserializer, Error as _, IntoDeserializer, MapAccess, Visitor};
use toml::Spanned;

pub type S<T> = Spanned<T>;
pub type Num = Option<S<f64>>;

/// A TOML table read as a list of entries in document order (serde maps lose it otherwise).
#[derive(Debug)]
pub struct Ordered<K, V>(pub Vec<(K, V)>);

impl<'de, K: Deserialize<'de>, V: Deserialize<'de>> Deserialize<'de> for Ordered<K, V> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V_<K, V>(std::marker::PhantomData<(K, V)>);
        impl<'de, K: Deserialize<'de>, V: Deserialize<'de>> Visitor<'de> for V_<K, V> {
            type Value = Ordered<K, V>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = map.next_entry()? {
                    out.push((k, v));
                }
                Ok(Ordered(out))
            }
        }
        deserializer.deserialize_map(V_(std::marker::PhantomData))
    }
}

/// A table with the span of its header (or of its inline `{ … }`) where it has one. Unlike
/// `toml::Spanned`, it also reads tables that have no span of their own (an implicit `[output]`
/// made by `[[output.picture]]`, a table made by dotted keys), with `span` None.
#[derive(Debug)]
pub struct Located<T> {
    pub span: Option<Range<usize>>,
    pub value: T,
}

impl<T> Located<T> {
    /// The span, or the start of the file where there is none.
    pub fn anchor(&self) -> Range<usize> {
        self.span.clone().unwrap_or(0..0)
    }

    pub fn get_ref(&self) -> &T {
        &self.value
    }
}

// The names by which `toml` recognises a request for a span (serde_spanned's protocol).
const SPANNED_NAME: &str = "$__serde_spanned_private_Spanned";
const SPANNED_START: &str = "$__serde_spanned_private_start";
const SPANNED_END: &str = "$__serde_spanned_private_end";
const SPANNED_VALUE: &str = "$__serde_spanned_private_value";

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Located<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V_<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V_<T> {
            type Value = Located<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let Some(first) = map.next_key::<String>()? else {
                    let empty = serde::de::value::MapDeserializer::<
                        std::iter::Empty<(String, String)>,
                        A::Error,
                    >::new(std::iter::empty());
                    return Ok(Located {
                        span: None,
                        value: T::deserialize(empty)?,
                    });
                };
                if first == SPANNED_START {
                    let start: usize = map.next_value()?;
                    let mut end = start;
                    let mut value = None;
                    while let Some(key) = map.next_key::<String>()? {
                        if key == SPANNED_END {
                            end = map.next_value()?;
                        } else if key == SPANNED_VALUE {
                            value = Some(map.next_value()?);
                        }
                    }
                    let value =
                        value.ok_or_else(|| A::Error::custom("spanned table without value"))?;
                    return Ok(Located {
                        span: Some(start..end),
                        value,
                    });
                }
                let replay = Replay {
                    first: Some(first),
                    inner: map,
                };
                Ok(Located {
                    span: None,
                    value: T::deserialize(serde::de::value::MapAccessDeserializer::new(replay))?,
                })
            }
        }
        deserializer.deserialize_struct(
            SPANNED_NAME,
            &[SPANNED_START, SPANNED_END, SPANNED_VALUE],
            V_(std::marker::PhantomData),
        )
    }
}

/// A map whose first key was already read.
struct Replay<A> {
    first: Option<String>,
    inner: A,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for Replay<A> {
    type Error = A::Error;
    fn next_key_seed<K: serde::de::DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        match self.first.take() {
            Some(key) => seed.deserialize(key.into_deserializer()).map(Some),
            None => self.inner.next_key_seed(seed),
        }
    }
    fn next_value_seed<V: serde::de::DeserializeSeed<'de>>(
        &mut self,
        seed: V,
    ) -> Result<V::Value, A::Error> {
        self.inner.next_value_seed(seed)
    }
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Deck {
    pub simulation: Option<Located<Simulation>>,
    pub materials: Option<Ordered<S<String>, Material>>,
    pub body: Option<Vec<Located<Body>>>,
    pub interaction: Option<Vec<Located<Interaction>>>,
    pub symmetry: Option<Vec<Located<Symmetry>>>,
    pub wall: Option<Vec<Located<Symmetry>>>,
    pub prescribed: Option<Vec<Located<Prescribed>>>,
    pub output: Option<Located<Output>>,
}

/// A `[[prescribed]]` set: the particles of a body within a region, moving at a set velocity.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prescribed {
    pub name: Option<S<String>>,
    pub body: Option<S<String>>,
    pub region: Option<Shape>,
    pub velocity: Option<S<Vec<f64>>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Simulation {
    pub name: Option<S<String>>,
    pub dimension: Option<S<i64>>,
    pub end_time: Num,
    pub cfl: Num,
    pub max_steps: Option<S<i64>>,
    pub kernel: Option<S<String>>,
    pub formulation: Option<S<String>>,
    pub smoothing_ratio: Num,
    pub viscosity: Option<Viscosity>,
    pub gravity: Option<S<Vec<f64>>>,
    pub smoothing_bounds: Option<S<Vec<f64>>>,
    pub smoothing_stretch: Option<S<f64>>,
    pub smoothing_shape: Option<S<String>>,
    pub density_diffusion: Num,
    pub impact_speed: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    pub alpha: Num,
    pub beta: Num,
    pub limiter: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub library: Option<S<String>>,
    pub density: Num,
    pub eos: Option<ModelTable>,
    pub strength: Option<ModelTable>,
    pub damage: Option<ModelTable>,
    pub pressure_cutoff: Num,
    pub artificial_stress: Num,
}

/// A model's table (`eos`, `strength`, `damage`): its `type` and its numeric parameters, in
/// document order. Which keys a type takes is the model's own list (`material::params`),
/// checked after reading.
#[derive(Debug, Default)]
pub struct ModelTable {
    pub kind: Option<S<String>>,
    pub values: Vec<(S<String>, S<Entry>)>,
}

/// A value in a model's table: a number (integers read as numbers) or some text.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(untagged)]
pub enum Entry {
    Number(f64),
    Text(String),
    Other(serde::de::IgnoredAny),
}

impl ModelTable {
    /// The entry of `key`, if the table has it.
    pub fn get(&self, key: &str) -> Option<&(S<String>, S<Entry>)> {
        self.values.iter().find(|(k, _)| k.get_ref() == key)
    }
}

impl<'de> Deserialize<'de> for ModelTable {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let Ordered(entries) = Ordered::<S<String>, S<Entry>>::deserialize(deserializer)?;
        let mut table = ModelTable::default();
        for (k, v) in entries {
            if k.get_ref() == "type" {
                let span = v.span();
                match v.into_inner() {
                    Entry::Text(t) => table.kind = Some(S::new(span, t)),
                    _ => {
                        return Err(D::Error::custom(
                            "invalid type: `type` must be a string, expected a string",
                        ))
                    }
                }
            } else {
                table.values.push((k, v));
            }
        }
        Ok(table)
    }
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    pub name: Option<S<String>>,
    pub material: Option<S<String>>,
    pub spacing: Num,
    pub velocity: Option<S<Vec<f64>>>,
    pub motion: Option<S<String>>,
    pub shape: Option<Shape>,
}

/// Every key any shape takes.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shape {
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub min: Option<S<Vec<f64>>>,
    pub max: Option<S<Vec<f64>>>,
    pub center: Option<S<Vec<f64>>>,
    pub radius: Num,
    pub base: Option<S<Vec<f64>>>,
    pub axis: Option<S<Vec<f64>>>,
    pub length: Num,
    pub inner_radius: Num,
    pub outer_radius: Num,
    pub file: Option<S<String>>,
    pub scale: Num,
    pub rotate: Option<S<Vec<f64>>>,
    pub translate: Option<S<Vec<f64>>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interaction {
    pub bodies: Option<S<Vec<S<String>>>>,
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub law: Option<S<String>>,
    pub stiffness: Num,
    pub exponent: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Symmetry {
    pub axis: Option<S<String>>,
    pub position: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    pub snapshot_interval: Num,
    pub history_every: Option<S<i64>>,
    pub picture: Option<Vec<Located<Picture>>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Picture {
    pub times: Option<S<Vec<S<f64>>>>,
    pub normal: Option<S<String>>,
    pub position: Num,
    pub thickness: Num,
    pub color_by: Option<S<String>>,
}
