//! The documents a user looks for exist and are complete: every deck key in docs/deck.md, every
//! library material (with a source) in docs/materials.md, every history column, snapshot field
//! and summary key with its unit in docs/outputs.md.

use std::path::Path;
use strike::deck::{library_names, parse};
use strike::Error;

fn doc(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("docs")
            .join(name),
    )
    .unwrap_or_else(|e| panic!("docs/{name}: {e}"))
}

const DECK: &str = r#"[simulation]
dimension = 2
end_time = 1.0e-6
viscosity = { alpha = 1.0 }
[materials.al]
library = "al_2024_t4"
eos = { type = "linear", bulk_modulus = 7e10 }
strength = { type = "elastic", shear_modulus = 2.6e10 }
[[body]]
name = "a"
material = "al"
spacing = 1.0e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [0.01, 0.01] }
[[interaction]]
bodies = ["a", "a"]
[[symmetry]]
axis = "x"
[[prescribed]]
body = "a"
region = { type = "rectangle", min = [0.0, 0.0], max = [2.0e-3, 0.01] }
[output]
history_every = 5
[[output.picture]]
times = [0.0]
"#;

/// The keys the deck reader accepts in the table holding `anchor`: an unknown key put right
/// after it is refused with the list of allowed keys.
fn allowed_after(anchor: &str, inline: bool) -> Vec<String> {
    let deck = if inline {
        DECK.replacen(anchor, &format!("{anchor} zzz = 1,"), 1)
    } else {
        DECK.replacen(anchor, &format!("{anchor}\nzzz = 1"), 1)
    };
    assert_ne!(deck, DECK, "{anchor}");
    let Err(Error::Deck { help, message, .. }) = parse(&deck, "keys.toml") else {
        panic!("`zzz` after {anchor} was accepted");
    };
    let help = help.unwrap_or_default();
    let list = help
        .split("the keys allowed here are ")
        .nth(1)
        .unwrap_or_else(|| panic!("{message}: {help}"));
    list.split(", ")
        .flat_map(|k| k.split(" or "))
        .map(|k| k.trim().trim_matches('`').to_string())
        .collect()
}

#[test]
fn every_deck_key_is_documented() {
    let reference = doc("deck.md");
    let tables = [
        ("end_time = 1.0e-6", false),
        ("viscosity = {", true),
        ("library = \"al_2024_t4\"", false),
        ("spacing = 1.0e-3", false),
        ("shape = {", true),
        ("bodies = [\"a\", \"a\"]", false),
        ("axis = \"x\"", false),
        ("body = \"a\"", false),
        ("history_every = 5", false),
        ("times = [0.0]", false),
    ];
    let mut count = 0;
    for (anchor, inline) in tables {
        for key in allowed_after(anchor, inline) {
            assert!(
                reference.contains(&format!("`{key}`")),
                "docs/deck.md does not document `{key}` (table of `{anchor}`)"
            );
            count += 1;
        }
    }
    // The models' own keys (each model lists its parameters) and their types.
    use strike::material::{DAMAGE_MODELS, ELASTIC_CONSTANTS, EOS_MODELS, STRENGTH_MODELS};
    for (kind, params) in STRENGTH_MODELS
        .iter()
        .chain(&EOS_MODELS)
        .chain(&DAMAGE_MODELS)
    {
        assert!(
            reference.contains(&format!("`\"{kind}\"`")),
            "docs/deck.md does not document the model `{kind}`"
        );
        for p in params.iter() {
            assert!(
                reference.contains(&format!("`{}`", p.key)),
                "docs/deck.md does not document `{}` of `{kind}`",
                p.key
            );
            count += 1;
        }
    }
    for key in ELASTIC_CONSTANTS {
        assert!(reference.contains(&format!("`{key}`")), "{key}");
    }
    // Top-level tables.
    for table in [
        "[simulation]",
        "[materials.",
        "[[body]]",
        "[[interaction]]",
        "[[symmetry]]",
        "[[wall]]",
        "[[prescribed]]",
        "[output]",
        "[[output.picture]]",
    ] {
        assert!(reference.contains(table), "docs/deck.md lacks {table}");
    }
    assert!(count > 50, "only {count} keys found");
}

#[test]
fn every_library_material_is_documented_with_a_source() {
    let text = doc("materials.md");
    for name in library_names() {
        let row = text
            .lines()
            .find(|l| l.starts_with(&format!("| `{name}`")))
            .unwrap_or_else(|| panic!("docs/materials.md lacks {name}"));
        let source = row.trim_end_matches('|').rsplit('|').next().unwrap().trim();
        assert!(source.len() > 10, "{name} has no source: {row}");
    }
}

#[test]
fn every_output_column_field_and_key_is_documented() {
    let text = doc("outputs.md");
    let dir = std::env::temp_dir().join(format!("strike_docs_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("history.csv");
    let w = strike::output::history::HistoryWriter::create(&path, &["plate".to_string()]).unwrap();
    drop(w);
    let h = strike::output::history::History::read(&path).unwrap();
    for c in &h.columns {
        let generic = c.replace("plate", "<body>");
        let generic = generic.trim_end_matches("_y").trim_end_matches("_z");
        assert!(
            text.contains(&format!("`{c}`")) || text.contains(&format!("`{generic}")),
            "docs/outputs.md lacks history column {c}"
        );
    }
    for (field, _, _) in strike::output::vtk::POINT_DATA {
        assert!(
            text.contains(&format!("| `{field}` |")),
            "docs/outputs.md lacks field {field}"
        );
    }
    let summary: serde_json::Value = serde_json::to_value(strike::output::summary::Summary {
        case: String::new(),
        dimension: 2,
        particles: 0,
        threads: 1,
        steps: 0,
        wall_seconds: 0.0,
        particle_steps_per_second: 0.0,
        interactions_per_second: 0.0,
        mean_neighbors: 0.0,
        searches: 0,
        partial_searches: 0,
        rebalances: 0,
        correction_fallbacks: 0,
        end_time: 0.0,
        energy_error: 0.0,
        initial_energy: 0.0,
        final_energy: 0.0,
        momentum_error: 0.0,
        min_interbody_distance: None,
        mixing: Vec::new(),
        peak_memory_bytes: Some(0),
        modelled_part: String::new(),
        status: String::new(),
        reason: String::new(),
    })
    .unwrap();
    for key in summary.as_object().unwrap().keys() {
        assert!(
            text.contains(&format!("`{key}`")),
            "docs/outputs.md lacks summary key {key}"
        );
    }
    assert!(text.contains("per metre of depth") && text.contains("part modelled"));
    let _ = std::fs::remove_dir_all(&dir);
}
