//! `strike check`: what a deck will do, before running it — and the closing text of a run.
//!
//! Everything is first estimated from the deck alone, before anything is allocated: particles
//! per body (shape volume / spacing^D), memory, the first time step (from the materials' sound
//! speeds and the bodies' speeds), steps, run time, snapshots and their disk volume. A case of
//! at most [`SET_UP_LIMIT`] particles is then set up and takes one step, for exact counts and
//! the exact first step; a larger one is described by the estimates alone, so that checking
//! ten million particles takes no longer than checking ten thousand.

use crate::case::{Case, Motion};
use crate::deck::estimate_case_particles;
use crate::error::{Error, Result};
use crate::material::Material;
use crate::output::summary::Summary;
use crate::particles::estimated_bytes;
use crate::physics::PairRule;
use crate::simulation::Simulation;
use std::fmt::Write;

/// Planning figure for the run-time estimate (particle-steps per second per core), a round
/// figure below what `strike bench` measures on one core of the 2-core reference machine.
pub const PLANNING_PARTICLE_STEPS_PER_CORE: f64 = 5.0e5;

/// CN-SPH's pass with its correction pass costs about twice conventional SPH's per
/// particle-step (`strike bench`, cubes_3d_cn against cubes_3d: 48 %).
pub const CN_COST: f64 = 2.0;

/// `check` sets a case up (and takes one step) only up to this many estimated particles.
pub const SET_UP_LIMIT: f64 = 1.0e6;

/// A body whose particles' mass misses its shape's (volume × ρ0, on the model's side of the
/// symmetry planes) by more than this share gets a warning: each particle carries ρ0 Δp^D, so
/// a coarse lattice's count is the body's mass, and a projectile's mass is what an impact
/// scales with. Set past the share a symmetry plane's sampled cut can be off
/// (`setup::shapes::model_share`: about a sample's width in 48 of the body's).
pub const MASS_WARNING: f64 = 0.05;

/// A run longer than this (s) gets a warning.
const LONG_RUN: f64 = 86_400.0;

/// Snapshots a run will write and what they take on disk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputPlan {
    /// Snapshots, the first and the last included.
    pub snapshots: u64,
    /// Bytes of one snapshot (.vtp).
    pub snapshot_bytes: f64,
    /// Bytes of the checkpoint (rewritten with every snapshot).
    pub checkpoint_bytes: f64,
    /// All snapshots plus the checkpoint twice (the new one is written beside the old).
    pub total_bytes: f64,
}

/// The snapshots of a case of `n` particles: one per interval (at most one per step, so the
/// count is an upper bound), plus the first and the last.
pub fn output_plan(case: &Case, n: usize) -> OutputPlan {
    let end = case.simulation.end_time;
    let by_interval = case
        .output
        .snapshot_interval
        .map_or(0.0, |i| (end / i).floor());
    let snapshots = (by_interval + 2.0).min(u64::MAX as f64) as u64;
    let snapshot_bytes = crate::output::vtk::snapshot_bytes(n) as f64;
    // The particle fields as the checkpoint writes them: 272 bytes a particle in 2D, 360 in 3D.
    let checkpoint_bytes = n as f64 * if case.dimension == 2 { 272.0 } else { 360.0 };
    OutputPlan {
        snapshots,
        snapshot_bytes,
        checkpoint_bytes,
        total_bytes: snapshots as f64 * snapshot_bytes + 2.0 * checkpoint_bytes,
    }
}

/// The first time step estimated from the deck: C h0 / (c (1 + 0.6 α) + v) for each body, with
/// c its material's reference sound speed and v the largest speed relative to another body
/// (the bodies meet at it). Returns the step and the body that sets it.
pub fn estimated_first_step(case: &Case) -> (f64, usize) {
    let s = &case.simulation;
    let mats: Vec<Material> = case.materials.iter().map(Material::from_spec).collect();
    let speed =
        |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    case.bodies
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let c = mats[b.material].sound_speed0();
            let v = case
                .bodies
                .iter()
                .map(|o| speed(&b.velocity, &o.velocity))
                .fold(0.0, f64::max);
            let h = s.smoothing_ratio * b.spacing;
            (s.cfl() * h / (c * (1.0 + 0.6 * s.viscosity_alpha) + v), i)
        })
        .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a })
}

