//! `history.csv`: one row of global quantities every N steps.

use crate::error::{Error, Result};
use crate::simulation::Diagnostics;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes the history file, flushing each row so that it survives a crash.
pub struct HistoryWriter {
    path: PathBuf,
    out: BufWriter<File>,
    /// Bytes in the file so far.
    len: u64,
}

impl HistoryWriter {
    /// Create the file and write the header. Columns: time, dt, kinetic_energy,
    /// internal_energy, contact_energy, gravity_energy, total_energy, momentum_x/y/z,
    /// max_pressure, min_interbody_distance (/Δp_avg; empty with no contact pair in range), and
    /// contact_force_<body>_x/y/z for each body.
    pub fn create(path: &Path, body_names: &[String]) -> Result<Self> {
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        let mut w = HistoryWriter {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            len: 0,
        };
        let mut header = String::from(
            "time,dt,kinetic_energy,internal_energy,contact_energy,gravity_energy,total_energy,\
             momentum_x,momentum_y,momentum_z,max_pressure,min_interbody_distance",
        );
        for name in body_names {
            for k in ["x", "y", "z"] {
                header.push_str(&format!(",contact_force_{name}_{k}"));
            }
        }
        header.push('\n');
        w.write(&header)?;
        Ok(w)
    }

    /// Continue an existing history file (a resumed run) from its first `len` bytes (what it
    /// held at the checkpoint: later rows, such as the closing row of the stopped run, go).
    pub fn append(path: &Path, len: u64) -> Result<Self> {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| Error::io(path, e))?;
        file.set_len(len).map_err(|e| Error::io(path, e))?;
        let mut file = file;
        std::io::Seek::seek(&mut file, std::io::SeekFrom::End(0))
            .map_err(|e| Error::io(path, e))?;
        Ok(HistoryWriter {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            len,
        })
    }

    /// Bytes written so far.
    pub fn len(&self) -> u64 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Append one row.
    pub fn row(&mut self, d: &Diagnostics) -> Result<()> {
        let mut line = format!(
            "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},",
            d.time,
            d.dt,
            d.kinetic,
            d.internal,
            d.contact,
            d.gravity,
            d.total,
            d.momentum[0],
            d.momentum[1],
            d.momentum[2],
            d.max_pressure
        );
        if let Some(g) = d.min_interbody_distance {
            line.push_str(&format!("{g:e}"));
        }
        for f in &d.body_contact_force {
            line.push_str(&format!(",{:e},{:e},{:e}", f[0], f[1], f[2]));
        }
        line.push('\n');
        self.write(&line)
    }

    fn write(&mut self, s: &str) -> Result<()> {
        self.len += s.len() as u64;
        self.out
            .write_all(s.as_bytes())
            .and_then(|_| self.out.flush())
            .map_err(|e| Error::io(&self.path, e))
    }
}

/// A history file read back: column names and rows (empty cells are NaN).
#[derive(Debug, Clone)]
pub struct History {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl History {
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut lines = text.lines();
        let columns = lines
            .next()
            .unwrap_or_default()
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|c| c.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        Ok(History { columns, rows })
    }

    /// A column by name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(
            self.rows
                .iter()
                .map(|r| r.get(k).copied().unwrap_or(f64::NAN))
                .collect(),
        )
    }
}
