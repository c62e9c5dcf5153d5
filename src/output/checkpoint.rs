//! Checkpoints: everything a run needs to go on bit for bit, in one postcard file.
//!
//! A checkpoint holds the real particles, the simulation's scalar state and the run's own
//! bookkeeping (summary tallies, output schedule, snapshots listed, cross-section frames taken).
//! Neighbour lists and ghosts are not stored: a resumed run rebuilds them, and since every sum
//! over neighbours runs in canonical order (see `neighbors`), when the lists were built changes
//! no bit of the results.

use crate::case::Case;
use crate::error::{Error, Result};
use crate::output::picture::SectionFrame;
use crate::particles::Particles;
use crate::simulation::{Diagnostics, SearchStats, SimState};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format version, checked on reading.
pub const FORMAT: u32 = 3;

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
    /// Largest mixing figures of each pair of bodies over the run.
    pub mixing: Vec<crate::mixing::PairMixing>,
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
    pub case: String,
    /// The deck's physical set-up ([`Case::physics_fingerprint`]): resuming with another is
    /// refused, naming what differs.
    pub physics: Vec<(String, String)>,
    pub particles: Particles<D>,
    pub sim: SimState,
    pub searches: SearchStats,
    pub run: RunState,
}

/// The file starts with these 8 bytes, then the format version (u32), the CRC-32 of the
/// payload (u32) and the payload's length (u64), all little-endian, then the payload (postcard).
const MAGIC: &[u8; 8] = b"STRIKECP";
const HEADER: usize = 8 + 4 + 4 + 8;

impl<const D: usize> Checkpoint<D> {
    /// Write atomically (see [`crate::output::atomic`]), so a crash never leaves half a
    /// checkpoint, with a checksum so that a damaged one is refused.
    pub fn write(&self, path: &Path) -> Result<()> {
        let payload = postcard::to_stdvec(self).map_err(|e| {
            Error::Invalid(format!("{}: cannot encode checkpoint: {e}", path.display()))
        })?;
        let mut bytes = Vec::with_capacity(HEADER + payload.len());
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT.to_le_bytes());
        bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&payload);
        crate::output::atomic::write(path, &bytes)
    }

    /// Read a checkpoint written for `case` in `D` dimensions: a file that is not a checkpoint,
    /// is damaged (checksum), is of another case or dimension, or was written with another
    /// physical set-up is refused with what is wrong.
    pub fn read(path: &Path, case: &Case) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let bad = |what: String| Error::Invalid(format!("{}: {what}", path.display()));
        if bytes.len() < HEADER || &bytes[..8] != MAGIC {
            return Err(bad(
                "not a strike checkpoint (checkpoint.bin in a run's output directory)".into(),
            ));
        }
        let word =
            |k: usize| u32::from_le_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]]);
        let format = word(8);
        if format != FORMAT {
            return Err(bad(format!(
                "checkpoint format {format} is not the {FORMAT} this strike reads"
            )));
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[16..24]);
        let payload = &bytes[HEADER..];
        if u64::from_le_bytes(len) != payload.len() as u64 {
            return Err(bad(format!(
                "damaged checkpoint: {} bytes of data where the header says {} (truncated?)",
                payload.len(),
                u64::from_le_bytes(len)
            )));
        }
        if crc32fast::hash(payload) != word(12) {
            return Err(bad(
                "damaged checkpoint: its checksum does not match its contents".into(),
            ));
        }
        let c: Self = postcard::from_bytes(payload).map_err(|e| {
            bad(format!(
                "not a checkpoint of a {D}D case (or a damaged one): {e}"
            ))
        })?;
        if c.case != case.name {
            return Err(bad(format!(
                "this checkpoint is of case '{}', not '{}': resume it with its own deck",
                c.case, case.name
            )));
        }
        let now = case.physics_fingerprint();
        let mut changes = Vec::new();
        for (key, then) in &c.physics {
            match now.iter().find(|(k, _)| k == key) {
                Some((_, v)) if v == then => {}
                Some((_, v)) => changes.push(format!("{key}: was {then}, is now {v}")),
                None => changes.push(format!("{key}: was {then}, is now absent")),
            }
        }
        for (key, v) in &now {
            if !c.physics.iter().any(|(k, _)| k == key) {
                changes.push(format!("{key}: new, {v}"));
            }
        }
        if !changes.is_empty() {
            return Err(bad(format!(
                "the deck's physical set-up changed since this checkpoint was written, so the run cannot go on from it ({}). Only the end time, the step cap and the output settings may change on resuming; start afresh for the rest",
                changes.join("; ")
            )));
        }
        Ok(c)
    }
}
