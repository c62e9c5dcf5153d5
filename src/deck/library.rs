//! The material library: every value with its source beside it (listed with sources by
//! `strike materials` and in docs/materials.md).
//!
//! EOS: Mie–Grüneisen referenced to the Hugoniot (s2 = s3 = a = 0), except basalt (Tillotson).
//! Strength: the paper's elastic–perfectly plastic von Mises where Steinberg tabulates G and
//! Y0 (the verification cases use these), Johnson–Cook for the metals of Johnson & Cook's
//! tables. Damage: every metal carries its spall strength (typical plate-impact values: spall
//! strengths are rate dependent, so treat them as a starting point), basalt too (its gabbro's
//! dynamic tensile strength), and the Johnson–Cook
//! metals also carry Johnson–Cook failure where its constants are published. A deck switches
//! failure off with `damage = { type = "none" }`.

use crate::case::{DamageSpec, EosSpec, Location, MaterialSpec, StrengthSpec};
use crate::material::params::Parameters;
use crate::material::{JohnsonCook, JohnsonCookFailure, Spall, Tillotson};

/// One library material.
pub struct Entry {
    pub name: &'static str,
    /// What it is, in a few words.
    pub what: &'static str,
    pub spec: MaterialSpec,
    /// Where its values come from.
    pub sources: &'static str,
}

/// Canonical names of the library materials.
pub fn library_names() -> &'static [&'static str] {
    &[
        "al_2024_t4",
        "al_2024_t3",
        "al_6061_t6",
        "al_7075_t6",
        "al_1100_o",
        "ofhc_copper",
        "armco_iron",
        "steel",
        "steel_4340",
        "steel_42crmo4",
        "ti_6al_4v",
        "tungsten_heavy_alloy",
        "nylon_66",
        "basalt",
    ]
}

fn mie_gruneisen(c0: f64, s1: f64, gamma0: f64) -> EosSpec {
    EosSpec::MieGruneisen {
        c0,
        s1,
        s2: 0.0,
        s3: 0.0,
        gamma0,
        a: 0.0,
    }
}

fn von_mises(g: f64, y0: f64) -> StrengthSpec {
    StrengthSpec::VonMises {
        shear_modulus: g,
        yield_stress: y0,
        hardening_modulus: 0.0,
    }
}

/// Johnson–Cook strength: G, A, B, n, C, m, T_melt (K), c_p; ε̇0 = 1/s, T_room = 293 K.
#[allow(clippy::too_many_arguments)]
fn johnson_cook(
    g: f64,
    a: f64,
    b: f64,
    n: f64,
    c: f64,
    m: f64,
    t_melt: f64,
    c_p: f64,
) -> StrengthSpec {
    StrengthSpec::JohnsonCook(JohnsonCook::from_pairs(&[
        ("shear_modulus", g),
        ("a", a),
        ("b", b),
        ("n", n),
        ("c", c),
        ("m", m),
        ("melt_temperature", t_melt),
        ("specific_heat", c_p),
    ]))
}

fn spall(strength: f64) -> DamageSpec {
    DamageSpec {
        spall: Some(Spall { strength }),
        ..DamageSpec::default()
    }
}

fn spall_and_jc(strength: f64, d: [f64; 5]) -> DamageSpec {
    DamageSpec {
        spall: Some(Spall { strength }),
        johnson_cook: Some(JohnsonCookFailure::from_pairs(&[
            ("d1", d[0]),
            ("d2", d[1]),
            ("d3", d[2]),
            ("d4", d[3]),
            ("d5", d[4]),
        ])),
        tuler_butcher: None,
    }
}

fn entry(
    name: &'static str,
    what: &'static str,
    density: f64,
    eos: EosSpec,
    strength: StrengthSpec,
    damage: DamageSpec,
    sources: &'static str,
) -> Entry {
    Entry {
        name,
        what,
        spec: MaterialSpec {
            name: name.to_string(),
            location: Location::default(),
            density,
            eos,
            strength,
            pressure_cutoff: None,
            artificial_stress: None,
            damage,
        },
        sources,
    }
}

