//! The recorder owns what a run writes: the probes on the output grid
//! (history.csv), the step log (steps.csv), both streamed and flushed at
//! every step so that an interrupted run keeps every computed point; VTK
//! snapshots with their .pvd index; the full fields at the snapshot lambdas
//! (HDF5); and the checkpoint from which `anm run --resume` continues.

use super::probe::{self, State};
use crate::error::{Error, Result};
use crate::fe::dof::{Component, node_vector};
use crate::mesh::Vec3;
use crate::output::vtk::{PointData, write_vtu_cells};
use crate::scene::shell::ShellScene;
use crate::shell::ShellModel;
use serde::{Deserialize, Serialize};
use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};

/// The mid-surface at one lambda: per node, reference position,
/// displacement, current director, normal reaction R and contact force R n,
/// and the full state they are computed from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Snapshot {
    pub lambda: f64,
    pub x0: Vec<[f64; 3]>,
    pub displacement: Vec<[f64; 3]>,
    pub director: Vec<[f64; 3]>,
    pub reaction: Vec<f64>,
    pub force: Vec<[f64; 3]>,
    /// 6 per node (fixed dofs included).
    pub state: Vec<f64>,
}

impl Snapshot {
    /// [x_lo, x_hi]: smallest and largest initial x of the nodes with R > threshold.
    pub fn contact_zone(&self, threshold: f64) -> Option<(f64, f64)> {
        let xs: Vec<f64> = self
            .x0
            .iter()
            .zip(&self.reaction)
            .filter(|(_, r)| **r > threshold)
            .map(|(x, _)| x[0])
            .collect();
        (!xs.is_empty()).then(|| {
            (
                xs.iter().copied().fold(f64::INFINITY, f64::min),
                xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        })
    }
}

/// One line of steps.csv.
pub struct StepRow {
    pub step: usize,
    pub lambda_start: f64,
    pub lambda_end: f64,
    /// Step length in the scaled arclength (ANM), or the scaled chord (Newton).
    pub length: f64,
    pub pade: bool,
    pub end_residual: f64,
    pub geometric: bool,
    pub factorizations: usize,
    pub solves: usize,
    /// Negative pivots of the step-start tangent (symmetric factorizations).
    pub negative_pivots: Option<usize>,
    /// Critical points found at this step's end (in this step or the one
    /// before: `EventRecord::step` says which).
    pub events: Vec<EventRecord>,
    /// Contact pairs that changed side of their law's switch during the
    /// step ([`ContactSides`]).
    pub contact_switches: usize,
}

/// A critical point of the path as written to summary.json (`events`) and
/// events.csv; steps.csv counts them in its column `events` on the row of
/// the step at whose end they were found (steps.csv stays all-numeric for
/// its readers).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EventRecord {
    /// `bifurcation`, `limit_point` or `geometric`
    /// ([`crate::series::bifurcation::Kind`]).
    pub kind: String,
    pub lambda: f64,
    /// The steps.csv step whose series holds the point.
    pub step: usize,
    /// Path parameter on that step's series.
    pub a: f64,
    /// Negative pivots of the tangent before and after the point.
    pub negative_pivots: Option<(usize, usize)>,
    /// Final bracket width in lambda (0: estimate without bracket).
    pub bracket: f64,
    /// Eigenvalue of the tangent nearest zero at the point (the test
    /// function; none for an estimate without location).
    pub kappa: Option<f64>,
    /// Tangent factorizations spent locating it.
    pub factorizations: usize,
    /// The mode's VTK file (in the output folder), if written.
    pub mode: Option<String>,
    /// The mode's dominant wavelength.
    pub wavelength: Option<f64>,
    pub half_waves: Option<f64>,
    pub wave_direction: Option<String>,
    /// The branch the path was on where the point was found: "primary", or
    /// "secondary" after a switch (`solver.branch = "secondary"`); the
    /// switching bifurcation itself is on the primary branch.
    #[serde(default = "primary")]
    pub branch: String,
}

fn primary() -> String {
    "primary".into()
}

const STEP_COLUMNS: [&str; 12] = [
    "step",
    "lambda_start",
    "lambda_end",
    "length",
    "pade",
    "end_residual",
    "geometric",
    "factorizations",
    "solves",
    "negative_pivots",
    "events",
    "contact_switches",
];

