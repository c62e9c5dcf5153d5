//! One run of a case, start to end: the time loop of [`Simulation`] with everything a user
//! sees around it — snapshots (.vtp + .pvd), `history.csv`, cross-section pictures, the history
//! plot, `summary.json`, a progress bar or log lines. Output reads particles, never changes them.

use crate::case::{Case, ColorBy, PictureSpec};
use crate::error::{Error, Result};
use crate::output::history::{History, HistoryWriter};
use crate::output::picture::{self, SectionFrame};
use crate::output::summary::Summary;
use crate::output::vtk::{self, PvdWriter};
use crate::simulation::{Diagnostics, Simulation};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output directory (created).
    pub out_dir: PathBuf,
    /// Show a progress bar (on a terminal) instead of log lines.
    pub progress: bool,
    /// Stop after this many steps (overrides the deck's max_steps when smaller).
    pub max_steps: Option<u64>,
    /// Write snapshots, pictures and plots (false: history and summary only, for tests).
    pub write_fields: bool,
}

/// Run a case; the summary is also written to `summary.json`. A run that goes unstable writes
/// its last good snapshot and a summary whose `status` gives the cause, then returns the error.
pub fn run(case: &Case, opts: &RunOptions) -> Result<Summary> {
    match case.dimension {
        2 => run_dim::<2>(case, opts),
        3 => run_dim::<3>(case, opts),
        d => Err(Error::Invalid(format!("dimension {d} is not 2 or 3"))),
    }
}

/// Running totals for the summary.
struct Tally {
    /// Momentum components that no symmetry plane acts on (a plane pushes along its normal).
    conserved: [bool; 3],
    e0: Option<f64>,
    p0: [f64; 3],
    energy_scale: f64,
    energy_dev: f64,
    gravity0: f64,
    momentum_dev: f64,
    momentum_scale: f64,
    min_gap: Option<f64>,
    interactions: u128,
    last: Diagnostics,
}

