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
    /// Solve a scene and write its files into DIR: history.csv, summary.json
    /// and plots always; steps.csv on a path in lambda and on a point-mass
    /// scene, friction.csv on a shell in time (README, "What a run writes"). Ctrl-C or SIGTERM stops a shell run at the next step end with consistent
    /// files; `anm run --resume DIR` continues it.
    Run {
        /// The scene file (not with --resume).
        #[arg(required_unless_present = "resume")]
        scene: Option<PathBuf>,
        #[arg(short, long, value_name = "DIR", required_unless_present = "resume")]
        out: Option<PathBuf>,
        /// Continue the interrupted shell run in DIR from its checkpoint.json.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "out"])]
        resume: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Run a shell scene even when its mesh needs more memory than the
        /// machine has (by the measured figures of `anm check`).
        #[arg(long)]
        ignore_memory: bool,
    },
    /// Read and validate a scene without solving it.
    Check {
        scene: PathBuf,
        /// Check a shell scene even when its mesh needs more memory than
        /// the machine has.
        #[arg(long)]
        ignore_memory: bool,
    },
    /// Linearized buckling of a shell scene (Abaqus *BUCKLE): the lowest
    /// eigenvalues mu and modes of (K_0 + mu K_sigma) about the state at
    /// --lambda (path followed by the ANM) or the initial state; the
    /// eigenvalue table on stdout, with -o also buckle.csv, buckle.json and
    /// one buckle_mode_K.vtu per mode.
    Buckle {
        scene: PathBuf,
        /// lambda of the base state (0: the initial state; negative: the
        /// load reversed, e.g. `--lambda -0.5`).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        lambda: f64,
        /// A scene with [friction]: the time (s) of the base state, reached
        /// by the run in time; sticking friction nodes are tied there.
        #[arg(long, conflicts_with = "lambda")]
        time: Option<f64>,
        /// Number of modes.
        #[arg(long, default_value_t = 4)]
        modes: usize,
        /// Instead: locate the path's first critical point by the ANM and by
        /// Newton load increments of this size with bisection on the
        /// tangent's negative pivots to 1e-6 (the incremental codes' way),
        /// and print what each cost (critical.md with -o).
        #[arg(long, value_name = "INCREMENT")]
        locate: Option<f64>,
        #[arg(short, long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Sweep regularization parameters (in parallel) and report how much they
    /// bend the key outputs and what they cost: the table on stdout; with -o,
    /// also audit.csv, audit.md, audit.svg.
    Audit {
        scene: PathBuf,
        /// Values of omega (velocity regularization, eq. 6), comma-separated.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        omega: Vec<f64>,
        /// Values of zeta (normal-force regularization, eq. 11, N).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        zeta: Vec<f64>,
        /// Values of eta (contact regularization, eq. 3, N; on a shell
        /// scene 0 is the penalty law, the limit eta -> 0).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        eta: Vec<f64>,
        /// Values of the penalty stiffness K (eq. 3, force per length in
        /// the scene's units).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        penalty: Vec<f64>,
        /// Write audit.csv, audit.md and audit.svg into DIR (otherwise no
        /// files), and every run's result as DIR/items/K.json.
        #[arg(short, long, value_name = "DIR")]
        out: Option<PathBuf>,
        #[command(flatten)]
        items: ItemArgs,
    },
    /// Work-precision benchmark: error against wall time per method and
    /// setting, tables on stdout; with -o, also bench.csv, bench.md, bench.svg
    /// and target.md. Wall times are medians.
    Bench {
        /// Folder holding the canonical scenes.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Cases to run (comma-separated).
        #[arg(long, value_delimiter = ',', default_values_t = ["friction-1d".to_string(), "friction-plane".to_string(), "friction-roller".to_string()])]
        cases: Vec<String>,
        /// Repetitions per setting (the median and minimum are reported).
        #[arg(long, default_value_t = 3)]
        repeat: usize,
        /// Scaling study instead of the cases: plate-cylinder strip meshes
        /// NXxNY (comma-separated, e.g. 40x4,80x8), each run in its own
        /// process for --scaling-steps steps (scaling.md).
        #[arg(long, value_delimiter = ',')]
        scaling: Vec<String>,
        #[arg(long, default_value_t = 10)]
        scaling_steps: usize,
        /// With --scaling: write each size's initial tangent as
        /// run-NXxNY/tangent.mtx and factor it with each backend in its own
        /// process (`anm factor`), and with the peers of reference/peers/ when
        /// they are installed (factor.md).
        #[arg(long)]
        write_matrix: bool,
        /// Error targets of the fastest-setting table (fastest.md) and of the
        /// head-to-head (target.md): the fastest ANM and baseline (IDA,
        /// diffsol BDF, diffsol ESDIRK) settings reaching each are timed
        /// again, interleaved. A case whose two references disagree by more
        /// than target / 1.2 is compared at 1.2 x their difference.
        #[arg(long, value_delimiter = ',', default_values_t = [1e-6, 1e-8])]
        target: Vec<f64>,
        /// Values of zeta (N) at which friction-plane and friction-roller
        /// are benchmarked, each a case of its own (friction-1d has no zeta).
        #[arg(long, value_delimiter = ',', default_values_t = [1e-1, 1e-4])]
        zeta: Vec<f64>,
        /// The stiffness grid instead (issue 13, stiffness.md): friction-plane
        /// and friction-roller over --zeta x --omega, the ANM with the scene's
        /// settings and solver.time_step = "auto" against IDA (needs --features reference); the error
        /// target is the first of --target.
        #[arg(long)]
        stiffness: bool,
        /// Values of omega (eq. 6) of the stiffness grid.
        #[arg(long, value_delimiter = ',', default_values_t = [1e-1])]
        omega: Vec<f64>,
        /// Interleaved rounds of the head-to-head.
        #[arg(long, default_value_t = 100)]
        rounds: usize,
        /// Also count the instructions of each head-to-head contender with
        /// valgrind's callgrind (a few seconds each).
        #[arg(long)]
        instructions: bool,
        /// Write the tables and plots into DIR (otherwise no files; --scaling
        /// needs it for its meshes, scenes and runs).
        #[arg(short, long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// With --scaling: one size per item (the work-precision benchmark
        /// and the head-to-head compare timings taken side by side on one
        /// machine and are not split).
        #[command(flatten)]
        items: ItemArgs,
    },
    /// Time one method and setting on a friction scene: `repeat` solves after
    /// a warm-up, wall min / median / max. Under callgrind (see
    /// `anm::study::timing::instructions`) it gives the instruction count.
    Time {
        scene: PathBuf,
        /// anm:ORDER:EPS (e.g. anm:15:1e-9), ida:RTOL (e.g. ida:1e-10),
        /// diffsol-bdf:RTOL or diffsol-esdirk:RTOL.
        #[arg(long)]
        method: anm::study::bench::Method,
        /// Timed repetitions after a warm-up run; 0: a single run (for callgrind).
        #[arg(long, default_value_t = 20)]
        repeat: usize,
    },
    /// Factor a sparse matrix (MatrixMarket, e.g. the tangent.mtx of a run
    /// with output.tangent_matrix = true) with one backend: analysis, numeric
    /// factorization (best of --repeat), one solve, factor entries, backward
    /// error, peak memory of the process. One JSON line on stdout.
    /// Duplicate entries of the file are summed (as SciPy's mmread does).
    Factor {
        matrix: PathBuf,
        /// auto (from the matrix's symmetry), ldlt, lblt or lu.
        #[arg(long, default_value = "auto")]
        backend: String,
        /// Threads of the factorization and solves.
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Numeric factorizations timed (the best is reported).
        #[arg(long, default_value_t = 3)]
        repeat: usize,
    },
    /// Solve a friction scene with an external reference solver (IDA with
    /// `--features reference`; diffsol always).
    Reference {
        #[command(subcommand)]
        solver: ReferenceSolver,
    },
    /// Stability stress matrix on the friction scenes and the coarse
    /// plate-cylinder: every run must meet its accuracy check or stop with a
    /// diagnosis (stress.md, stress.csv).
    Stress {
        /// Folder holding the scenes named by --cases.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Scenes to stress (file stems in --scenes, comma-separated).
        #[arg(long, value_delimiter = ',', default_values_t = ["friction-1d".to_string(), "friction-plane".to_string(), "friction-roller".to_string(), "plate-cylinder-coarse".to_string()])]
        cases: Vec<String>,
        /// Step budget per run.
        #[arg(long, default_value_t = 20000)]
        max_steps: usize,
        /// Write stress.md, stress.csv and every run's result as
        /// DIR/items/K.json (required, except with --list-items).
        #[arg(
            short,
            long,
            value_name = "DIR",
            required_unless_present = "list_items"
        )]
        out: Option<PathBuf>,
        #[command(flatten)]
        items: ItemArgs,
    },
    /// Build the tables and plots of a sweep run item by item (`anm audit |
    /// stress | bench --scaling ... --item K -o DIR`) from DIR/sweep.json and
    /// DIR/items/*.json: the same files as the single-process run. Names the
    /// missing items, if any.
    Merge {
        /// The -o DIR of the items.
        dir: PathBuf,
    },
}