/// What the recorder keeps between steps: written into the checkpoint. The
/// history rows themselves are not: history.csv holds them (in full
/// precision), and a resume reads them back.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RecorderState {
    #[serde(skip)]
    pub history: Vec<Vec<f64>>,
    pub history_rows: usize,
    pub steps_rows: usize,
    pub pvd: Vec<(f64, usize, String)>,
    pub snapshots: Vec<Snapshot>,
    pub arclength: f64,
    pub grid_corrections: usize,
    pub grid_factorizations: usize,
    pub skipped_pull_bound: f64,
    pub active_sum: usize,
    /// Wall time of the run before a resume.
    pub wall_s_before: f64,
    /// Critical points found so far.
    #[serde(default)]
    pub events: Vec<EventRecord>,
    /// lambda of the bifurcation where a secondary-branch run left the path.
    #[serde(default)]
    pub switched_at: Option<f64>,
    /// Contact switches so far and each pair's side of its law's switch
    /// ([`ContactSides`]).
    #[serde(default)]
    pub contact: ContactSides,
    /// The deepest node outside the contact group inside an obstacle at a
    /// step end so far (run::penetration).
    #[serde(default)]
    pub penetration: Option<crate::run::penetration::Inside>,
    /// The furthest lambda toward lambda_end of a step end so far, times
    /// lambda_end's sign (a path that turned back, run::shell).
    #[serde(default)]
    pub reach: f64,
    /// The first step's largest translation per unit of lambda_end, in
    /// model sizes, and its lambda (a mechanism at the start, run::shell).
    #[serde(default)]
    pub first_rate: Option<(f64, f64)>,
}

/// Which side of its law's switch each contact pair is on, with
/// hysteresis: in contact below g = h / w = 1 (R above 0.62 K w in eq. 3's
/// r (r + g) = 1), open above g = 10 (R below 0.1 K w), unchanged in
/// between, so that a node moving about in the band does not count. A
/// switch is a pair changing side between two step ends (a touch or a
/// lift-off).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ContactSides {
    pub switches: usize,
    closed: Vec<Option<bool>>,
}

impl ContactSides {
    /// Updates the sides from the pairs' g at a step end (not finite:
    /// unknown, left as it was); returns the switches of this step.
    pub fn update(&mut self, g: &[f64]) -> usize {
        self.closed.resize(g.len(), None);
        let mut n = 0;
        for (side, &g) in self.closed.iter_mut().zip(g) {
            let now = if g < 1.0 {
                Some(true)
            } else if g > 10.0 {
                Some(false)
            } else {
                *side
            };
            if let (Some(a), Some(b)) = (*side, now)
                && a != b
            {
                n += 1;
            }
            if now.is_some() {
                *side = now;
            }
        }
        self.switches += n;
        n
    }
}

pub struct Recorder<'s> {
    pub scene: &'s ShellScene,
    pub dir: Option<PathBuf>,
    pub columns: Vec<String>,
    pub state: RecorderState,
    /// The full state of the last history row (lambda, vector): the
    /// corrected grid point, which the final files take where the path
    /// ends on it (review 24: written from the step end instead, they
    /// held 3e-5 of the load less contact force than history.csv's last
    /// row, with a moving obstacle).
    pub last_full: Option<(f64, Vec<f64>)>,
    history: Option<csv::Writer<File>>,
    steps: Option<csv::Writer<File>>,
}

fn io_err(file: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        file: file.to_path_buf(),
        source,
    }
}

fn csv_err(file: &Path) -> impl Fn(csv::Error) -> Error + '_ {
    move |e| Error::write(file, e)
}

