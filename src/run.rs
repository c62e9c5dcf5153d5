//! One run of a case, start to end: the time loop of [`Simulation`] with everything a user
//! sees around it — snapshots (.vtp + .pvd), `history.csv`, cross-section pictures, the history
//! plot, `summary.json`, `checkpoint.bin`, a progress bar or log lines. Output reads particles,
//! never changes them.
//!
//! **Every exit writes `summary.json`** with the true status: `completed` (the end time was
//! reached), `max_steps` (stopped by the step cap, as asked), `interrupted` (SIGINT or SIGTERM:
//! the step in progress is finished and a checkpoint written), `unstable` (the last good state
//! is kept as a snapshot and a checkpoint) or `failed` (an output could not be written, say on
//! a full disk; the summary is then written if there is room for it). Every file is written
//! atomically (see [`crate::output::atomic`]).
//!
//! **Output times never stall a run.** A snapshot or picture time is landed on exactly when
//! that shortens the step by at most a factor 2; an output time closer than half a step is
//! taken at the end of the step that passes it instead. At most one snapshot is written per
//! step, and the next snapshot time is counted from the current time, never by adding up
//! intervals (so an interval far below the time step cannot loop).

use crate::case::{Case, ColorBy, PictureSpec};
use crate::error::{Error, Result};
use crate::output::atomic;
use crate::output::checkpoint::{Checkpoint, CheckpointRef, RunState, Tally};
use crate::output::history::{History, HistoryWriter};
use crate::output::picture::{self, SectionFrame};
use crate::output::summary::Summary;
use crate::output::vtk::{self, PvdWriter};
use crate::particles::RealParticles;
use crate::ranks::Ranks;
use crate::simulation::{Diagnostics, Simulation};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// How to run.
#[derive(Debug, Clone, Default)]
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
    /// Replace the files of an earlier run in `out_dir` (without it such a directory is
    /// refused, unless resuming). Other files are never touched.
    pub overwrite: bool,
    /// Set from outside (on SIGINT or SIGTERM) to end the run after the step in progress, with
    /// a checkpoint and the status `interrupted`.
    pub stop: Option<Arc<AtomicBool>>,
    /// The ranks of a distributed run (see `ranks`): each takes every step, the root alone
    /// writes files.
    pub ranks: Ranks,
}

/// Run a case; the summary is also written to `summary.json`. A run that goes unstable writes
/// its last good snapshot, a checkpoint of it and a summary whose `status` gives the cause, then
/// returns the error; so does an interrupted one (a checkpoint of its last step).
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
        self.mixing
            .resize(d.mixing.len(), crate::mixing::PairMixing::default());
        for (m, x) in self.mixing.iter_mut().zip(&d.mixing) {
            m.penetration = m.penetration.max(x.penetration);
            m.mixed = m.mixed.max(x.mixed);
        }
        self.interactions += d.interactions as u128;
        self.last = d.clone();
    }
}

/// How the time loop ended.
enum Ending {
    Completed,
    MaxSteps(u64),
    Interrupted,
    Unstable(Error),
    Failed(Error),
}

