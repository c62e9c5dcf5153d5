//! One run of a case, start to end: the time loop of [`Simulation`] with everything a user
//! sees around it — snapshots (.vtp + .pvd), `history.csv`, cross-section pictures, the history
//! plot, `summary.json`, `checkpoint.bin`, a progress bar or log lines. Output reads particles,
//! never changes them.

use crate::case::{Case, ColorBy, PictureSpec};
use crate::error::{Error, Result};
use crate::output::checkpoint::{Checkpoint, RunState, Tally};
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
    /// Stop after this many steps in all (overrides the deck's max_steps when smaller).
    pub max_steps: Option<u64>,
    /// Write snapshots, pictures, plots and checkpoints (false: history and summary only).
    pub write_fields: bool,
    /// Go on from this checkpoint (written by a run of the same case).
    pub resume: Option<PathBuf>,
}

/// Run a case; the summary is also written to `summary.json`. A run that goes unstable writes
/// its last good snapshot, a checkpoint of it and a summary whose `status` gives the cause, then
/// returns the error.
pub fn run(case: &Case, opts: &RunOptions) -> Result<Summary> {
    match case.dimension {
        2 => run_dim::<2>(case, opts),
        3 => run_dim::<3>(case, opts),
        d => Err(Error::Invalid(format!("dimension {d} is not 2 or 3"))),
    }
}

impl Tally {
    fn new(case: &Case) -> Self {
        let mut conserved = [true; 3];
        for plane in &case.symmetry {
            conserved[plane.axis] = false;
        }
        Tally {
            conserved,
            ..Default::default()
        }
    }