/// Running a sweep item by item (GNU parallel, Slurm job arrays; see
/// docs/cluster.md).
#[derive(clap::Args)]
struct ItemArgs {
    /// Run item K of the sweep only and write DIR/items/K.json (needs -o
    /// DIR); `anm merge DIR` builds the tables once every item has run.
    #[arg(long, value_name = "K", requires = "out", allow_hyphen_values = true)]
    item: Option<usize>,
    /// Print the items of the sweep, `K<TAB>label` per line, and exit.
    #[arg(long, conflicts_with = "item")]
    list_items: bool,
}

#[derive(Subcommand)]
enum ReferenceSolver {
    /// SUNDIALS IDA on a friction scene's DAE: writes history.csv, steps.csv,
    /// summary.json and steps.svg into DIR. On a shell scene with
    /// [friction]: the residual `anm run` integrates, from the same start,
    /// with its history.csv columns, friction.csv, friction.svg and
    /// summary.json (dense linear algebra: up to 2,500 unknowns).
    #[cfg(feature = "reference")]
    Ida {
        scene: PathBuf,
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Relative tolerance.
        #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
        rtol: f64,
        /// Absolute tolerance of the differential unknowns (positions);
        /// default: rtol on a point-mass scene (m), rtol × the model's
        /// length scale on a shell scene (its length unit).
        #[arg(long, allow_hyphen_values = true)]
        atol: Option<f64>,
        /// The algebraic unknowns (velocities, forces; u_y on the plane) in
        /// the local error test: `suppress` (default: out of it,
        /// IDASetSuppressAlg) or their absolute tolerance (IDASVtolerances).
        #[arg(long, default_value = "suppress", allow_hyphen_values = true)]
        atol_algebraic: String,
        /// The friction law in the DAE: `product` (R_T Vc^q |w|_reg^(1-q) +
        /// f N w = 0, not steep in w; default) or `direct` (R_T + f N g(w) = 0).
        #[arg(long, default_value = "product")]
        friction_row: String,
        /// Newton iterations per step attempt (IDASetMaxNonlinIters; IDA's
        /// own default is 4) [default: 20 on a point-mass scene, 10 on a
        /// shell scene].
        #[arg(long)]
        max_nonlin_iters: Option<usize>,
    },
    /// diffsol (pure Rust, BDF or ESDIRK34, singular mass matrix) on a
    /// friction scene's DAE: the same outputs as `anm reference ida`.
    Diffsol {
        scene: PathBuf,
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// `bdf` (variable order 1-5) or `esdirk` (ESDIRK34, order 3).
        #[arg(long, default_value = "bdf")]
        method: String,
        /// Relative tolerance.
        #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
        rtol: f64,
        /// Absolute tolerance of the differential unknowns (positions, m);
        /// default: rtol.
        #[arg(long, allow_hyphen_values = true)]
        atol: Option<f64>,
        /// Absolute tolerance of the algebraic unknowns (diffsol has no
        /// suppress-alg; its error norm covers every unknown).
        #[arg(long, default_value_t = anm::reference::diffsol::ATOL_ALGEBRAIC, allow_hyphen_values = true)]
        atol_algebraic: f64,
        /// Newton convergence failures allowed over the whole run (diffsol
        /// counts them per run, not per step; its default is 50).
        #[arg(long, default_value_t = anm::reference::diffsol::MAX_NONLINEAR_FAILURES)]
        max_nonlinear_failures: usize,
        /// Evaluate df/dy at every step and after every Newton failure
        /// (`false`: diffsol's defaults, every 50 steps).
        #[arg(long, default_value_t = anm::reference::diffsol::FRESH_JACOBIAN, action = clap::ArgAction::Set)]
        fresh_jacobian: bool,
        /// The friction law in the DAE: `product` (default) or `direct`.
        #[arg(long, default_value = "product")]
        friction_row: String,
    },
}