/// Every library material, in [`library_names`] order.
pub fn entries() -> Vec<Entry> {
    vec![
        entry(
            "al_2024_t4",
            "aluminium alloy 2024-T4, elastic–perfectly plastic",
            2785.0, // Steinberg 1996
            mie_gruneisen(5328.0, 1.338, 2.00), // Steinberg 1996
            von_mises(28.6e9, 0.26e9),          // Steinberg 1996: G0, Y0
            spall(1.3e9),                       // Kanel et al. 2004 (2024: 1.2–1.5 GPa)
            "EOS, G, Y0: Steinberg 1996; spall: Kanel et al. 2004",
        ),
        entry(
            "al_2024_t3",
            "aluminium alloy 2024-T3, Johnson–Cook with failure",
            2785.0,                             // Steinberg 1996 (2024)
            mie_gruneisen(5328.0, 1.338, 2.00), // Steinberg 1996 (2024)
            // Lesuer 2000 (LLNL UCRL-ID-138213): A, B, n, C, m; T_melt 775 K; c_p 875.
            johnson_cook(28.6e9, 369e6, 684e6, 0.73, 0.0083, 1.7, 775.0, 875.0),
            // Lesuer 2000: D1–D5; spall: Kanel et al. 2004.
            spall_and_jc(1.3e9, [0.13, 0.13, -1.5, 0.011, 0.0]),
            "EOS, G: Steinberg 1996; JC strength and failure: Lesuer 2000; spall: Kanel et al. 2004",
        ),
        entry(
            "al_6061_t6",
            "aluminium alloy 6061-T6, elastic–perfectly plastic",
            2703.0,                            // Steinberg 1996
            mie_gruneisen(5240.0, 1.40, 1.97), // Steinberg 1996
            von_mises(27.6e9, 0.29e9),         // Steinberg 1996: G0, Y0
            spall(1.2e9),                      // Kanel et al. 2004 (6061-T6: 1.0–1.3 GPa)
            "EOS, G, Y0: Steinberg 1996; spall: Kanel et al. 2004",
        ),
        entry(
            "al_7075_t6",
            "aluminium alloy 7075-T6, elastic–perfectly plastic",
            2804.0,                            // Steinberg 1996
            mie_gruneisen(5200.0, 1.36, 2.20), // Steinberg 1996
            von_mises(26.7e9, 0.42e9),         // Steinberg 1996: G0, Y0
            spall(1.5e9),                      // Kanel et al. 2004 (7075: 1.2–1.7 GPa)
            "EOS, G, Y0: Steinberg 1996; spall: Kanel et al. 2004",
        ),
        entry(
            "al_1100_o",
            "aluminium 1100-O, hydrodynamic (no strength data)",
            2707.0,                             // Steinberg 1996
            mie_gruneisen(5386.0, 1.339, 1.97), // Steinberg 1996
            StrengthSpec::Hydrodynamic,
            spall(1.0e9), // Kanel et al. 2004 (pure Al: 0.8–1.2 GPa)
            "EOS: Steinberg 1996; spall: Kanel et al. 2004",
        ),
        entry(
            "ofhc_copper",
            "OFHC copper, Johnson–Cook with failure",
            8930.0,                             // Steinberg 1996
            mie_gruneisen(3940.0, 1.489, 2.02), // Steinberg 1996
            // Johnson & Cook 1983: A, B, n, C, m, T_melt 1356 K; G Steinberg 1996; c_p 383.
            johnson_cook(47.7e9, 90e6, 292e6, 0.31, 0.025, 1.09, 1356.0, 383.0),
            // Johnson & Cook 1985: D1–D5; spall 1.3 GPa (VALIDATION.md; Kanel et al. 2004).
            spall_and_jc(1.3e9, [0.54, 4.89, -3.03, 0.014, 1.12]),
            "EOS, G: Steinberg 1996; JC strength: Johnson & Cook 1983; JC failure: Johnson & Cook 1985; spall: Kanel et al. 2004",
        ),
        entry(
            "armco_iron",
            "Armco iron, Johnson–Cook with failure (no α–ε transition)",
            7850.0,                            // Steinberg 1996 (iron)
            mie_gruneisen(3574.0, 1.92, 1.69), // Steinberg 1996 (iron; valid below 13 GPa)
            // Johnson & Cook 1983: A, B, n, C, m, T_melt 1811 K; G 81.8 GPa Steinberg 1996;
            // c_p 452.
            johnson_cook(81.8e9, 175e6, 380e6, 0.32, 0.060, 0.55, 1811.0, 452.0),
            // Johnson & Cook 1985: D1–D5; spall: Kanel et al. 2004 (Armco iron 1.5–2 GPa).
            spall_and_jc(1.7e9, [-2.20, 5.43, -0.47, 0.016, 0.63]),
            "EOS, G: Steinberg 1996; JC strength: Johnson & Cook 1983; JC failure: Johnson & Cook 1985; spall: Kanel et al. 2004",
        ),
        entry(
            "steel",
            "steel, elastic–perfectly plastic",
            7900.0,                            // Howell & Ball 2002
            mie_gruneisen(4600.0, 1.49, 2.17), // Howell & Ball 2002
            von_mises(85.3e9, 0.979e9),        // Howell & Ball 2002
            spall(2.5e9),                      // Kanel et al. 2004 (steels 2–4 GPa)
            "Howell & Ball 2002; spall: Kanel et al. 2004",
        ),
        entry(
            "steel_4340",
            "4340 steel (Rc 30), Johnson–Cook with failure",
            7830.0,                            // Johnson & Cook 1983
            mie_gruneisen(4578.0, 1.33, 1.67), // Steinberg 1996 (4340)
            // Johnson & Cook 1983: A, B, n, C, m, T_melt 1793 K; G 77.5 GPa Steinberg 1996;
            // c_p 477.
            johnson_cook(77.5e9, 792e6, 510e6, 0.26, 0.014, 1.03, 1793.0, 477.0),
            // Johnson & Cook 1985: D1–D5; spall: Kanel et al. 2004 (4340: 3–4 GPa).
            spall_and_jc(3.0e9, [0.05, 3.44, -2.12, 0.002, 0.61]),
            "EOS, G: Steinberg 1996; JC strength: Johnson & Cook 1983; JC failure: Johnson & Cook 1985; spall: Kanel et al. 2004",
        ),
        entry(
            "steel_42crmo4",
            "42CrMo4 steel, Johnson–Cook (the Taylor-bar steel of VALIDATION.md §F)",
            7830.0,                            // DynELA Taylor-bar benchmark
            mie_gruneisen(4578.0, 1.33, 1.67), // Steinberg 1996 (4340, a similar steel)
            // DynELA documentation (Pantalé): A, B, n, C, m, T_melt 1540 °C; E 206.9 GPa,
            // ν 0.3 → G = E/2.6; c_p 460.
            johnson_cook(206.9e9 / 2.6, 806e6, 614e6, 0.168, 0.0089, 1.1, 1813.15, 460.0),
            spall(3.0e9), // Kanel et al. 2004 (steels 2–4 GPa)
            "JC strength, ρ, E, ν, c_p: DynELA Taylor-bar benchmark (Pantalé); EOS: Steinberg 1996 (4340); spall: Kanel et al. 2004",
        ),
        entry(
            "ti_6al_4v",
            "titanium alloy Ti-6Al-4V, Johnson–Cook with failure",
            4419.0,                             // Steinberg 1996
            mie_gruneisen(5130.0, 1.028, 1.23), // Steinberg 1996
            // Johnson 1985 via Lesuer 2000: A, B, n, C, m, T_melt 1878 K; G 41.9 GPa
            // Steinberg 1996; c_p 526.
            johnson_cook(41.9e9, 862e6, 331e6, 0.34, 0.012, 0.8, 1878.0, 526.0),
            // Lesuer 2000: D1–D5; spall: Kanel et al. 2004 (Ti-6Al-4V: 3.5–4.5 GPa).
            spall_and_jc(4.0e9, [-0.09, 0.25, -0.5, 0.014, 3.87]),
            "EOS, G: Steinberg 1996; JC strength and failure: Lesuer 2000; spall: Kanel et al. 2004",
        ),
        entry(
            "tungsten_heavy_alloy",
            "tungsten heavy alloy (90W–7Ni–3Fe), Johnson–Cook",
            17000.0,                            // Johnson & Cook 1983
            mie_gruneisen(4029.0, 1.237, 1.54), // Steinberg 1996 (tungsten)
            // Johnson & Cook 1983: A, B, n, C, m, T_melt 1723 K; G 160 GPa Steinberg 1996
            // (tungsten); c_p 134.
            johnson_cook(160e9, 1506e6, 177e6, 0.12, 0.016, 1.0, 1723.0, 134.0),
            spall(2.5e9), // Kanel et al. 2004 (heavy alloys 2–3 GPa)
            "EOS, G: Steinberg 1996 (tungsten); JC strength: Johnson & Cook 1983; spall: Kanel et al. 2004",
        ),
        entry(
            "nylon_66",
            "nylon 6/6 (light-gas-gun projectiles), hydrodynamic",
            1140.0,                             // Marsh 1980 (LASL shock Hugoniot data)
            mie_gruneisen(2570.0, 1.849, 0.87), // Marsh 1980; γ0 Steinberg 1996 (nylon)
            StrengthSpec::Hydrodynamic,
            // Pan et al. 2025 (Int. J. Mech. Sci. 110127), plate impact: PA66 0.23 GPa, nearly
            // constant up to 1.1 GPa of peak stress, brittle (PA6 0.18 GPa).
            spall(0.23e9),
            "Marsh 1980 (LASL Shock Hugoniot Data); γ0: Steinberg 1996; spall: Pan et al. 2025",
        ),
        entry(
            "basalt",
            "basalt, Tillotson, elastic–perfectly plastic, with spall",
            2700.0, // Benz & Asphaug 1999
            EosSpec::Tillotson(Tillotson::from_pairs(2700.0, &[
                ("a", 0.5),       // Benz & Asphaug 1999, Table II
                ("b", 1.5),       //
                ("A", 26.7e9),    //
                ("B", 26.7e9),    //
                ("e0", 487e6),    //
                ("alpha", 5.0),   //
                ("beta", 5.0),    //
                ("e_iv", 4.72e6), //
                ("e_cv", 18.2e6), //
            ])),
            von_mises(22.7e9, 3.5e9), // Benz & Asphaug 1999: μ = 22.7 GPa, Y = 3.5 GPa
            // A rock is far weaker in tension than in compression: without a spall strength the
            // basalt held 0.85 GPa of tension in the expanding projectile of a 4 km/s impact.
            // San Marcos gabbro, basalt's coarse-grained twin, spalls at 147 ± 9 MPa under
            // 1e4–1e5 /s (Lange, Ahrens & Boslough 1984; about 150 MPa, Ai & Ahrens 2004).
            spall(0.15e9),
            "Tillotson, G, Y: Benz & Asphaug 1999; spall: Lange, Ahrens & Boslough 1984 and Ai & Ahrens 2004 (San Marcos gabbro)",
        ),
    ]
}

