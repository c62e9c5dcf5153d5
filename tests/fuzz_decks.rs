//! A deck fuzzer: the example decks mutated at random (seeded, so a failure reproduces) — lines
//! deleted, doubled, swapped or cut short, numbers made zero, negative, huge, tiny, NaN or
//! text, strings changed, keys inserted, garbage typed in. Every mutated deck must give either
//! a clean error (a deck error naming file, line, column and key, or another error with a
//! message) or, for `check` and a run of a few steps, a result — never a panic, never a hang.

// Errors travel by value here as in the library (see lib.rs).
#![allow(clippy::result_large_err)]

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;
use strike::deck::{estimate_case_particles, parse};
use strike::run::{run, RunOptions};
use strike::Error;

/// Decks per test run, and the largest case (estimated particles) that is also run.
const DECKS: usize = 500;
const RUN_LIMIT: f64 = 20_000.0;
/// A case that takes longer than this to check and run three steps has hung.
const HANG: Duration = Duration::from_secs(120);

/// splitmix64: a small, seeded generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

const NUMBERS: [&str; 16] = [
    "0",
    "0.0",
    "-1.0",
    "1e308",
    "-1e308",
    "1e-308",
    "nan",
    "inf",
    "-inf",
    "3",
    "2",
    "\"7\"",
    "[]",
    "true",
    "9223372036854775807",
    "-9223372036854775808",
];
const STRINGS: [&str; 12] = [
    "\"\"",
    "\"x\"",
    "\"sphere\"",
    "\"plate\"",
    "\"box\"",
    "\"al_2024_t4\"",
    "\"welded\"",
    "\"z\"",
    "\"../up\"",
    "\"ünïcode\"",
    "\"a,b\"",
    "1.0",
];
const KEYS: [&str; 14] = [
    "dimension = 2",
    "dimension = 3",
    "smoothing_ratio = 2.0",
    "cfl = 1.0",
    "max_steps = 1",
    "history_every = 1",
    "spacing = 1e-9",
    "pressure_cutoff = -1e9",
    "artificial_stress = 0.3",
    "exponent = 12.0",
    "stiffness = 1e30",
    "axis = \"z\"",
    "position = 1e300",
    "gravity = [0.0, -1e30]",
];

/// The value tokens of a line: (start, end) byte ranges of numbers and quoted strings after
/// an `=` or inside brackets.
fn tokens(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut k = match line.find('=') {
        Some(e) => e + 1,
        None => return out,
    };
    while k < b.len() {
        let c = b[k];
        if c == b'"' {
            let end = line[k + 1..].find('"').map_or(b.len(), |e| k + e + 2);
            out.push((k, end));
            k = end;
        } else if c.is_ascii_digit() || c == b'-' || c == b'.' {
            let start = k;
            while k < b.len() && (b[k].is_ascii_alphanumeric() || b"-+.".contains(&b[k])) {
                k += 1;
            }
            out.push((start, k));
        } else {
            k += 1;
        }
    }
    out
}

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(3) {
        if lines.is_empty() {
            break;
        }
        let i = rng.below(lines.len());
        match rng.below(9) {
            0 => {
                lines.remove(i);
            }
            1 => lines.insert(i, lines[i].clone()),
            2 => {
                let j = rng.below(lines.len());
                lines.swap(i, j);
            }
            3 | 4 => {
                let t = tokens(&lines[i]);
                if !t.is_empty() {
                    let (a, b) = *rng.pick(&t);
                    let old = lines[i][a..b].to_string();
                    let new = if old.starts_with('"') {
                        rng.pick(&STRINGS).to_string()
                    } else {
                        match rng.below(4) {
                            0 => rng.pick(&NUMBERS).to_string(),
                            1 => format!("-{old}"),
                            2 => format!("{old}e{}", rng.below(40) as i64 - 20),
                            _ => format!("{}", rng.below(1000)),
                        }
                    };
                    lines[i].replace_range(a..b, &new);
                }
            }
            5 => lines.insert(i, rng.pick(&KEYS).to_string()),
            6 => {
                let garbage = ["{", "]", "=", "\"", "[[body]]", "[output]", "\u{0}", "é"];
                let at = rng.below(lines[i].len() + 1);
                let at = (0..=at)
                    .rev()
                    .find(|&k| lines[i].is_char_boundary(k))
                    .unwrap_or(0);
                let g: &str = garbage[rng.below(garbage.len())];
                lines[i].insert_str(at, g);
            }
            7 => lines.truncate(i),
            _ => {
                let t = tokens(&lines[i]);
                if let Some(&(a, b)) = t.first() {
                    lines[i].replace_range(a..b, "");
                }
            }
        }
    }
    lines.join("\n")
}

