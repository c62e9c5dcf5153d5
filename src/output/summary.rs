//! `summary.json`: the closing figures of a run.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What a run reports when it ends.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub case: String,
    pub dimension: usize,
    /// Real particles.
    pub particles: usize,
    pub threads: usize,
    pub steps: u64,
    pub wall_seconds: f64,
    pub particle_steps_per_second: f64,
    /// Particle-neighbour interactions per second (each particle's neighbours once per step).
    pub interactions_per_second: f64,
    pub mean_neighbors: f64,
    /// Full neighbour searches, and steps with a partial rebuild (see `neighbors`).
    pub searches: u64,
    pub partial_searches: u64,
    /// Under MPI: full searches made early to balance the ranks' loads (counted since this
    /// process started, so a resumed run's from its resume; 0 on one rank).
    #[serde(default)]
    pub rebalances: u64,
    /// CN-SPH: particle-steps that kept the uncorrected gradient (0 in conventional SPH).
    pub correction_fallbacks: u64,
    /// Simulated time reached (s).
    pub end_time: f64,
    /// Largest |E(t) − E(0)| over the run divided by the largest energy in play,
    /// max(kinetic + |internal| + contact) (+ the largest change of gravitational energy).
    pub energy_error: f64,
    pub initial_energy: f64,
    pub final_energy: f64,
    /// Largest |P(t) − P(0)| / max(|P(0)|, Σ m|v|) over the run, over the momentum components
    /// parallel to every symmetry plane (a plane exerts force along its normal). Gravity and
    /// prescribed bodies change momentum too.
    pub momentum_error: f64,
    /// Smallest distance between particles of different bodies over the run, / Δp_avg
    /// (None: bodies never came within the kernel support, or one body).
    pub min_interbody_distance: Option<f64>,
    /// The mixing figures of each pair of bodies, their largest over the run (see `mixing`).
    pub mixing: Vec<PairMixing>,
    /// Peak resident memory of the process (bytes; None where the system does not report it;
    /// under MPI, the root rank's).
    #[serde(default)]
    pub peak_memory_bytes: Option<u64>,
    /// Which part of the bodies the run models (symmetry planes), and so what the totals above
    /// and in `history.csv` are totals of.
    pub modelled_part: String,
    /// How the run ended: `completed` (end time reached), `max_steps` (the step cap, as asked),
    /// `interrupted` (SIGINT/SIGTERM, checkpoint written), `unstable` (last good state kept) or
    /// `failed` (an output could not be written).
    pub status: String,
    /// The ending in words: for `unstable`, the particle, its body, place and cause.
    pub reason: String,
}

/// The no-mixing figures of one pair of bodies over a run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PairMixing {
    pub bodies: [String; 2],
    /// Deepest penetration of a particle of one past the other's surface layer (Δp_avg).
    pub max_penetration: f64,
    /// Most particles whose neighbourhood was dominated by the other body at once.
    pub max_mixed: u64,
}

impl Summary {
    pub fn write(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self).map_err(|e| Error::Invalid(e.to_string()))?;
        crate::output::atomic::write(path, (text + "\n").as_bytes())
    }

    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        serde_json::from_str(&text).map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))
    }
}