/// A run in progress: the simulation and its outputs.
struct Run<'a, const D: usize> {
    case: &'a Case,
    opts: &'a RunOptions,
    sim: Simulation<D>,
    /// The history (the root rank's only).
    history: Option<HistoryWriter>,
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

    /// Snapshot (and checkpoint) of the current state, once per step. On several ranks each
    /// writes its own range of the particles as a piece (`<case>_<step>_<rank>.vtp`) and the
    /// root the index that joins them (`<case>_<step>.pvtp`) once every piece is on disk; the
    /// pieces in rank order hold the serial snapshot's particles in its order.
    fn snapshot(&mut self) -> Result<()> {
        let ranks = self.opts.ranks;
        if !self.opts.write_fields || self.last_snapshot == Some(self.sim.state.step) {
            return Ok(());
        }
        self.last_snapshot = Some(self.sim.state.step);
        // The checkpoint holds every particle: under MPI each rank has advanced only its own.
        self.sim.gather();
        let (step, time) = (self.sim.state.step, self.sim.state.time);
        let name = if ranks.size() == 1 {
            let name = format!("{}_{step:06}.vtp", self.case.name);
            vtk::write_snapshot(&self.out(&name), &self.sim.particles, time)?;
            name
        } else {
            let piece = |r: usize| format!("{}_{step:06}_{r}.vtp", self.case.name);
            let ranges = self.sim.rank_ranges();
            let mine = ranks.rank();
            let written = vtk::write_piece(
                &self.out(&piece(mine)),
                &self.sim.particles,
                ranges[mine].clone(),
                time,
            );
            // Also the barrier: no index before every piece is written.
            let failed = ranks.any(written.is_err());
            written?;
            if failed {
                return Err(Error::Invalid(format!(
                    "another rank could not write its piece of the snapshot at step {step} in {}",
                    self.opts.out_dir.display()
                )));
            }
            if !ranks.is_root() {
                return Ok(());
            }
            let name = format!("{}_{step:06}.pvtp", self.case.name);
            let pieces: Vec<String> = (0..ranks.size()).map(piece).collect();
            vtk::write_parallel_index(&self.out(&name), &pieces)?;
            name
        };
        self.pvd.add(time, &name)?;
        self.checkpoint()
    }

    fn checkpoint(&mut self) -> Result<()> {
        let mut run = self.state.clone();
        run.snapshots = self.pvd.entries().to_vec();
        run.history_len = self.history.as_ref().map_or(0, HistoryWriter::len);
        run.wall_seconds += self.start.elapsed().as_secs_f64();
        let physics = self.case.physics_fingerprint();
        let c = CheckpointRef::<D> {
            case: &self.case.name,
            physics: &physics,
            particles: RealParticles(&self.sim.particles),
            sim: &self.sim.state,
            searches: &self.sim.stats,
            run: &run,
        };
        c.write(&self.out("checkpoint.bin"))
    }

    /// Cross sections due at the current time (taken at the first step at or past their time).
    fn take_pictures(&mut self) {
        let tol = time_tolerance(self.case);
        while let Some(&(k, t)) = self.state.pending_pictures.first() {
            if t > self.sim.state.time + tol {
                break;
            }
            // A section may cut any particle: under MPI each rank has advanced only its own.
            self.sim.gather();
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

    /// The longest step allowed by the end time and the next output time (see the module
    /// doc): the end time is always landed on, output times only where that costs at most
    /// half a step.
    fn step_limit(&self) -> f64 {
        let (time, dt_prev) = (self.sim.state.time, self.sim.state.dt_prev);
        let mut next_output = self.state.next_snapshot;
        if let Some(&(_, t)) = self.state.pending_pictures.first() {
            next_output = next_output.min(t);
        }
        let end = self.case.simulation.end_time;
        land(end - time, dt_prev, true).min(land(next_output - time, dt_prev, false))
    }

    /// Steps until the end time, the step cap, a stop request or a failure.
    fn time_loop(&mut self, max_steps: Option<u64>) -> Ending {
        let n = self.sim.particles.n_real;
        let end = self.case.simulation.end_time;
        let tol = time_tolerance(self.case);
        let interval = self.case.output.snapshot_interval;
        let bar = self.opts.progress.then(|| progress_bar(end));
        let first_step = self.sim.state.step;
        let mut last_log = Instant::now();
        let ending = loop {
            if self.sim.state.time >= end - tol {
                break Ending::Completed;
            }
            if let Some(m) = max_steps.filter(|&m| self.sim.state.step >= m) {
                break Ending::MaxSteps(m);
            }
            // Every rank stops at the same step, however the signal reached them.
            let stop = self
                .opts
                .stop
                .as_ref()
                .is_some_and(|s| s.load(Ordering::Relaxed));
            if self.opts.ranks.any(stop) {
                break Ending::Interrupted;
            }
            let d = match self.sim.step(self.step_limit()) {
                Ok(d) => d,
                Err(e) => break Ending::Unstable(e),
            };
            self.state.tally.add(&d);
            if (self.sim.state.step - 1).is_multiple_of(self.case.output.history_every) {
                if let Some(Err(e)) = self.history.as_mut().map(|h| h.row(&d)) {
                    break Ending::Failed(e);
                }
            }
            if self.sim.state.time >= self.state.next_snapshot - tol {
                self.state.next_snapshot = interval.map_or(f64::INFINITY, |i| {
                    next_output_time(self.sim.state.time, i, tol)
                });
                if let Err(e) = self.snapshot() {
                    break Ending::Failed(e);
                }
            }
            self.take_pictures();
            let wall = self.start.elapsed().as_secs_f64();
            let rate = n as f64 * (self.sim.state.step - first_step) as f64 / wall.max(1e-9);
            if let Some(bar) = &bar {
                bar.set_position((self.sim.state.time / end * 1000.0) as u64);
                bar.set_message(format!(
                    "t = {:.4e} s, step {}, {:.3e} particle-steps/s",
                    self.sim.state.time, self.sim.state.step, rate
                ));
            } else if last_log.elapsed().as_secs_f64() > 10.0 {
                last_log = Instant::now();
                tracing::info!(
                    "t = {:.4e} s ({:.1} %), step {}, dt = {:.3e} s, {:.3e} particle-steps/s",
                    self.sim.state.time,
                    100.0 * self.sim.state.time / end,
                    self.sim.state.step,
                    d.dt,
                    rate
                );
            }
        };
        if let Some(bar) = &bar {
            bar.finish_and_clear();
        }
        ending
    }

    /// The closing outputs of a run that ended with `ending`: the last snapshot and checkpoint
    /// (of the last good state when unstable), the closing history row, the pictures. Returns
    /// the ending, turned into `Failed` if one of them cannot be written.
    fn close(&mut self, ending: Ending) -> Ending {
        if matches!(ending, Ending::Failed(_)) {
            return ending;
        }
        let unstable = matches!(ending, Ending::Unstable(_));
        // The checkpoint first, so that a resumed run drops the closing row.
        let mut done = self.snapshot();
        if !unstable {
            let last = self.state.tally.last.clone();
            if let Some(h) = &mut self.history {
                done = done.and_then(|()| h.row(&last));
            }
        }
        if self.opts.write_fields && self.opts.ranks.is_root() {
            done = done.and_then(|()| {
                write_pictures(
                    self.case,
                    &self.opts.out_dir,
                    &self.sim.body_names,
                    &self.state.frames,
                )
            });
        }
        match done {
            Ok(()) => ending,
            Err(e) => Ending::Failed(e),
        }
    }

    fn summary(&self, status: &str, reason: String) -> Summary {
        let n = self.sim.particles.n_real;
        let wall = self.state.wall_seconds + self.start.elapsed().as_secs_f64();
        let steps = self.sim.state.step;
        let tally = &self.state.tally;
        Summary {
            case: self.case.name.clone(),
            dimension: D,
            particles: n,
            threads: rayon::current_num_threads(),
            steps,
            wall_seconds: wall,
            particle_steps_per_second: n as f64 * steps as f64 / wall.max(1e-12),
            interactions_per_second: tally.interactions as f64 / wall.max(1e-12),
            mean_neighbors: tally.interactions as f64 / (n as f64 * steps.max(1) as f64),
            searches: self.sim.stats.searches,
            partial_searches: self.sim.stats.partial_searches,
            rebalances: self.sim.rebalances,
            correction_fallbacks: self.sim.stats.correction_fallbacks,
            end_time: self.sim.state.time,
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
            mixing: pair_mixing(&self.sim.body_names, &tally.mixing),
            peak_memory_bytes: crate::machine::peak_resident_memory(),
            modelled_part: modelled_part(self.case),
            status: status.to_string(),
            reason,
        }
    }
}

/// The run's largest mixing figures, by body pair.
fn pair_mixing(
    names: &[String],
    tally: &[crate::mixing::PairMixing],
) -> Vec<crate::output::summary::PairMixing> {
    let mut out = Vec::new();
    for (a, na) in names.iter().enumerate() {
        for (b, nb) in names.iter().enumerate().skip(a + 1) {
            let m = tally
                .get(crate::mixing::pair_index(names.len(), a, b))
                .copied()
                .unwrap_or_default();
            out.push(crate::output::summary::PairMixing {
                bodies: [na.clone(), nb.clone()],
                max_penetration: m.penetration,
                max_mixed: m.mixed,
            });
        }
    }
    out
}

/// The step limit for an output `remaining` seconds ahead, after a step of `dt_prev` (0 before
/// the first step). Approaching it, two steps share what is left when it is less than two
/// steps away; one that is closer than half a step (outputs denser than the steps) is not
/// landed on unless `must` (the end time).
fn land(remaining: f64, dt_prev: f64, must: bool) -> f64 {
    if must {
        return if dt_prev > 0.0 && remaining > dt_prev && remaining < 2.0 * dt_prev {
            0.5 * remaining
        } else {
            remaining
        };
    }
    if dt_prev <= 0.0 || remaining < 0.5 * dt_prev {
        f64::INFINITY
    } else if remaining <= dt_prev {
        remaining
    } else if remaining < 2.0 * dt_prev {
        0.5 * remaining
    } else {
        remaining
    }
}

/// The first multiple of `interval` after `time` (by more than `tol`), counted from the time
/// itself; never `time` or earlier, whatever the sizes.
pub fn next_output_time(time: f64, interval: f64, tol: f64) -> f64 {
    let k = ((time + tol) / interval).floor() + 1.0;
    (k * interval).max(time.next_up())
}

/// Times closer than this are the same time (s).
fn time_tolerance(case: &Case) -> f64 {
    1e-9 * case.simulation.end_time
}

/// What `summary.json` says about the part of the bodies a run models.
pub fn modelled_part(case: &Case) -> String {
    // A wall cuts nothing off: the bodies on its side are whole.
    let planes: Vec<String> = case
        .symmetry
        .iter()
        .filter(|p| !p.wall)
        .map(|p| format!("{} = {}", ["x", "y", "z"][p.axis], p.position))
        .collect();
    if planes.is_empty() {
        return "the whole bodies: masses, forces, momenta and energies are those of the bodies"
            .into();
    }
    format!(
        "the part on one side of the symmetry planes {}: masses, forces, momenta and energies are those of the part modelled (for bodies cut in two by each plane, ×{} for the whole)",
        planes.join(", "),
        1u64 << planes.len().min(63)
    )
}

fn section_thickness(case: &Case, spec: &PictureSpec) -> f64 {
    spec.thickness.unwrap_or_else(|| {
        case.bodies
            .iter()
            .map(|b| b.spacing)
            .fold(f64::INFINITY, f64::min)
    })
}

/// The files an earlier run of `case` leaves in `dir`: snapshots and their series, history,
/// summary, checkpoint, pictures, and temporary files of an interrupted write.
pub fn earlier_outputs(dir: &Path, case: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    // `<case>_<step>.vtp`, and a parallel run's `<case>_<step>.pvtp` and its pieces
    // `<case>_<step>_<rank>.vtp`.
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let snapshot = |name: &str| {
        let Some(rest) = name.strip_prefix(case).and_then(|r| r.strip_prefix('_')) else {
            return false;
        };
        if let Some(step) = rest.strip_suffix(".pvtp") {
            return digits(step);
        }
        rest.strip_suffix(".vtp")
            .is_some_and(|r| match r.split_once('_') {
                Some((step, rank)) => digits(step) && digits(rank),
                None => digits(r),
            })
    };
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let own = matches!(
                name.as_str(),
                "summary.json" | "history.csv" | "history.png" | "checkpoint.bin"
            ) || name == format!("{case}.pvd")
                || snapshot(&name)
                || (name.starts_with("section") && name.ends_with(".png"))
                || atomic::is_temp_name(&name);
            own.then(|| e.path())
        })
        .collect();
    found.sort();
    found
}

