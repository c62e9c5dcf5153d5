//! Library materials: Steinberg's constants as quoted by several hydrocodes (see the project's
//! VALIDATION.md), Mie–Grüneisen EOS with s2 = s3 = a = 0, and von Mises strength without
//! hardening where the shear modulus and yield stress are given.

use crate::case::{EosSpec, Location, MaterialSpec, StrengthSpec};

/// Canonical names of the library materials.
pub fn library_names() -> &'static [&'static str] {
    &[
        "al_2024_t4",
        "al_6061_t6",
        "al_1100_o",
        "ofhc_copper",
        "steel",
    ]
}

/// (name, ρ0, C, S1, γ0, G, Y0); G and Y0 zero: no strength data (hydrodynamic).
const TABLE: [(&str, f64, f64, f64, f64, f64, f64); 5] = [
    ("al_2024_t4", 2785.0, 5328.0, 1.338, 2.00, 28.6e9, 0.26e9),
    ("al_6061_t6", 2703.0, 5240.0, 1.40, 1.97, 27.6e9, 0.29e9),
    ("al_1100_o", 2707.0, 5386.0, 1.339, 1.97, 0.0, 0.0),
    ("ofhc_copper", 8930.0, 3940.0, 1.489, 2.02, 47.7e9, 0.12e9),
    ("steel", 7900.0, 4600.0, 1.49, 2.17, 85.3e9, 0.979e9),
];

/// The canonical library name for `name`: case-insensitive, `-`, ` ` and `_` alike, a few
/// spellings of the common names accepted ("Al2024-T4", "aluminium_2024_t4", "copper").
pub fn canonical_name(name: &str) -> Option<&'static str> {
    let squashed: String = name
        .chars()
        .filter(|c| !matches!(c, '-' | '_' | ' ' | '.'))
        .flat_map(char::to_lowercase)
        .collect();
    let squashed = squashed
        .strip_prefix("aluminium")
        .or_else(|| squashed.strip_prefix("aluminum"))
        .map(|rest| format!("al{rest}"))
        .unwrap_or(squashed);
    match squashed.as_str() {
        "al2024t4" => Some("al_2024_t4"),
        "al6061t6" => Some("al_6061_t6"),
        "al1100o" | "al1100" => Some("al_1100_o"),
        "ofhccopper" | "ofhccu" | "copper" | "cu" => Some("ofhc_copper"),
        "steel" => Some("steel"),
        _ => None,
    }
}

/// A library material by name (aliases accepted, see [`canonical_name`]); its `name` is the
/// canonical one and its location the default (it is defined nowhere in a deck).
pub fn library_material(name: &str) -> Option<MaterialSpec> {
    let canonical = canonical_name(name)?;
    let &(name, density, c0, s1, gamma0, g, y0) =
        TABLE.iter().find(|entry| entry.0 == canonical)?;
    let strength = if g > 0.0 {
        StrengthSpec::VonMises {
            shear_modulus: g,
            yield_stress: y0,
            hardening_modulus: 0.0,
        }
    } else {
        StrengthSpec::Hydrodynamic
    };
    Some(MaterialSpec {
        name: name.to_string(),
        location: Location::default(),
        density,
        eos: EosSpec::MieGruneisen {
            c0,
            s1,
            s2: 0.0,
            s3: 0.0,
            gamma0,
            a: 0.0,
        },
        strength,
        pressure_cutoff: None,
        artificial_stress: None,
        damage: Default::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_resolves_and_aliases_work() {
        for name in library_names() {
            assert_eq!(library_material(name).unwrap().name, *name);
        }
        assert_eq!(canonical_name("Al2024-T4"), Some("al_2024_t4"));
        assert_eq!(canonical_name("aluminium_2024_t4"), Some("al_2024_t4"));
        assert_eq!(canonical_name("OFHC Copper"), Some("ofhc_copper"));
        assert_eq!(canonical_name("unobtainium"), None);
        assert_eq!(
            library_material("al_1100_o").unwrap().strength,
            StrengthSpec::Hydrodynamic
        );
    }
}