/// One model's parameters as `key = value, …` (its list's order).
fn model_line(
    models: &[(&'static str, &'static [crate::material::params::Param])],
    kind: &str,
    values: &[f64],
) -> String {
    let params = crate::material::params_of(models, kind);
    let pairs: Vec<String> = params
        .iter()
        .zip(values)
        .map(|(p, v)| {
            if *v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
                format!("{} = {v:e}", p.key)
            } else {
                format!("{} = {v}", p.key)
            }
        })
        .collect();
    if pairs.is_empty() {
        kind.to_string()
    } else {
        format!("{kind}: {}", pairs.join(", "))
    }
}

/// A library material as `strike materials` lists it: its name and what it is, its models
/// with every value, and its sources.
pub fn describe(e: &Entry) -> String {
    use crate::material::{DAMAGE_MODELS, EOS_MODELS, STRENGTH_MODELS};
    let s = &e.spec;
    // Johnson–Cook failure lists Tuler–Butcher's three constants last: only where it is used.
    let mut damage = s.damage.values();
    if s.damage.johnson_cook.is_some() && s.damage.tuler_butcher.is_none() {
        damage.truncate(damage.len() - 3);
    }
    format!(
        "{} — {}\n  density  {} kg/m³\n  eos      {}\n  strength {}\n  damage   {}\n  sources  {}\n",
        e.name,
        e.what,
        s.density,
        model_line(&EOS_MODELS, s.eos.kind(), &s.eos.values()),
        model_line(&STRENGTH_MODELS, s.strength.kind(), &s.strength.values()),
        model_line(&DAMAGE_MODELS, s.damage.kind(), &damage),
        e.sources
    )
}

