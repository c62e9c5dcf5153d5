//! TOML case decks → validated [`crate::case::Case`].
//!
//! [`parse`] reads the deck with serde into the structs of `raw` (every key checked against the
//! keys a table takes, every validated value kept with its byte span), then checks each value
//! and builds the [`Case`]. Every mistake becomes an [`Error::Deck`] naming the file, line,
//! column and dotted key (`body[1].spacing`, `materials.al.density`), saying what is wrong and
//! what would be right.

// `crate::Error` is large (a deck error carries location, key, message and help); boxing it is
// the error module's call, not this one's.

mod keypath;
pub mod library;
mod material;
mod raw;

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use crate::case::{
    BodySpec, Case, ColorBy, ContactLaw, Formulation, InteractionKind, InteractionSpec, KernelKind,
    Location, Motion, OutputSpec, PictureSpec, Shape, Simulation, SymmetryPlane,
};
use crate::error::{DeckLocation, Error, Result};
pub use library::{library_material, library_names};
use raw::S;

/// A `[[symmetry]]` or `[[wall]]` table as read.
type Plane = raw::Located<raw::Symmetry>;

/// Reads and validates the deck at `path`.
pub fn load(path: &Path) -> Result<Case> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse(&text, &path.display().to_string())
}

/// Validates the deck `text`; `file` names it in messages (and its stem is the default name).
pub fn parse(text: &str, file: &str) -> Result<Case> {
    let ctx = Ctx { text, file };
    let deck: raw::Deck = toml::from_str(text).map_err(|e| ctx.toml_error(&e))?;
    ctx.build(&deck, available_memory())
}

/// Expected number of particles of a body: its volume (area in 2D) on the model's side of the
/// symmetry planes `planes` ([`crate::setup::symmetry_planes`]) over spacing^D.
pub fn estimate_particles(
    shape: &Shape,
    spacing: f64,
    dimension: usize,
    planes: &[crate::boundary::Plane],
) -> f64 {
    let share = match dimension {
        2 => crate::setup::shapes::model_share::<2>(shape, planes),
        _ => crate::setup::shapes::model_share::<3>(shape, planes),
    };
    share * whole_shape_particles(shape, spacing, dimension)
}

/// [`estimate_particles`] of each body of a case, with the case's symmetry planes: what
/// `check` and the deck's tests read.
pub fn estimate_case_particles(case: &Case) -> Vec<f64> {
    let planes = crate::setup::symmetry_planes(case);
    // A prescribed set's particles are its body's, counted there.
    case.bodies
        .iter()
        .map(|b| match b.part_of {
            Some(_) => 0.0,
            None => estimate_particles(&b.shape, b.spacing, case.dimension, &planes),
        })
        .collect()
}

/// Expected ghosts of the bodies: their particles that the symmetry planes `planes` mirror
/// ([`crate::setup::shapes::ghost_estimate`]), those within the ghost layers' reach at the
/// start, (2 + skin) h of the largest spacing's h = `ratio` × spacing.
pub fn estimate_ghosts(
    bodies: &[BodySpec],
    dimension: usize,
    planes: &[crate::boundary::Plane],
    ratio: f64,
) -> f64 {
    let spacing = bodies.iter().map(|b| b.spacing).fold(0.0, f64::max);
    let reach = (2.0 + crate::simulation::SKIN) * ratio * spacing;
    let ghosts = |b: &BodySpec| match dimension {
        2 => crate::setup::shapes::ghost_estimate::<2>(&b.shape, b.spacing, planes, reach),
        _ => crate::setup::shapes::ghost_estimate::<3>(&b.shape, b.spacing, planes, reach),
    };
    // A prescribed set's particles are its body's, counted there.
    bodies
        .iter()
        .filter(|b| b.part_of.is_none())
        .map(ghosts)
        .sum()
}

/// The interactions of prescribed set `set` (body index `set`, taken out of body `parent`):
/// welded to its body and to the body's other sets, and meeting every other body (and its
/// sets) as its body does: where the deck gives that pair an interaction, the set gets the
/// same; otherwise both keep the default.
fn inherit_interactions(
    interactions: &mut Vec<InteractionSpec>,
    bodies: &[BodySpec],
    set: &BodySpec,
    index: usize,
) {
    let Some(parent) = set.part_of else { return };
    let root = |b: usize| bodies[b].part_of.unwrap_or(b);
    for other in 0..index {
        let inherited = if root(other) == parent {
            Some((InteractionKind::Welded, set.location))
        } else {
            let pair = [parent, root(other)];
            interactions
                .iter()
                .find(|i| i.bodies == pair || i.bodies == [pair[1], pair[0]])
                .map(|i| (i.kind, i.location))
        };
        if let Some((kind, location)) = inherited {
            interactions.push(InteractionSpec {
                location,
                bodies: [other, index],
                kind,
            });
        }
    }
}

/// The whole shape's volume (area in 2D) over spacing^D.
fn whole_shape_particles(shape: &Shape, spacing: f64, dimension: usize) -> f64 {
    crate::setup::shapes::measure(shape, dimension) / spacing.powi(dimension as i32)
}

/// Memory this process may still use (see [`crate::machine::available_memory`]).
fn available_memory() -> Option<f64> {
    crate::machine::available_memory()
}

// ---------------------------------------------------------------------------------------------
// Formatting helpers.

/// A number as a user would write it: plain where short, exponent form otherwise.
fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-3..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A byte count with a binary unit.
fn bytes(b: f64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if v >= 1e4 {
        format!("{v:.1e} {}", UNITS[unit])
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

/// Rounds to three significant digits (a figure that reads well).
fn round_sig(x: f64) -> f64 {
    format!("{x:.2e}").parse().unwrap_or(x)
}

/// Rounds up to two significant digits (a spacing that surely fits).
fn round_up_2(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powf(x.log10().floor() - 1.0);
    let r = (x / scale).ceil() * scale;
    format!("{r:.1e}").parse().unwrap_or(r)
}

/// Rounds down to one significant digit (a suggestion that reads well).
fn round_down_1(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powf(x.log10().floor());
    let r = (x / scale * (1.0 + 1e-9)).floor() * scale;
    // Through the printed form, so that 5e-5 is not 5.000000000000001e-5.
    format!("{r:.0e}").parse().unwrap_or(r)
}

/// A table key as it appears in a dotted path.
fn key_seg(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        format!("{k:?}")
    }
}

/// The last segment of a dotted key, for messages ("density must be positive").
fn leaf(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur.push(sub.min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The candidate closest to `word`, if close enough to be a likely typo.
fn closest<'c>(word: &str, candidates: impl IntoIterator<Item = &'c str>) -> Option<&'c str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(word, c), c))
        .filter(|(d, c)| *d <= 1 + c.len().max(word.len()) / 3)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn did_you_mean<'c>(word: &str, candidates: impl IntoIterator<Item = &'c str>) -> String {
    closest(word, candidates).map_or(String::new(), |c| format!("did you mean `{c}`? "))
}

fn list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

// ---------------------------------------------------------------------------------------------
// Errors.

struct Ctx<'a> {
    text: &'a str,
    file: &'a str,
}

