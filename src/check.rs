//! `strike check`: what a deck will do, before running it — and the closing text of a run.

use crate::case::Case;
use crate::error::{Error, Result};
use crate::output::summary::Summary;
use crate::particles::estimated_bytes_per_particle;
use crate::physics::PairRule;
use crate::simulation::Simulation;
use std::fmt::Write;

/// Planning figure for the run-time estimate (particle-steps per second per core), a round
/// figure below what `strike bench` measures on one core of the 2-core reference machine.
pub const PLANNING_PARTICLE_STEPS_PER_CORE: f64 = 5.0e5;

/// Validate a case fully (set it up and take one step) and describe it.
pub fn check(case: &Case) -> Result<String> {
    match case.dimension {
        2 => check_dim::<2>(case),
        3 => check_dim::<3>(case),
        d => Err(Error::Invalid(format!("dimension {d} is not 2 or 3"))),
    }
}

fn check_dim<const D: usize>(case: &Case) -> Result<String> {
    let mut sim = Simulation::<D>::new(case)?;
    let p = &sim.particles;
    let n = p.n_real;
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "case '{}' ({}, {}D{})",
        case.name,
        case.file,
        D,
        if D == 2 { ", plane strain" } else { "" }
    );
    let _ = writeln!(w, "bodies:");
    let mut warnings = Vec::new();
    for (b, body) in case.bodies.iter().enumerate() {
        let count = p.body.iter().filter(|&&x| x as usize == b).count();
        let mat = &sim.model.materials[body.material];
        let _ = writeln!(
            w,
            "  {:<16} {:>9} particles  spacing {:.4e} m  h0 {:.4e} m  material {} (ρ0 {} kg/m³, c {:.0} m/s)  |v0| {:.4e} m/s{}",
            body.name,
            count,
            body.spacing,
            body.spacing * case.simulation.smoothing_ratio,
            mat.name,
            mat.rho0,
            mat.sound_speed0(),
            body.velocity.iter().map(|v| v * v).sum::<f64>().sqrt(),
            if body.motion == crate::case::Motion::Prescribed { "  (prescribed motion)" } else { "" }
        );
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
                "symmetry plane {}={} touches no body: it has no effect",
                ["x", "y", "z"][pl.axis],
                pl.position
            ));
        }
    }
    if case.output.snapshot_interval.is_none() {
        warnings.push(
            "no [output] snapshot_interval: only the first and last snapshots are written".into(),
        );
    }
    let d = sim.step(f64::INFINITY)?;
    let steps = (case.simulation.end_time / d.dt).ceil();
    let bytes = n as f64 * estimated_bytes_per_particle(D) as f64;
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get()) as f64;
    let seconds = steps * n as f64 / (PLANNING_PARTICLE_STEPS_PER_CORE * cores);
    let _ = writeln!(
        w,
        "particles: {n}   mean neighbours: {:.1}",
        d.interactions as f64 / n as f64
    );
    let _ = writeln!(
        w,
        "first time step: {:.4e} s  → about {:.0} steps to {:.4e} s (contact may shorten it)",
        d.dt, steps, case.simulation.end_time
    );
    let _ = writeln!(w, "estimated memory: {:.1} MB", bytes / 1e6);
    let _ = writeln!(
        w,
        "estimated run time: {} on {} cores (planning figure {:.0e} particle-steps/s per core)",
        human_seconds(seconds),
        cores,
        PLANNING_PARTICLE_STEPS_PER_CORE
    );
    if let Some(g) = d.min_interbody_distance {
        let _ = writeln!(
            w,
            "bodies start within contact range: closest pair at {g:.3} Δp_avg"
        );
    }
    if warnings.is_empty() {
        let _ = writeln!(w, "no warnings");
    } else {
        for wn in warnings {
            let _ = writeln!(w, "warning: {wn}");
        }
    }
    Ok(s)
}

/// The closing text of a run.
pub fn summary_text(s: &Summary) -> String {
    format!(
        "{}: {} particles, {} steps to t = {:.4e} s in {} ({:.3e} particle-steps/s, {:.3e} interactions/s, {} threads)\n\
         energy error {:.3e}, momentum error {:.3e}, min inter-body distance {}",
        s.status,
        s.particles,
        s.steps,
        s.end_time,
        human_seconds(s.wall_seconds),
        s.particle_steps_per_second,
        s.interactions_per_second,
        s.threads,
        s.energy_error,
        s.momentum_error,
        s.min_interbody_distance.map_or("— (no contact)".to_string(), |g| format!("{g:.3} Δp"))
    )
}

fn human_seconds(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}