/// Loads a friction scene for a reference solver, or says why not.
fn reference_scene(
    scene: &std::path::Path,
    solver: &str,
) -> anyhow::Result<anm::scene::friction::FrictionScene> {
    let (kind, friction) = load(scene)?;
    let Some(sc) = friction else {
        anyhow::bail!(
            "{}: {solver} solves the friction scenes only, not `{}`",
            scene.display(),
            kind.name()
        );
    };
    Ok(sc)
}

/// Writes a reference run's outputs, prints its summary line; exit code 2
/// when it did not reach the end.
fn reference_report(
    scene: &std::path::Path,
    run: &anm::reference::IdaRun,
    out: &std::path::Path,
) -> anyhow::Result<ExitCode> {
    anm::reference::output::write(run, out)?;
    let c = &run.counters;
    println!(
        "{}: {} {} ({}): stop = {} at t = {:.9} s; {} steps ({} at order 1), {} error-test failures, {} convergence failures, {} residual evals, {} Jacobian evals, {} factorizations, {:.3} s; outputs in {}",
        scene.display(),
        run.tool,
        run.version,
        run.method,
        run.stop.reason,
        run.stop.t,
        c.steps,
        run.order_one_steps(),
        c.error_test_failures,
        c.convergence_failures,
        c.residual_evaluations,
        c.jacobian_evaluations,
        c.factorizations,
        run.wall_s,
        out.display()
    );
    if let Some(m) = &run.stop.message {
        println!("  {m}");
    }
    if let Some((t1, t10)) = run.surge_window() {
        println!("  |slip| rises from Vc to 10 Vc over [{t1:.9}, {t10:.9}] s");
    }
    Ok(match run.stop.reason.as_str() {
        "end" => ExitCode::SUCCESS,
        _ => ExitCode::from(2),
    })
}

/// Prints `anm reference ida`'s summary line on a shell scene; exit code 2
/// when IDA did not reach t_end.
#[cfg(feature = "reference")]
fn shell_reference_summary(
    r: &anm::run::shell_reference::ShellReferenceReport,
    out: &std::path::Path,
) -> ExitCode {
    let c = &r.counters;
    println!(
        "{}: {} {} ({}, rtol {:e}, atol {:e}): stop = {} at t = {:.9} s; {} unknowns ({} friction nodes); {} steps, {} error-test failures, {} convergence failures, {} residual evals, {} Jacobian evals, {} factorizations, {:.3} s; outputs in {}",
        r.scene,
        r.tool,
        r.version,
        r.method,
        r.rtol,
        r.atol,
        r.stop.reason,
        r.stop.t,
        r.unknowns,
        r.friction_nodes,
        c.steps,
        c.error_test_failures,
        c.convergence_failures,
        c.residual_evaluations,
        c.jacobian_evaluations,
        c.factorizations,
        r.wall_s,
        out.display()
    );
    if let Some(m) = &r.stop.message {
        println!("  {m}");
    }
    for n in &r.notes {
        println!("note: {n}");
    }
    match r.stop.reason.as_str() {
        "end" => ExitCode::SUCCESS,
        _ => ExitCode::from(2),
    }
}

/// The error and its causes, each once: our errors already print their
/// source (e.g. the I/O error after the file name), which `{:#}` would repeat.
fn error_chain(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.ends_with(&c) {
            msg = format!("{msg}: {c}");
        }
    }
    msg
}

fn main() -> ExitCode {
    // Built for x86-64-v3 (.cargo/config.toml): on a CPU without AVX2 the
    // first vector instruction would end the process with SIGILL and no word.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    if !(std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
        && std::arch::is_x86_feature_detected!("movbe")
        && std::arch::is_x86_feature_detected!("f16c"))
    {
        eprintln!(
            "error: this anm was built for x86-64-v3 (AVX2, FMA, BMI1/2, LZCNT, MOVBE, F16C; \
             .cargo/config.toml) \
             and this CPU lacks them; rebuild with \
             RUSTFLAGS=\"-C target-cpu=x86-64\" cargo build --release"
        );
        return ExitCode::from(2);
    }
    // A closed stdout (`anm ... | head`) ends the process as for any Unix
    // tool, not with a panic in println!.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // glibc serves each allocation above 32 MB (a tangent's values, the
    // sparse factor: 42 and 136 MB at 98,400 unknowns) with fresh pages that
    // the kernel faults in and zeroes, at every step: 8–12% of the engine
    // step there (README, "Step cost and scaling"). From the heap instead,
    // kept between steps, they reuse the same pages.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX);
    }
    // The main thread is one of the pool's threads: a parallel element loop
    // started by the step then runs on it at once, instead of waiting for
    // two pool threads to wake after a sequential factorization or solve
    // (measured: one of them often came ~2 ms late, and the loop ran on one
    // core; README, "Step cost and scaling").
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
    let cli = Cli::parse();
    // MPI lives for the whole process (feature mumps): every MUMPS instance
    // is dropped inside `dispatch`, before MPI_Finalize.
    #[cfg(feature = "mumps")]
    anm::linalg::mpi::mpi_init();
    let code = match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::FAILURE
        }
    };
    #[cfg(feature = "mumps")]
    anm::linalg::mpi::mpi_finalize();
    code
}

fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Factor {
            matrix,
            backend,
            threads,
            repeat,
        } => {
            let choice = match backend.as_str() {
                "auto" => anm::linalg::Choice::Auto,
                name => anm::linalg::Choice::Only(
                    anm::linalg::Backend::from_name(name).ok_or_else(|| {
                        anyhow::anyhow!("--backend: expected auto, ldlt, lblt or lu, got `{name}`")
                    })?,
                ),
            };
            if threads == 0 {
                anyhow::bail!("--threads: must be >= 1");
            }
            if repeat == 0 {
                anyhow::bail!("--repeat: must be >= 1");
            }
            let report = anm::study::factor::run(&matrix, choice, threads, repeat)?;
            println!("{}", serde_json::to_string(&report)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Check {
            scene,
            ignore_memory,
        } => {
            let (kind, point_mass) = load(&scene)?;
            if let Some(fs) = &point_mass {
                // The start a run would take: exact initial values checked,
                // the Newton start converged, the first step taken.
                anm::model::friction_run::check_start(fs)?;
            }
            if kind == Kind::Shell {
                let sc = anm::scene::shell::load(&scene)?;
                fits_in_memory(&sc, ignore_memory)?;
                // A run in time starts from its own tangent (with friction),
                // so its step 0 is the check; the static one would build the
                // model a second time for a matrix the run never factors.
                if sc.friction.is_some() {
                    anm::run::shell_time::check_start(&sc)?;
                } else {
                    anm::run::shell::check_factorizes(&sc)?;
                }
                println!(
                    "mesh {}: {} nodes, {} elements",
                    sc.mesh.file.display(),
                    sc.mesh.nodes.len(),
                    sc.mesh.quads.len()
                );
                for note in &sc.mesh.notes {
                    println!("  {note}");
                }
                println!(
                    "  {}",
                    anm::run::memory::summary(&sc, anm::run::memory::available())
                );
                for w in &sc.warnings {
                    eprintln!("warning: {w}");
                }
            }
            println!("{}: valid `{}` scene", scene.display(), kind.name());
            Ok(ExitCode::SUCCESS)
        }
        #[cfg(feature = "reference")]
        Command::Reference {
            solver:
                ReferenceSolver::Ida {
                    scene,
                    out,
                    rtol,
                    atol,
                    atol_algebraic,
                    friction_row,
                    max_nonlin_iters,
                },
        } => {
            use anm::reference::settings::{AlgebraicControl, Tolerances};
            if let (Kind::Shell, _) = load(&scene)? {
                // The shell's DAE has its own form: its law rows are
                // `anm run`'s, its algebraic unknowns out of the test.
                for (flag, value, default) in [
                    ("--atol-algebraic", atol_algebraic.as_str(), "suppress"),
                    ("--friction-row", friction_row.as_str(), "product"),
                ] {
                    if value != default {
                        anyhow::bail!(
                            "{flag} {value}: applies to the point-mass friction scenes; on a shell scene IDA integrates `anm run`'s residual with its algebraic unknowns out of the error test"
                        );
                    }
                }
                let sc = anm::scene::shell::load(&scene)?;
                fresh_output(&out)?;
                let settings = anm::run::shell_reference::ShellIdaSettings {
                    rtol,
                    atol,
                    max_nonlin_iters: max_nonlin_iters
                        .unwrap_or(anm::run::shell_reference::MAX_NONLIN_ITERS),
                };
                let r = anm::run::shell_reference::ida(&sc, &settings, &out)?;
                return Ok(shell_reference_summary(&r, &out));
            }
            let settings = anm::reference::IdaSettings {
                tol: Tolerances::new(rtol, atol)?,
                algebraic: AlgebraicControl::parse("atol-algebraic", &atol_algebraic)?,
                friction_row: friction_row
                    .parse()
                    .map_err(|e: String| anyhow::anyhow!("--friction-row: {e}"))?,
                max_nonlin_iters: max_nonlin_iters
                    .unwrap_or(anm::reference::ida_run::MAX_NONLIN_ITERS),
            };
            let sc = reference_scene(&scene, "IDA")?;
            // An earlier run's files would stand beside this one's (review
            // 6: an ANM plot of another scene next to IDA's summary).
            fresh_output(&out)?;
            let run = anm::reference::solve(&sc, &settings)
                .with_context(|| format!("IDA on {}", scene.display()))?;
            reference_report(&scene, &run, &out)
        }
        Command::Reference {
            solver:
                ReferenceSolver::Diffsol {
                    scene,
                    out,
                    method,
                    rtol,
                    atol,
                    atol_algebraic,
                    max_nonlinear_failures,
                    fresh_jacobian,
                    friction_row,
                },
        } => {
            use anm::reference::diffsol::DiffsolSettings;
            use anm::reference::settings::{DiffsolMethod, Tolerances, positive};
            let method: DiffsolMethod = method
                .parse()
                .map_err(|e: String| anyhow::anyhow!("--method: {e}"))?;
            positive("atol-algebraic", atol_algebraic)?;
            let settings = DiffsolSettings {
                method,
                tol: Tolerances::new(rtol, atol)?,
                atol_algebraic,
                max_nonlinear_failures,
                fresh_jacobian,
                friction_row: friction_row
                    .parse()
                    .map_err(|e: String| anyhow::anyhow!("--friction-row: {e}"))?,
            };
            let sc = reference_scene(&scene, "diffsol")?;
            fresh_output(&out)?;
            let run = anm::reference::diffsol::solve(&sc, &settings)
                .with_context(|| format!("diffsol on {}", scene.display()))?;
            reference_report(&scene, &run, &out)
        }
        Command::Audit {
            scene,
            omega,
            zeta,
            eta,
            penalty,
            out,
            items,
        } => {
            // −0 is 0 (review 19: `--eta=-0` was labelled eta=-0e0).
            let [omega, zeta, eta, penalty] = [omega, zeta, eta, penalty]
                .map(|v| v.into_iter().map(|x| x + 0.0).collect::<Vec<f64>>());
            // A value given twice would run twice and print two rows.
            for (key, values) in [
                ("omega", &omega),
                ("zeta", &zeta),
                ("eta", &eta),
                ("penalty", &penalty),
            ] {
                if let Some(v) = values
                    .iter()
                    .enumerate()
                    .find_map(|(i, v)| values[..i].contains(v).then_some(v))
                {
                    anyhow::bail!("--{key}: {v:e} is given twice");
                }
            }
            let spec = anm::study::sweep::Spec::Audit {
                scene,
                omega,
                zeta,
                eta,
                penalty,
            };
            sweep(&spec, &items, out.as_deref())
        }
        Command::Bench {
            scenes,
            cases,
            repeat,
            scaling,
            scaling_steps,
            write_matrix,
            target,
            zeta,
            stiffness,
            omega,
            rounds,
            instructions,
            out,
            items,
        } => {
            use anm::study::{bench, target as head};
            for &z in zeta.iter().chain(&omega) {
                anm::reference::settings::positive("zeta and omega", z)?;
            }
            // 0 ran once and reported a "median" of one run (review 6).
            if repeat == 0 || rounds == 0 {
                anyhow::bail!(
                    "--repeat and --rounds must be at least 1 (got {repeat} and {rounds})"
                );
            }
            // The folder before the runs, not after them (review 6: a
            // folder that cannot be made failed after the whole bench).
            if let Some(out) = &out
                && !items.list_items
            {
                anm::output::create_dir(out)?;
            }
            if stiffness {
                bench_stiffness(
                    &scenes,
                    &cases,
                    &zeta,
                    &omega,
                    &target,
                    repeat,
                    out.as_deref(),
                )?;
                return Ok(ExitCode::SUCCESS);
            }
            for &t in &target {
                anm::reference::settings::positive("target", t)?;
            }
            if !scaling.is_empty() {
                if out.is_none() && !items.list_items {
                    anyhow::bail!(
                        "--scaling writes its meshes, scenes and runs into a folder: give -o DIR"
                    );
                }
                return bench_scaling(
                    &scenes.join("plate-cylinder.toml"),
                    &scaling,
                    scaling_steps,
                    write_matrix,
                    &items,
                    out.as_deref(),
                );
            }
            if items.item.is_some() || items.list_items {
                anyhow::bail!(
                    "--item and --list-items split the --scaling study only: the work-precision benchmark and the head-to-head compare timings taken side by side on one machine"
                );
            }
            // The plate-cylinder skip study times runs that write their
            // outputs: without -o they go to a scratch folder, removed after.
            let scratch = bench::Scratch::new();
            let skip_dir = out.clone().unwrap_or_else(|| scratch.path().to_path_buf());
            let with_ida = cfg!(feature = "reference");
            let exe = if instructions {
                Some(std::env::current_exe()?)
            } else {
                None
            };
            let mut rows = vec![];
            let mut heads = vec![];
            let mut reference_name = String::new();
            let mut shell_notes = String::new();
            for case in &cases {
                let path = scenes.join(format!("{case}.toml"));
                let (_, sc) = load(&path)?;
                let Some(sc) = sc else {
                    let (r, notes) = bench_shell(case, &path, repeat, &skip_dir)?;
                    shell_notes += &notes;
                    rows.extend(r);
                    continue;
                };
                // One case per zeta where zeta enters the equations.
                let variants: Vec<(String, anm::scene::friction::FrictionScene)> =
                    if sc.contact.is_some() {
                        zeta.iter()
                            .map(|&z| {
                                let mut s = sc.clone();
                                s.friction.zeta = Some(z);
                                (format!("{case} zeta={z:.0e}"), s)
                            })
                            .collect()
                    } else {
                        vec![(case.clone(), sc)]
                    };
                for (name, sc) in variants {
                    let reference = bench::reference(&sc, with_ida)?;
                    reference_name = reference.name.clone();
                    eprintln!(
                        "{name}: reference {reference_name}; ANM(30, 1e-14) differs from it by {:.2e} on t <= {:.4}",
                        reference.anm_floor, reference.t_max
                    );
                    let methods = bench::friction_methods(with_ida);
                    let r = bench::work_precision(
                        &name,
                        &sc,
                        &methods,
                        &reference.solution,
                        reference.t_max,
                        repeat,
                    );
                    print!("{}", bench::markdown(&r, &reference_name));
                    print!("\n{}", bench::fastest_markdown(&r, &target));
                    for &t in &target {
                        let h = head::head_to_head(
                            &name,
                            &sc,
                            &r,
                            &methods,
                            reference.target(t),
                            rounds,
                            exe.as_deref(),
                        )?;
                        heads.push(h);
                    }
                    rows.extend(r);
                }
            }
            if let Some(out) = &out {
                bench::write(&rows, &reference_name, out)?;
                let file = out.join("fastest.md");
                std::fs::write(&file, bench::fastest_markdown(&rows, &target))
                    .with_context(|| format!("writing {}", file.display()))?;
                if !shell_notes.is_empty() {
                    let file = out.join("bench-shell.md");
                    std::fs::write(&file, &shell_notes)
                        .with_context(|| format!("writing {}", file.display()))?;
                }
                head::write(&heads, out)?;
            }
            print!("\n{}", head::markdown(&heads));
            if let Some(out) = &out {
                println!("outputs in {}", out.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Time {
            scene,
            method,
            repeat,
        } => {
            let (kind, friction) = load(&scene)?;
            let Some(sc) = friction else {
                anyhow::bail!("`anm time` runs friction scenes, not `{}`", kind.name());
            };
            // --repeat 0 (under callgrind): exactly one solve, no warm-up.
            let timed =
                anm::study::timing::interleaved(&sc, std::slice::from_ref(&method), repeat)?
                    .remove(0);
            let (spread, sol) = (timed.spread, timed.solution);
            println!(
                "{} {}: stop = {}, {} steps, {} factorizations; wall over {} runs: min {:.3e} s, median {:.3e} s, max {:.3e} s",
                scene.display(),
                method.spec(),
                sol.stop,
                sol.stats.steps,
                sol.stats.factorizations,
                spread.samples.len(),
                spread.min(),
                spread.median(),
                spread.quantile(1.0)
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Stress {
            scenes,
            cases,
            max_steps,
            out,
            items,
        } => {
            if max_steps == 0 {
                anyhow::bail!("--max-steps 0: the step budget must be at least 1");
            }
            let spec = anm::study::sweep::Spec::Stress {
                scenes,
                cases,
                max_steps,
            };
            sweep(&spec, &items, out.as_deref())
        }
        Command::Merge { dir } => {
            use anm::study::sweep;
            let merged = sweep::merge_dir(&dir, sweep::open)
                .with_context(|| format!("merging the sweep in {}", dir.display()))?;
            print!("{}", merged.markdown);
            println!("\noutputs in {}", dir.display());
            Ok(if merged.failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
        Command::Buckle {
            scene,
            lambda,
            time,
            modes,
            locate,
            out,
        } => {
            let sc = anm::scene::shell::load(&scene)?;
            if let Some(increment) = locate {
                use anm::study::critical_cost;
                anm::reference::settings::positive("locate", increment)?;
                // The ANM's location is shown whatever the baseline's fate
                // (review 14: a Newton failure hid it); a baseline that
                // cannot locate the point is a numerical stop (exit 2).
                let mut rows = vec![critical_cost::anm(&sc)?];
                let baseline = critical_cost::newton_bisection(&sc, increment, 1e-6);
                let failed = match baseline {
                    Ok(row) => {
                        rows.push(row);
                        None
                    }
                    Err(e @ anm::Error::Study { .. }) => Some(e.to_string()),
                    Err(e) => return Err(e.into()),
                };
                let mut table = critical_cost::table(&scene.display().to_string(), &rows);
                if let Some(why) = &failed {
                    table += &format!(
                        "| Newton, increments {increment}, bisection on the negative pivots | not located | – | – | – |\n\n{why}\n"
                    );
                }
                print!("{table}");
                if let Some(d) = out {
                    std::fs::create_dir_all(&d)?;
                    std::fs::write(d.join("critical.md"), &table)?;
                }
                return Ok(match failed {
                    None => ExitCode::SUCCESS,
                    Some(_) => ExitCode::from(2),
                });
            }
            use anm::study::buckle::Base;
            let base = time.map_or(Base::Lambda(lambda), Base::Time);
            if let Some(d) = &out {
                // Fewer modes than an earlier analysis: no stale mode files.
                clear_earlier(
                    d,
                    anm::output::earlier_run::clear_buckling,
                    "buckling analysis",
                )?;
            }
            let report = anm::study::buckle::buckle(&sc, base, modes, out.as_deref())
                .map_err(|e| doing("buckling analysis of", e, &scene))?;
            print!("{}", anm::study::buckle::table(&report));
            if let Some(d) = out {
                println!("outputs in {}", d.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Run {
            scene,
            out,
            resume,
            quiet,
            ignore_memory,
        } => {
            if let Some(dir) = resume {
                // One run per folder (review 23: two runs mixed their files).
                let _lock = anm::output::lock::OutputLock::take(&dir)?;
                anm::run::interrupt::install();
                if anm::run::time_checkpoint::TimeCheckpoint::is_in(&dir) {
                    let r = anm::run::shell_time::resume(&dir, !quiet)
                        .with_context(|| format!("resuming the run in {}", dir.display()))?;
                    return Ok(time_summary(&r, &dir));
                }
                let report = anm::run::shell::resume(&dir, !quiet)
                    .with_context(|| format!("resuming the run in {}", dir.display()))?;
                return Ok(shell_summary(&report, &dir));
            }
            let (Some(scene), Some(out)) = (scene, out) else {
                anyhow::bail!("`anm run` needs SCENE and -o DIR (or --resume DIR)");
            };
            anm::output::folder_or_absent(&out)?;
            let (kind, friction) = load(&scene)?;
            match kind {
                Kind::Shell => {
                    let sc = anm::scene::shell::load(&scene)?;
                    fits_in_memory(&sc, ignore_memory)?;
                    if sc.friction.is_some() {
                        for w in &sc.warnings {
                            eprintln!("warning: {w}");
                        }
                        let _lock = anm::output::lock::OutputLock::take(&out)?;
                        fresh_output(&out)?;
                        // Ctrl-C / SIGTERM end the run at the next step end
                        // with its outputs and a checkpoint (--resume).
                        anm::run::interrupt::install();
                        let r = anm::run::shell_time::run_with(&sc, Some(&out), !quiet)
                            .map_err(|e| running(e, &scene))?;
                        return Ok(time_summary(&r, &out));
                    }
                    // Ctrl-C / SIGTERM end a shell run at the next step end.
                    anm::run::interrupt::install();
                    // Under `mpirun -n P` (feature mumps) every rank runs
                    // the same path for MUMPS's collective calls; only rank
                    // 0 writes files and prints.
                    #[cfg(feature = "mumps")]
                    if !anm::linalg::mpi::is_root() {
                        anm::run::shell::run_loaded(&sc, None, false)
                            .map_err(|e| running(e, &scene))?;
                        return Ok(ExitCode::SUCCESS);
                    }
                    for w in &sc.warnings {
                        eprintln!("warning: {w}");
                    }
                    // Review 9: under mpirun a faer backend ran the whole
                    // path on every rank without a word.
                    #[cfg(feature = "mumps")]
                    if anm::linalg::mpi::ranks() > 1
                        && sc.solver.linear
                            != anm::linalg::Choice::Only(anm::linalg::Backend::Mumps)
                    {
                        eprintln!(
                            "warning: {} MPI ranks, but solver.linear_solver is not \"mumps\": every rank solves the whole problem (rank 0 writes the files); only MUMPS shares the factorization among ranks",
                            anm::linalg::mpi::ranks()
                        );
                    }
                    let _lock = anm::output::lock::OutputLock::take(&out)?;
                    fresh_output(&out)?;
                    let report = anm::run::shell::run_loaded(&sc, Some(&out), !quiet)
                        .map_err(|e| running(e, &scene))?;
                    Ok(shell_summary(&report, &out))
                }
                _ => {
                    let sc = friction.expect("friction kinds parse into a friction scene");
                    // Ctrl-C / SIGTERM end the run at the next step end,
                    // with history.csv and steps.csv holding every step.
                    anm::run::interrupt::install();
                    let _lock = anm::output::lock::OutputLock::take(&out)?;
                    fresh_output(&out)?;
                    let run = anm::model::friction_run::run(&sc, Some(&out), !quiet)
                        .map_err(|e| running(e, &scene))?;
                    // How many steps were implicit, and how many implicit
                    // tries were rejected (review 8: `implicit` on
                    // friction-1d took none and 10× the factorizations).
                    println!(
                        "{}: stop = {} at t = {:.6} s; {} steps ({} implicit, {} implicit tries rejected; time_step = {}), {} factorizations, {} solves, {:.3} s; outputs in {}",
                        scene.display(),
                        run.stop.reason,
                        run.stop.t.unwrap_or(f64::NAN),
                        run.stats.steps,
                        run.implicit.steps,
                        run.implicit.rejected,
                        sc.stepping.name(),
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
                        "interrupted" => ExitCode::from(130),
                        _ => ExitCode::from(2),
                    })
                }
            }
        }
    }
}

/// A sweep: its items (`--list-items`), one item (`--item K -o DIR`), or
/// all of them in this process then the merge (exit 1 when the sweep's
/// verdict is a failure, as for `anm merge`).
fn sweep(
    spec: &anm::study::sweep::Spec,
    items: &ItemArgs,
    out: Option<&std::path::Path>,
) -> anyhow::Result<ExitCode> {
    use anm::study::sweep;
    let s = sweep::open(spec)?;
    if items.list_items {
        print!("{}", sweep::list(s.as_ref()));
        return Ok(ExitCode::SUCCESS);
    }
    if let Some(k) = items.item {
        let out = out.context("--item K writes DIR/items/K.json: give -o DIR")?;
        let file = sweep::run_one(spec, s.as_ref(), k, out)?;
        eprintln!("item {k}: {}", file.display());
        return Ok(ExitCode::SUCCESS);
    }
    let merged = sweep::run_all(spec, s.as_ref(), out, sweep::open)?;
    print!("{}", merged.markdown);
    if let Some(out) = out {
        println!("\noutputs in {}", out.display());
    }
    Ok(if merged.failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// The scaling study (`anm bench --scaling 40x4,80x8,...`).
/// `anm bench --stiffness`: the zeta x omega grid of issue 13.
fn bench_stiffness(
    scenes: &std::path::Path,
    cases: &[String],
    zeta: &[f64],
    omega: &[f64],
    target: &[f64],
    repeat: usize,
    out: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    use anm::study::stiffness;
    if !cfg!(feature = "reference") {
        anyhow::bail!("--stiffness compares with IDA: build with --features reference");
    }
    let target = target.first().copied().unwrap_or(1e-8);
    let mut cells = vec![];
    let mut paper = vec![];
    for case in cases {
        let (_, sc) = load(&scenes.join(format!("{case}.toml")))?;
        let Some(mut sc) = sc.filter(|s| s.contact.is_some()) else {
            eprintln!("{case}: no zeta (skipped)");
            continue;
        };
        // The grid measures the per-step choice (solver.time_step = "auto").
        sc.stepping = anm::series::dae::Stepping::Auto;
        let base = stiffness::cell(case, &sc, target, repeat)?;
        paper.push((case.clone(), base.steps));
        for &z in zeta {
            for &w in omega {
                let mut s = sc.clone();
                s.friction.zeta = Some(z);
                s.friction.omega = w;
                let c = stiffness::cell(case, &s, target, repeat)?;
                eprintln!(
                    "{case} zeta={z:.0e} omega={w:.0e}: {} steps, {:.1e} from IDA",
                    c.steps, c.deviation
                );
                cells.push(c);
            }
        }
    }
    let table = stiffness::markdown(&cells, &paper, target);
    print!("{table}");
    if let Some(dir) = out {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join("stiffness.md"), &table)?;
    }
    Ok(())
}

fn bench_scaling(
    template: &std::path::Path,
    sizes: &[String],
    steps: usize,
    write_matrix: bool,
    items: &ItemArgs,
    out: Option<&std::path::Path>,
) -> anyhow::Result<ExitCode> {
    let parsed: Vec<(usize, usize)> = sizes
        .iter()
        .map(|s| {
            s.split_once('x')
                .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                .filter(|&(nx, ny): &(usize, usize)| nx >= 1 && ny >= 1)
                .with_context(|| format!("--scaling: `{s}` is not NXxNY with NX, NY >= 1"))
        })
        .collect::<anyhow::Result<_>>()?;
    // Checked before any size runs (review 7: 30x3 failed after the sizes
    // before it had run): the plate-cylinder probes and loads need node
    // rows at x = 1.0, 1.1, 1.2 and nodes at y = 0, ±0.1 (meshes/README.md).
    if let Some((s, _)) = sizes
        .iter()
        .zip(&parsed)
        .find(|(_, (nx, ny))| nx % 20 != 0 || ny % 2 != 0)
    {
        anyhow::bail!(
            "--scaling: `{s}`: NX must be a multiple of 20 and NY even (the plate-cylinder probes' node rows at x = 1.0, 1.1, 1.2 and the loads' nodes at y = 0, ±0.1: meshes/README.md)"
        );
    }
    // Review 26: a size given twice gave NaN fitted exponents, and as two
    // items wrote into one run folder.
    if let Some(k) = (1..parsed.len()).find(|&k| parsed[..k].contains(&parsed[k])) {
        anyhow::bail!(
            "--scaling: `{}` is given twice: each size is one run (its folder run-NXxNY)",
            sizes[k]
        );
    }
    if steps == 0 {
        anyhow::bail!("--scaling-steps must be >= 1");
    }
    let spec = anm::study::sweep::Spec::Scaling {
        template: template.to_path_buf(),
        sizes: parsed,
        steps,
        write_matrix,
    };
    sweep(&spec, items, out)
}

/// The plate-cylinder work-precision benchmark of one scene: the rows, and
/// the reference, target and step-cost notes (printed and returned).
fn bench_shell(
    case: &str,
    path: &std::path::Path,
    repeat: usize,
    out: &std::path::Path,
) -> anyhow::Result<(Vec<anm::study::bench::BenchRow>, String)> {
    use anm::study::bench_shell as bs;
    let scene = anm::scene::shell::load(path)?;
    eprintln!("{case}: reference runs (ANM N=20 eps=1e-12; Newton) ...");
    let reference = bs::reference(&scene)?;
    // The key probe: the first history column after lambda.
    let probe = reference
        .report
        .columns
        .get(1)
        .cloned()
        .unwrap_or_else(|| "the key probe".into());
    let mut notes = format!(
        "## {case}\n\nReference: {}; Newton (load control, |R|/|F| <= {:.0e}) differs from it by {:.2e} on {probe}. Output grid: lambda step {}. Wall times are medians of {repeat}.\n",
        reference.name,
        reference.residual,
        reference.floor,
        bs::LAMBDA_STEP
    );
    eprint!("{notes}");
    let (rows, costs) = bs::work_precision(
        case,
        &scene,
        &bs::methods(),
        &reference.report,
        repeat,
        |_, r| {
            eprintln!(
                "  {} {}: error {:.2e}, {:.3} s, {} steps, {} factorizations ({})",
                r.method, r.setting, r.error, r.wall_s, r.steps, r.factorizations, r.stop
            )
        },
    );
    notes += &anm::study::bench::markdown(&rows, &reference.name);
    notes += &bs::targets(&rows, &costs, &probe);
    eprintln!("{case}: skip measurements ...");
    notes += &bs::skip_markdown(&bs::skip_study(&scene, out)?);
    print!("{notes}");
    Ok((rows, notes))
}

fn load(
    path: &std::path::Path,
) -> anm::Result<(Kind, Option<anm::scene::friction::FrictionScene>)> {
    let text = scene::read(path)?;
    let kind = scene::kind(path, &text)?;
    match kind {
        Kind::Shell => Ok((kind, None)),
        _ => Ok((kind, Some(scene::friction::load(path, &text, kind)?))),
    }
}

/// Prints a shell run in time's summary line and diagnosis; exit code 0 at
/// the end or a detected singularity, 130 when interrupted, 2 on numerical
/// trouble.
fn time_summary(r: &anm::run::shell_time::TimeReport, out: &std::path::Path) -> ExitCode {
    println!(
        "{}: stop = {} at t = {:.6} s; {} steps ({} implicit, {} of them fully implicit; time_step = {}), {} factorizations, {} corrections, {:.3} s; {} friction nodes; outputs in {}",
        r.scene,
        r.stop.reason,
        r.stop.t.unwrap_or(f64::NAN),
        r.steps,
        r.implicit_steps,
        r.newton_steps,
        r.time_step,
        r.factorizations,
        r.corrections,
        r.wall_s,
        r.friction_nodes,
        out.display()
    );
    // The last output row, as a static run prints its probes (review 17:
    // the main job's answer was only in history.csv).
    let last: Vec<String> = r
        .end
        .iter()
        .filter(|(k, _)| !matches!(k.as_str(), "t" | "lambda"))
        .map(|(k, v)| format!("{k} = {v:.6e}"))
        .collect();
    if let Some(t) = r.end.get("t") {
        println!("  at t = {t:.6} s (last output row): {}", last.join(", "));
    }
    match (r.stop.node, r.stop.reason.as_str()) {
        (Some(n), "singularity") => println!("  singular point at node {n}"),
        (Some(n), _) => println!("  the trouble is located at node {n}"),
        (None, _) => {}
    }
    if let Some(m) = &r.stop.message {
        println!("  {m}");
    }
    for n in &r.notes {
        println!("  note: {n}");
    }
    for e in &r.events {
        // A dip without a count change is a point crossed or closely
        // passed: its depth says how closely (review 25).
        let (what, how) = match e.dip {
            Some(d) => (
                "critical or near-critical point",
                format!("kappa dip to {d:.3} of its largest, no negative pivot at the outputs"),
            ),
            None => ("critical point", e.detected_by.to_string()),
        };
        println!(
            "  {what} ({} tangent, {how}): t = {:.6e} s, lambda = {:.6e} (between outputs {:.6e} and {:.6e} s{}; negative pivots {} -> {}), {}",
            e.tangent,
            e.t,
            e.lambda,
            e.outputs[0],
            e.outputs[1],
            match e.restarts {
                0 => String::new(),
                n => format!(
                    ", located in [{:.9e}, {:.9e}] s by {n} restarts",
                    e.bracket[0], e.bracket[1]
                ),
            },
            e.negative_pivots[0],
            e.negative_pivots[1],
            e.mode.as_deref().unwrap_or("")
        );
    }
    // A stop on numerical trouble is a failure (its files hold the run up
    // to there); a detected singularity is a result.
    match r.stop.reason.as_str() {
        "end" | "singularity" => ExitCode::SUCCESS,
        "interrupted" => ExitCode::from(130),
        _ => ExitCode::from(2),
    }
}

/// A shell scene whose mesh cannot fit in this machine's memory is refused
/// before anything is built (run::memory); a warning where it may not fit.
fn fits_in_memory(sc: &anm::scene::shell::ShellScene, ignore: bool) -> anyhow::Result<()> {
    if ignore {
        return Ok(());
    }
    if let Some(w) = anm::run::memory::check(sc, anm::run::memory::available())? {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// Removes an earlier run's files from the output directory of a new run
/// (output::earlier_run), saying how many.
fn fresh_output(out: &std::path::Path) -> anyhow::Result<()> {
    clear_earlier(
        out,
        anm::output::earlier_run::clear,
        "run (summary.json, snapshots, modes, checkpoint; other files are kept)",
    )
}

/// Removes the files `clear` names in `dir`, saying how many ("files of an
/// earlier `what`").
fn clear_earlier(
    dir: &std::path::Path,
    clear: fn(&std::path::Path) -> anm::Result<Vec<std::path::PathBuf>>,
    what: &str,
) -> anyhow::Result<()> {
    let removed = clear(dir)?;
    if !removed.is_empty() {
        eprintln!(
            "note: removed {} files of an earlier {what} from {}",
            removed.len(),
            dir.display()
        );
    }
    Ok(())
}

/// Prints a shell run's summary line; exit code 0 at the end of the path, 2
/// on a numerical stop, 130 when interrupted.
fn shell_summary(report: &anm::run::RunReport, out: &std::path::Path) -> ExitCode {
    let mut ends: Vec<String> = report
        .end
        .iter()
        .filter(|(k, _)| *k != "lambda")
        .map(|(k, v)| format!("{k} = {v:.6e}"))
        .collect();
    // The probes are those of the last output row, which a stop between
    // rows leaves behind the stop (review 7: an interrupted run printed
    // the values of lambda = 0.01 after "stop at lambda = 0.0192").
    if let (Some(row), Some(stop)) = (report.end.get("lambda"), report.stop.lambda)
        && (row - stop).abs() > 1e-12 * stop.abs().max(1.0)
        && !ends.is_empty()
    {
        ends[0] = format!("at lambda = {row:.6} (last output row): {}", ends[0]);
    }
    println!(
        "{}: stop = {} at lambda = {:.6}; {} dofs, {} steps, {} factorizations, {} solves, {:.3} s; {}; outputs in {}",
        report.scene,
        report.stop.reason,
        report.stop.lambda.unwrap_or(f64::NAN),
        report.dofs,
        report.steps,
        report.factorizations,
        report.solves,
        report.wall_s,
        ends.join(", "),
        out.display()
    );
    if let Some(m) = &report.stop.message {
        println!("  {m}");
    }
    if let Some(l) = report.switched_at {
        println!("  switched to the secondary branch at lambda = {l:.6e}");
    }
    for n in &report.notes {
        println!("  note: {n}");
    }
    // The critical points the path crossed (summary.json `events`), the
    // first SHOWN_EVENTS of them (review 17: 290 lines of a path
    // wandering about a mechanism flooded the console).
    const SHOWN_EVENTS: usize = 20;
    if report.events.len() > SHOWN_EVENTS {
        println!(
            "  {} critical points; the first {SHOWN_EVENTS} below, all in summary.json `events`",
            report.events.len()
        );
    }
    for e in report.events.iter().take(SHOWN_EVENTS) {
        let pivots = e.negative_pivots.map_or(String::new(), |(a, b)| {
            format!("; negative pivots {a} -> {b}")
        });
        let wave = e
            .wavelength
            .map_or(String::new(), |w| format!("; wavelength {w:.4e}"));
        println!(
            "  {} at lambda = {:.6e} (step {}{pivots}{wave}) {}",
            e.kind.replace('_', " "),
            e.lambda,
            e.step,
            e.mode.as_deref().unwrap_or("")
        );
    }
    match report.stop.reason.as_str() {
        "end" => ExitCode::SUCCESS,
        "interrupted" => ExitCode::from(130),
        _ => ExitCode::from(2),
    }
}

/// A run's error, with "running SCENE" in front unless it already names
/// the scene file (a bad key of the scene: "error: running f.toml: f.toml:
/// key ..." said the file twice).
fn running(e: anm::Error, scene: &std::path::Path) -> anyhow::Error {
    doing("running", e, scene)
}

/// An error of `what` (e.g. "running") on a scene, with "what SCENE" in
/// front unless the error already names the scene file.
fn doing(what: &str, e: anm::Error, scene: &std::path::Path) -> anyhow::Error {
    let names_it = e.to_string().starts_with(&scene.display().to_string());
    let e = anyhow::Error::new(e);
    if names_it {
        e
    } else {
        e.context(format!("{what} {}", scene.display()))
    }
}