/// Validate a case and describe it (see the module doc).
pub fn check(case: &Case) -> Result<String> {
    let estimated = estimate_case_particles(case);
    let total: f64 = estimated.iter().sum();
    let (dt, body) = estimated_first_step(case);
    if !(dt.is_finite() && dt > 0.0) {
        let b = &case.bodies[body];
        let speed = b.velocity.iter().map(|v| v * v).sum::<f64>().sqrt();
        return Err(Error::Invalid(format!(
            "the first time step would be {dt:e} s, so the run could not advance: body '{}' (spacing {:e} m, speed {speed:e} m/s) sets it; check its velocity, spacing and material",
            b.name, b.spacing
        )));
    }
    if total > SET_UP_LIMIT {
        return Ok(describe_estimated(case, &estimated, dt));
    }
    match case.dimension {
        2 => check_dim::<2>(case),
        3 => check_dim::<3>(case),
        d => Err(Error::Invalid(format!("dimension {d} is not 2 or 3"))),
    }
}

/// The lines every check prints after the bodies: steps, memory, run time, outputs, warnings.
fn plan_lines(case: &Case, n: f64, dt: f64, w: &mut String, warnings: &mut Vec<String>) {
    let steps = (case.simulation.end_time / dt).ceil();
    let corrected = case.simulation.formulation == crate::case::Formulation::Corrected;
    let planes = crate::setup::symmetry_planes(case);
    let ratio = case.simulation.smoothing_ratio;
    let ghosts = crate::deck::estimate_ghosts(&case.bodies, case.dimension, &planes, ratio);
    let bytes = estimated_bytes(n, ghosts, case.dimension, corrected, case.may_fail());
    let cores = crate::machine::cores() as f64;
    let per_core = match case.simulation.formulation {
        crate::case::Formulation::Conventional => PLANNING_PARTICLE_STEPS_PER_CORE,
        crate::case::Formulation::Corrected => PLANNING_PARTICLE_STEPS_PER_CORE / CN_COST,
    };
    let seconds = steps * n / (per_core * cores);
    let _ = writeln!(
        w,
        "first time step: {dt:.4e} s  → about {steps:.0} steps to {:.4e} s (contact may shorten it)",
        case.simulation.end_time
    );
    for (plane, spec) in planes.iter().zip(&case.symmetry) {
        let walled: Vec<&str> = (0..case.bodies.len())
            .filter(|&b| !spec.wall && plane.wall.is_some_and(|x| x.walls(b as u32)))
            .map(|b| case.bodies[b].name.as_str())
            .collect();
        if !walled.is_empty() {
            let _ = writeln!(
                w,
                "symmetry plane {} = {}: '{}' {} across it and {} it as a frictionless wall (a twin impact: the mirror image parts where it would pull)",
                ["x", "y", "z"][plane.axis],
                plane.position,
                walled.join("', '"),
                if walled.len() == 1 { "moves" } else { "move" },
                if walled.len() == 1 { "meets" } else { "meet" }
            );
        }
    }
    let _ = write!(w, "estimated memory: {}", human_bytes(bytes));
    if case.may_fail() {
        // The crack lists (`physics::CrackLists`: the index of each failed neighbour, each
        // severed pair from both sides, and 13 bytes a particle) grow with the share that
        // fails, which the deck does not tell.
        let _ = write!(
            w,
            " (materials that fail: the crack lists add 4 bytes for each failed neighbour in a particle's support and 16 for each pair a crack severs, about 25 bytes a particle where 6 % of the particles have failed)"
        );
    }
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "estimated run time: {} on {} cores (planning figure {:.0e} particle-steps/s per core)",
        human_seconds(seconds),
        cores,
        per_core
    );
    if seconds > LONG_RUN {
        warnings.push(format!(
            "the run would take about {} on this machine ({:.0} steps of {n:.3e} particles): coarsen the spacing, shorten end_time, or run on more cores",
            human_seconds(seconds),
            steps
        ));
    }
    let plan = output_plan(case, n as usize);
    let shown = plan.snapshots.min(steps as u64 + 1);
    let volume = shown as f64 * plan.snapshot_bytes + 2.0 * plan.checkpoint_bytes;
    let _ = writeln!(
        w,
        "snapshots: {shown} of about {} each, {} in all with the checkpoint ({})",
        human_bytes(plan.snapshot_bytes),
        human_bytes(volume),
        match case.output.snapshot_interval {
            Some(i) => format!("every {i:e} s"),
            None => "first and last only".into(),
        }
    );
    let default_out = std::path::Path::new("runs").join(&case.name);
    if let Some(free) = default_out
        .ancestors()
        .find(|p| p.exists() || p.as_os_str().is_empty())
        .and_then(|p| {
            fs4::available_space(if p.as_os_str().is_empty() {
                std::path::Path::new(".")
            } else {
                p
            })
            .ok()
        })
    {
        if volume > free as f64 {
            warnings.push(format!(
                "the snapshots would take {}, more than the {} free on the disk holding {}: `run` refuses this; raise snapshot_interval or free disk space",
                human_bytes(volume),
                human_bytes(free as f64),
                default_out.display()
            ));
        }
    }
    if let Some(i) = case.output.snapshot_interval {
        if i < dt && plan.snapshots > steps as u64 + 1 {
            warnings.push(format!(
                "snapshot_interval {i:e} s is shorter than the time step ({dt:.3e} s): one snapshot per step will be written, about {shown}"
            ));
        }
    } else {
        warnings.push(
            "no [output] snapshot_interval: only the first and last snapshots are written".into(),
        );
    }
}

