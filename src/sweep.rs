//! Parameter sweeps and ballistic limits: one deck run at many values of its numeric keys.
//!
//! A key is named by its path in the deck: tables and keys by name, a `[[body]]` (or any array
//! of tables) by its `name` or its index (`body.sphere.velocity`, `body[1].spacing`,
//! `materials.al.density`, `simulation.end_time`), a vector's component by its index
//! (`body.sphere.velocity[2]`). A number given for a whole vector sets its magnitude and keeps
//! its direction: `body.sphere.velocity=5000` is a 5 km/s impact along the deck's direction.
//! The edited deck goes through the deck reader like any other, so a value out of range is the
//! reader's clear error.
//!
//! **Outcomes** (per run; [`Outcome`]): the projectile is the body named (`--projectile`, or the
//! fastest body at the start), its line of flight n̂ its initial direction, and the target's
//! rear face the farthest point of every other body along n̂ at the start. The target's main
//! piece is the heaviest set of its unfailed particles connected to each other (the plate and
//! its clamp; not a plug, not debris). At the end time, the projectile's material beyond the
//! rear face with none of the main piece ahead of it is "through" — a bulge that still holds
//! the projectile lies ahead of it, a hole does not; its mass (a fraction of the projectile's)
//! and its mean velocity along n̂ are the residual mass and velocity. The target counts as
//! **perforated** when at least [`THROUGH_MASS`] of the projectile (or of its debris) is
//! through and moving on at more than [`THROUGH_SPEED`] of the impact speed. The end time must
//! let the outcome settle: a projectile still tearing its way out is not yet through.
//!
//! **Ballistic limit** ([`ballistic_limit`]): the impact speed is bracketed by a speed that does
//! not perforate and one that does, then the bracket is cut in J + 1 parts at each round, J the
//! runs done at once (`--jobs`; bisection for one), until it is narrower than the tolerance.
//! The result is the bracket with the runs that bound it: a limit is only known to lie between
//! two runs.

use crate::case::Case;
use crate::error::{Error, Result};
use crate::output::{atomic, picture};
use crate::particles::{to3, Particles};
use crate::simulation::Simulation;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A run perforates when at least this fraction of the projectile's mass is through...
pub const THROUGH_MASS: f64 = 0.05;
/// ...and moving on at more than this fraction of the impact speed.
pub const THROUGH_SPEED: f64 = 0.05;

/// One swept key and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    pub key: String,
    pub values: Vec<f64>,
}

/// `KEY=VALUES`, VALUES a list `a,b,c` or a range `a:b:n` (n values from a to b, both
/// included).
pub fn parse_setting(arg: &str) -> Result<Setting> {
    let Some((key, values)) = arg.split_once('=') else {
        return Err(Error::Invalid(format!(
            "--set {arg}: expected KEY=VALUES, e.g. body.sphere.velocity=5000,6000,7000 or body.sphere.velocity=4000:8000:5"
        )));
    };
    let key = key.trim();
    if key.is_empty() {
        return Err(Error::Invalid(format!("--set {arg}: the key is empty")));
    }
    Ok(Setting {
        key: key.to_string(),
        values: parse_values(values.trim())
            .map_err(|m| Error::Invalid(format!("--set {arg}: {m}")))?,
    })
}

/// `a,b,c` or `a:b:n`.
pub fn parse_values(text: &str) -> std::result::Result<Vec<f64>, String> {
    let number = |s: &str| -> std::result::Result<f64, String> {
        match s.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(format!("`{}` is not a finite number", s.trim())),
        }
    };
    if let Some((a, rest)) = text.split_once(':') {
        let Some((b, n)) = rest.split_once(':') else {
            return Err("a range is start:stop:count, e.g. 4000:8000:5".into());
        };
        let (a, b) = (number(a)?, number(b)?);
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("the count `{}` is not a whole number", n.trim()))?;
        if n < 2 {
            return Err("a range needs a count of at least 2".into());
        }
        if n > 10_000 {
            return Err(format!("a range of {n} runs is more than 10 000"));
        }
        return Ok((0..n)
            .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
            .collect());
    }
    let values = text
        .split(',')
        .map(number)
        .collect::<std::result::Result<Vec<_>, _>>()?;
    if values.is_empty() {
        return Err("no values".into());
    }
    Ok(values)
}

/// One segment of a key path: a name, and an index (`velocity[2]`, `body[1]`).
fn segments(key: &str) -> std::result::Result<Vec<(String, Option<usize>)>, String> {
    key.split('.')
        .map(|seg| {
            let seg = seg.trim();
            let (name, index) = match seg.split_once('[') {
                Some((name, rest)) => {
                    let k = rest
                        .strip_suffix(']')
                        .and_then(|k| k.trim().parse::<usize>().ok())
                        .ok_or_else(|| {
                            format!(
                                "`{seg}`: an index is a whole number in brackets, e.g. velocity[2]"
                            )
                        })?;
                    (name, Some(k))
                }
                None => (seg, None),
            };
            if name.is_empty() {
                return Err(format!("`{key}` has an empty part"));
            }
            Ok((name.to_string(), index))
        })
        .collect()
}