/// Opens a streamed CSV: new with its header, or (resume) cut back to its
/// header and first `keep` rows, which are returned, and appended to.
fn open_csv(
    path: &Path,
    header: &[String],
    keep: Option<usize>,
) -> Result<(csv::Writer<File>, Vec<String>)> {
    if let Some(keep) = keep {
        let text = std::fs::read_to_string(path).map_err(io_err(path))?;
        let whole: Vec<&str> = text.split_inclusive('\n').take(keep + 1).collect();
        let lines: Vec<String> = whole
            .iter()
            .map(|l| l.trim_end_matches('\n').to_string())
            .collect();
        if lines.len() != keep + 1 || lines[0] != header.join(",") {
            return Err(Error::Resume {
                file: path.to_path_buf(),
                problem: format!(
                    "does not match the checkpoint ({} rows expected with header `{}`)",
                    keep,
                    header.join(",")
                ),
            });
        }
        // Review 23: a last row cut mid-line (a file damaged from outside)
        // passed the row count; the resumed run then appended to it and
        // panicked at the end, leaving rn_D = 4.300 for 4.30065e-5. Every
        // kept row is whole: ended by a newline, one number (or an empty
        // cell) per column.
        for (k, (line, raw)) in lines.iter().zip(&whole).enumerate().skip(1) {
            let cells: Vec<&str> = line.split(',').collect();
            let whole_row = raw.ends_with('\n')
                && cells.len() == header.len()
                && cells
                    .iter()
                    .all(|c| c.is_empty() || c.parse::<f64>().is_ok());
            if !whole_row {
                return Err(Error::Resume {
                    file: path.to_path_buf(),
                    problem: format!(
                        "row {k} is not a whole row of {} numbers (cut or edited since the run stopped): `{line}`",
                        header.len()
                    ),
                });
            }
        }
        let mut text = lines.join("\n");
        text.push('\n');
        std::fs::write(path, text).map_err(io_err(path))?;
        let f = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(io_err(path))?;
        Ok((csv::Writer::from_writer(f), lines[1..].to_vec()))
    } else {
        let mut w = csv::Writer::from_path(path).map_err(csv_err(path))?;
        w.write_record(header).map_err(csv_err(path))?;
        w.flush().map_err(io_err(path))?;
        Ok((w, vec![]))
    }
}