/// Make the output directory ready: created, and free of an earlier run's files (removed with
/// `overwrite`, kept when resuming, refused otherwise).
fn prepare_output(case: &Case, opts: &RunOptions) -> Result<()> {
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    if opts.resume.is_some() {
        return Ok(());
    }
    let earlier = earlier_outputs(out, &case.name);
    if earlier.is_empty() {
        return Ok(());
    }
    if !opts.overwrite {
        let names: Vec<String> = earlier
            .iter()
            .take(4)
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        return Err(Error::Invalid(format!(
            "{} holds an earlier run of '{}' ({} files: {}{}): add --overwrite to replace them, --resume {} to go on from it, or choose another --out",
            out.display(),
            case.name,
            earlier.len(),
            names.join(", "),
            if earlier.len() > 4 { ", …" } else { "" },
            out.join("checkpoint.bin").display()
        )));
    }
    for f in earlier {
        std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
    }
    Ok(())
}

/// Refuse snapshots that would not fit on the output directory's disk.
fn check_disk_space(case: &Case, n: usize, out: &Path) -> Result<()> {
    let plan = crate::check::output_plan(case, n);
    let Ok(free) = fs4::available_space(out) else {
        return Ok(());
    };
    if plan.total_bytes > free as f64 {
        return Err(Error::Invalid(format!(
            "the run would write {} snapshots of {} each ({} in all, with the checkpoint), but the disk holding {} has {} free: raise [output] snapshot_interval, or free disk space",
            plan.snapshots,
            crate::check::human_bytes(plan.snapshot_bytes),
            crate::check::human_bytes(plan.total_bytes),
            out.display(),
            crate::check::human_bytes(free as f64)
        )));
    }
    Ok(())
}