/// The full references behind the library's short source names.
pub const REFERENCES: &[&str] = &[
    "Steinberg 1996: D. J. Steinberg, Equation of State and Strength Properties of Selected Materials, LLNL UCRL-MA-106439 (change 1, 1996)",
    "Johnson & Cook 1983: G. R. Johnson, W. H. Cook, A constitutive model and data for metals subjected to large strains, high strain rates and high temperatures, Proc. 7th Int. Symp. Ballistics, The Hague, 541–547",
    "Johnson & Cook 1985: G. R. Johnson, W. H. Cook, Fracture characteristics of three metals subjected to various strains, strain rates, temperatures and pressures, Eng. Fract. Mech. 21 (1985) 31–48",
    "Lesuer 2000: D. R. Lesuer, Experimental investigations of material models for Ti-6Al-4V titanium and 2024-T3 aluminum, FAA report DOT/FAA/AR-00/25 (LLNL UCRL-ID-134691)",
    "Kanel et al. 2004: G. I. Kanel, S. V. Razorenov, V. E. Fortov, Shock-Wave Phenomena and the Properties of Condensed Matter, Springer 2004 (spall strengths)",
    "Howell & Ball 2002: B. P. Howell, G. J. Ball, A free-Lagrange augmented Godunov method for the simulation of elastic–plastic solids, J. Comput. Phys. 175 (2002) 128–167",
    "Marsh 1980: S. P. Marsh (ed.), LASL Shock Hugoniot Data, University of California Press 1980",
    "Pan et al. 2025: R. C. Pan, B. X. Bie, Y. Cai, N. B. Zhang, L. Z. Chen, Y. X. Zhao, K. Li, H. W. Chai, L. Lu, S. N. Luo, Shock compression and spallation of polyamides 6 and 66, Int. J. Mech. Sci. (2025) 110127 (spall strengths of PA66 and PA6)",
    "Benz & Asphaug 1999: W. Benz, E. Asphaug, Catastrophic disruptions revisited, Icarus 142 (1999) 5–20",
    "Lange, Ahrens & Boslough 1984: M. A. Lange, T. J. Ahrens, M. B. Boslough, Impact cratering and spall failure of gabbro, Icarus 58 (1984) 383–395 (San Marcos gabbro's dynamic tensile strength, 147 ± 9 MPa at 1e4–1e5 /s)",
    "Ai & Ahrens 2004: H.-A. Ai, T. J. Ahrens, Dynamic tensile strength of terrestrial rocks and application to impact cratering, Meteorit. Planet. Sci. 39 (2004) 233–246 (San Marcos gabbro about 150 MPa)",
    "DynELA: O. Pantalé, DynELA finite-element code documentation, Taylor-bar benchmark (42CrMo4)",
];