/// A case too large to set up for a check, from the deck's figures alone.
fn describe_estimated(case: &Case, estimated: &[f64], dt: f64) -> String {
    let mut s = String::new();
    let w = &mut s;
    let total: f64 = estimated.iter().sum();
    header(case, w);
    let _ = writeln!(
        w,
        "bodies (estimated: the case is too large for check to set up; `run` does):"
    );
    for (body, count) in case.bodies.iter().zip(estimated) {
        let count = match body.part_of {
            Some(of) => format!("a prescribed set of '{}'", case.bodies[of].name),
            None => format!("~{count:>9.3e} particles"),
        };
        let _ = writeln!(
            w,
            "  {:<16} {count}  spacing {:.4e} m  h0 {:.4e} m  material {}",
            body.name,
            body.spacing,
            body.spacing * case.simulation.smoothing_ratio,
            case.materials[body.material].name
        );
    }
    let _ = writeln!(w, "particles: ~{total:.3e}");
    let mut warnings = Vec::new();
    plan_lines(case, total, dt, w, &mut warnings);
    warning_lines(w, warnings);
    s
}

fn header(case: &Case, w: &mut String) {
    let _ = writeln!(
        w,
        "case '{}' ({}, {}D{}, {})",
        case.name,
        case.file,
        case.dimension,
        if case.dimension == 2 {
            ", plane strain"
        } else {
            ""
        },
        match case.simulation.formulation {
            crate::case::Formulation::Conventional => "conventional SPH",
            crate::case::Formulation::Corrected => "CN-SPH (corrected gradients)",
        }
    );
}

fn warning_lines(w: &mut String, warnings: Vec<String>) {
    if warnings.is_empty() {
        let _ = writeln!(w, "no warnings");
    } else {
        for wn in warnings {
            let _ = writeln!(w, "warning: {wn}");
        }
    }
}