/// The deck `text` with `key` set to `value` (see the module doc).
pub fn set_key(text: &str, key: &str, value: f64) -> Result<String> {
    let fail = |m: String| Error::Invalid(format!("--set {key}: {m}"));
    let mut doc: toml::Table = text
        .parse()
        .map_err(|e| fail(format!("the deck is not valid TOML: {e}")))?;
    let segs = segments(key).map_err(fail)?;
    set_in(&mut doc, &segs, value, "").map_err(fail)?;
    toml::to_string(&doc).map_err(|e| fail(format!("cannot write the deck: {e}")))
}

type Segment = (String, Option<usize>);

/// Sets the key `segs` (non-empty) below table `t`, whose own path is `path`.
fn set_in(
    t: &mut toml::Table,
    segs: &[Segment],
    value: f64,
    path: &str,
) -> std::result::Result<(), String> {
    let Some(((name, index), rest)) = segs.split_first() else {
        return Err("the key is empty".into());
    };
    if rest.is_empty() && index.is_none() && !t.contains_key(name) {
        // A key the deck leaves at its default: add it (the reader checks it is one).
        t.insert(name.clone(), toml::Value::Float(value));
        return Ok(());
    }
    let mut path = if path.is_empty() {
        name.clone()
    } else {
        format!("{path}.{name}")
    };
    let mut v = t
        .get_mut(name)
        .ok_or_else(|| format!("the deck has no `{path}`"))?;
    if let Some(k) = index {
        let toml::Value::Array(a) = v else {
            return Err(format!("`{path}` is not a list, it has no [{k}]"));
        };
        let len = a.len();
        v = a
            .get_mut(*k)
            .ok_or_else(|| format!("`{path}` has {len} entries, no [{k}]"))?;
        path = format!("{path}[{k}]");
    }
    if rest.is_empty() {
        return set_value(v, value, &path);
    }
    match v {
        toml::Value::Table(inner) => set_in(inner, rest, value, &path),
        // An array of tables ([[body]]) is entered by the next segment's name.
        toml::Value::Array(a) if is_table_array(a) => {
            let want = &rest[0].0;
            let named = |t: &toml::Value| t.get("name").and_then(|s| s.as_str()).map(String::from);
            let Some(k) = a
                .iter()
                .position(|t| named(t).as_deref() == Some(want.as_str()))
            else {
                let names: Vec<String> = a.iter().filter_map(named).collect();
                return Err(format!(
                    "no `{path}` is named `{want}` (the names are {})",
                    names.join(", ")
                ));
            };
            let path = format!("{path}.{want}");
            if rest.len() == 1 {
                return Err(format!("`{path}` is a table, not a number"));
            }
            match &mut a[k] {
                toml::Value::Table(inner) => set_in(inner, &rest[1..], value, &path),
                _ => Err(format!("`{path}` is not a table")),
            }
        }
        _ => Err(format!("`{path}` is a value, not a table")),
    }
}

fn is_table_array(a: &[toml::Value]) -> bool {
    !a.is_empty() && a.iter().all(|v| v.is_table())
}

/// Sets a number, or a vector's magnitude.
fn set_value(v: &mut toml::Value, value: f64, path: &str) -> std::result::Result<(), String> {
    match v {
        toml::Value::Float(x) => *x = value,
        toml::Value::Integer(x) => {
            if value.fract() != 0.0 || value.abs() > 9.0e15 {
                return Err(format!("`{path}` takes whole numbers, not {value}"));
            }
            *x = value as i64;
        }
        toml::Value::Array(a) => {
            let comps: Option<Vec<f64>> = a
                .iter()
                .map(|c| c.as_float().or_else(|| c.as_integer().map(|i| i as f64)))
                .collect();
            let Some(comps) = comps else {
                return Err(format!("`{path}` is not a list of numbers"));
            };
            let norm = comps.iter().map(|c| c * c).sum::<f64>().sqrt();
            if norm == 0.0 {
                return Err(format!(
                    "`{path}` is the zero vector: a magnitude needs a direction; set a component instead, e.g. {path}[2]"
                ));
            }
            *a = comps
                .iter()
                .map(|c| toml::Value::Float(c / norm * value))
                .collect();
        }
        _ => return Err(format!("`{path}` is not a number")),
    }
    Ok(())
}

