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
use crate::particles::{Particles, RealParticles};
use crate::simulation::{Diagnostics, SearchStats, SimState};
use serde::{Deserialize, Serialize};
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

/// Format version, checked on reading (5 since S, b and the strain rate keep one triangle and
/// u is single precision: a format-4 checkpoint is refused, naming both versions).
pub const FORMAT: u32 = 5;

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

/// What a checkpoint holds, borrowed from the running simulation, serialised exactly as a
/// [`Checkpoint`] is read back (the same fields in the same order; the resume tests read what
/// it writes). Writing it copies nothing: the payload streams to the file
/// (a copy of the particles and of the encoded payload would each cost about the state's 400
/// bytes a particle in 3D, at the moment a large run is closest to its memory limit).
#[derive(Serialize)]
pub struct CheckpointRef<'a, const D: usize> {
    pub case: &'a str,
    pub physics: &'a [(String, String)],
    pub particles: RealParticles<'a, D>,
    pub sim: &'a SimState,
    pub searches: &'a SearchStats,
    pub run: &'a RunState,
}

/// A writer that passes bytes on while it sums their CRC-32 and counts them, and keeps the
/// first I/O error (postcard would not say what the disk said).
struct Summed<W: Write> {
    inner: W,
    crc: crc32fast::Hasher,
    len: u64,
    error: Option<std::io::Error>,
}

impl<W: Write> Write for Summed<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf).inspect_err(|e| {
            self.error
                .get_or_insert_with(|| std::io::Error::new(e.kind(), e.to_string()));
        })?;
        self.crc.update(&buf[..n]);
        self.len += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Passes postcard's bytes on to a [`Summed`] writer, 64 at a time (an error is kept there).
struct Sink<'a, W: Write>(&'a mut Summed<W>);

impl<W: Write> Extend<u8> for Sink<'_, W> {
    fn extend<I: IntoIterator<Item = u8>>(&mut self, bytes: I) {
        let mut buf = [0u8; 64];
        let mut n = 0;
        for b in bytes {
            buf[n] = b;
            n += 1;
            if n == buf.len() {
                let _ = self.0.write_all(&buf);
                n = 0;
            }
        }
        let _ = self.0.write_all(&buf[..n]);
    }
}

impl<const D: usize> CheckpointRef<'_, D> {
    /// Write atomically (see [`crate::output::atomic`]), so a crash never leaves half a
    /// checkpoint, with a checksum so that a damaged one is refused. The header's checksum and
    /// length are filled in once the payload is out.
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::output::atomic::write_with(path, |tmp| {
            let io = |e: std::io::Error| Error::io(path, e);
            let mut file = std::fs::File::create(tmp).map_err(io)?;
            file.write_all(&[0; HEADER]).map_err(io)?;
            let (crc, len) = {
                let mut out = Summed {
                    inner: std::io::BufWriter::with_capacity(1 << 20, &mut file),
                    crc: crc32fast::Hasher::new(),
                    len: 0,
                    error: None,
                };
                // Through `Extend`, not `postcard::to_io`: with `to_io` in the binary, LLVM
                // stopped vectorising the AVX2 rate pass (half its speed, as `strike bench`
                // showed), for no reason we could find.
                let encoded = postcard::to_extend(self, Sink(&mut out)).map(drop);
                if let Some(e) = out.error.take() {
                    return Err(io(e));
                }
                if let Err(e) = encoded {
                    return Err(Error::Invalid(format!(
                        "{}: cannot encode checkpoint: {e}",
                        path.display()
                    )));
                }
                out.flush().map_err(io)?;
                (out.crc.clone().finalize(), out.len)
            };
            let mut header = Vec::with_capacity(HEADER);
            header.extend_from_slice(MAGIC);
            header.extend_from_slice(&FORMAT.to_le_bytes());
            header.extend_from_slice(&crc.to_le_bytes());
            header.extend_from_slice(&len.to_le_bytes());
            file.seek(SeekFrom::Start(0)).map_err(io)?;
            file.write_all(&header).map_err(io)
        })
    }
}

impl<const D: usize> Checkpoint<D> {
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