fn run_dim<const D: usize>(case: &Case, opts: &RunOptions) -> Result<Summary> {
    let root = opts.ranks.is_root();
    let prepared = if root {
        prepare_output(case, opts)
    } else {
        Ok(())
    };
    // The other ranks write their snapshot pieces only into the folder the root has prepared.
    if opts.ranks.any(prepared.is_err()) {
        prepared?;
        return Err(Error::Invalid(format!(
            "the root rank could not prepare {}",
            opts.out_dir.display()
        )));
    }
    let out = &opts.out_dir;
    let mut sim = Simulation::<D>::new(case)?;
    sim.distribute(opts.ranks);
    let n = sim.particles.n_real;
    if opts.write_fields && root {
        check_disk_space(case, n, out)?;
    }
    let max_steps = match (case.simulation.max_steps, opts.max_steps) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    let pvd_path = out.join(format!("{}.pvd", case.name));
    let history_path = out.join("history.csv");

    let (state, history, pvd) = match &opts.resume {
        Some(path) => {
            let c = Checkpoint::<D>::read(path, case)?;
            if c.particles.n_real != n {
                return Err(Error::Invalid(format!(
                    "{}: the checkpoint has {} particles, the deck makes {n}: the deck changed since",
                    path.display(),
                    c.particles.n_real
                )));
            }
            sim.restore(c.particles, c.sim, c.searches);
            let pvd = PvdWriter::resume(&pvd_path, c.run.snapshots.clone());
            let history = root
                .then(|| HistoryWriter::append(&history_path, c.run.history_len))
                .transpose()?;
            let mut state = c.run;
            // The output settings may have changed since: the next snapshot is counted anew.
            state.next_snapshot = case.output.snapshot_interval.map_or(f64::INFINITY, |i| {
                next_output_time(sim.state.time, i, time_tolerance(case))
            });
            (state, history, pvd)
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
                next_snapshot: case.output.snapshot_interval.unwrap_or(f64::INFINITY),
                snapshots: Vec::new(),
                frames: vec![Vec::new(); case.output.pictures.len()],
                pending_pictures: pending,
                wall_seconds: 0.0,
                history_len: 0,
            };
            (
                state,
                root.then(|| HistoryWriter::create(&history_path, &sim.body_names))
                    .transpose()?,
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
    let ending = if resumed {
        run.time_loop(max_steps)
    } else {
        match run.snapshot() {
            Ok(()) => {
                run.take_pictures();
                run.time_loop(max_steps)
            }
            Err(e) => Ending::Failed(e),
        }
    };
    let ending = run.close(ending);
    let step = run.sim.state.step;
    let time = run.sim.state.time;
    let (status, reason, error) = match ending {
        Ending::Completed => ("completed", format!("reached the end time {:e} s", case.simulation.end_time), None),
        Ending::MaxSteps(m) => (
            "max_steps",
            format!("stopped at step {m}, the step cap, at t = {time:e} s of {:e} s; resume from checkpoint.bin to go on", case.simulation.end_time),
            None,
        ),
        Ending::Interrupted => (
            "interrupted",
            format!("stopped by a signal after step {step}, t = {time:e} s; a checkpoint was written: resume from checkpoint.bin to go on"),
            Some(Error::Interrupted { step, time }),
        ),
        Ending::Unstable(e) => ("unstable", e.to_string(), Some(e)),
        Ending::Failed(e) => ("failed", e.to_string(), Some(e)),
    };
    let summary = run.summary(status, reason);
    let written = if root {
        summary.write(&out.join("summary.json"))
    } else {
        Ok(())
    };
    match (error, written) {
        (Some(e), _) => Err(e),
        (None, Err(e)) => Err(e),
        (None, Ok(())) => Ok(summary),
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
        ColorBy::Damage => "damage",
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An earlier run's files are its own: serial snapshots, a parallel run's indexes and
    /// pieces, the series and the rest, not another case's or a user's files.
    #[test]
    fn earlier_outputs_are_the_runs_own_files() {
        let d = std::env::temp_dir().join(format!("strike-earlier-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let own = [
            "cube_000000.vtp",
            "cube_000120.pvtp",
            "cube_000120_0.vtp",
            "cube_000120_12.vtp",
            "cube.pvd",
            "history.csv",
            "checkpoint.bin",
        ];
        let other = [
            "cube_000120_a.vtp",
            "cube_.vtp",
            "cube_000120_.vtp",
            "cube_1_2_3.vtp",
            "cubes_000000.vtp",
            "cube_000120.pvtu",
            "notes.txt",
        ];
        for f in own.iter().chain(&other) {
            std::fs::write(d.join(f), "x").unwrap();
        }
        let mut found: Vec<String> = earlier_outputs(&d, "cube")
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        found.sort();
        let mut expect: Vec<String> = own.iter().map(|s| s.to_string()).collect();
        expect.sort();
        assert_eq!(found, expect);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// The next output time always lies ahead, however small the interval against the time.
    #[test]
    fn next_output_time_always_advances() {
        assert_eq!(next_output_time(0.0, 1e-8, 1e-16), 1e-8);
        let t = next_output_time(1e-8, 1e-8, 1e-16);
        assert!((t - 2e-8).abs() < 1e-22, "{t}");
        for (time, interval) in [(1e-7, 1e-300), (1e-7, 1e-12), (0.3, 1e-17), (5.0, 1.0)] {
            let next = next_output_time(time, interval, 0.0);
            assert!(next > time, "{time} {interval} → {next}");
        }
    }

    /// Landing on an output shortens a step by at most 2; an output closer than half a step is
    /// passed; the end time is always landed on.
    #[test]
    fn landing_costs_at_most_half_a_step() {
        let dt = 1e-9;
        for k in 1..400 {
            let remaining = 1e-12 * k as f64 * k as f64 / 20.0;
            let limit = land(remaining, dt, false);
            assert!(limit >= 0.5 * dt, "{remaining}: {limit}");
            let end = land(remaining, dt, true);
            assert!(end <= remaining && end > 0.0);
        }
        assert_eq!(land(1e-15, dt, false), f64::INFINITY);
        assert_eq!(land(0.7e-9, dt, false), 0.7e-9);
        assert_eq!(land(1.5e-9, dt, false), 0.75e-9);
        assert_eq!(land(1e-15, dt, true), 1e-15);
    }
}