impl Tally {
    fn add(&mut self, d: &Diagnostics) {
        let e0 = *self.e0.get_or_insert(d.total);
        if self.last.time == 0.0 && self.interactions == 0 {
            self.p0 = d.momentum;
            self.gravity0 = d.gravity;
            self.momentum_scale = d.momentum_scale;
        }
        self.energy_scale = self
            .energy_scale
            .max(d.kinetic + d.internal.abs() + d.contact + (d.gravity - self.gravity0).abs());
        self.energy_dev = self.energy_dev.max((d.total - e0).abs());
        let dp: f64 = (0..3)
            .filter(|&k| self.conserved[k])
            .map(|k| (d.momentum[k] - self.p0[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        self.momentum_dev = self.momentum_dev.max(dp);
        if let Some(g) = d.min_interbody_distance {
            self.min_gap = Some(self.min_gap.map_or(g, |m: f64| m.min(g)));
        }
        self.interactions += d.interactions as u128;
        self.last = d.clone();
    }
}

fn run_dim<const D: usize>(case: &Case, opts: &RunOptions) -> Result<Summary> {
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut sim = Simulation::<D>::new(case)?;
    let n = sim.particles.n_real;
    let end = case.simulation.end_time;
    let max_steps = match (case.simulation.max_steps, opts.max_steps) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };

    let mut history = HistoryWriter::create(&out.join("history.csv"), &sim.body_names)?;
    let mut pvd = PvdWriter::new(&out.join(format!("{}.pvd", case.name)));
    let mut last_snapshot = None;
    let mut snapshot = |sim: &Simulation<D>, pvd: &mut PvdWriter| -> Result<()> {
        if !opts.write_fields || last_snapshot == Some(sim.step) {
            return Ok(());
        }
        last_snapshot = Some(sim.step);
        let name = format!("{}_{:06}.vtp", case.name, sim.step);
        vtk::write_snapshot(&out.join(&name), &sim.particles, sim.time)?;
        pvd.add(sim.time, &name)
    };
    snapshot(&sim, &mut pvd)?;

    // Output events: snapshot times and picture times; steps are shortened to land on them.
    let interval = case.output.snapshot_interval;
    let mut next_snapshot = interval.unwrap_or(f64::INFINITY);
    let mut picture_times: Vec<(usize, f64)> = case
        .output
        .pictures
        .iter()
        .enumerate()
        .flat_map(|(k, p)| p.times.iter().map(move |&t| (k, t)))
        .collect();
    picture_times.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut frames: Vec<Vec<SectionFrame>> = vec![Vec::new(); case.output.pictures.len()];
    let thickness = |spec: &PictureSpec| {
        spec.thickness.unwrap_or_else(|| {
            case.bodies
                .iter()
                .map(|b| b.spacing)
                .fold(f64::INFINITY, f64::min)
        })
    };
    let tol = 1e-9 * end;
    let mut take_pictures = |sim: &Simulation<D>, pending: &mut Vec<(usize, f64)>| {
        while let Some(&(k, t)) = pending.first() {
            if t > sim.time + tol {
                break;
            }
            let spec = &case.output.pictures[k];
            frames[k].push(picture::extract_section(
                &sim.particles,
                sim.time,
                spec,
                thickness(spec),
            ));
            pending.remove(0);
        }
    };
    take_pictures(&sim, &mut picture_times);

    let mut conserved = [true; 3];
    for plane in &case.symmetry {
        conserved[plane.axis] = false;
    }
    let mut tally = Tally {
        conserved,
        e0: None,
        p0: [0.0; 3],
        energy_scale: 0.0,
        energy_dev: 0.0,
        gravity0: 0.0,
        momentum_dev: 0.0,
        momentum_scale: 0.0,
        min_gap: None,
        interactions: 0,
        last: Diagnostics::default(),
    };
    let bar = opts.progress.then(|| progress_bar(end));
    let start = Instant::now();
    let mut last_log = Instant::now();
    let mut status = "completed".to_string();
    let mut failure = None;

    while sim.time < end - tol && max_steps.is_none_or(|m| sim.step < m) {
        let mut next_event = end.min(next_snapshot);
        if let Some(&(_, t)) = picture_times.first() {
            next_event = next_event.min(t);
        }
        let d = match sim.step((next_event - sim.time).max(tol)) {
            Ok(d) => d,
            Err(e) => {
                status = format!("unstable: {e}");
                // The particles are still at the last good state: keep it on disk.
                snapshot(&sim, &mut pvd)?;
                failure = Some(e);
                break;
            }
        };
        tally.add(&d);
        if (sim.step - 1) % case.output.history_every == 0 {
            history.row(&d)?;
        }
        if sim.time >= next_snapshot - tol {
            snapshot(&sim, &mut pvd)?;
            while next_snapshot <= sim.time + tol {
                next_snapshot += interval.unwrap_or(f64::INFINITY);
            }
        }
        take_pictures(&sim, &mut picture_times);
        let wall = start.elapsed().as_secs_f64();
        let rate = n as f64 * sim.step as f64 / wall.max(1e-9);
        if let Some(bar) = &bar {
            bar.set_position((sim.time / end * 1000.0) as u64);
            bar.set_message(format!(
                "t = {:.4e} s, step {}, {:.3e} particle-steps/s",
                sim.time, sim.step, rate
            ));
        } else if last_log.elapsed().as_secs_f64() > 10.0 {
            last_log = Instant::now();
            tracing::info!(
                "t = {:.4e} s ({:.1} %), step {}, dt = {:.3e} s, {:.3e} particle-steps/s",
                sim.time,
                100.0 * sim.time / end,
                sim.step,
                d.dt,
                rate
            );
        }
    }
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    if failure.is_none() {
        history.row(&tally.last)?;
        snapshot(&sim, &mut pvd)?;
    }
    if opts.write_fields {
        write_pictures(case, out, &sim.body_names, &frames)?;
    }

    let steps = sim.step;
    let summary = Summary {
        case: case.name.clone(),
        dimension: D,
        particles: n,
        threads: rayon::current_num_threads(),
        steps,
        wall_seconds: wall,
        particle_steps_per_second: n as f64 * steps as f64 / wall.max(1e-12),
        interactions_per_second: tally.interactions as f64 / wall.max(1e-12),
        mean_neighbors: tally.interactions as f64 / (n as f64 * steps.max(1) as f64),
        end_time: sim.time,
        energy_error: tally.energy_dev / tally.energy_scale.max(f64::MIN_POSITIVE),
        initial_energy: tally.e0.unwrap_or(0.0),
        final_energy: tally.last.total,
        momentum_error: tally.momentum_dev
            / (0..3)
                .filter(|&k| tally.conserved[k])
                .map(|k| tally.p0[k] * tally.p0[k])
                .sum::<f64>()
                .sqrt()
                .max(tally.momentum_scale)
                .max(f64::MIN_POSITIVE),
        min_interbody_distance: tally.min_gap,
        status,
    };
    summary.write(&out.join("summary.json"))?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

/// Cross sections (one PNG per time, and all times side by side) and the history plot.
fn write_pictures(
    case: &Case,
    out: &Path,
    body_names: &[String],
    frames: &[Vec<SectionFrame>],
) -> Result<()> {
    let axis_names = ["x", "y", "z"];
    for (k, (spec, frames)) in case.output.pictures.iter().zip(frames).enumerate() {
        if frames.is_empty() {
            continue;
        }
        let axes = picture::in_plane_axes(case.dimension, spec.normal_axis);
        let labels = [axis_names[axes[0]], axis_names[axes[1]]];
        let field = color_name(spec.color_by);
        for f in frames {
            let name = format!("section{k}_{field}_{:.4}us.png", f.time * 1e6);
            picture::draw_sections(
                &out.join(name),
                std::slice::from_ref(f),
                spec.color_by,
                body_names,
                labels,
            )?;
        }
        picture::draw_sections(
            &out.join(format!("section{k}_{field}.png")),
            frames,
            spec.color_by,
            body_names,
            labels,
        )?;
    }
    let h = History::read(&out.join("history.csv"))?;
    let col = |c: &str| h.column(c).unwrap_or_default();
    let time = col("time");
    if time.len() >= 2 {
        let energies = vec![
            ("kinetic", col("kinetic_energy")),
            ("internal", col("internal_energy")),
            ("contact", col("contact_energy")),
            ("total", col("total_energy")),
        ];
        let mut forces = Vec::new();
        for name in body_names {
            let fx = col(&format!("contact_force_{name}_x"));
            let fy = col(&format!("contact_force_{name}_y"));
            let fz = col(&format!("contact_force_{name}_z"));
            let mag = (0..fx.len())
                .map(|i| (fx[i] * fx[i] + fy[i] * fy[i] + fz[i] * fz[i]).sqrt())
                .collect();
            forces.push((name.as_str(), mag));
        }
        let mut panels = vec![("energy (J)", energies)];
        if body_names.len() > 1 {
            panels.push(("contact force (N)", forces));
        }
        picture::plot_history(&out.join("history.png"), &time, &panels)?;
    }
    Ok(())
}

fn color_name(c: ColorBy) -> &'static str {
    match c {
        ColorBy::Body => "body",
        ColorBy::Pressure => "pressure",
        ColorBy::PlasticStrain => "plastic_strain",
        ColorBy::Velocity => "velocity",
        ColorBy::Density => "density",
        ColorBy::VonMises => "von_mises",
    }
}

fn progress_bar(end: f64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40.cyan/blue} {percent:>3}% ETA {eta} | {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(format!("0 of {end:.4e} s"));
    bar
}
