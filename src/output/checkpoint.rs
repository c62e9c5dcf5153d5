//! Checkpoints: everything a run needs to go on bit for bit, in one postcard file.
//!
//! A checkpoint holds the real particles, the simulation's scalar state and the run's own
//! bookkeeping (summary tallies, output schedule, snapshots listed, cross-section frames taken).
//! Neighbour lists and ghosts are not stored: taking a checkpoint makes the live run search
//! afresh at its next step, as a resumed one must, so both continue identically.

use crate::error::{Error, Result};
use crate::output::picture::SectionFrame;
use crate::particles::Particles;
use crate::simulation::{Diagnostics, SimState};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format version, checked on reading.
pub const FORMAT: u32 = 1;

/// The running totals behind `summary.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Tally {
    /// Momentum components that no symmetry plane acts on (a plane pushes along its normal).
    pub conserved: [bool; 3],
    pub e0: Option<f64>,
    pub p0: [f64; 3],
    pub energy_scale: f64,
    pub energy_dev: f64,
    pub gravity0: f64,
    pub momentum_dev: f64,
    pub momentum_scale: f64,
    pub min_gap: Option<f64>,
    pub interactions: u128,
    pub last: Diagnostics,
}

/// The run's state besides the simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    pub tally: Tally,
    pub next_snapshot: f64,
    pub snapshots: Vec<(f64, String)>,
    /// Cross-section frames taken so far, per picture, and the picture times still to come.
    pub frames: Vec<Vec<SectionFrame>>,
    pub pending_pictures: Vec<(usize, f64)>,
    /// Wall time already spent (s).
    pub wall_seconds: f64,
    /// Length of `history.csv` at the checkpoint (bytes).
    pub history_len: u64,
}

/// A checkpoint of a `D`-dimensional run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint<const D: usize> {
    pub format: u32,
    pub case: String,
    pub particles: Particles<D>,
    pub sim: SimState,
    pub run: RunState,
}

impl<const D: usize> Checkpoint<D> {
    /// Write through a temporary file and a rename, so a crash never leaves half a checkpoint.
    pub fn write(&self, path: &Path) -> Result<()> {
        let bytes = postcard::to_stdvec(self).map_err(|e| {
            Error::Invalid(format!("{}: cannot encode checkpoint: {e}", path.display()))
        })?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        std::fs::write(&tmp, bytes).map_err(|e| Error::io(&tmp, e))?;
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    }

    /// Read a checkpoint written for case `case` in `D` dimensions.
    pub fn read(path: &Path, case: &str) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let c: Self = postcard::from_bytes(&bytes).map_err(|e| {
            Error::Invalid(format!(
                "{}: not a strike checkpoint of a {D}D case (or a damaged one): {e}",
                path.display()
            ))
        })?;
        if c.format != FORMAT {
            return Err(Error::Invalid(format!(
                "{}: checkpoint format {} is not the {FORMAT} this strike reads",
                path.display(),
                c.format
            )));
        }
        if c.case != case {
            return Err(Error::Invalid(format!(
                "{}: this checkpoint is of case '{}', not '{case}': resume it with its own deck",
                path.display(),
                c.case
            )));
        }
        Ok(c)
    }
}