/// The canonical library name for `name`: case-insensitive, `-`, ` ` and `_` alike, a few
/// spellings of the common names accepted ("Al2024-T4", "aluminium_2024_t4", "copper").
pub fn canonical_name(name: &str) -> Option<&'static str> {
    let squashed: String = name
        .chars()
        .filter(|c| !matches!(c, '-' | '_' | ' ' | '.' | '/'))
        .flat_map(char::to_lowercase)
        .collect();
    let squashed = squashed
        .strip_prefix("aluminium")
        .or_else(|| squashed.strip_prefix("aluminum"))
        .map(|rest| format!("al{rest}"))
        .unwrap_or(squashed);
    let alias = match squashed.as_str() {
        "al1100" => Some("al_1100_o"),
        "ofhccu" | "copper" | "cu" => Some("ofhc_copper"),
        "iron" | "armco" => Some("armco_iron"),
        "4340" | "4340steel" | "aisi4340" => Some("steel_4340"),
        "42crmo4" | "42crmo4steel" => Some("steel_42crmo4"),
        "ti64" | "titanium" => Some("ti_6al_4v"),
        "wha" | "tungsten" | "tungstenalloy" => Some("tungsten_heavy_alloy"),
        "nylon" | "pa66" => Some("nylon_66"),
        _ => None,
    };
    alias.or_else(|| {
        library_names()
            .iter()
            .find(|n| n.replace('_', "") == squashed)
            .copied()
    })
}

/// A library material by name (aliases accepted, see [`canonical_name`]); its `name` is the
/// canonical one and its location the default (it is defined nowhere in a deck).
pub fn library_material(name: &str) -> Option<MaterialSpec> {
    let canonical = canonical_name(name)?;
    entries()
        .into_iter()
        .find(|e| e.name == canonical)
        .map(|e| e.spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_resolves_and_aliases_work() {
        let entries = entries();
        assert_eq!(entries.len(), library_names().len());
        for (name, e) in library_names().iter().zip(&entries) {
            assert_eq!(e.name, *name);
            assert_eq!(library_material(name).unwrap().name, *name);
            // Each model's cross-checks pass on its library values.
            let m = crate::material::Material::from_spec(&e.spec);
            assert!(m.sound_speed0() > 0.0, "{name}");
        }
        assert_eq!(canonical_name("Al2024-T4"), Some("al_2024_t4"));
        assert_eq!(canonical_name("aluminium_2024_t4"), Some("al_2024_t4"));
        assert_eq!(canonical_name("OFHC Copper"), Some("ofhc_copper"));
        assert_eq!(canonical_name("Ti-6Al-4V"), Some("ti_6al_4v"));
        assert_eq!(canonical_name("42CrMo4"), Some("steel_42crmo4"));
        assert_eq!(canonical_name("unobtainium"), None);
        assert_eq!(
            library_material("al_1100_o").unwrap().strength,
            StrengthSpec::Hydrodynamic
        );
        // Library metals carry failure by default, and so does the rock.
        for name in [
            "al_6061_t6",
            "ofhc_copper",
            "steel_4340",
            "ti_6al_4v",
            "basalt",
        ] {
            assert!(!library_material(name).unwrap().damage.is_none(), "{name}");
        }
    }
}