impl Ctx<'_> {
    /// 1-based line and column (in characters) of a byte offset.
    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        (line, before[line_start..].chars().count() + 1)
    }

    fn location(&self, span: &Range<usize>) -> Location {
        let (line, column) = self.line_col(span.start);
        Location { line, column }
    }

    fn fail(
        &self,
        span: Range<usize>,
        key: impl Into<String>,
        message: impl Into<String>,
        help: impl Into<String>,
    ) -> Error {
        let (line, column) = self.line_col(span.start);
        let help: String = help.into();
        Error::Deck {
            location: DeckLocation {
                file: self.file.to_string(),
                line,
                column,
                offset: span.start,
                length: span.end.saturating_sub(span.start),
            },
            key: key.into(),
            message: message.into(),
            help: (!help.is_empty()).then_some(help),
        }
    }

    /// A syntax, type or unknown-key error from `toml`.
    fn toml_error(&self, e: &toml::de::Error) -> Error {
        let span = e.span().unwrap_or(0..0);
        let key = match keypath::key_path_at(self.text, span.start) {
            k if k.is_empty() => "(top level)".to_string(),
            k => k,
        };
        let msg = match e.message().trim() {
            // toml says nothing when the text ends in the middle of a key-value pair.
            "" if span.start >= self.text.trim_end().len() => {
                "the deck ends here in the middle of an entry: a value or a closing bracket or quote is missing"
            }
            "" => "this is not valid TOML",
            m => m,
        };
        if let Some(rest) = msg.strip_prefix("unknown field `") {
            let (field, tail) = rest.split_once('`').unwrap_or((rest, ""));
            let expected = tail
                .trim_start_matches(',')
                .trim()
                .trim_start_matches("expected one of ")
                .trim_start_matches("expected ");
            let names: Vec<&str> = expected
                .split(", ")
                .map(|s| s.trim_matches('`'))
                .filter(|s| !s.is_empty())
                .collect();
            let here = if key.contains('.') || key.contains('[') {
                key.rsplit_once('.')
                    .map_or(String::new(), |(parent, _)| format!(" in `{parent}`"))
            } else {
                " at the top level".to_string()
            };
            let hint = did_you_mean(field, names.iter().copied());
            return self.fail(
                span,
                key,
                format!("unknown key `{field}`{here}"),
                format!("{hint}the keys allowed here are {}", list(&names)),
            );
        }
        if let Some(rest) = msg.strip_prefix("invalid type: ") {
            let (found, expected) = rest.rsplit_once(", expected ").unwrap_or((rest, ""));
            let (want, help) = match expected {
                "f64" => ("a number", "write a number without quotes, e.g. 2.0e-5"),
                "i64" => (
                    "an integer",
                    "write a whole number without quotes or decimal point, e.g. 3",
                ),
                "a string" => ("a string", "write text in quotes, e.g. \"sphere\""),
                "a sequence" => (
                    "an array",
                    "write an array in brackets, e.g. [0.0, 0.0, -7000.0]",
                ),
                e if e.starts_with("struct ") || e.contains("map") || e == "a table" => (
                    "a table",
                    "write a table: an inline { key = value, … } or a [header] section",
                ),
                other => (other, ""),
            };
            return self.fail(
                span,
                key,
                format!("wrong type: expected {want}, found {found}"),
                help,
            );
        }
        let help = if msg.contains("duplicate key") {
            "each key may appear once per table; remove or rename one of them"
        } else {
            "the deck is not valid TOML here (see https://toml.io): check quotes, brackets and `key = value` syntax"
        };
        self.fail(span, key, msg.replace('\n', " "), help)
    }

    fn finite(&self, v: &S<f64>, key: &str) -> Result<f64> {
        let x = *v.get_ref();
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.fail(
                v.span(),
                key,
                format!("{} must be a finite number, got {x}", leaf(key)),
                "give an ordinary number (not inf or nan)",
            ))
        }
    }

    /// A finite number satisfying `ok`; otherwise "`leaf` `rule`, got x".
    fn check(
        &self,
        v: &S<f64>,
        key: &str,
        ok: impl Fn(f64) -> bool,
        rule: &str,
        help: &str,
    ) -> Result<f64> {
        let x = self.finite(v, key)?;
        if ok(x) {
            Ok(x)
        } else {
            Err(self.fail(
                v.span(),
                key,
                format!("{} {rule}, got {}", leaf(key), num(x)),
                help,
            ))
        }
    }

    fn positive(&self, v: &S<f64>, key: &str, help: &str) -> Result<f64> {
        self.check(v, key, |x| x > 0.0, "must be positive", help)
    }

    fn non_negative(&self, v: &S<f64>, key: &str, help: &str) -> Result<f64> {
        self.check(v, key, |x| x >= 0.0, "must not be negative", help)
    }

    fn missing(&self, anchor: &Range<usize>, key: &str, what: &str, help: &str) -> Error {
        self.fail(
            anchor.clone(),
            key,
            format!("missing `{}`: {what}", leaf(key)),
            help,
        )
    }

    /// One of `options` (exact match); otherwise an error listing them.
    fn choice<'o>(
        &self,
        v: &S<String>,
        key: &str,
        options: &[&'o str],
        what: &str,
    ) -> Result<&'o str> {
        let given = v.get_ref().as_str();
        if let Some(o) = options.iter().find(|o| **o == given) {
            return Ok(o);
        }
        let lower = given.to_lowercase();
        let hint = if let Some(o) = options.iter().find(|o| **o == lower) {
            format!("did you mean `{o}`? ")
        } else {
            did_you_mean(given, options.iter().copied())
        };
        Err(self.fail(
            v.span(),
            key,
            format!("unknown {what} `{given}`"),
            format!("{hint}{what} is one of {}", list(options)),
        ))
    }

    /// A vector of the deck's dimension, padded to 3 components with zeros.
    fn vector(&self, v: &S<Vec<f64>>, key: &str, dim: usize, example: &str) -> Result<[f64; 3]> {
        let values = v.get_ref();
        if values.len() != dim {
            return Err(self.fail(
                v.span(),
                key,
                format!(
                    "{} has {} component{}, but the deck is {dim}D",
                    leaf(key),
                    values.len(),
                    if values.len() == 1 { "" } else { "s" }
                ),
                format!("give {dim} components, e.g. {example}"),
            ));
        }
        let mut out = [0.0; 3];
        for (k, x) in values.iter().enumerate() {
            if !x.is_finite() {
                return Err(self.fail(
                    v.span(),
                    format!("{key}[{k}]"),
                    format!("{}[{k}] must be a finite number, got {x}", leaf(key)),
                    "give ordinary numbers (not inf or nan)",
                ));
            }
            out[k] = *x;
        }
        Ok(out)
    }

    /// Errors on each key of `fields` that is given but does not belong to `what`.
    fn forbid(
        &self,
        prefix: &str,
        fields: &[(&str, Option<Range<usize>>)],
        allowed: &[&str],
        what: &str,
    ) -> Result<()> {
        for (name, span) in fields {
            if let Some(span) = span {
                if !allowed.contains(name) {
                    return Err(self.fail(
                        span.clone(),
                        format!("{prefix}.{name}"),
                        format!("`{name}` is not a key of {what}"),
                        format!("{what} takes {}", list(allowed)),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Names (the case's, the bodies') name files in the output directory and columns of
/// `history.csv`: ASCII letters, digits, `_`, `-` and `.`, starting with a letter or digit, at
/// most this many characters — never a path, never anything a CSV field or a shell must quote.
const MAX_NAME: usize = 64;

fn safe_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.')
}

impl Ctx<'_> {
    /// A name of the safe set (see [`MAX_NAME`]).
    fn safe_name(&self, v: &S<String>, key: &str, what: &str, example: &str) -> Result<()> {
        let name = v.get_ref();
        let problem = if name.is_empty() {
            Some("must not be empty".to_string())
        } else if name.chars().count() > MAX_NAME {
            Some(format!(
                "is {} characters long, more than {MAX_NAME}",
                name.chars().count()
            ))
        } else if let Some(c) = name.chars().find(|&c| !safe_char(c)) {
            Some(format!("holds {c:?}, which is not allowed"))
        } else if !name.starts_with(|c: char| c.is_ascii_alphanumeric()) {
            Some("must start with a letter or a digit".to_string())
        } else {
            None
        };
        match problem {
            None => Ok(()),
            Some(p) => Err(self.fail(
                v.span(),
                key,
                format!("{what} {name:?} {p}"),
                format!("{what} names output files and history columns: use only ASCII letters, digits, `_`, `-` and `.`, starting with a letter or digit, at most {MAX_NAME} characters, e.g. {example}"),
            )),
        }
    }
}

fn span_of<T>(v: &Option<S<T>>) -> Option<Range<usize>> {
    v.as_ref().map(|s| s.span())
}

// ---------------------------------------------------------------------------------------------
// Building the case.

const AXES: [&str; 3] = ["x", "y", "z"];

/// Body speeds at or above this (m/s) are refused: a thousandth of the speed of light, far
/// above any impact of solids (meteoroids reach about 7e4 m/s), far below where the first time
/// step h/(c + v) would round away.
const MAX_SPEED: f64 = 3.0e5;

/// A run writes at most this many snapshots.
pub const MAX_SNAPSHOTS: f64 = 100_000.0;

impl Ctx<'_> {
    fn build(&self, deck: &raw::Deck, memory: Option<f64>) -> Result<Case> {
        let Some(sim) = &deck.simulation else {
            return Err(self.fail(
                0..0,
                "simulation",
                "the deck has no [simulation] table",
                "add a [simulation] table with at least `dimension` (2 or 3) and `end_time` (s)",
            ));
        };
        let (name, dimension, simulation) = self.simulation(sim)?;

        // Materials defined in the deck, in deck order.
        let mut materials = Vec::new();
        let mut by_name: HashMap<String, usize> = HashMap::new();
        if let Some(raw::Ordered(entries)) = &deck.materials {
            for (key, m) in entries {
                let spec = self.material(key, m)?;
                by_name.insert(key.get_ref().clone(), materials.len());
                materials.push(spec);
            }
        }
        let user_names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();

        // Bodies.
        let Some(raw_bodies) = deck.body.as_ref().filter(|b| !b.is_empty()) else {
            return Err(self.fail(
                self.text.len()..self.text.len(),
                "body",
                "the deck defines no body",
                "add at least one [[body]] table with name, material, spacing and shape",
            ));
        };
        let mut bodies: Vec<BodySpec> = Vec::new();
        let mut body_names: HashMap<String, Range<usize>> = HashMap::new();
        let mut library_added: HashMap<&'static str, usize> = HashMap::new();
        for (i, b) in raw_bodies.iter().enumerate() {
            let prefix = format!("body[{i}]");
            let anchor = b.anchor();
            let b = b.get_ref();
            let name = b.name.as_ref().ok_or_else(|| {
                self.missing(
                    &anchor,
                    &format!("{prefix}.name"),
                    "every body needs a unique name",
                    "add e.g. `name = \"plate\"`",
                )
            })?;
            self.safe_name(name, &format!("{prefix}.name"), "a body name", "\"plate\"")?;
            if let Some(first) = body_names.get(name.get_ref()) {
                let (line, _) = self.line_col(first.start);
                return Err(self.fail(
                    name.span(),
                    format!("{prefix}.name"),
                    format!(
                        "duplicate body name `{}` (already used on line {line})",
                        name.get_ref()
                    ),
                    "give every body a different name",
                ));
            }
            body_names.insert(name.get_ref().clone(), name.span());

            // Material: a [materials] key, else a library name.
            let mat = b.material.as_ref().ok_or_else(|| {
                self.missing(
                    &anchor,
                    &format!("{prefix}.material"),
                    "the body's material",
                    "add e.g. `material = \"al_2024_t4\"` (a library material) or the name of a [materials] table",
                )
            })?;
            let material = if let Some(&idx) = by_name.get(mat.get_ref()) {
                idx
            } else if let Some(canonical) = library::canonical_name(mat.get_ref()) {
                *library_added.entry(canonical).or_insert_with(|| {
                    let mut spec =
                        library_material(canonical).expect("canonical library names resolve");
                    spec.location = self.location(&mat.span());
                    materials.push(spec);
                    materials.len() - 1
                })
            } else {
                let candidates: Vec<&str> = user_names
                    .iter()
                    .map(String::as_str)
                    .chain(library_names().iter().copied())
                    .collect();
                let defined = if user_names.is_empty() {
                    "none".to_string()
                } else {
                    list(&user_names.iter().map(String::as_str).collect::<Vec<_>>())
                };
                return Err(self.fail(
                    mat.span(),
                    format!("{prefix}.material"),
                    format!("unknown material `{}`", mat.get_ref()),
                    format!(
                        "{}known materials: defined in [materials]: {defined}; library: {}",
                        did_you_mean(mat.get_ref(), candidates.iter().copied()),
                        list(library_names())
                    ),
                ));
            };

            let spacing_key = format!("{prefix}.spacing");
            let spacing = match &b.spacing {
                Some(s) => {
                    self.positive(s, &spacing_key, "the lattice spacing in m, e.g. 2.0e-5")?
                }
                None => {
                    return Err(self.missing(
                        &anchor,
                        &spacing_key,
                        "the particle lattice spacing (m)",
                        "add e.g. `spacing = 2.0e-5`",
                    ))
                }
            };
            let velocity = match &b.velocity {
                Some(v) => {
                    let key = format!("{prefix}.velocity");
                    let velocity = self.vector(
                        v,
                        &key,
                        dimension,
                        if dimension == 2 {
                            "[0.0, -7000.0]"
                        } else {
                            "[0.0, 0.0, -7000.0]"
                        },
                    )?;
                    let speed = velocity.iter().fold(0.0_f64, |a, &c| a.hypot(c));
                    if speed >= MAX_SPEED {
                        return Err(self.fail(
                            v.span(),
                            key,
                            format!(
                                "the speed {} m/s is at or beyond {} m/s: no solid impact happens there, and the first time step would vanish",
                                num(speed),
                                num(MAX_SPEED)
                            ),
                            "give the velocity in m/s, e.g. 7000 for a hypervelocity impact",
                        ));
                    }
                    velocity
                }
                None => [0.0; 3],
            };
            let motion = match &b.motion {
                Some(m) => match self.choice(
                    m,
                    &format!("{prefix}.motion"),
                    &["free", "prescribed"],
                    "motion",
                )? {
                    "prescribed" => Motion::Prescribed,
                    _ => Motion::Free,
                },
                None => Motion::Free,
            };
            let shape_key = format!("{prefix}.shape");
            let shape = match &b.shape {
                Some(s) => self.shape(s, &shape_key, dimension, &anchor)?,
                None => {
                    return Err(self.missing(
                        &anchor,
                        &shape_key,
                        "the body's shape",
                        if dimension == 2 {
                            "add e.g. `shape = { type = \"rectangle\", min = [0.0, 0.0], max = [1e-3, 2e-4] }`"
                        } else {
                            "add e.g. `shape = { type = \"sphere\", center = [0.0, 0.0, 0.0], radius = 3e-4 }`"
                        },
                    ))
                }
            };
            let (smallest, what) = smallest_size(&shape, dimension);
            if spacing > smallest {
                let spacing_span = b.spacing.as_ref().map_or(anchor.clone(), |s| s.span());
                return Err(self.fail(
                    spacing_span,
                    spacing_key,
                    format!(
                        "spacing {} m is larger than the shape's {what} {} m: no particle (or no full layer) would be made",
                        num(spacing),
                        num(smallest)
                    ),
                    format!(
                        "use a spacing well below {} m (several particles across), e.g. {} m, or enlarge the shape",
                        num(smallest),
                        num(round_down_1(smallest / 10.0))
                    ),
                ));
            }
            bodies.push(BodySpec {
                name: name.get_ref().clone(),
                location: self.location(&name.span()),
                material,
                spacing,
                velocity,
                shape,
                motion,
                part_of: None,
            });
        }
        let symmetry =
            self.symmetry((deck.symmetry.as_deref(), deck.wall.as_deref()), dimension)?;
        let corrected = simulation.formulation == Formulation::Corrected;
        let planes = crate::setup::planes_of(&bodies, &symmetry);
        let fails = bodies
            .iter()
            .any(|b| !materials[b.material].damage.is_none());
        let ghosts = estimate_ghosts(&bodies, dimension, &planes, simulation.smoothing_ratio);
        let kind = (dimension, corrected, fails);
        self.check_memory(raw_bodies, &bodies, (&planes, ghosts), kind, memory)?;

        let mut interactions = self.interactions(deck.interaction.as_deref(), &bodies)?;
        let sets = self.prescribed(deck.prescribed.as_deref(), &bodies, &body_names, dimension)?;
        for set in sets {
            inherit_interactions(&mut interactions, &bodies, &set, bodies.len());
            bodies.push(set);
        }
        let output = self.output(deck.output.as_ref(), simulation.end_time)?;

        Ok(Case {
            name,
            file: self.file.to_string(),
            dimension,
            simulation,
            materials,
            bodies,
            interactions,
            symmetry,
            output,
        })
    }

    fn simulation(
        &self,
        sim: &raw::Located<raw::Simulation>,
    ) -> Result<(String, usize, Simulation)> {
        let anchor = sim.anchor();
        let s = sim.get_ref();
        let name = match &s.name {
            Some(n) => {
                self.safe_name(n, "simulation.name", "the case name", "\"sphere_plate\"")?;
                n.get_ref().clone()
            }
            // The file's stem, with anything outside the safe set made an underscore.
            None => {
                let stem: String = Path::new(self.file)
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
                    .chars()
                    .map(|c| if safe_char(c) { c } else { '_' })
                    .take(MAX_NAME)
                    .collect();
                if stem.starts_with(|c: char| c.is_ascii_alphanumeric()) {
                    stem
                } else {
                    format!("case{stem}").chars().take(MAX_NAME).collect()
                }
            }
        };
        let dimension = match &s.dimension {
            Some(d) if matches!(d.get_ref(), 2 | 3) => *d.get_ref() as usize,
            Some(d) => {
                return Err(self.fail(
                    d.span(),
                    "simulation.dimension",
                    format!("dimension must be 2 or 3, got {}", d.get_ref()),
                    "2 for plane strain, 3 for a 3D case",
                ))
            }
            None => {
                return Err(self.missing(
                    &anchor,
                    "simulation.dimension",
                    "2 (plane strain) or 3",
                    "add `dimension = 3` (or 2 for plane strain)",
                ))
            }
        };
        let end_time = match &s.end_time {
            Some(t) => self.positive(
                t,
                "simulation.end_time",
                "the simulated end time in s, e.g. 2.0e-7",
            )?,
            None => {
                return Err(self.missing(
                    &anchor,
                    "simulation.end_time",
                    "the simulated end time (s)",
                    "add e.g. `end_time = 2.0e-7`",
                ))
            }
        };
        let cfl = match &s.cfl {
            Some(c) => Some(self.check(
                c,
                "simulation.cfl",
                |x| x > 0.0 && x <= 1.0,
                "must be in (0, 1]",
                "a Courant number, typically 0.15–0.4; default 0.3 (0.15 in CN-SPH)",
            )?),
            None => None,
        };
        let max_steps = match &s.max_steps {
            Some(m) if *m.get_ref() > 0 => Some(*m.get_ref() as u64),
            Some(m) => {
                return Err(self.fail(
                    m.span(),
                    "simulation.max_steps",
                    format!("max_steps must be positive, got {}", m.get_ref()),
                    "a positive step count, e.g. 100000, or leave it out for no cap",
                ))
            }
            None => None,
        };
        let kernel = match &s.kernel {
            Some(k) => match self.choice(
                k,
                "simulation.kernel",
                &["cubic_spline", "wendland_c2"],
                "kernel",
            )? {
                "wendland_c2" => KernelKind::WendlandC2,
                _ => KernelKind::CubicSpline,
            },
            None => KernelKind::CubicSpline,
        };
        let formulation = match &s.formulation {
            Some(f) => match self.choice(
                f,
                "simulation.formulation",
                &["conventional", "corrected"],
                "formulation",
            )? {
                "corrected" => Formulation::Corrected,
                _ => Formulation::Conventional,
            },
            None => Formulation::Conventional,
        };
        let smoothing_ratio = match &s.smoothing_ratio {
            Some(r) => self.check(
                r,
                "simulation.smoothing_ratio",
                |x| (1.0..=2.0).contains(&x),
                "must be in [1.0, 2.0]",
                "h0 = smoothing_ratio × spacing; 1.2–1.3 is usual (default 1.2)",
            )?,
            None => 1.2,
        };
        let (mut viscosity_alpha, mut viscosity_beta) = (1.0, 2.0);
        let mut viscosity_limiter = crate::physics::viscosity::LIMITER;
        if let Some(v) = &s.viscosity {
            if let Some(a) = &v.alpha {
                viscosity_alpha = self.non_negative(
                    a,
                    "simulation.viscosity.alpha",
                    "Monaghan–Gingold α ≥ 0, typically 1 for impact",
                )?;
            }
            if let Some(b) = &v.beta {
                viscosity_beta = self.non_negative(
                    b,
                    "simulation.viscosity.beta",
                    "Monaghan–Gingold β ≥ 0, typically 2 for impact",
                )?;
            }
            if let Some(k) = &v.limiter {
                viscosity_limiter = self.check(
                    k,
                    "simulation.viscosity.limiter",
                    |x| (0.0..=1.0).contains(&x),
                    "must be in [0, 1]",
                    "the closing speed, as a fraction of the sound speed, below which a pair's \
                     velocity jump is reconstructed and limited (default 0.003; 0: the plain \
                     viscosity)",
                )?;
            }
        }
        let gravity = match &s.gravity {
            Some(g) => self.vector(
                g,
                "simulation.gravity",
                dimension,
                if dimension == 2 {
                    "[0.0, -9.8]"
                } else {
                    "[0.0, 0.0, -9.8]"
                },
            )?,
            None => [0.0; 3],
        };
        let (h_min_ratio, h_max_ratio) = match &s.smoothing_bounds {
            Some(b) => {
                let key = "simulation.smoothing_bounds";
                let help = "[h_min_ratio, h_max_ratio] with 0 < h_min_ratio < 1 < h_max_ratio, e.g. [0.5, 2.0]";
                let v = b.get_ref();
                if v.len() != 2 {
                    return Err(self.fail(
                        b.span(),
                        key,
                        format!("smoothing_bounds has {} values, expected 2", v.len()),
                        help,
                    ));
                }
                if !(v[0].is_finite() && v[1].is_finite() && v[0] > 0.0 && v[0] < 1.0 && v[1] > 1.0)
                {
                    return Err(self.fail(
                        b.span(),
                        key,
                        format!(
                            "smoothing_bounds must satisfy 0 < h_min_ratio < 1 < h_max_ratio, got [{}, {}]",
                            num(v[0]),
                            num(v[1])
                        ),
                        help,
                    ));
                }
                (v[0], v[1])
            }
            None => (0.5, 2.0),
        };
        let smoothing_stretch = match &s.smoothing_stretch {
            Some(r) => self.check(
                r,
                "simulation.smoothing_stretch",
                |x| (1.0..=2.0).contains(&x),
                "must be in [1.0, 2.0]",
                "the most h grows with the material's stretch (default 1.25; 1.0 switches it off)",
            )?,
            None => 1.25,
        };
        let tensor_smoothing = match &s.smoothing_shape {
            Some(k) => {
                let shape = self.choice(
                    k,
                    "simulation.smoothing_shape",
                    &["isotropic", "tensor"],
                    "smoothing shape",
                )?;
                shape == "tensor"
            }
            None => false,
        };
        let density_diffusion = match &s.density_diffusion {
            Some(d) => self.check(
                d,
                "simulation.density_diffusion",
                |x| (0.0..=1.0).contains(&x),
                "must be in [0, 1]",
                "δ of the density diffusion (Molteni & Colagrossi 2009): 0.1 is usual, 0 \
                 switches it off (the default)",
            )?,
            None => 0.0,
        };
        let impact_speed = match &s.impact_speed {
            Some(v) => Some(self.positive(
                v,
                "simulation.impact_speed",
                "an impact speed in m/s, e.g. 7000",
            )?),
            None => None,
        };
        Ok((
            name,
            dimension,
            Simulation {
                end_time,
                cfl,
                max_steps,
                kernel,
                formulation,
                smoothing_ratio,
                viscosity_alpha,
                viscosity_beta,
                viscosity_limiter,
                gravity,
                h_min_ratio,
                h_max_ratio,
                smoothing_stretch,
                density_diffusion,
                tensor_smoothing,
                impact_speed,
            },
        ))
    }

    fn shape(
        &self,
        r: &raw::Shape,
        prefix: &str,
        dim: usize,
        anchor: &Range<usize>,
    ) -> Result<Shape> {
        let types: &[&str] = if dim == 2 {
            &["rectangle", "box", "disc", "ring"]
        } else {
            &["box", "sphere", "cylinder", "ring", "stl"]
        };
        let Some(kind) = &r.kind else {
            return Err(self.missing(
                anchor,
                &format!("{prefix}.type"),
                "which shape",
                &format!("add `type = …`, one of {}", list(types)),
            ));
        };
        let type_key = format!("{prefix}.type");
        let kind_name =
            match kind.get_ref().as_str() {
                "disk" if dim == 2 => "disc",
                "sphere" if dim == 2 => {
                    return Err(self.fail(
                        kind.span(),
                        type_key,
                        "a sphere is a 3D shape, but the deck is 2D",
                        "in 2D use `type = \"disc\"` with center and radius",
                    ))
                }
                "disc" | "disk" | "circle" | "rectangle" if dim == 3 => return Err(self.fail(
                    kind.span(),
                    type_key,
                    format!("a {} is a 2D shape, but the deck is 3D", kind.get_ref()),
                    "in 3D use `type = \"sphere\"` (center, radius) or `type = \"box\"` (min, max)",
                )),
                "cylinder" | "stl" if dim == 2 => {
                    return Err(self.fail(
                        kind.span(),
                        type_key,
                        format!(
                            "a{} {} is a 3D shape, but the deck is 2D",
                            if kind.get_ref() == "stl" { "n" } else { "" },
                            kind.get_ref()
                        ),
                        "in 2D (plane strain) use `type = \"rectangle\"` (min, max)",
                    ))
                }
                _ => self.choice(kind, &type_key, types, &format!("{dim}D shape type"))?,
            };
        let fields = [
            ("min", span_of(&r.min)),
            ("max", span_of(&r.max)),
            ("center", span_of(&r.center)),
            ("radius", span_of(&r.radius)),
            ("base", span_of(&r.base)),
            ("axis", span_of(&r.axis)),
            ("length", span_of(&r.length)),
            ("inner_radius", span_of(&r.inner_radius)),
            ("outer_radius", span_of(&r.outer_radius)),
            ("file", span_of(&r.file)),
            ("scale", span_of(&r.scale)),
            ("rotate", span_of(&r.rotate)),
            ("translate", span_of(&r.translate)),
        ];
        let allowed: &[&str] = match kind_name {
            "box" | "rectangle" => &["type", "min", "max"],
            "sphere" | "disc" => &["type", "center", "radius"],
            "cylinder" => &["type", "base", "axis", "radius", "length"],
            "stl" => &["type", "file", "scale", "rotate", "translate"],
            _ => &["type", "center", "inner_radius", "outer_radius"],
        };
        self.forbid(prefix, &fields, allowed, &format!("a {kind_name} shape"))?;
        let at = kind.span();
        let ex_point = if dim == 2 {
            "[0.0, 0.0]"
        } else {
            "[0.0, 0.0, 0.0]"
        };
        let vec = |v: &Option<S<Vec<f64>>>, name: &str| -> Result<[f64; 3]> {
            let key = format!("{prefix}.{name}");
            match v {
                Some(v) => self.vector(v, &key, dim, ex_point),
                None => Err(self.missing(
                    &at,
                    &key,
                    &format!("a {kind_name} needs {}", list(&allowed[1..])),
                    &format!("add `{name} = {ex_point}` (m)"),
                )),
            }
        };
        let scalar = |v: &Option<S<f64>>, name: &str| -> Result<f64> {
            let key = format!("{prefix}.{name}");
            match v {
                Some(v) => self.positive(v, &key, &format!("the {name} in m, e.g. 3e-4")),
                None => Err(self.missing(
                    &at,
                    &key,
                    &format!("a {kind_name} needs {}", list(&allowed[1..])),
                    &format!("add `{name} = …` (m)"),
                )),
            }
        };
        Ok(match kind_name {
            "stl" => self.stl(r, prefix, &at)?,
            "box" | "rectangle" => {
                let min = vec(&r.min, "min")?;
                let max = vec(&r.max, "max")?;
                if let Some(k) = (0..dim).find(|&k| max[k] <= min[k]) {
                    let span = r.max.as_ref().map_or(at.clone(), |m| m.span());
                    return Err(self.fail(
                        span,
                        format!("{prefix}.max"),
                        format!(
                            "max[{k}] = {} is not greater than min[{k}] = {}",
                            num(max[k]),
                            num(min[k])
                        ),
                        "every component of max must be greater than the same component of min",
                    ));
                }
                Shape::Box { min, max }
            }
            "sphere" | "disc" => Shape::Sphere {
                center: vec(&r.center, "center")?,
                radius: scalar(&r.radius, "radius")?,
            },
            "cylinder" => {
                let base = vec(&r.base, "base")?;
                let axis = vec(&r.axis, "axis")?;
                let norm = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
                if norm == 0.0 || !norm.is_finite() {
                    let span = r.axis.as_ref().map_or(at.clone(), |a| a.span());
                    return Err(self.fail(
                        span,
                        format!("{prefix}.axis"),
                        "the cylinder axis is the zero vector",
                        "give the axis direction, e.g. [0.0, 0.0, 1.0] (it is normalised)",
                    ));
                }
                Shape::Cylinder {
                    base,
                    axis: axis.map(|x| x / norm),
                    radius: scalar(&r.radius, "radius")?,
                    length: scalar(&r.length, "length")?,
                }
            }
            _ => {
                let center = vec(&r.center, "center")?;
                let inner_key = format!("{prefix}.inner_radius");
                let inner = match &r.inner_radius {
                    Some(v) => {
                        self.non_negative(v, &inner_key, "the inner radius in m, e.g. 0.03")?
                    }
                    None => {
                        return Err(self.missing(
                            &at,
                            &inner_key,
                            "a ring needs center, inner_radius and outer_radius",
                            "add `inner_radius = …` (m, 0 for a full disc or ball)",
                        ))
                    }
                };
                let outer = scalar(&r.outer_radius, "outer_radius")?;
                if inner >= outer {
                    let span = r.outer_radius.as_ref().map_or(at.clone(), |o| o.span());
                    return Err(self.fail(
                        span,
                        format!("{prefix}.outer_radius"),
                        format!(
                            "outer_radius {} must be greater than inner_radius {}",
                            num(outer),
                            num(inner)
                        ),
                        "0 <= inner_radius < outer_radius",
                    ));
                }
                Shape::Ring {
                    center,
                    inner_radius: inner,
                    outer_radius: outer,
                }
            }
        })
    }

    /// An STL surface: read, placed and built into its tree here, so that a missing or damaged
    /// file is reported at the deck's `file` key.
    fn stl(&self, r: &raw::Shape, prefix: &str, at: &Range<usize>) -> Result<Shape> {
        use crate::setup::mesh::{Mesh, Placement};
        let file_key = format!("{prefix}.file");
        let Some(file) = &r.file else {
            return Err(self.missing(
                at,
                &file_key,
                "an stl shape needs the surface's file",
                "add `file = \"projectile.stl\"` (ASCII or binary STL; relative to the deck's folder)",
            ));
        };
        let scale = match &r.scale {
            Some(v) => self.positive(
                v,
                &format!("{prefix}.scale"),
                "the factor from the file's units to m, e.g. 1e-3 for mm",
            )?,
            None => 1.0,
        };
        let ex = "[0.0, 0.0, 0.0]";
        let rotate_deg = match &r.rotate {
            Some(v) => self.vector(v, &format!("{prefix}.rotate"), 3, ex)?,
            None => [0.0; 3],
        };
        let translate = match &r.translate {
            Some(v) => self.vector(v, &format!("{prefix}.translate"), 3, ex)?,
            None => [0.0; 3],
        };
        let name = file.get_ref();
        let path = Path::new(self.file)
            .parent()
            .unwrap_or(Path::new(""))
            .join(name);
        let placement = Placement {
            scale,
            rotate_deg,
            translate,
        };
        let mesh = Mesh::read(&path, name, &placement).map_err(|e| {
            self.fail(
                file.span(),
                file_key.clone(),
                format!("{e} (looked for {})", path.display()),
                "give an ASCII or binary STL file, its path relative to the deck's folder",
            )
        })?;
        if mesh.volume == 0.0 {
            return Err(self.fail(
                file.span(),
                file_key,
                format!("the surface in {name} encloses no volume"),
                "give a closed surface (a solid's outer skin)",
            ));
        }
        Ok(Shape::Mesh(std::sync::Arc::new(mesh)))
    }

    fn check_memory(
        &self,
        raw_bodies: &[raw::Located<raw::Body>],
        bodies: &[BodySpec],
        (planes, ghosts): (&[crate::boundary::Plane], f64),
        (dim, corrected, fails): (usize, bool, bool),
        memory: Option<f64>,
    ) -> Result<()> {
        let counts: Vec<f64> = bodies
            .iter()
            .map(|b| estimate_particles(&b.shape, b.spacing, dim, planes))
            .collect();
        let total: f64 = counts.iter().sum();
        // Bytes a particle at this size (the records' share is not quite proportional).
        let per = crate::particles::estimated_bytes(total, ghosts, dim, corrected, fails)
            / total.max(1.0);
        // The particle store numbers particles with u32.
        let limit_count = u32::MAX as f64;
        let limit_memory = memory.map_or(f64::INFINITY, |m| m / per);
        let limit = limit_count.min(limit_memory);
        if total <= limit {
            return Ok(());
        }
        let Some((worst, &n_worst)) = counts.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))
        else {
            return Ok(());
        };
        let body = &bodies[worst];
        let key = format!("body[{worst}].spacing");
        let span = raw_bodies[worst]
            .get_ref()
            .spacing
            .as_ref()
            .map_or(raw_bodies[worst].anchor(), |s| s.span());
        let others = total - n_worst;
        let fit = if others < 0.9 * limit {
            let target = 0.9 * limit - others;
            let s = round_up_2(body.spacing * (n_worst / target).powf(1.0 / dim as f64));
            format!(
                "a spacing of at least {} m for body `{}` would fit (or shrink the shapes)",
                num(s),
                body.name
            )
        } else {
            "the other bodies alone already fill it: coarsen their spacing too".to_string()
        };
        let message = if limit_memory <= limit_count {
            format!(
                "the case would need about {:.2e} particles ({:.2e} in body `{}`), about {} of memory, but only {} is available to this process (free memory, less any cgroup or ulimit limit)",
                total,
                n_worst,
                body.name,
                bytes(total * per),
                bytes(memory.unwrap_or(0.0))
            )
        } else {
            format!(
                "the case would need about {:.2e} particles ({:.2e} in body `{}`), more than the {} particles a run can hold",
                total, n_worst, body.name, u32::MAX
            )
        };
        Err(self.fail(span, key, message, fit))
    }

    /// The index of the body named `name` among `names`, or an error at `key` naming the
    /// bodies (and the likeliest one meant).
    fn body_index(&self, name: &S<String>, names: &[&str], key: &str) -> Result<usize> {
        names
            .iter()
            .position(|b| *b == name.get_ref())
            .ok_or_else(|| {
                self.fail(
                    name.span(),
                    key,
                    format!("unknown body `{}`", name.get_ref()),
                    format!(
                        "{}the bodies are {}",
                        did_you_mean(name.get_ref(), names.iter().copied()),
                        list(names)
                    ),
                )
            })
    }

    /// The `[[prescribed]]` sets: each a body of its own (see [`BodySpec::part_of`]), named
    /// uniquely, its region a shape of the deck's dimension, its velocity (zero by default: held
    /// fixed) in m/s.
    fn prescribed(
        &self,
        raw: Option<&[raw::Located<raw::Prescribed>]>,
        bodies: &[BodySpec],
        body_names: &HashMap<String, Range<usize>>,
        dimension: usize,
    ) -> Result<Vec<BodySpec>> {
        let names: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
        let mut out: Vec<BodySpec> = Vec::new();
        for (k, set) in raw.unwrap_or(&[]).iter().enumerate() {
            let prefix = format!("prescribed[{k}]");
            let anchor = set.anchor();
            let r = set.get_ref();
            let Some(body) = &r.body else {
                return Err(self.missing(
                    &anchor,
                    &format!("{prefix}.body"),
                    "the body whose particles the set takes",
                    &format!("add e.g. `body = \"{}\"`", names[0]),
                ));
            };
            let parent = self.body_index(body, &names, &format!("{prefix}.body"))?;
            let name = match &r.name {
                Some(n) => {
                    let key = format!("{prefix}.name");
                    self.safe_name(n, &key, "a set's name", "\"clamp\"")?;
                    let taken = body_names
                        .get(n.get_ref())
                        .map(|s| self.line_col(s.start).0);
                    let taken = taken.or_else(|| {
                        out.iter()
                            .find(|b| &b.name == n.get_ref())
                            .map(|b| b.location.line)
                    });
                    if let Some(line) = taken {
                        return Err(self.fail(
                            n.span(),
                            key,
                            format!(
                                "duplicate body name `{}` (already used on line {line})",
                                n.get_ref()
                            ),
                            "give the set a name no body or other set has",
                        ));
                    }
                    n.get_ref().clone()
                }
                None => {
                    let mut name = format!("{}_prescribed", names[parent]);
                    let mut count = 1;
                    while body_names.contains_key(&name) || out.iter().any(|b| b.name == name) {
                        count += 1;
                        name = format!("{}_prescribed{count}", names[parent]);
                    }
                    name
                }
            };
            let region_key = format!("{prefix}.region");
            let region = match &r.region {
                Some(s) => self.shape(s, &region_key, dimension, &anchor)?,
                None => {
                    return Err(self.missing(
                        &anchor,
                        &region_key,
                        "the region whose particles of the body the set takes",
                        if dimension == 2 {
                            "add e.g. `region = { type = \"rectangle\", min = [15e-3, -1e-3], max = [17e-3, 0.0] }`"
                        } else {
                            "add e.g. `region = { type = \"box\", min = [0.0, 0.0, -1e-3], max = [5e-3, 5e-3, 0.0] }`"
                        },
                    ))
                }
            };
            let velocity = match &r.velocity {
                Some(v) => {
                    let key = format!("{prefix}.velocity");
                    let example = if dimension == 2 {
                        "[0.0, 10.0]"
                    } else {
                        "[0.0, 0.0, 10.0]"
                    };
                    let velocity = self.vector(v, &key, dimension, example)?;
                    let speed = velocity.iter().fold(0.0_f64, |a, &c| a.hypot(c));
                    if speed >= MAX_SPEED {
                        return Err(self.fail(
                            v.span(),
                            key,
                            format!(
                                "the speed {} m/s is at or beyond {} m/s: the first time step would vanish",
                                num(speed),
                                num(MAX_SPEED)
                            ),
                            "give the set's velocity in m/s, e.g. 10 for a piston",
                        ));
                    }
                    velocity
                }
                None => [0.0; 3],
            };
            out.push(BodySpec {
                name,
                location: self.location(&anchor),
                velocity,
                shape: region,
                motion: Motion::Prescribed,
                part_of: Some(parent),
                ..bodies[parent].clone()
            });
        }
        Ok(out)
    }

    fn interactions(
        &self,
        raw: Option<&[raw::Located<raw::Interaction>]>,
        bodies: &[BodySpec],
    ) -> Result<Vec<InteractionSpec>> {
        let mut out = Vec::new();
        let mut seen: HashMap<(usize, usize), usize> = HashMap::new();
        let names: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
        for (i, it) in raw.unwrap_or(&[]).iter().enumerate() {
            let prefix = format!("interaction[{i}]");
            let anchor = it.anchor();
            let r = it.get_ref();
            let Some(pair) = &r.bodies else {
                return Err(self.missing(
                    &anchor,
                    &format!("{prefix}.bodies"),
                    "the two bodies the interaction is between",
                    &format!(
                        "add e.g. `bodies = [\"{}\", \"{}\"]`",
                        names[0],
                        names.get(1).unwrap_or(&"other")
                    ),
                ));
            };
            if pair.get_ref().len() != 2 {
                return Err(self.fail(
                    pair.span(),
                    format!("{prefix}.bodies"),
                    format!("bodies names {} bodies, expected 2", pair.get_ref().len()),
                    "an interaction is between two distinct bodies, e.g. [\"sphere\", \"plate\"]",
                ));
            }
            let mut idx = [0; 2];
            for (k, n) in pair.get_ref().iter().enumerate() {
                idx[k] = self.body_index(n, &names, &format!("{prefix}.bodies[{k}]"))?;
            }
            if idx[0] == idx[1] {
                return Err(self.fail(
                    pair.span(),
                    format!("{prefix}.bodies"),
                    format!("an interaction of body `{}` with itself", names[idx[0]]),
                    "name two different bodies",
                ));
            }
            let key = (idx[0].min(idx[1]), idx[0].max(idx[1]));
            if let Some(first) = seen.get(&key) {
                return Err(self.fail(
                    pair.span(),
                    format!("{prefix}.bodies"),
                    format!(
                        "bodies `{}` and `{}` already have an interaction (interaction[{first}])",
                        names[key.0], names[key.1]
                    ),
                    "give each pair of bodies at most one [[interaction]]",
                ));
            }
            seen.insert(key, i);
            let kind = match &r.kind {
                Some(k) => self.choice(
                    k,
                    &format!("{prefix}.type"),
                    &["contact", "welded"],
                    "interaction type",
                )?,
                None => "contact",
            };
            let paper_keys = [
                ("stiffness", span_of(&r.stiffness)),
                ("exponent", span_of(&r.exponent)),
            ];
            let kind = if kind == "welded" {
                self.forbid(
                    &prefix,
                    &[
                        ("law", span_of(&r.law)),
                        paper_keys[0].clone(),
                        paper_keys[1].clone(),
                    ],
                    &["bodies", "type"],
                    "a welded interaction",
                )?;
                InteractionKind::Welded
            } else {
                let law = match &r.law {
                    Some(l) => match self.choice(
                        l,
                        &format!("{prefix}.law"),
                        &["colour", "color", "paper"],
                        "contact law",
                    )? {
                        "paper" => ContactLaw::Paper,
                        _ => ContactLaw::Colour,
                    },
                    None => ContactLaw::Colour,
                };
                if law == ContactLaw::Colour {
                    for (name, span) in &paper_keys {
                        if let Some(span) = span {
                            return Err(self.fail(
                                span.clone(),
                                format!("{prefix}.{name}"),
                                format!("`{name}` belongs to the paper's law, but this contact uses the colour law (the default)"),
                                format!("add `law = \"paper\"` to use eq. (5) as printed with this {name}, or remove it: the colour law takes its stiffness from the materials"),
                            ));
                        }
                    }
                }
                InteractionKind::Contact {
                    law,
                    stiffness: match &r.stiffness {
                        Some(k) => Some(self.positive(
                            k,
                            &format!("{prefix}.stiffness"),
                            "the contact stiffness K in Pa, e.g. 1.0e11; leave it out for the default",
                        )?),
                        None => None,
                    },
                    exponent: match &r.exponent {
                        Some(n) => Some(self.check(
                            n,
                            &format!("{prefix}.exponent"),
                            |x| (1.0..=12.0).contains(&x),
                            "must be in [1, 12]",
                            "the contact exponent n, usually 2–6 (4 is Monaghan's)",
                        )?),
                        None => None,
                    },
                }
            };
            out.push(InteractionSpec {
                location: self.location(it.span.as_ref().unwrap_or(&pair.span())),
                bodies: idx,
                kind,
            });
        }
        Ok(out)
    }

    /// The `[[symmetry]]` planes, then the `[[wall]]` ones (a frictionless rigid wall: a
    /// symmetry plane that only pushes, see `boundary`).
    fn symmetry(
        &self,
        (planes, walls): (Option<&[Plane]>, Option<&[Plane]>),
        dim: usize,
    ) -> Result<Vec<SymmetryPlane>> {
        let mut out: Vec<SymmetryPlane> = Vec::new();
        let tables = [(planes, "symmetry", false), (walls, "wall", true)];
        for (raw, table, wall) in tables {
            let what = if wall { "wall" } else { "symmetry plane" };
            for (i, sy) in raw.unwrap_or(&[]).iter().enumerate() {
                let prefix = format!("{table}[{i}]");
                let r = sy.get_ref();
                let Some(axis) = &r.axis else {
                    return Err(self.missing(
                        &sy.anchor(),
                        &format!("{prefix}.axis"),
                        &format!("the normal axis of the {what}"),
                        "add e.g. `axis = \"x\"`",
                    ));
                };
                if dim == 2 && axis.get_ref() == "z" {
                    return Err(self.fail(
                        axis.span(),
                        format!("{prefix}.axis"),
                        format!("a {what} normal to z in a 2D deck"),
                        format!("in 2D (plane strain) the {what}'s axis is `x` or `y`"),
                    ));
                }
                let name = self.choice(axis, &format!("{prefix}.axis"), &AXES[..dim], "axis")?;
                let axis_index = AXES.iter().position(|a| *a == name).unwrap_or(0);
                let position = match &r.position {
                    Some(p) => self.finite(p, &format!("{prefix}.position"))?,
                    None => 0.0,
                };
                if let Some(twice) = out
                    .iter()
                    .find(|p| p.axis == axis_index && p.position == position)
                {
                    let first = if twice.wall {
                        "[[wall]]"
                    } else {
                        "[[symmetry]]"
                    };
                    return Err(self.fail(
                        axis.span(),
                        format!("{prefix}.axis"),
                        format!("the plane {name} = {} is given twice", num(position)),
                        format!("remove this [[{table}]] table or the {first} one"),
                    ));
                }
                out.push(SymmetryPlane {
                    axis: axis_index,
                    position,
                    wall,
                });
            }
        }
        Ok(out)
    }

    fn output(&self, raw: Option<&raw::Located<raw::Output>>, end_time: f64) -> Result<OutputSpec> {
        let mut out = OutputSpec {
            snapshot_interval: None,
            history_every: 10,
            pictures: Vec::new(),
        };
        let Some(o) = raw else {
            return Ok(out);
        };
        let o = o.get_ref();
        if let Some(s) = &o.snapshot_interval {
            let interval = self.positive(
                s,
                "output.snapshot_interval",
                "simulated time between snapshots in s, e.g. 1.0e-8",
            )?;
            let count = end_time / interval;
            if count > MAX_SNAPSHOTS {
                return Err(self.fail(
                    s.span(),
                    "output.snapshot_interval",
                    format!(
                        "snapshot_interval {} s would write {count:.3e} snapshots over end_time = {} s, more than {MAX_SNAPSHOTS} (each holds every particle)",
                        num(interval),
                        num(end_time)
                    ),
                    format!(
                        "use at least end_time / {MAX_SNAPSHOTS} = {} s; e.g. {} s gives 100 snapshots",
                        num(round_sig(end_time / MAX_SNAPSHOTS)),
                        num(round_sig(end_time / 100.0))
                    ),
                ));
            }
            out.snapshot_interval = Some(interval);
        }
        if let Some(h) = &o.history_every {
            if *h.get_ref() < 1 {
                return Err(self.fail(
                    h.span(),
                    "output.history_every",
                    format!("history_every must be at least 1, got {}", h.get_ref()),
                    "a history row every this many steps, e.g. 10",
                ));
            }
            out.history_every = *h.get_ref() as u64;
        }
        for (i, p) in o.picture.as_deref().unwrap_or(&[]).iter().enumerate() {
            let prefix = format!("output.picture[{i}]");
            let r = p.get_ref();
            let Some(times) = r.times.as_ref().filter(|t| !t.get_ref().is_empty()) else {
                let at = r.times.as_ref().map_or(p.anchor(), |t| t.span());
                return Err(self.missing(
                    &at,
                    &format!("{prefix}.times"),
                    "the simulated times of the pictures (none given)",
                    &format!("add e.g. `times = [0.0, {}]`", num(end_time)),
                ));
            };
            let mut ts = Vec::new();
            for (k, t) in times.get_ref().iter().enumerate() {
                ts.push(self.check(
                    t,
                    &format!("{prefix}.times[{k}]"),
                    |x| (0.0..=end_time).contains(&x),
                    &format!("must be in [0, end_time = {}]", num(end_time)),
                    "a picture time between 0 and simulation.end_time (s)",
                )?);
            }
            let normal_axis = match &r.normal {
                Some(n) => {
                    let a = self.choice(n, &format!("{prefix}.normal"), &AXES, "axis")?;
                    AXES.iter().position(|x| *x == a).unwrap_or(1)
                }
                None => 1,
            };
            let position = match &r.position {
                Some(x) => self.finite(x, &format!("{prefix}.position"))?,
                None => 0.0,
            };
            let thickness = match &r.thickness {
                Some(t) => Some(self.positive(
                    t,
                    &format!("{prefix}.thickness"),
                    "the slab thickness in m, e.g. 2e-5; leave it out for one spacing",
                )?),
                None => None,
            };
            let color_by = match &r.color_by {
                Some(c) => match self.choice(
                    c,
                    &format!("{prefix}.color_by"),
                    &[
                        "body",
                        "pressure",
                        "plastic_strain",
                        "damage",
                        "velocity",
                        "density",
                        "von_mises",
                    ],
                    "colouring",
                )? {
                    "pressure" => ColorBy::Pressure,
                    "plastic_strain" => ColorBy::PlasticStrain,
                    "damage" => ColorBy::Damage,
                    "velocity" => ColorBy::Velocity,
                    "density" => ColorBy::Density,
                    "von_mises" => ColorBy::VonMises,
                    _ => ColorBy::Body,
                },
                None => ColorBy::Body,
            };
            out.pictures.push(PictureSpec {
                times: ts,
                normal_axis,
                position,
                thickness,
                color_by,
            });
        }
        Ok(out)
    }
}

/// The shape's smallest size (m) and its name, for the "smaller than the spacing" check.
fn smallest_size(shape: &Shape, dim: usize) -> (f64, &'static str) {
    match shape {
        Shape::Box { min, max } => (
            (0..dim)
                .map(|k| max[k] - min[k])
                .fold(f64::INFINITY, f64::min),
            "smallest side",
        ),
        Shape::Sphere { radius, .. } => (2.0 * radius, "diameter"),
        Shape::Cylinder { radius, length, .. } => (
            (2.0 * radius).min(*length),
            "smallest size (diameter or length)",
        ),
        Shape::Ring {
            inner_radius,
            outer_radius,
            ..
        } => (outer_radius - inner_radius, "wall thickness"),
        Shape::Mesh(m) => (
            (0..3)
                .map(|k| m.max[k] - m.min[k])
                .fold(f64::INFINITY, f64::min),
            "smallest side of the surface's bounding box",
        ),
    }
}

#[cfg(test)]
mod tests;