fn examples() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut v: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// What a mutated deck gave.
#[derive(Debug, Default)]
struct Tally {
    deck_errors: usize,
    check_errors: usize,
    run_errors: usize,
    runs: usize,
    too_large: usize,
}

#[test]
fn mutated_decks_give_clean_errors_or_results() {
    let seed: u64 = std::env::var("STRIKE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20261123);
    let mut rng = Rng(seed);
    let bases = examples();
    let out_root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz");
    let _ = std::fs::remove_dir_all(&out_root);
    let mut tally = Tally::default();
    for k in 0..DECKS {
        let (name, base) = rng.pick(&bases);
        let text = mutate(base, &mut rng);
        let file = format!("fuzz{k}_{name}");
        let what = format!("deck {k} (seed {seed}, from {name}):\n{text}");
        let parsed = catch_unwind(|| parse(&text, &file))
            .unwrap_or_else(|_| panic!("parse panicked on {what}"));
        let case = match parsed {
            Ok(case) => case,
            Err(Error::Deck {
                location,
                key,
                message,
                ..
            }) => {
                assert!(
                    location.file == file
                        && location.line >= 1
                        && location.column >= 1
                        && !key.is_empty()
                        && !message.is_empty(),
                    "unlocated deck error {location:?} `{key}`: {message} for {what}"
                );
                tally.deck_errors += 1;
                continue;
            }
            Err(e) => {
                assert!(!e.to_string().is_empty(), "empty error for {what}");
                tally.deck_errors += 1;
                continue;
            }
        };
        let particles: f64 = estimate_case_particles(&case).iter().sum();
        if particles > RUN_LIMIT {
            tally.too_large += 1;
            continue;
        }
        // Check, then three steps with every output, on a thread watched for a hang.
        let out_dir: PathBuf = out_root.join(format!("{k}"));
        let (send, receive) = mpsc::channel();
        let job = case.clone();
        std::thread::spawn(move || {
            let result = catch_unwind(AssertUnwindSafe(|| {
                let checked = strike::check::check(&job).map(|_| ());
                let opts = RunOptions {
                    out_dir,
                    max_steps: Some(3),
                    write_fields: true,
                    overwrite: true,
                    ..Default::default()
                };
                let ran = checked.as_ref().ok().map(|_| run(&job, &opts).map(|_| ()));
                (
                    checked.map_err(|e| e.to_string()),
                    ran.map(|r| r.map_err(|e| e.to_string())),
                )
            }));
            let _ = send.send(result);
        });
        match receive.recv_timeout(HANG) {
            Err(_) => panic!("check and 3 steps took over {HANG:?} on {what}"),
            Ok(Err(_)) => panic!("check or run panicked on {what}"),
            Ok(Ok((checked, ran))) => {
                if let Err(e) = checked {
                    println!("deck {k}: check refused: {e}");
                    assert!(!e.is_empty(), "empty check error on {what}");
                    tally.check_errors += 1;
                }
                match ran {
                    Some(Err(e)) => {
                        println!("deck {k}: run stopped: {e}");
                        assert!(!e.is_empty(), "empty run error on {what}");
                        tally.run_errors += 1;
                    }
                    Some(Ok(())) => tally.runs += 1,
                    None => {}
                }
            }
        }
    }
    println!("{DECKS} mutated decks (seed {seed}): {tally:?}");
    // The mutations must reach every stage, or the fuzzer tests little.
    assert!(tally.deck_errors > DECKS / 4, "{tally:?}");
    assert!(tally.runs > DECKS / 10, "{tally:?}");
    let _ = std::fs::remove_dir_all(&out_root);
}