impl<'s> Recorder<'s> {
    /// A recorder writing into `dir` (None: in memory only), fresh or
    /// continuing `resumed`.
    pub fn new(
        scene: &'s ShellScene,
        dir: Option<&Path>,
        resumed: Option<RecorderState>,
    ) -> Result<Self> {
        let mut columns = vec!["lambda".to_string()];
        columns.extend(scene.probes.iter().map(|p| p.name.clone()));
        let mut state = resumed.unwrap_or_default();
        let (history, steps) = match dir {
            Some(d) => {
                crate::output::create_dir(d)?;
                let resuming = state.history_rows + state.steps_rows > 0;
                let step_header: Vec<String> = STEP_COLUMNS.iter().map(|s| s.to_string()).collect();
                let path = d.join("history.csv");
                let (h, rows) = open_csv(&path, &columns, resuming.then_some(state.history_rows))?;
                state.history = rows
                    .iter()
                    .map(|l| {
                        l.split(',')
                            .map(str::parse)
                            .collect::<std::result::Result<_, _>>()
                    })
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|e| Error::Resume {
                        file: path.clone(),
                        problem: format!("unreadable row: {e}"),
                    })?;
                let (s, _) = open_csv(
                    &d.join("steps.csv"),
                    &step_header,
                    resuming.then_some(state.steps_rows),
                )?;
                (Some(h), Some(s))
            }
            None => (None, None),
        };
        Ok(Self {
            scene,
            dir: dir.map(Path::to_path_buf),
            columns,
            state,
            last_full: None,
            history,
            steps,
        })
    }

    /// Signed grid step: multiples of output.lambda_step toward lambda_end.
    pub fn grid_step(&self) -> f64 {
        self.scene.output.lambda_step * self.scene.solver.lambda_end.signum()
    }

    /// Grid values crossed by a move from lambda a to lambda b (a excluded,
    /// b included), in the order they are met.
    pub fn grid_between(&self, a: f64, b: f64) -> Vec<f64> {
        let d = self.grid_step();
        let tol = 1e-12 * d.abs().max(1.0);
        let end = self.scene.solver.lambda_end;
        let mut out = vec![];
        let ka = (a / d).floor() as i64 - 1;
        let kb = (b / d).ceil() as i64 + 1;
        let (lo, hi) = (ka.min(kb) - 1, ka.max(kb) + 1);
        for k in lo..=hi {
            let g = k as f64 * d;
            let inside = if b >= a {
                g > a + tol && g <= b + tol
            } else {
                g < a - tol && g >= b - tol
            };
            // Stay within [0, lambda_end] of the scene.
            let in_range = g * end.signum() >= -tol && (g - end) * end.signum() <= tol;
            if inside && in_range {
                out.push(g);
            }
        }
        // In the order met (the grid step is negative where lambda_end is).
        match b < a {
            true => out.sort_by(|x, y| y.total_cmp(x)),
            false => out.sort_by(|x, y| x.total_cmp(y)),
        }
        out
    }

    /// A history row at a state; a snapshot too when lambda is one of the
    /// scene's snapshot values.
    pub fn record(&mut self, model: &ShellModel, s: &State) -> Result<()> {
        let mut row = vec![s.lambda];
        row.extend(probe::evaluate(model, &self.scene.probes, s)?);
        if let Some(bad) = row.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                step: self.state.steps_rows,
                param: "lambda",
                at: s.lambda,
                what: format!("probe `{}` = {}", self.columns[bad], row[bad]),
            });
        }
        if let Some(w) = &mut self.history {
            w.write_record(row.iter().map(|&x| crate::output::csv_number(x)))
                .and_then(|_| w.flush().map_err(csv::Error::from))
                .map_err(|e| {
                    Error::write(self.dir.clone().unwrap_or_default().join("history.csv"), e)
                })?;
        }
        self.state.history.push(row);
        self.state.history_rows += 1;
        self.last_full = Some((s.lambda, s.full.to_vec()));
        if self
            .scene
            .output
            .snapshots
            .iter()
            .any(|v| (v - s.lambda).abs() < 1e-9)
        {
            self.state.snapshots.push(snapshot(model, s));
        }
        Ok(())
    }

    /// Appends a steps.csv line.
    pub fn step(&mut self, r: &StepRow) -> Result<()> {
        if let Some(w) = &mut self.steps {
            let rec = [
                r.step.to_string(),
                format!("{:.17e}", r.lambda_start),
                format!("{:.17e}", r.lambda_end),
                format!("{:.6e}", r.length),
                (r.pade as u8).to_string(),
                // Empty where the end's residual was refused (NaN).
                if r.end_residual.is_finite() {
                    format!("{:.3e}", r.end_residual)
                } else {
                    String::new()
                },
                (r.geometric as u8).to_string(),
                r.factorizations.to_string(),
                r.solves.to_string(),
                r.negative_pivots.map(|k| k.to_string()).unwrap_or_default(),
                r.events.len().to_string(),
                r.contact_switches.to_string(),
            ];
            w.write_record(&rec)
                .and_then(|_| w.flush().map_err(csv::Error::from))
                .map_err(|e| {
                    Error::write(self.dir.clone().unwrap_or_default().join("steps.csv"), e)
                })?;
        }
        self.state.steps_rows += 1;
        Ok(())
    }

    /// VTK of the deformed shell at a state, indexed in the .pvd.
    pub fn vtk(&mut self, model: &ShellModel, full: &[f64], lambda: f64, name: &str) -> Result<()> {
        let Some(d) = &self.dir else { return Ok(()) };
        let s = snapshot(
            model,
            &State {
                full,
                lambda,
                arclength: 0.0,
                residual: None,
                linear: None,
            },
        );
        let v = |a: &[[f64; 3]]| {
            a.iter()
                .map(|x| Vec3::new(x[0], x[1], x[2]))
                .collect::<Vec<_>>()
        };
        let x: Vec<Vec3> =
            s.x0.iter()
                .zip(&s.displacement)
                .map(|(a, b)| Vec3::new(a[0] + b[0], a[1] + b[1], a[2] + b[2]))
                .collect();
        let mesh = &self.scene.mesh;
        let mut cells = vec![PointData::Tags("element", &mesh.quad_tags)];
        cells.extend(super::section::stress_cells(
            model,
            full,
            self.scene.thickness,
            matches!(self.scene.method, crate::scene::shell::Method::Linear),
        ));
        write_vtu_cells(
            &d.join(name),
            &x,
            &mesh.quads,
            &[
                PointData::Vector("displacement", v(&s.displacement)),
                PointData::Vector("director", v(&s.director)),
                PointData::Vector("contact_force", v(&s.force)),
                PointData::Scalar("contact_reaction", s.reaction),
                PointData::Tags("node", &mesh.node_tags),
            ],
            &cells,
        )?;
        self.state.pvd.push((lambda, 0, name.to_string()));
        Ok(())
    }

    /// Records an event and rewrites events.csv (branch, kind, lambda, step, a,
    /// negative pivots before and after, bracket, kappa, factorizations,
    /// half-waves, wavelength, direction, mode file).
    pub fn event(&mut self, e: EventRecord) -> Result<()> {
        self.state.events.push(e);
        let Some(d) = &self.dir else { return Ok(()) };
        let path = d.join("events.csv");
        let mut w = csv::Writer::from_path(&path).map_err(csv_err(&path))?;
        w.write_record([
            "branch",
            "kind",
            "lambda",
            "step",
            "a",
            "negative_pivots_before",
            "negative_pivots_after",
            "bracket",
            "kappa",
            "factorizations",
            "half_waves",
            "wavelength",
            "wave_direction",
            "mode",
        ])
        .map_err(csv_err(&path))?;
        let opt = |x: Option<f64>| x.map(|v| format!("{v:.9e}")).unwrap_or_default();
        for e in &self.state.events {
            w.write_record([
                e.branch.clone(),
                e.kind.clone(),
                format!("{:.17e}", e.lambda),
                e.step.to_string(),
                format!("{:.9e}", e.a),
                e.negative_pivots
                    .map(|p| p.0.to_string())
                    .unwrap_or_default(),
                e.negative_pivots
                    .map(|p| p.1.to_string())
                    .unwrap_or_default(),
                format!("{:.3e}", e.bracket),
                opt(e.kappa),
                e.factorizations.to_string(),
                opt(e.half_waves),
                opt(e.wavelength),
                e.wave_direction.clone().unwrap_or_default(),
                e.mode.clone().unwrap_or_default(),
            ])
            .map_err(csv_err(&path))?;
        }
        w.flush().map_err(io_err(&path))
    }

    /// Writes the checkpoint (atomically: a temporary file renamed).
    pub fn checkpoint<T: Serialize>(&self, value: &T) -> Result<()> {
        let Some(d) = &self.dir else { return Ok(()) };
        let tmp = d.join("checkpoint.json.tmp");
        let text = serde_json::to_string(value).map_err(|e| Error::write(&tmp, e))?;
        // Renamed into place: a process stopped at any point leaves the old
        // or the new checkpoint, never half of one.
        std::fs::write(&tmp, text).map_err(io_err(&tmp))?;
        let path = d.join("checkpoint.json");
        std::fs::rename(&tmp, &path).map_err(io_err(&path))
    }
}