/// What a run gave (see the module doc).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Outcome {
    /// "completed", "max_steps", or the instability's message.
    pub status: String,
    pub end_time: f64,
    pub steps: u64,
    /// Largest |E − E0|/E0 over the run.
    pub energy_error: f64,
    /// Largest pressure any particle had (Pa).
    pub peak_pressure: f64,
    /// Failed particles at the end.
    pub failed: usize,
    /// The projectile's through mass over its mass, and their mean velocity along n̂ (m/s; NaN
    /// when none is through).
    pub residual_mass_fraction: f64,
    pub residual_velocity: f64,
    pub perforated: bool,
}

/// The body that counts as the projectile: `name`, or the fastest body at the start.
pub fn projectile(case: &Case, name: Option<&str>) -> Result<usize> {
    let names: Vec<&str> = case.bodies.iter().map(|b| b.name.as_str()).collect();
    if let Some(n) = name {
        return names.iter().position(|b| *b == n).ok_or_else(|| {
            Error::Invalid(format!(
                "no body is named `{n}` (the bodies are {})",
                names.join(", ")
            ))
        });
    }
    let speed = |k: usize| case.bodies[k].velocity.iter().map(|c| c * c).sum::<f64>();
    (0..case.bodies.len())
        .max_by(|&a, &b| speed(a).total_cmp(&speed(b)))
        .ok_or_else(|| Error::Invalid("the deck has no body".into()))
}

/// Runs the case to its end time (or step cap) and measures its outcome for `body`.
pub fn simulate(case: &Case, body: usize) -> Result<Outcome> {
    match case.dimension {
        2 => simulate_dim::<2>(case, body),
        _ => simulate_dim::<3>(case, body),
    }
}

fn simulate_dim<const D: usize>(case: &Case, body: usize) -> Result<Outcome> {
    let v0 = case.bodies[body].velocity;
    let speed = v0.iter().map(|c| c * c).sum::<f64>().sqrt();
    let dir = v0.map(|c| if speed > 0.0 { c / speed } else { 0.0 });
    let mut sim = Simulation::<D>::new(case)?;
    let rear = rear_face(&sim.particles, body as u32, dir);
    let reach = BLOCK_REACH * case.bodies.iter().map(|b| b.spacing).fold(0.0, f64::max);
    let end = case.simulation.end_time;
    let cap = case.simulation.max_steps.unwrap_or(u64::MAX);
    let (mut e0, mut energy_error, mut peak) = (None, 0.0_f64, 0.0_f64);
    let mut status = "completed".to_string();
    while sim.state.time < end * (1.0 - 1e-12) {
        if sim.state.step >= cap {
            status = "max_steps".into();
            break;
        }
        match sim.step(end - sim.state.time) {
            Ok(d) => {
                let e0 = *e0.get_or_insert(d.total);
                if e0 != 0.0 {
                    energy_error = energy_error.max((d.total - e0).abs() / e0.abs());
                }
                peak = peak.max(d.max_pressure);
            }
            Err(e) => {
                status = format!("unstable: {e}");
                break;
            }
        }
    }
    let p = &sim.particles;
    let (fraction, velocity) = through(p, body as u32, dir, rear, reach);
    Ok(Outcome {
        status,
        end_time: sim.state.time,
        steps: sim.state.step,
        energy_error,
        peak_pressure: peak,
        failed: (0..p.n_real).filter(|&i| p.damage[i] >= 1.0).count(),
        residual_mass_fraction: fraction,
        residual_velocity: velocity,
        perforated: speed > 0.0 && fraction >= THROUGH_MASS && velocity > THROUGH_SPEED * speed,
    })
}

