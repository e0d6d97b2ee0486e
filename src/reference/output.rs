//! Outputs of `anm reference ida|diffsol`: history.csv (the columns of `anm
//! run`), steps.csv (t, h, slip, order of every internal step), summary.json
//! (the common counters of [`super::counters`] under `"counters"`, the
//! settings, how the run stopped) and steps.svg (step size and |slip speed|
//! against time, log y axes).

use super::counters::Counters;
use super::run::{Crossing, IdaRun, IdaStop};
use crate::error::Result;
use crate::output::plot::{Curve, Panel, draw};
use crate::output::{create_dir, write_csv, write_json};
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Summary<'a> {
    tool: &'a str,
    version: &'a str,
    method: &'a str,
    scene: &'a str,
    kind: &'a str,
    rtol: f64,
    /// atol of the differential unknowns.
    atol: f64,
    /// "suppress" (algebraic unknowns out of the error test) or their atol.
    algebraic: &'a str,
    /// Other settings departing from the library's defaults.
    options: std::collections::BTreeMap<&'a str, &'a str>,
    counters: &'a Counters,
    /// Steps taken at order 1.
    order_one_steps: usize,
    /// Per unknown: accepted steps on which it had the largest weighted local
    /// error estimate (IDA only: which variable limits the step).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    dominant_error: std::collections::BTreeMap<&'a str, usize>,
    wall_s: f64,
    stop: &'a IdaStop,
    columns: &'a [String],
    output_rows: usize,
    y0: &'a [f64],
    yp0: &'a [f64],
    /// First up-crossings of |v_s| through Vc and 10 Vc.
    slip_crossings: &'a [Crossing],
    /// [t(|v_s| = Vc), t(|v_s| = 10 Vc)].
    #[serde(skip_serializing_if = "Option::is_none")]
    surge_window: Option<(f64, f64)>,
    /// Smallest internal step after the start-up (t >= 1% of the end time)
    /// and where: where the step size collapses, if it does.
    #[serde(skip_serializing_if = "Option::is_none")]
    min_step: Option<MinStep>,
    max_constraint_drift: f64,
}

#[derive(Serialize)]
struct MinStep {
    t: f64,
    h: f64,
    slip: f64,
}

/// Writes the outputs of `run` into `dir`.
pub fn write(run: &IdaRun, dir: &Path) -> Result<()> {
    create_dir(dir)?;
    let cols: Vec<&str> = run.columns.iter().map(String::as_str).collect();
    write_csv(&dir.join("history.csv"), &cols, &run.history)?;
    let rows: Vec<Vec<f64>> = run
        .steps
        .iter()
        .map(|s| vec![s.t, s.h, s.slip, s.order as f64])
        .collect();
    write_csv(&dir.join("steps.csv"), &["t", "h", "slip", "order"], &rows)?;
    let summary = Summary {
        tool: &run.tool,
        version: &run.version,
        method: &run.method,
        scene: &run.scene,
        kind: &run.kind,
        rtol: run.rtol,
        atol: run.atol,
        algebraic: &run.algebraic,
        options: run
            .options
            .iter()
            .map(|(k, v)| (k.as_str(), v.as_str()))
            .collect(),
        counters: &run.counters,
        order_one_steps: run.order_one_steps(),
        dominant_error: run
            .unknowns
            .iter()
            .zip(&run.dominant_error)
            .map(|(k, v)| (k.as_str(), *v))
            .collect(),
        wall_s: run.wall_s,
        stop: &run.stop,
        columns: &run.columns,
        output_rows: run.history.len(),
        y0: &run.y0,
        yp0: &run.yp0,
        slip_crossings: &run.crossings,
        surge_window: run.surge_window(),
        min_step: run.min_step_after(0.01 * run.stop.t).map(|s| MinStep {
            t: s.t,
            h: s.h,
            slip: s.slip,
        }),
        max_constraint_drift: run.max_constraint_drift,
    };
    write_json(&dir.join("summary.json"), &summary)?;
    if !run.steps.is_empty() {
        plot(run, &dir.join("steps.svg"))?;
    }
    Ok(())
}

fn plot(run: &IdaRun, path: &Path) -> Result<()> {
    let title = format!(
        "{} — {} {} {} (rtol {:e}) — stop: {} at t = {:.6} s",
        run.kind, run.tool, run.version, run.method, run.rtol, run.stop.reason, run.stop.t
    );
    let panels = [
        Panel {
            title: &title,
            x_label: "t (s)",
            y_label: "step size h (s)",
            curves: vec![Curve {
                label: "h",
                points: run.steps.iter().map(|s| (s.t, s.h)).collect(),
            }],
            log: (false, true),
        },
        Panel {
            title: "slip speed",
            x_label: "t (s)",
            y_label: "|v_s| (m/s)",
            curves: vec![Curve {
                label: "|v_s|",
                points: run.steps.iter().map(|s| (s.t, s.slip.abs())).collect(),
            }],
            log: (false, true),
        },
    ];
    draw(path, &panels)
}
