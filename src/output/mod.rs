//! Run outputs: CSV curves, summary.json, SVG plots.

pub mod earlier_run;
#[cfg(feature = "hdf5")]
pub mod hdf5;
pub mod lock;
pub mod mode;
pub mod plot;
pub mod vtk;

use crate::error::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// A CSV value in full precision (17 significant digits, round-trip
/// exact); a negative zero is written as 0 (a column of rests reads 0, not
/// -0).
pub fn csv_number(x: f64) -> String {
    format!("{:.17e}", x + 0.0)
}

/// A CSV cell: an identifier as an integer, any other value by
/// [`csv_number`].
fn cell(id: bool, x: f64) -> String {
    if id {
        format!("{}", x as u64)
    } else {
        csv_number(x)
    }
}

/// Writes a CSV file with a header row; values in full precision.
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<()> {
    write_csv_ids(path, header, 0, rows)
}

/// [`write_csv`] whose first `ids` columns hold identifiers (node tags,
/// obstacle and mode numbers): written as integers, not as 1.0e0.
pub fn write_csv_ids(path: &Path, header: &[&str], ids: usize, rows: &[Vec<f64>]) -> Result<()> {
    let err = |e: csv::Error| Error::write(path, e);
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    w.write_record(header).map_err(err)?;
    for row in rows {
        if let Some(bad) = row.iter().position(|x| !x.is_finite()) {
            return Err(Error::write(
                path,
                format!(
                    "refusing to write non-finite `{}` = {}",
                    header.get(bad).unwrap_or(&"?"),
                    row[bad]
                ),
            ));
        }
        w.write_record(row.iter().enumerate().map(|(k, &x)| cell(k < ids, x)))
            .map_err(err)?;
    }
    w.flush().map_err(|e| Error::write(path, e))
}

/// A CSV file written row by row and flushed after each row, so that a run
/// stopped at any point leaves every row it computed.
pub struct CsvStream {
    path: std::path::PathBuf,
    writer: csv::Writer<std::fs::File>,
    header: Vec<String>,
    /// Leading columns of identifiers (step numbers), written as integers.
    ids: usize,
}

impl CsvStream {
    /// Creates the file with its header row.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self> {
        let mut writer = csv::Writer::from_path(path).map_err(|e| Error::write(path, e))?;
        writer
            .write_record(header)
            .and_then(|_| writer.flush().map_err(csv::Error::from))
            .map_err(|e| Error::write(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            header: header.iter().map(|s| s.to_string()).collect(),
            ids: 0,
        })
    }

    /// The first `ids` columns hold identifiers: written as integers.
    pub fn with_ids(mut self, ids: usize) -> Self {
        self.ids = ids;
        self
    }

    /// Appends a row in full precision; a non-finite value is refused.
    pub fn row(&mut self, row: &[f64]) -> Result<()> {
        if let Some(bad) = row.iter().position(|x| !x.is_finite()) {
            return Err(Error::write(
                &self.path,
                format!(
                    "refusing to write non-finite `{}` = {}",
                    self.header.get(bad).map_or("?", |s| s.as_str()),
                    row[bad]
                ),
            ));
        }
        let ids = self.ids;
        self.writer
            .write_record(row.iter().enumerate().map(|(k, &x)| cell(k < ids, x)))
            .and_then(|_| self.writer.flush().map_err(csv::Error::from))
            .map_err(|e| Error::write(&self.path, e))
    }
}

/// Writes any serializable value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::write(path, e))?;
    std::fs::write(path, text + "\n").map_err(|e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    })
}

/// Peak resident set size of this process (VmHWM of /proc/self/status), in
/// bytes; None where /proc is not available.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// An output folder that exists or can be made: neither it nor a folder
/// above it is a file.
pub fn folder_or_absent(dir: &Path) -> Result<()> {
    match dir.ancestors().find(|a| a.is_file()) {
        Some(file) => Err(Error::write(
            dir,
            format!(
                "{} is a file, not a folder (-o names the folder the outputs go to)",
                file.display()
            ),
        )),
        None => Ok(()),
    }
}

/// A stop compares with its reason (`report.stop == "end"`).
impl PartialEq<&str> for Stop {
    fn eq(&self, reason: &&str) -> bool {
        self.reason == *reason
    }
}

/// Creates the output directory (and parents).
pub fn create_dir(dir: &Path) -> Result<()> {
    folder_or_absent(dir)?;
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::write(dir, format!("cannot create the folder: {e}")))
}

/// Why and where a run stopped (summary.json `stop`).
#[derive(Clone, Debug, Serialize)]
pub struct Stop {
    /// "end", "singularity", "max_steps" or an error kind.
    pub reason: String,
    /// Time of the stop (DAE runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// Load parameter of the stop (continuation runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// The node (its mesh tag) of a singular point, or the node that a
    /// numerical stop's diagnosis names (shell runs in time).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// Human-readable diagnosis for anything but a normal end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
}

/// The progress bar of a run (per mille of the path), with the time spent
/// and an estimate of the time left: a run that crawls says so early
/// (review 12: a capstan at omega = 1e-8 had covered 0.035% of its time
/// after 300 s, silently).
pub fn progress_bar() -> indicatif::ProgressBar {
    let b = indicatif::ProgressBar::new(1000);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {percent:>3}% [{elapsed_precise}, ~{eta} left] {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    b
}