    fn add(&mut self, d: &Diagnostics) {
        let e0 = *self.e0.get_or_insert(d.total);
        if self.interactions == 0 {
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

/// A run in progress: the simulation and its outputs.
struct Run<'a, const D: usize> {
    case: &'a Case,
    opts: &'a RunOptions,
    sim: Simulation<D>,
    history: HistoryWriter,
    pvd: PvdWriter,
    state: RunState,
    last_snapshot: Option<u64>,
    /// Wall time of this process's part of the run.
    start: Instant,
}

impl<const D: usize> Run<'_, D> {
    fn out(&self, name: &str) -> PathBuf {
        self.opts.out_dir.join(name)
    }

    /// Snapshot (and checkpoint) of the current state, once per step.
    fn snapshot(&mut self) -> Result<()> {
        if !self.opts.write_fields || self.last_snapshot == Some(self.sim.state.step) {
            return Ok(());
        }
        self.last_snapshot = Some(self.sim.state.step);
        let name = format!("{}_{:06}.vtp", self.case.name, self.sim.state.step);
        vtk::write_snapshot(&self.out(&name), &self.sim.particles, self.sim.state.time)?;
        self.pvd.add(self.sim.state.time, &name)?;
        self.checkpoint()
    }

    fn checkpoint(&mut self) -> Result<()> {
        let (particles, sim) = self.sim.checkpoint_state();
        let mut run = self.state.clone();
        run.snapshots = self.pvd.entries().to_vec();
        run.history_len = self.history.len();
        run.wall_seconds += self.start.elapsed().as_secs_f64();
        let c = Checkpoint::<D> {
            format: crate::output::checkpoint::FORMAT,
            case: self.case.name.clone(),
            particles,
            sim,
            run,
        };
        c.write(&self.out("checkpoint.bin"))
    }

    /// Cross sections due at the current time.
    fn take_pictures(&mut self) {
        let tol = 1e-9 * self.case.simulation.end_time;
        while let Some(&(k, t)) = self.state.pending_pictures.first() {
            if t > self.sim.state.time + tol {
                break;
            }
            let spec = &self.case.output.pictures[k];
            let thickness = section_thickness(self.case, spec);
            self.state.frames[k].push(picture::extract_section(
                &self.sim.particles,
                self.sim.state.time,
                spec,
                thickness,
            ));
            self.state.pending_pictures.remove(0);
        }
    }
}

fn section_thickness(case: &Case, spec: &PictureSpec) -> f64 {
    spec.thickness.unwrap_or_else(|| {
        case.bodies
            .iter()
            .map(|b| b.spacing)
            .fold(f64::INFINITY, f64::min)
    })
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
    let interval = case.output.snapshot_interval;
    let pvd_path = out.join(format!("{}.pvd", case.name));
    let history_path = out.join("history.csv");

    let (state, history, pvd) = match &opts.resume {
        Some(path) => {
            let c = Checkpoint::<D>::read(path, &case.name)?;
            if c.particles.n_real != n {
                return Err(Error::Invalid(format!(
                    "{}: the checkpoint has {} particles, the deck makes {n}: the deck changed since",
                    path.display(),
                    c.particles.n_real
                )));
            }
            sim.restore(c.particles, c.sim);
            let pvd = PvdWriter::resume(&pvd_path, c.run.snapshots.clone());
            let history = HistoryWriter::append(&history_path, c.run.history_len)?;
            (c.run, history, pvd)
        }
        None => {
            let mut pending: Vec<(usize, f64)> = case
                .output
                .pictures
                .iter()
                .enumerate()
                .flat_map(|(k, p)| p.times.iter().map(move |&t| (k, t)))
                .collect();
            pending.sort_by(|a, b| a.1.total_cmp(&b.1));
            let state = RunState {
                tally: Tally::new(case),
                next_snapshot: interval.unwrap_or(f64::INFINITY),
                snapshots: Vec::new(),
                frames: vec![Vec::new(); case.output.pictures.len()],
                pending_pictures: pending,
                wall_seconds: 0.0,
                history_len: 0,
            };
            (
                state,
                HistoryWriter::create(&history_path, &sim.body_names)?,
                PvdWriter::new(&pvd_path),
            )
        }
    };
    let resumed = opts.resume.is_some();
    // A checkpoint is written with a snapshot of its step: a resumed run has that one already.
    let last_snapshot = resumed.then_some(sim.state.step);
    let mut run = Run {
        case,
        opts,
        sim,
        history,
        pvd,
        state,
        last_snapshot,
        start: Instant::now(),
    };
    if !resumed {
        run.snapshot()?;
        run.take_pictures();
    }

    let bar = opts.progress.then(|| progress_bar(end));
    let first_step = run.sim.state.step;
    let mut last_log = Instant::now();
    let mut status = "completed".to_string();
    let mut failure = None;
    let tol = 1e-9 * end;

    while run.sim.state.time < end - tol && max_steps.is_none_or(|m| run.sim.state.step < m) {
        let mut next_event = end.min(run.state.next_snapshot);
        if let Some(&(_, t)) = run.state.pending_pictures.first() {
            next_event = next_event.min(t);
        }
        let d = match run.sim.step((next_event - run.sim.state.time).max(tol)) {
            Ok(d) => d,
            Err(e) => {
                status = format!("unstable: {e}");
                // The particles are still at the last good state: keep it on disk.
                run.snapshot()?;
                failure = Some(e);
                break;
            }
        };
        run.state.tally.add(&d);
        if (run.sim.state.step - 1).is_multiple_of(case.output.history_every) {
            run.history.row(&d)?;
        }
        if run.sim.state.time >= run.state.next_snapshot - tol {
            while run.state.next_snapshot <= run.sim.state.time + tol {
                run.state.next_snapshot += interval.unwrap_or(f64::INFINITY);
            }
            run.snapshot()?;
        }
        run.take_pictures();
        let wall = run.start.elapsed().as_secs_f64();
        let rate = n as f64 * (run.sim.state.step - first_step) as f64 / wall.max(1e-9);
        if let Some(bar) = &bar {
            bar.set_position((run.sim.state.time / end * 1000.0) as u64);
            bar.set_message(format!(
                "t = {:.4e} s, step {}, {:.3e} particle-steps/s",
                run.sim.state.time, run.sim.state.step, rate
            ));
        } else if last_log.elapsed().as_secs_f64() > 10.0 {
            last_log = Instant::now();
            tracing::info!(
                "t = {:.4e} s ({:.1} %), step {}, dt = {:.3e} s, {:.3e} particle-steps/s",
                run.sim.state.time,
                100.0 * run.sim.state.time / end,
                run.sim.state.step,
                d.dt,
                rate
            );
        }
    }
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    if failure.is_none() {
        // The checkpoint first, so that a resumed run drops this closing row.
        run.snapshot()?;
        let last = run.state.tally.last.clone();
        run.history.row(&last)?;
    }
    if opts.write_fields {
        write_pictures(case, out, &run.sim.body_names, &run.state.frames)?;
    }

    let wall = run.state.wall_seconds + run.start.elapsed().as_secs_f64();
    let steps = run.sim.state.step;
    let tally = &run.state.tally;
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
        searches: run.sim.state.searches,
        partial_searches: run.sim.state.partial_searches,
        end_time: run.sim.state.time,
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