/// The farthest point of every body but `body` along `dir` (−∞ if none).
fn rear_face<const D: usize>(p: &Particles<D>, body: u32, dir: [f64; 3]) -> f64 {
    (0..p.n_real)
        .filter(|&i| p.body[i] != body)
        .map(|i| dot3(to3(&p.x[i]), dir))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A particle of the target's main piece within this many spacings sideways of the line of
/// flight, and ahead, blocks the way.
const BLOCK_REACH: f64 = 1.5;

/// The fraction of `body`'s mass that is through the target, and its mean velocity along
/// `dir` (NaN if none): beyond the target's initial rear face `rear`, with no particle of the
/// target's main piece ([`main_piece`]: the plate and its clamp, not a plug or debris) ahead of
/// it within `reach` sideways: a bulge still holding the projectile lies ahead of it, a hole
/// does not.
fn through<const D: usize>(
    p: &Particles<D>,
    body: u32,
    dir: [f64; 3],
    rear: f64,
    reach: f64,
) -> (f64, f64) {
    let main = main_piece(p, body);
    // The main piece seen along the line of flight: the farthest point ahead in each cell of
    // the plane across it.
    let across = |x: [f64; 3]| -> [i64; 3] {
        let s = dot3(x, dir);
        let lateral = [0, 1, 2].map(|k| x[k] - s * dir[k]);
        lateral.map(|c| (c / reach).floor() as i64)
    };
    let mut ahead: std::collections::HashMap<[i64; 3], f64> = std::collections::HashMap::new();
    for &j in &main {
        let x = to3(&p.x[j]);
        let e = ahead.entry(across(x)).or_insert(f64::NEG_INFINITY);
        *e = e.max(dot3(x, dir));
    }
    let blocked = |x: [f64; 3]| -> bool {
        let c = across(x);
        let s = dot3(x, dir);
        let r = |k: usize| if D == 2 && k == 2 { 0 } else { 1 };
        for a in -r(0)..=r(0) {
            for b in -r(1)..=r(1) {
                for d in -r(2)..=r(2) {
                    if ahead
                        .get(&[c[0] + a, c[1] + b, c[2] + d])
                        .is_some_and(|&far| far > s)
                    {
                        return true;
                    }
                }
            }
        }
        false
    };
    let (mut total, mut mass, mut momentum) = (0.0, 0.0, 0.0);
    for i in (0..p.n_real).filter(|&i| p.body[i] == body) {
        total += p.m[i];
        let x = to3(&p.x[i]);
        if dot3(x, dir) > rear && !blocked(x) {
            mass += p.m[i];
            momentum += p.m[i] * dot3(to3(&p.v[i]), dir);
        }
    }
    let velocity = if mass > 0.0 {
        momentum / mass
    } else {
        f64::NAN
    };
    (if total > 0.0 { mass / total } else { 0.0 }, velocity)
}

/// The heaviest set of unfailed particles of the bodies other than `body` that hold together:
/// connected through pairs within the kernel's support, r < h_i + h_j, as the SPH sums connect
/// them (union–find over a grid of cells 2 h_max wide).
fn main_piece<const D: usize>(p: &Particles<D>, body: u32) -> Vec<usize> {
    let members: Vec<usize> = (0..p.n_real)
        .filter(|&i| p.body[i] != body && p.damage[i] < 1.0)
        .collect();
    let size = 2.0 * members.iter().map(|&i| p.h[i]).fold(0.0, f64::max);
    if size <= 0.0 {
        return members;
    }
    let cell = |i: usize| to3(&p.x[i]).map(|c| (c / size).floor() as i64);
    let mut grid: std::collections::HashMap<[i64; 3], Vec<usize>> =
        std::collections::HashMap::new();
    for (k, &i) in members.iter().enumerate() {
        grid.entry(cell(i)).or_default().push(k);
    }
    let mut parent: Vec<usize> = (0..members.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for (k, &i) in members.iter().enumerate() {
        let c = cell(i);
        for a in -1..=1 {
            for b in -1..=1 {
                for d in -1..=1 {
                    let Some(others) = grid.get(&[c[0] + a, c[1] + b, c[2] + d]) else {
                        continue;
                    };
                    for &l in others {
                        let j = members[l];
                        if l > k && (p.x[i] - p.x[j]).norm() < p.h[i] + p.h[j] {
                            let (ra, rb) = (root(&mut parent, k), root(&mut parent, l));
                            if ra != rb {
                                parent[ra.max(rb)] = ra.min(rb);
                            }
                        }
                    }
                }
            }
        }
    }
    let mut mass = vec![0.0; members.len()];
    for (k, &i) in members.iter().enumerate() {
        let r = root(&mut parent, k);
        mass[r] += p.m[i];
    }
    let Some(heaviest) = (0..members.len()).max_by(|&a, &b| mass[a].total_cmp(&mass[b])) else {
        return Vec::new();
    };
    (0..members.len())
        .filter(|&k| root(&mut parent, k) == heaviest)
        .map(|k| members[k])
        .collect()
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A ballistic limit: the bracket and every run made to find it, by speed.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BallisticLimit {
    /// The fastest run that did not perforate and the slowest that did (m/s).
    pub below: f64,
    pub above: f64,
    /// (speed, outcome) of every run, by speed.
    pub runs: Vec<(f64, Outcome)>,
    /// Whether a slower run perforated while a faster one did not (the bracket is then the
    /// lowest perforating run's).
    pub non_monotonic: bool,
}

/// Brackets the speed between `lo` (must not perforate) and `hi` (must), cutting the bracket
/// until it is narrower than `tolerance`; `outcomes` runs a set of speeds (at once, if it can)
/// and returns their outcomes in the same order.
pub fn ballistic_limit(
    lo: f64,
    hi: f64,
    tolerance: f64,
    per_round: usize,
    mut outcomes: impl FnMut(&[f64]) -> Result<Vec<Outcome>>,
) -> Result<BallisticLimit> {
    if !(lo > 0.0 && hi > lo && tolerance > 0.0) {
        return Err(Error::Invalid(format!(
            "the speeds must satisfy 0 < low < high and the tolerance be positive (got {lo}, {hi}, {tolerance})"
        )));
    }
    let mut runs: Vec<(f64, Outcome)> = Vec::new();
    let ends = outcomes(&[lo, hi])?;
    runs.extend([lo, hi].into_iter().zip(ends));
    if runs[0].1.perforated {
        return Err(Error::Invalid(format!(
            "the slowest speed, {lo} m/s, already perforates: give a lower one"
        )));
    }
    if !runs[1].1.perforated {
        return Err(Error::Invalid(format!(
            "the fastest speed, {hi} m/s, does not perforate (residual mass {:.3}, velocity {:.1} m/s at the end time): give a higher one, or a later end time",
            runs[1].1.residual_mass_fraction, runs[1].1.residual_velocity
        )));
    }
    let (mut below, mut above) = (lo, hi);
    let mut non_monotonic = false;
    let j = per_round.max(1);
    while above - below > tolerance {
        let speeds: Vec<f64> = (1..=j)
            .map(|k| below + (above - below) * k as f64 / (j + 1) as f64)
            .collect();
        let got = outcomes(&speeds)?;
        // The first perforating speed bounds from above, the one before it from below.
        let mut row: Vec<(f64, bool)> = vec![(below, false)];
        row.extend(speeds.iter().zip(&got).map(|(&s, o)| (s, o.perforated)));
        row.push((above, true));
        let first = row.iter().position(|r| r.1).unwrap_or(row.len() - 1);
        if row[first..].iter().any(|r| !r.1) {
            non_monotonic = true;
        }
        (below, above) = (row[first - 1].0, row[first].0);
        runs.extend(speeds.into_iter().zip(got));
    }
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(BallisticLimit {
        below,
        above,
        runs,
        non_monotonic,
    })
}

/// How a sweep runs and where it writes.
#[derive(Debug, Clone)]
pub struct SweepOptions {
    pub out_dir: PathBuf,
    /// Runs at once, and the threads they share.
    pub jobs: usize,
    pub threads: usize,
    /// The projectile's name (None: the fastest body).
    pub projectile: Option<String>,
    /// Replace an earlier sweep's files in `out_dir`.
    pub overwrite: bool,
}

/// Every combination of the settings' values, the first key varying slowest.
pub fn combinations(settings: &[Setting]) -> Vec<Vec<f64>> {
    settings.iter().fold(vec![Vec::new()], |acc, s| {
        acc.iter()
            .flat_map(|head| {
                s.values.iter().map(move |&v| {
                    let mut row = head.clone();
                    row.push(v);
                    row
                })
            })
            .collect()
    })
}

/// The deck `text` (read from `file`, which names it in errors and anchors relative paths)
/// with every key of `keys` set to its value, read and validated.
pub fn edited_case(text: &str, file: &str, keys: &[(&str, f64)]) -> Result<Case> {
    let mut t = text.to_string();
    for &(k, v) in keys {
        t = set_key(&t, k, v)?;
    }
    let shown: Vec<String> = keys.iter().map(|(k, v)| format!("{k} = {v}")).collect();
    crate::deck::parse(&t, file).map_err(|e| match e {
        Error::Deck { key, message, .. } => Error::Invalid(format!(
            "{file} with {}: `{key}`: {message}",
            shown.join(", ")
        )),
        other => other,
    })
}

/// Runs the cases (each with its projectile), `jobs` at a time, each on its share of the
/// threads; the outcomes in the cases' order. A case's results do not depend on its threads.
pub fn run_many(
    cases: &[(Case, usize)],
    jobs: usize,
    threads: usize,
    mut done: impl FnMut(usize, &Result<Outcome>) + Send,
) -> Vec<Result<Outcome>> {
    let jobs = jobs.clamp(1, cases.len().max(1));
    let per_job = (threads / jobs).max(1);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<Outcome>>>> =
        Mutex::new((0..cases.len()).map(|_| None).collect());
    let report = Mutex::new(&mut done);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(per_job).build();
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    if k >= cases.len() {
                        break;
                    }
                    let (case, body) = &cases[k];
                    let out = match &pool {
                        Ok(pool) => pool.install(|| simulate(case, *body)),
                        Err(e) => Err(Error::Invalid(format!("cannot start threads: {e}"))),
                    };
                    if let Ok(mut f) = report.lock() {
                        (*f)(k, &out);
                    }
                    if let Ok(mut r) = results.lock() {
                        r[k] = Some(out);
                    }
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err(Error::Invalid("a run did not finish".into()))))
        .collect()
}

/// A line for the log: what a run gave.
pub fn describe(o: &Outcome) -> String {
    if o.status.starts_with("unstable") {
        return o.status.clone();
    }
    format!(
        "{}; through {:.1} % of the projectile at {:.1} m/s; peak pressure {:.3} GPa; {} failed; energy {:.2} %",
        if o.perforated { "perforated" } else { "not perforated" },
        100.0 * o.residual_mass_fraction,
        o.residual_velocity,
        o.peak_pressure / 1e9,
        o.failed,
        100.0 * o.energy_error
    )
}

/// The outcome columns of the tables, after the swept keys.
const OUTCOME_COLUMNS: [&str; 9] = [
    "status",
    "end_time_s",
    "steps",
    "energy_error",
    "peak_pressure_pa",
    "failed_particles",
    "residual_mass_fraction",
    "residual_velocity_m_s",
    "perforated",
];

fn outcome_fields(o: &Outcome) -> Vec<String> {
    vec![
        o.status.clone(),
        format!("{:e}", o.end_time),
        o.steps.to_string(),
        format!("{:e}", o.energy_error),
        format!("{:e}", o.peak_pressure),
        o.failed.to_string(),
        format!("{:e}", o.residual_mass_fraction),
        if o.residual_velocity.is_finite() {
            format!("{:e}", o.residual_velocity)
        } else {
            String::new()
        },
        o.perforated.to_string(),
    ]
}

/// Writes a table: a header of `keys` and the outcome columns, one row per run.
fn write_table(path: &Path, keys: &[&str], rows: &[(Vec<f64>, Outcome)]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| Error::Invalid(format!("{}: {e}", path.display()));
    let mut header: Vec<String> = vec!["run".into()];
    header.extend(keys.iter().map(|k| k.to_string()));
    header.extend(OUTCOME_COLUMNS.iter().map(|c| c.to_string()));
    w.write_record(&header).map_err(csv_err)?;
    for (k, (values, o)) in rows.iter().enumerate() {
        let mut rec = vec![k.to_string()];
        rec.extend(values.iter().map(|v| format!("{v}")));
        rec.extend(outcome_fields(o));
        w.write_record(&rec).map_err(csv_err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
    atomic::write(path, &bytes)
}

/// Refuses to overwrite an earlier sweep's table unless asked to.
fn prepare(opts: &SweepOptions, table: &str) -> Result<()> {
    let path = opts.out_dir.join(table);
    if path.exists() && !opts.overwrite {
        return Err(Error::Invalid(format!(
            "{} exists (an earlier sweep): give another --out, or --overwrite",
            path.display()
        )));
    }
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| Error::io(&opts.out_dir, e))
}

/// A sweep: every combination of the settings, run and tabulated (`sweep.csv`) and plotted
/// against the first key (`sweep.png`, one line per combination of the others).
pub fn sweep(
    text: &str,
    file: &str,
    settings: &[Setting],
    opts: &SweepOptions,
) -> Result<Vec<(Vec<f64>, Outcome)>> {
    prepare(opts, "sweep.csv")?;
    let keys: Vec<&str> = settings.iter().map(|s| s.key.as_str()).collect();
    let combos = combinations(settings);
    let mut cases = Vec::new();
    for values in &combos {
        let pairs: Vec<(&str, f64)> = keys.iter().copied().zip(values.iter().copied()).collect();
        let case = edited_case(text, file, &pairs)?;
        let body = projectile(&case, opts.projectile.as_deref())?;
        cases.push((case, body));
    }
    let total = cases.len();
    let outcomes = run_many(&cases, opts.jobs, opts.threads, |k, o| {
        let set: Vec<String> = keys
            .iter()
            .zip(&combos[k])
            .map(|(key, v)| format!("{key} = {v}"))
            .collect();
        match o {
            Ok(o) => tracing::info!(
                "run {}/{total} ({}): {}",
                k + 1,
                set.join(", "),
                describe(o)
            ),
            Err(e) => tracing::warn!("run {}/{total} ({}): {e}", k + 1, set.join(", ")),
        }
    });
    let rows: Vec<(Vec<f64>, Outcome)> = combos
        .into_iter()
        .zip(outcomes)
        .map(|(v, o)| o.map(|o| (v, o)))
        .collect::<Result<_>>()?;
    write_table(&opts.out_dir.join("sweep.csv"), &keys, &rows)?;
    plot_sweep(&opts.out_dir.join("sweep.png"), &keys, &rows)?;
    Ok(rows)
}

/// The outcomes against the first key, one line per combination of the other keys.
fn plot_sweep(path: &Path, keys: &[&str], rows: &[(Vec<f64>, Outcome)]) -> Result<()> {
    let mut xs: Vec<f64> = rows.iter().map(|r| r.0[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let mut groups: Vec<Vec<f64>> = Vec::new();
    for r in rows {
        if !groups.contains(&r.0[1..].to_vec()) {
            groups.push(r.0[1..].to_vec());
        }
    }
    let label = |g: &[f64]| -> String {
        if g.is_empty() {
            "runs".into()
        } else {
            keys[1..]
                .iter()
                .zip(g)
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let labels: Vec<String> = groups.iter().map(|g| label(g)).collect();
    let column = |f: &dyn Fn(&Outcome) -> f64| -> Vec<picture::Series<'_>> {
        groups
            .iter()
            .zip(&labels)
            .map(|(g, name)| {
                let values = xs
                    .iter()
                    .map(|&x| {
                        rows.iter()
                            .find(|r| r.0[0] == x && r.0[1..] == g[..])
                            .map_or(f64::NAN, |r| f(&r.1))
                    })
                    .collect();
                (name.as_str(), values)
            })
            .collect()
    };
    let panels = vec![
        ("residual velocity (m/s)", column(&|o| o.residual_velocity)),
        (
            "through (fraction of mass)",
            column(&|o| o.residual_mass_fraction),
        ),
        ("peak pressure (GPa)", column(&|o| o.peak_pressure / 1e9)),
        ("failed particles", column(&|o| o.failed as f64)),
    ];
    picture::plot_lines(path, keys[0], &xs, &panels, true)
}

/// The ballistic limit of the projectile `body` between `speeds` (low, high) to `tolerance`
/// (m/s), its runs tabulated (`ballistic_limit.csv`), plotted (residual velocity against
/// impact speed, `ballistic_limit.png`) and summed up (`ballistic_limit.json`).
pub fn ballistic(
    text: &str,
    file: &str,
    body: &str,
    speeds: (f64, f64),
    tolerance: f64,
    opts: &SweepOptions,
) -> Result<BallisticLimit> {
    prepare(opts, "ballistic_limit.csv")?;
    let key = format!("body.{body}.velocity");
    // The body must exist and move: its velocity is scaled.
    let first = edited_case(text, file, &[(&key, speeds.0)])?;
    let index = projectile(&first, Some(body))?;
    let mut round = 0;
    let limit = ballistic_limit(speeds.0, speeds.1, tolerance, opts.jobs, |vs| {
        round += 1;
        let cases = vs
            .iter()
            .map(|&v| edited_case(text, file, &[(&key, v)]).map(|c| (c, index)))
            .collect::<Result<Vec<_>>>()?;
        let outs = run_many(&cases, opts.jobs, opts.threads, |k, o| match o {
            Ok(o) => tracing::info!("round {round}, {:.1} m/s: {}", vs[k], describe(o)),
            Err(e) => tracing::warn!("round {round}, {:.1} m/s: {e}", vs[k]),
        });
        outs.into_iter().collect()
    })?;
    let rows: Vec<(Vec<f64>, Outcome)> = limit
        .runs
        .iter()
        .map(|(v, o)| (vec![*v], o.clone()))
        .collect();
    write_table(
        &opts.out_dir.join("ballistic_limit.csv"),
        &["impact_speed_m_s"],
        &rows,
    )?;
    let xs: Vec<f64> = limit.runs.iter().map(|r| r.0).collect();
    let split = |perforated: bool| -> Vec<f64> {
        limit
            .runs
            .iter()
            .map(|(_, o)| {
                if o.perforated == perforated {
                    o.residual_velocity.max(0.0)
                } else {
                    f64::NAN
                }
            })
            .collect()
    };
    let (through, held) = (split(true), split(false));
    // The runs that held count at zero residual velocity.
    let held: Vec<f64> = held
        .iter()
        .map(|v| if v.is_finite() { 0.0 } else { *v })
        .collect();
    let panels = vec![(
        "residual velocity (m/s)",
        vec![("perforated", through), ("held", held)],
    )];
    picture::plot_lines(
        &opts.out_dir.join("ballistic_limit.png"),
        "impact speed (m/s)",
        &xs,
        &panels,
        true,
    )?;
    let json = serde_json::to_string_pretty(&limit)
        .map_err(|e| Error::Invalid(format!("ballistic_limit.json: {e}")))?;
    atomic::write(
        &opts.out_dir.join("ballistic_limit.json"),
        (json + "\n").as_bytes(),
    )?;
    Ok(limit)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DECK: &str = r#"
[simulation]
end_time = 1.0e-6
history_every = 5

[[body]]
name = "sphere"
spacing = 2.0e-5
velocity = [0.0, 3.0, -4.0]

[[body]]
name = "plate"
spacing = 2.0e-5
"#;

    #[test]
    fn values_from_lists_and_ranges() {
        assert_eq!(parse_values("1,2.5,4").unwrap(), vec![1.0, 2.5, 4.0]);
        assert_eq!(
            parse_values("100:200:5").unwrap(),
            vec![100.0, 125.0, 150.0, 175.0, 200.0]
        );
        assert!(parse_values("1,x").is_err());
        assert!(parse_values("1:2").is_err());
        assert!(parse_values("1:2:1").is_err());
        assert!(parse_values("nan").is_err());
        let s = parse_setting("body.sphere.velocity = 1:3:3").unwrap();
        assert_eq!(s.key, "body.sphere.velocity");
        assert_eq!(s.values, vec![1.0, 2.0, 3.0]);
        assert!(parse_setting("velocity").is_err());
    }

    fn get(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    #[test]
    fn keys_by_name_index_and_component() {
        // A vector's magnitude, direction kept.
        let t = get(&set_key(DECK, "body.sphere.velocity", 10.0).unwrap());
        let v = t["body"][0]["velocity"].as_array().unwrap();
        let v: Vec<f64> = v.iter().map(|c| c.as_float().unwrap()).collect();
        assert_eq!(v, vec![0.0, 6.0, -8.0]);
        // A component, by index and by name.
        let t = get(&set_key(DECK, "body[1].spacing", 1e-5).unwrap());
        assert_eq!(t["body"][1]["spacing"].as_float(), Some(1e-5));
        let t = get(&set_key(DECK, "body.sphere.velocity[2]", -7.0).unwrap());
        assert_eq!(t["body"][0]["velocity"][2].as_float(), Some(-7.0));
        // Tables, integers, and a key left at its default.
        let t = get(&set_key(DECK, "simulation.end_time", 2e-6).unwrap());
        assert_eq!(t["simulation"]["end_time"].as_float(), Some(2e-6));
        let t = get(&set_key(DECK, "simulation.history_every", 10.0).unwrap());
        assert_eq!(t["simulation"]["history_every"].as_integer(), Some(10));
        let t = get(&set_key(DECK, "simulation.cfl", 0.2).unwrap());
        assert_eq!(t["simulation"]["cfl"].as_float(), Some(0.2));
        // Mistakes, each with its reason.
        let err = |k: &str, v: f64| set_key(DECK, k, v).unwrap_err().to_string();
        assert!(err("body.rod.velocity", 1.0).contains("sphere, plate"));
        assert!(err("body[5].spacing", 1.0).contains("no [5]"));
        assert!(err("simulation.history_every", 2.5).contains("whole numbers"));
        assert!(err("body.plate.velocity[0]", 1.0).contains("no `body.plate.velocity`"));
        assert!(err("simulation.end_time.x", 1.0).contains("not a table"));
    }

    fn outcome(perforated: bool) -> Outcome {
        Outcome {
            status: "completed".into(),
            end_time: 1.0,
            steps: 1,
            energy_error: 0.0,
            peak_pressure: 0.0,
            failed: 0,
            residual_mass_fraction: if perforated { 1.0 } else { 0.0 },
            residual_velocity: f64::NAN,
            perforated,
        }
    }

    /// Against a known limit, 437 m/s: the bracket holds it and is narrower than the
    /// tolerance, with one run per round (bisection) and with three.
    #[test]
    fn the_bracket_closes_on_a_known_limit() {
        for per_round in [1, 3] {
            let mut calls = 0;
            let got = ballistic_limit(100.0, 1000.0, 5.0, per_round, |speeds| {
                calls += 1;
                assert!(speeds.len() <= per_round.max(2));
                Ok(speeds.iter().map(|&s| outcome(s > 437.0)).collect())
            })
            .unwrap();
            assert!(got.below <= 437.0 && got.above > 437.0, "{got:?}");
            assert!(got.above - got.below <= 5.0);
            assert!(!got.non_monotonic);
            assert!(got.runs.windows(2).all(|w| w[0].0 <= w[1].0));
            println!(
                "{per_round} a round: {calls} rounds, {} runs",
                got.runs.len()
            );
        }
        // A bracket that does not hold the limit is refused.
        let never = |s: &[f64]| Ok(s.iter().map(|_| outcome(false)).collect());
        assert!(ballistic_limit(100.0, 200.0, 5.0, 1, never)
            .unwrap_err()
            .to_string()
            .contains("does not perforate"));
        let always = |s: &[f64]| Ok(s.iter().map(|_| outcome(true)).collect());
        assert!(ballistic_limit(100.0, 200.0, 5.0, 1, always)
            .unwrap_err()
            .to_string()
            .contains("already perforates"));
    }
}
