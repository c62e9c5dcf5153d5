//! The deck as written: serde structs mirroring the TOML, every value that gets validated kept
//! with its byte span. Nothing here is checked beyond TOML syntax, types and key names; `super`
//! turns these into a [`crate::case::Case`].

use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
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

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Deck {
    pub simulation: Option<S<Simulation>>,
    pub materials: Option<Ordered<S<String>, Material>>,
    pub body: Option<Vec<S<Body>>>,
    pub interaction: Option<Vec<S<Interaction>>>,
    pub symmetry: Option<Vec<S<Symmetry>>>,
    pub output: Option<S<Output>>,
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
    pub smoothing_ratio: Num,
    pub viscosity: Option<Viscosity>,
    pub gravity: Option<S<Vec<f64>>>,
    pub smoothing_bounds: Option<S<Vec<f64>>>,
    pub impact_speed: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    pub alpha: Num,
    pub beta: Num,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub library: Option<S<String>>,
    pub density: Num,
    pub eos: Option<Eos>,
    pub strength: Option<Strength>,
    pub pressure_cutoff: Num,
    pub artificial_stress: Num,
}

/// Every key any EOS takes; which ones belong to which `type` is checked after reading.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Eos {
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub c0: Num,
    pub s1: Num,
    pub s2: Num,
    pub s3: Num,
    pub gamma0: Num,
    pub a: Num,
    pub bulk_modulus: Num,
}

/// Every key any strength model takes.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Strength {
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub shear_modulus: Num,
    pub yield_stress: Num,
    pub hardening_modulus: Num,
    pub youngs_modulus: Num,
    pub poissons_ratio: Num,
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
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interaction {
    pub bodies: Option<S<Vec<S<String>>>>,
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
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
    pub picture: Option<Vec<S<Picture>>>,
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