/// The mid-surface fields at a state.
pub fn snapshot(model: &ShellModel, s: &State) -> Snapshot {
    let n = model.n_nodes();
    let (r, f) = probe::nodal_contact(n, &probe::contacts(model, s.full, s.lambda));
    let arr = |v: Vec3| [v[0], v[1], v[2]];
    Snapshot {
        lambda: s.lambda,
        x0: model.x0.iter().map(|x| arr(*x)).collect(),
        displacement: (0..n)
            .map(|i| node_vector(s.full, i, Component::DISPLACEMENT))
            .collect(),
        director: (0..n)
            .map(|i| {
                let w = node_vector(s.full, i, Component::DIRECTOR);
                arr(model.a30[i] + Vec3::new(w[0], w[1], w[2]))
            })
            .collect(),
        reaction: r,
        force: f.into_iter().map(arr).collect(),
        state: s.full.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::ContactSides;

    #[test]
    fn contact_sides_count_crossings_of_the_band_not_moves_inside_it() {
        let mut s = ContactSides::default();
        // First values: sides set, nothing counted; the second pair starts
        // between the thresholds (side unknown).
        assert_eq!(s.update(&[1e5, 5.0, -3.0]), 0);
        // The first pair moves but stays open; the third pair opens.
        assert_eq!(s.update(&[9.0, 2.0, 20.0]), 1);
        // The first pair touches, the second gets a side (no switch).
        assert_eq!(s.update(&[0.5, 0.9, f64::NAN]), 1);
        // Back and forth between the thresholds, then the third pair touches.
        assert_eq!(s.update(&[9.0, 5.0, -1.5]), 1);
        assert_eq!(s.switches, 3);
    }
}