fn check_dim<const D: usize>(case: &Case) -> Result<String> {
    let mut sim = Simulation::<D>::new(case)?;
    let p = &sim.particles;
    let n = p.n_real;
    let mut s = String::new();
    let w = &mut s;
    header(case, w);
    let _ = writeln!(w, "bodies:");
    let mut warnings = Vec::new();
    let shapes = estimate_case_particles(case);
    let mut counts = vec![0usize; case.bodies.len()];
    for &x in &p.body {
        if let Some(c) = counts.get_mut(x as usize) {
            *c += 1;
        }
    }
    for (b, body) in case.bodies.iter().enumerate() {
        let count = counts[b];
        let mat = &sim.model.materials[body.material];
        let mass = count as f64 * mat.rho0 * body.spacing.powi(D as i32);
        // A body's lattice holds its prescribed sets' particles too; a set has no shape of its
        // own to weigh against.
        let whole: usize = (0..case.bodies.len())
            .filter(|&s| s == b || case.bodies[s].part_of == Some(b))
            .map(|s| counts[s])
            .sum();
        let excess = whole as f64 / shapes[b] - 1.0;
        let share = match body.part_of {
            Some(of) => format!("(a prescribed set of '{}')", case.bodies[of].name),
            None if whole > count => {
                format!("({:+.1} % of its shape's, with its sets)", 100.0 * excess)
            }
            None => format!("({:+.1} % of its shape's)", 100.0 * excess),
        };
        let _ = writeln!(
            w,
            "  {:<16} {:>9} particles  spacing {:.4e} m  h0 {:.4e} m  material {} (ρ0 {} kg/m³, c {:.0} m/s)  |v0| {:.4e} m/s  mass {:.4e} {} {share}{}",
            body.name,
            count,
            body.spacing,
            body.spacing * case.simulation.smoothing_ratio,
            mat.name,
            mat.rho0,
            mat.sound_speed0(),
            body.velocity.iter().map(|v| v * v).sum::<f64>().sqrt(),
            mass,
            if D == 2 { "kg/m" } else { "kg" },
            if body.motion == Motion::Prescribed { "  (prescribed motion)" } else { "" }
        );
        if body.part_of.is_none() && excess.abs() > MASS_WARNING {
            warnings.push(format!(
                "body '{}' carries {:+.1} % of its shape's mass: its {count} particles at spacing {:e} m for a volume of {:.1} spacings^{D}: the lattice at this spacing does not hold the shape's volume; a finer spacing (or, for a box, sides that are whole multiples of it) brings the mass nearer",
                body.name,
                100.0 * excess,
                body.spacing,
                shapes[b]
            ));
        }
    }
    let nb = case.bodies.len();
    if nb > 1 {
        let _ = writeln!(w, "interactions:");
        for a in 0..nb {
            for b in a + 1..nb {
                let (na, nbn) = (&case.bodies[a].name, &case.bodies[b].name);
                match sim.model.pairs.rule(a as u32, b as u32) {
                    PairRule::Conserve => {
                        let _ = writeln!(w, "  {na} – {nbn}: welded (conventional SPH)");
                    }
                    // Only between a body and a wall's image (never two real bodies).
                    PairRule::Wall => {}
                    PairRule::Contact(c) => {
                        let explicit = case.interactions.iter().any(|i| {
                            (i.bodies == [a, b] || i.bodies == [b, a])
                                && matches!(
                                    i.kind,
                                    crate::case::InteractionKind::Contact {
                                        stiffness: Some(_),
                                        ..
                                    }
                                )
                        });
                        let _ = writeln!(
                            w,
                            "  {na} – {nbn}: contact, K = {:.4e} Pa{}, n = {}, Δp_avg = {:.4e} m",
                            c.stiffness,
                            if explicit { "" } else { " (default)" },
                            c.exponent,
                            c.spacing
                        );
                        let (da, db) = (case.bodies[a].spacing, case.bodies[b].spacing);
                        if da.max(db) > 2.0 * da.min(db) {
                            warnings.push(format!("bodies '{na}' and '{nbn}' are in contact with spacings {da:e} and {db:e} m, more than 2× apart: the contact layer is uneven; use similar spacings"));
                        }
                    }
                }
            }
        }
    }
    for pl in &sim.symmetry {
        let touching = (0..n).any(|i| pl.depth(p.x[i][pl.axis]) < 2.0 * p.h[i]);
        if !touching {
            warnings.push(format!(
                "{} {}={} touches no body: it has no effect",
                if pl.wall.is_some() {
                    "wall"
                } else {
                    "symmetry plane"
                },
                ["x", "y", "z"][pl.axis],
                pl.position
            ));
        }
    }
    let d = match sim.step(f64::INFINITY) {
        Ok(d) => d,
        Err(Error::Unstable { cause, .. }) => {
            return Err(Error::Invalid(format!(
                "the case cannot start: its first step fails: {cause}"
            )))
        }
        Err(e) => return Err(e),
    };
    let _ = writeln!(
        w,
        "particles: {n}   mean neighbours: {:.1}",
        d.interactions as f64 / n as f64
    );
    plan_lines(case, n as f64, d.dt, w, &mut warnings);
    if let Some(g) = d.min_interbody_distance {
        let _ = writeln!(
            w,
            "bodies start within contact range: closest pair at {g:.3} Δp_avg"
        );
    }
    warning_lines(w, warnings);
    Ok(s)
}

/// The closing text of a run.
pub fn summary_text(s: &Summary) -> String {
    format!(
        "{} ({}): {} particles, {} steps to t = {:.4e} s in {} ({:.3e} particle-steps/s, {:.3e} interactions/s, {} threads)\n\
         energy error {:.3e}, momentum error {:.3e}, min inter-body distance {}{}",
        s.status,
        s.reason,
        s.particles,
        s.steps,
        s.end_time,
        human_seconds(s.wall_seconds),
        s.particle_steps_per_second,
        s.interactions_per_second,
        s.threads,
        s.energy_error,
        s.momentum_error,
        s.min_interbody_distance.map_or("— (no contact)".to_string(), |g| format!("{g:.3} Δp")),
        s.mixing
            .iter()
            .map(|m| format!(
                "\n{} – {}: deepest penetration {:.3} Δp, at most {} particles mixed",
                m.bodies[0], m.bodies[1], m.max_penetration, m.max_mixed
            ))
            .collect::<String>()
    )
}

/// Seconds in the largest unit that keeps them readable.
pub fn human_seconds(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 3.0 * 86_400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86_400.0)
    }
}

/// A byte count in decimal units (kB, MB, GB, TB).
pub fn human_bytes(b: f64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = b;
    let mut unit = 0;
    while v >= 1000.0 && unit + 1 < UNITS.len() {
        v /= 1000.0;
        unit += 1;
    }
    format!("{v:.1} {}", UNITS[unit])
}
