//! `anm`: command-line front end.

use anm::scene::{self, Kind};
use anyhow::Context;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "anm",
    version,
    about = "Asymptotic Numerical Method for shells in contact with friction"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a scene and write history.csv, steps.csv, summary.json and a plot into DIR.
    Run {
        scene: PathBuf,
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Read and validate a scene without solving it.
    Check { scene: PathBuf },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Check { scene } => {
            let (kind, _) = load(&scene)?;
            println!("{}: valid `{}` scene", scene.display(), kind.name());
            Ok(ExitCode::SUCCESS)
        }
        Command::Run { scene, out, quiet } => {
            let (kind, friction) = load(&scene)?;
            match kind {
                Kind::PlateCylinder => anyhow::bail!(
                    "{}: plate-cylinder scenes are not wired into this build yet",
                    scene.display()
                ),
                _ => {
                    let sc = friction.expect("friction kinds parse into a friction scene");
                    let run = anm::model::friction_run::run(&sc, Some(&out), !quiet)
                        .with_context(|| format!("running {}", scene.display()))?;
                    println!(
                        "{}: stop = {} at t = {:.6} s; {} steps, {} factorizations, {} solves, {:.3} s; outputs in {}",
                        scene.display(),
                        run.stop.reason,
                        run.stop.t.unwrap_or(f64::NAN),
                        run.stats.steps,
                        run.stats.factorizations,
                        run.stats.solves,
                        run.wall_s,
                        out.display()
                    );
                    if let Some(m) = &run.stop.message {
                        println!("  {m}");
                    }
                    // A stop on an error is a failure; a detected singularity is a result.
                    Ok(match run.stop.reason.as_str() {
                        "end" | "singularity" => ExitCode::SUCCESS,
                        _ => ExitCode::from(2),
                    })
                }
            }
        }
    }
}

fn load(
    path: &std::path::Path,
) -> anm::Result<(Kind, Option<anm::scene::friction::FrictionScene>)> {
    let text = scene::read(path)?;
    let kind = scene::kind(path, &text)?;
    match kind {
        Kind::PlateCylinder => Ok((kind, None)),
        _ => Ok((kind, Some(scene::friction::load(path, &text, kind)?))),
    }
}
