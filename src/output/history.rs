//! `history.csv`: one row of global quantities every N steps, written and read as CSV
//! (RFC 4180 quoting, by the `csv` crate: a body name is a header field whatever it holds).

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
    /// max_pressure, min_interbody_distance (/Δp_avg; empty with no contact pair in range),
    /// failed_particles (damage 1),
    /// `contact_force_<body>_x/y/z` for each body, and `penetration_<a>_<b>` (Δp_avg) and
    /// `mixed_<a>_<b>` for each pair of bodies (see `mixing`).
    pub fn create(path: &Path, body_names: &[String]) -> Result<Self> {
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        let mut w = HistoryWriter {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            len: 0,
        };
        let mut header: Vec<String> = [
            "time",
            "dt",
            "kinetic_energy",
            "internal_energy",
            "contact_energy",
            "gravity_energy",
            "total_energy",
            "momentum_x",
            "momentum_y",
            "momentum_z",
            "max_pressure",
            "min_interbody_distance",
            "failed_particles",
        ]
        .map(String::from)
        .to_vec();
        for name in body_names {
            for k in ["x", "y", "z"] {
                header.push(format!("contact_force_{name}_{k}"));
            }
        }
        for (a, na) in body_names.iter().enumerate() {
            for nb in &body_names[a + 1..] {
                header.push(format!("penetration_{na}_{nb}"));
                header.push(format!("mixed_{na}_{nb}"));
            }
        }
        w.write_record(&header)?;
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
        let mut fields: Vec<String> = [
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
            d.max_pressure,
        ]
        .iter()
        .map(|x| format!("{x:e}"))
        .collect();
        fields.push(
            d.min_interbody_distance
                .map_or(String::new(), |g| format!("{g:e}")),
        );
        fields.push(d.failed.to_string());
        for f in &d.body_contact_force {
            fields.extend(f.iter().map(|x| format!("{x:e}")));
        }
        for m in &d.mixing {
            fields.push(format!("{:e}", m.penetration));
            fields.push(m.mixed.to_string());
        }
        self.write_record(&fields)
    }

    /// One CSV record, flushed.
    fn write_record(&mut self, fields: &[String]) -> Result<()> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(fields)
            .map_err(|e| Error::Invalid(format!("{}: {e}", self.path.display())))?;
        let bytes = w
            .into_inner()
            .map_err(|e| Error::Invalid(format!("{}: {e}", self.path.display())))?;
        self.len += bytes.len() as u64;
        self.out
            .write_all(&bytes)
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
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let bad = |e: csv::Error| Error::Invalid(format!("{}: {e}", path.display()));
        let mut r = csv::ReaderBuilder::new().flexible(true).from_reader(file);
        let columns = r
            .headers()
            .map_err(bad)?
            .iter()
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        for record in r.records() {
            let record = record.map_err(bad)?;
            rows.push(
                record
                    .iter()
                    .map(|c| c.parse().unwrap_or(f64::NAN))
                    .collect(),
            );
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Body names with a comma or a quote stay one header field each, and every row has as
    /// many fields as the header.
    #[test]
    fn names_with_commas_and_quotes_are_quoted() {
        let dir = std::env::temp_dir().join(format!("strike_history_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("history.csv");
        let names = vec!["a,b".to_string(), "say \"hi\"".to_string()];
        let mut w = HistoryWriter::create(&path, &names).unwrap();
        let d = Diagnostics {
            time: 1.5,
            body_contact_force: vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
            mixing: vec![crate::mixing::PairMixing {
                penetration: 0.5,
                mixed: 3,
            }],
            ..Default::default()
        };
        w.row(&d).unwrap();
        drop(w);
        let h = History::read(&path).unwrap();
        assert_eq!(h.columns.len(), 13 + 6 + 2);
        assert!(h.rows.iter().all(|r| r.len() == h.columns.len()));
        assert_eq!(h.column("contact_force_a,b_y").unwrap(), vec![2.0]);
        assert_eq!(h.column("contact_force_say \"hi\"_z").unwrap(), vec![6.0]);
        assert_eq!(h.column("mixed_a,b_say \"hi\"").unwrap(), vec![3.0]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
