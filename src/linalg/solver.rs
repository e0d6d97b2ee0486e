//! One interface for every sparse tangent: analyse a pattern once, factorize
//! many times, solve many times per factorization.
//!
//! The backend is chosen per factorization from the assembled values: a
//! tangent symmetric to [`SYMMETRY_TOLERANCE`] (frictionless contact, dead
//! and conservative loads) goes to faer's supernodal LDLᵀ after an AMD
//! ordering (measured on a 98,400-unknown strip: 13× faster than the LU and a
//! tenth of its memory, README "Linear algebra"); a non-symmetric one
//! (follower pressure, friction) to faer's sparse LU. Every factorization is
//! checked by the normwise backward error of one solve,
//! η = |b − A x|∞ / (|A|∞ |x|∞ + |b|∞) (Higham, *Accuracy and Stability of
//! Numerical Algorithms*, 2002, eq. 7.23), and a backend whose η exceeds
//! [`BACKWARD_ERROR_LIMIT`] (LDLᵀ without pivoting meeting a tiny pivot on an
//! indefinite tangent) hands over to the next: LDLᵀ → LBLᵀ (Bunch–Kaufman
//! inside supernodes) → LU. The check costs one solve and two products with
//! A; the checks on the values (finite, symmetric) and one product run on
//! another thread beside the sequential factorization, and the solve beside
//! the caller's first solve ([`LinearSolver::factorize_solve`]).

use std::sync::{Arc, Mutex, Weak};
use std::time::Instant;

use faer::Par;

use super::lu::{LuFactor, LuSymbolic};
use super::sparse_matrix::{SparseMatrix, Structure};
use super::split::{SplitFactor, SplitSymbolic};
use super::symmetric::{Pivoting, SymmetricFactor, SymmetricSymbolic, set_spare_budget};

/// Relative tolerance of the symmetry test, entry by entry:
/// |a_ij − a_ji| ≤ tol · max(|a_ij|, |a_ji|, 1e-3 max|A|). The floor
/// 1e-13 max|A| (about 450 u) covers entries that are round-off sums: on the
/// stretched sheet (scenes/sheet-wrinkling.toml, 200 × 80 elements) entries
/// of 4e-15 max|A| differ from their transposes by 1.05e-15 max|A|, which
/// the former floor (1e-15 max|A|) took for asymmetry, so the automatic
/// choice fell back to LU and lost the inertia. The shell tangents are
/// symmetric to about 1e-15 of the largest entry; a follower load's
/// asymmetry is of the order of the load, and a matrix wrongly taken for
/// symmetric is still caught by the backward-error check.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// Largest accepted backward error of a factorization. A backward-stable
/// factorization gives about n^(1/2) u ≈ 1e-13 at a million unknowns; growth
/// in an unpivoted LDLᵀ on an indefinite matrix shows as 1e-8 and worse.
pub const BACKWARD_ERROR_LIMIT: f64 = 1e-10;

/// Fewest unknowns for which LDLᵀ is split over two threads (`split.rs`):
/// below it the split's set-up (two analyses, the separator's dense
/// Schur complement) outweighs the second core. Measured with `anm factor`
/// on the plate-cylinder strips (README "Linear algebra").
pub const SPLIT_MIN_UNKNOWNS: usize = 50_000;

/// Largest ratio of a split's factor entries to the whole factor's: the
/// halves are ordered with the separator last, which can add fill (measured
/// +4% on the 400×40 strip, +25% on the crowned-roll strip at a million
/// unknowns, where the split factorization took 8.8 s against 6.9 s).
pub const SPLIT_MAX_FILL: f64 = 1.1;

/// A factorization method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// faer supernodal LDLᵀ, no pivoting (symmetric tangents).
    Ldlt,
    /// faer supernodal LBLᵀ, Bunch–Kaufman pivoting inside supernodes
    /// (symmetric indefinite tangents).
    Lblt,
    /// faer supernodal LU, partial pivoting (any tangent).
    Lu,
    /// MUMPS 5 over MPI (feature `mumps`): symmetric (SYM = 2) or general,
    /// never chosen automatically.
    #[cfg(feature = "mumps")]
    Mumps,
}

impl Backend {
    /// The faer backends, in the order of the automatic hand-over.
    pub const ALL: [Backend; 3] = [Backend::Ldlt, Backend::Lblt, Backend::Lu];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Ldlt => "ldlt",
            Backend::Lblt => "lblt",
            Backend::Lu => "lu",
            #[cfg(feature = "mumps")]
            Backend::Mumps => "mumps",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        #[cfg(feature = "mumps")]
        if name == "mumps" {
            return Some(Backend::Mumps);
        }
        Self::ALL.into_iter().find(|b| b.name() == name)
    }

    /// Needs a symmetric matrix.
    fn symmetric(self) -> bool {
        matches!(self, Backend::Ldlt | Backend::Lblt)
    }
}

/// How the backend is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Choice {
    /// From the symmetry of each tangent, with the backward-error fallback.
    #[default]
    Auto,
    /// This backend only (a failed check is an error).
    Only(Backend),
}

/// Counters of a solver's factorizations, for summary.json.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SolverStats {
    /// Accepted factorizations per backend: ldlt, lblt, lu.
    pub ldlt: usize,
    pub lblt: usize,
    pub lu: usize,
    pub mumps: usize,
    /// MUMPS's memory in use during the last factorization (MB = 1e6 bytes):
    /// this rank, the largest rank, all ranks (INFO(22), INFOG(21),
    /// INFOG(22)).
    pub mumps_memory_mb: Option<(f64, f64, f64)>,
    /// Factorizations rejected by the backward-error check (or failed) and
    /// handed to the next backend.
    pub fallbacks: usize,
    /// Symbolic analyses (a new pattern).
    pub analyses: usize,
    /// Largest backward error of an accepted factorization.
    pub max_backward_error: f64,
    /// Entries of the last factor (L for the symmetric backends, 0 for LU).
    pub factor_entries: usize,
    /// Entries of the last assembled pattern.
    pub matrix_entries: usize,
    /// Negative pivots of the last symmetric factorization (the number of
    /// negative eigenvalues of the tangent), `None` after an LU.
    pub negative_pivots: Option<usize>,
    /// Symmetric matrices factored without inertia (by the LU: named, or
    /// after the symmetric backends failed), whose critical points the
    /// inertia cannot show.
    pub symmetric_without_inertia: usize,
    /// Seconds in symbolic analyses (ordering, supernodes).
    pub analysis_s: f64,
    /// Unknowns of the separator where LDLᵀ is split over two threads.
    pub split_separator: Option<usize>,
}

impl SolverStats {
    /// Counts an accepted factorization `f` of `solver`, which handed over
    /// `fallbacks` times on the way, and takes the solver's latest sizes.
    pub fn record(&mut self, f: &Factorization, fallbacks: usize, solver: &SolverStats) {
        self.count(f, fallbacks);
        self.factor_entries = solver.factor_entries;
        self.matrix_entries = solver.matrix_entries;
        self.analyses = self.analyses.max(solver.analyses);
        self.analysis_s = self.analysis_s.max(solver.analysis_s);
        self.split_separator = solver.split_separator.or(self.split_separator);
    }

    /// Counts an accepted factorization that handed over `fallbacks` times.
    fn count(&mut self, f: &Factorization, fallbacks: usize) {
        match f.backend {
            Backend::Ldlt => self.ldlt += 1,
            Backend::Lblt => self.lblt += 1,
            Backend::Lu => self.lu += 1,
            #[cfg(feature = "mumps")]
            Backend::Mumps => self.mumps += 1,
        }
        if let Some(m) = f.mumps_memory_mb {
            self.mumps_memory_mb = Some(m);
        }
        self.fallbacks += fallbacks;
        self.max_backward_error = self.max_backward_error.max(f.backward_error);
        self.negative_pivots = f.inertia.map(|i| i.0);
        if f.symmetric && f.inertia.is_none() {
            self.symmetric_without_inertia += 1;
        }
    }
}

/// Sparse factorizations with the pattern's analyses kept across calls.
pub struct LinearSolver {
    choice: Choice,
    par: Par,
    structure: Option<Arc<Structure>>,
    symmetric: Option<Arc<SymmetricSymbolic>>,
    /// LDLᵀ's split over two threads: not looked for yet (`None`), or
    /// found (`Some(Some)`), or not possible on this pattern.
    split: Option<Option<Arc<SplitSymbolic>>>,
    /// Threads for LDLᵀ (2 or more: split when the pattern allows).
    threads: usize,
    lu: Option<Arc<LuSymbolic>>,
    #[cfg(feature = "mumps")]
    mumps: Option<Arc<std::sync::Mutex<mumps_backend::Instance>>>,
    /// The outcome of the last symmetry check ([`LinearSolver::last_check_symmetric`]).
    last_check_symmetric: Option<bool>,
    stats: SolverStats,
    /// The backend of the last accepted factorization on this pattern.
    last: Option<Backend>,
}

impl Default for LinearSolver {
    fn default() -> Self {
        Self::new(Choice::Auto)
    }
}

enum Factor {
    Symmetric(Arc<SymmetricSymbolic>, SymmetricFactor),
    Split(Arc<SplitSymbolic>, SplitFactor),
    Lu(Arc<LuSymbolic>, Box<LuFactor>),
    /// MUMPS keeps the factors inside its instance: a factorization is valid
    /// until the solver's next one (checked by the generation number).
    #[cfg(feature = "mumps")]
    Mumps(Arc<std::sync::Mutex<mumps_backend::Instance>>, u64),
}

/// A numeric factorization, ready for any number of solves.
pub struct Factorization {
    factor: Factor,
    par: Par,
    n: usize,
    backend: Backend,
    backward_error: f64,
    inertia: Option<(usize, usize, usize)>,
    /// The matrix passed the symmetry check (set with the checks).
    symmetric: bool,
    /// Seconds of the numeric factorization alone (no analysis, no check).
    numeric_s: f64,
    /// Seconds of the caller's solve beside its test
    /// ([`LinearSolver::factorize_solve`]).
    caller_solve_s: f64,
    mumps_memory_mb: Option<(f64, f64, f64)>,
}

impl LinearSolver {
    /// faer's factorizations sequential (measured on the 98,400-unknown
    /// strip, its supernodal LDLᵀ on 2 threads was slower than on 1); LDLᵀ
    /// split over two threads where rayon's pool has them (README).
    pub fn new(choice: Choice) -> Self {
        Self {
            choice,
            par: Par::Seq,
            structure: None,
            symmetric: None,
            split: None,
            threads: rayon::current_num_threads(),
            lu: None,
            #[cfg(feature = "mumps")]
            mumps: None,
            last_check_symmetric: None,
            stats: SolverStats::default(),
            last: None,
        }
    }

    /// Factorizations on `threads` threads (1: sequential): LDLᵀ split in
    /// two, LBLᵀ and LU by faer's own parallel codes.
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self.par = if threads <= 1 {
            Par::Seq
        } else {
            Par::rayon(threads)
        };
        self
    }

    pub fn stats(&self) -> &SolverStats {
        &self.stats
    }

    /// Factorizes `a`, trying the backends of the choice in turn. Returns a
    /// message describing the failure, for the caller to wrap with step and
    /// lambda.
    ///
    /// The factorization is sequential and the checks on the values
    /// (finite, symmetric, the product and row sums of the backward-error
    /// test) do not need it: after the first factorization they run on
    /// another thread while the backend that factorized the last tangent
    /// factorizes this one; if the checks then choose another backend, that
    /// factor is dropped and the choice runs as without the guess.
    pub fn factorize(&mut self, a: &SparseMatrix) -> Result<Factorization, String> {
        self.factorize_checked(a, None).map(|(f, _)| f)
    }

    /// [`LinearSolver::factorize`] and the solve of A x = b, on another
    /// thread beside the solve of the backward-error test (the two read the
    /// same factor; sequential, they cost two solves).
    pub fn factorize_solve(
        &mut self,
        a: &SparseMatrix,
        b: &[f64],
    ) -> Result<(Factorization, Vec<f64>), String> {
        let (f, x) = self.factorize_checked(a, Some(b))?;
        Ok((f, x.expect("solved with b")))
    }

    /// The factorization, and with `b` the solve of A x = b.
    fn factorize_checked(
        &mut self,
        a: &SparseMatrix,
        b: Option<&[f64]>,
    ) -> Result<(Factorization, Option<Vec<f64>>), String> {
        let (s, values) = a.compressed(self.structure.as_ref())?;
        if self.structure.as_ref().map(|k| k.id()) != Some(s.id()) {
            self.structure = Some(Arc::clone(&s));
            self.symmetric = None;
            self.split = None;
            self.lu = None;
            self.last = None;
            #[cfg(feature = "mumps")]
            {
                self.mumps = None;
            }
        }
        let (guess, checks) = match self.last {
            Some(backend) => {
                // MUMPS is analysed as symmetric or not: the guess keeps
                // the last factorization's choice (a guess analysed as
                // general lost the inertia of every symmetric tangent after
                // the first: review 9) and is redone below if the checks
                // disagree.
                let symmetric = self.last_symmetric(backend);
                let (f, checks) = self
                    .numeric_beside(backend, &s, &values, symmetric, || Checks::of(&s, &values));
                (Some((backend, symmetric, f)), checks)
            }
            None => (None, Checks::of(&s, &values)),
        };
        if let Some(k) = checks.non_finite {
            let (r, c) = position(&s, k);
            return Err(format!("non-finite entry {} at ({r}, {c})", values[k]));
        }
        self.stats.matrix_entries = s.nnz();
        let symmetric = checks.symmetric;
        self.last_check_symmetric = Some(symmetric);
        let candidates: Vec<Backend> = match self.choice {
            Choice::Only(b) => vec![b],
            Choice::Auto if symmetric => Backend::ALL.to_vec(),
            Choice::Auto => vec![Backend::Lu],
        };
        let mut guess = guess.filter(|(b, sym, _)| {
            Some(b) == candidates.first() && (!self.is_mumps(*b) || *sym == symmetric)
        });
        let mut reasons = vec![];
        for backend in candidates {
            if backend.symmetric() && !symmetric {
                reasons.push(format!(
                    "{}: the matrix is not symmetric (tolerance {SYMMETRY_TOLERANCE:e})",
                    backend.name()
                ));
                continue;
            }
            let factored = match guess.take() {
                Some((_, _, f)) => f,
                None => {
                    self.numeric_beside(backend, &s, &values, symmetric, || ())
                        .0
                }
            };
            // The caller's solve beside the test's (two solves of one
            // factor, independent): kept if the test passes.
            let tested = factored.map(|mut f| {
                let (eta, (x, seconds)) = match b {
                    Some(b) => rayon::join(
                        || checks.backward_error(&f, &s, &values),
                        || {
                            let t = Instant::now();
                            (f.solve(b), t.elapsed().as_secs_f64())
                        },
                    ),
                    None => (checks.backward_error(&f, &s, &values), (vec![], 0.0)),
                };
                f.backward_error = eta;
                f.caller_solve_s = seconds;
                f.symmetric = symmetric;
                (f, x)
            });
            match tested {
                Ok((f, x)) if f.backward_error <= BACKWARD_ERROR_LIMIT => {
                    self.stats.count(&f, reasons.len());
                    self.last = Some(backend);
                    return Ok((f, b.map(|_| x)));
                }
                // Not necessarily singular: LBLᵀ pivots only inside a
                // supernode and fails on some non-singular saddle-point
                // matrices (review 9: a KKT matrix with |eigenvalues| ≥
                // 9.3e-3, which the LU factors).
                Ok((f, _)) if f.backward_error.is_nan() => reasons.push(format!(
                    "{}: the solve is not finite (a zero pivot: a singular matrix, or for ldlt and lblt one that pivoting within supernodes cannot avoid)",
                    backend.name()
                )),
                Ok((f, _)) => reasons.push(format!(
                    "{}: backward error {:.1e} > {BACKWARD_ERROR_LIMIT:e}",
                    backend.name(),
                    f.backward_error
                )),
                Err(e) => reasons.push(format!("{}: {e}", backend.name())),
            }
        }
        self.stats.fallbacks += reasons.len();
        self.last = None;
        Err(format!("no factorization passed: {}", reasons.join("; ")))
    }

    /// Whether the last matrix passed the symmetry check (None before any,
    /// or when it was refused for a non-finite entry).
    pub fn last_check_symmetric(&self) -> Option<bool> {
        self.last_check_symmetric
    }

    /// The symmetry `backend` factors with when guessed before the checks:
    /// a faer backend's own; MUMPS's last analysis (general at first).
    fn last_symmetric(&self, backend: Backend) -> bool {
        #[cfg(feature = "mumps")]
        if backend == Backend::Mumps {
            return self
                .mumps
                .as_ref()
                .is_some_and(|m| m.lock().expect("MUMPS lock").symmetric());
        }
        backend.symmetric()
    }

    /// Whether `backend` is MUMPS (analysed as symmetric or general).
    fn is_mumps(&self, backend: Backend) -> bool {
        #[cfg(feature = "mumps")]
        if backend == Backend::Mumps {
            return true;
        }
        let _ = backend;
        false
    }

    /// The numeric factorization by `backend` (split over two threads where
    /// [`LinearSolver::split`] allows, else [`LinearSolver::numeric`]), with
    /// `beside` on another thread: beside the whole factorization, or with
    /// the smaller half of a split one.
    fn numeric_beside<R: Send>(
        &mut self,
        backend: Backend,
        s: &Arc<Structure>,
        values: &[f64],
        symmetric: bool,
        beside: impl FnOnce() -> R + Send,
    ) -> (Result<Factorization, String>, R) {
        let split = match backend {
            Backend::Ldlt => self.split(s),
            _ => Ok(None),
        };
        match split {
            Ok(Some(split)) => {
                set_spare_budget(split.stored_values());
                let start = Instant::now();
                let (f, side) = SplitFactor::new(&split, values, beside);
                let f = f.map(|f| {
                    self.stats.factor_entries = split.factor_entries();
                    let mut f = self.factorization(Factor::Split(split, f), s, backend);
                    f.numeric_s = start.elapsed().as_secs_f64();
                    f
                });
                (f, side)
            }
            Ok(None) => rayon::join(|| self.numeric(backend, s, values, symmetric), beside),
            Err(e) => (Err(e), beside()),
        }
    }

    /// The numeric factorization by `backend` on one factor (and the
    /// pattern's analysis the first time), not yet checked. `symmetric` chooses the MUMPS
    /// analysis; the faer backends know theirs.
    #[cfg_attr(not(feature = "mumps"), allow(unused_variables))]
    fn numeric(
        &mut self,
        backend: Backend,
        s: &Arc<Structure>,
        values: &[f64],
        symmetric: bool,
    ) -> Result<Factorization, String> {
        let start = Instant::now();
        let mut analysis = self.stats.analysis_s;
        #[cfg(feature = "mumps")]
        if backend == Backend::Mumps {
            // MUMPS is analysed as symmetric (SYM = 2) or general: a change of
            // symmetry on the same pattern needs a new instance.
            if let Some(m) = &self.mumps
                && m.lock().expect("MUMPS lock").symmetric() != symmetric
            {
                self.mumps = None;
            }
            if self.mumps.is_none() {
                let t = Instant::now();
                let inst = mumps_backend::Instance::new(s, symmetric)?;
                self.mumps = Some(Arc::new(std::sync::Mutex::new(inst)));
                self.stats.analysis_s += t.elapsed().as_secs_f64();
                self.stats.analyses += 1;
            }
            let shared = Arc::clone(self.mumps.as_ref().expect("set above"));
            let t = Instant::now();
            let (generation, memory, negative, entries) =
                shared.lock().expect("MUMPS lock").factorize(values)?;
            self.stats.factor_entries = entries;
            let f = Factorization {
                numeric_s: t.elapsed().as_secs_f64(),
                caller_solve_s: 0.0,
                factor: Factor::Mumps(shared, generation),
                par: self.par,
                n: s.n(),
                backend,
                backward_error: f64::NAN,
                inertia: symmetric.then_some((negative, 0, s.n() - negative)),
                symmetric: false,
                mumps_memory_mb: Some(memory),
            };
            return Ok(f);
        }
        let factor = if backend.symmetric() {
            let sym = self.whole(s)?;
            set_spare_budget(sym.factor_entries());
            self.stats.factor_entries = sym.factor_entries();
            let pivoting = if backend == Backend::Ldlt {
                Pivoting::None
            } else {
                Pivoting::BunchKaufman
            };
            let f = SymmetricFactor::new(&sym, values, pivoting, self.par)?;
            Factor::Symmetric(sym, f)
        } else {
            if self.lu.is_none() {
                let t = Instant::now();
                self.lu = Some(Arc::new(LuSymbolic::new(s)?));
                self.stats.analysis_s += t.elapsed().as_secs_f64();
                self.stats.analyses += 1;
            }
            let sym = Arc::clone(self.lu.as_ref().expect("set above"));
            self.stats.factor_entries = 0;
            let f = LuFactor::new(&sym, s, values, self.par)?;
            Factor::Lu(sym, Box::new(f))
        };
        analysis = self.stats.analysis_s - analysis;
        let mut f = self.factorization(factor, s, backend);
        f.numeric_s = start.elapsed().as_secs_f64() - analysis;
        Ok(f)
    }

    /// A faer factor as a [`Factorization`] (with its inertia), unchecked.
    fn factorization(&self, factor: Factor, s: &Structure, backend: Backend) -> Factorization {
        let inertia = match &factor {
            Factor::Symmetric(sym, sf) => Some(sf.inertia(sym)),
            Factor::Split(sym, sf) => Some(sf.inertia(sym)),
            _ => None,
        };
        Factorization {
            numeric_s: 0.0,
            caller_solve_s: 0.0,
            factor,
            par: self.par,
            n: s.n(),
            backend,
            backward_error: f64::NAN,
            inertia,
            symmetric: false,
            mumps_memory_mb: None,
        }
    }

    /// The symmetric analysis of the whole pattern (shared, or made here).
    fn whole(&mut self, s: &Arc<Structure>) -> Result<Arc<SymmetricSymbolic>, String> {
        if self.symmetric.is_none() {
            self.symmetric = shared(&ANALYSES, s);
        }
        if self.symmetric.is_none() {
            let t = Instant::now();
            let sym = Arc::new(SymmetricSymbolic::new(s)?);
            share(&ANALYSES, s, &sym);
            self.symmetric = Some(sym);
            self.stats.analysis_s += t.elapsed().as_secs_f64();
            self.stats.analyses += 1;
        }
        Ok(Arc::clone(self.symmetric.as_ref().expect("set above")))
    }

    /// The split of LDLᵀ over two threads for this pattern, where it has
    /// them and the pattern is large enough, splits, and its halves hold at
    /// most [`SPLIT_MAX_FILL`] times the whole factor's entries (analysed
    /// once per pattern and process).
    fn split(&mut self, s: &Arc<Structure>) -> Result<Option<Arc<SplitSymbolic>>, String> {
        if self.threads < 2 || s.n() < SPLIT_MIN_UNKNOWNS {
            return Ok(None);
        }
        if self.split.is_none() {
            self.split = shared(&SPLITS, s).map(Some);
        }
        if self.split.is_none() && shared(&REFUSED, s).is_some() {
            self.split = Some(None);
        }
        if self.split.is_none() {
            let whole = self.whole(s)?.factor_entries();
            let t = Instant::now();
            let found = SplitSymbolic::new(s)?
                .filter(|f| f.factor_entries() as f64 <= SPLIT_MAX_FILL * whole as f64)
                .map(Arc::new);
            match &found {
                Some(split) => {
                    share(&SPLITS, s, split);
                    // Rebuilt if LBLᵀ takes over (0.3 GB at a million unknowns).
                    self.symmetric = None;
                }
                // Forgotten with the pattern, as the analyses are.
                None => share(&REFUSED, s, s),
            }
            self.split = Some(found);
            self.stats.analysis_s += t.elapsed().as_secs_f64();
            self.stats.analyses += 1;
        }
        let split = self.split.clone().flatten();
        self.stats.split_separator = split.as_ref().map(|f| f.separator());
        Ok(split)
    }
}

impl Factorization {
    /// Solves A x = b. Non-finite entries in x mean A is (numerically) singular.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        debug_assert_eq!(x.len(), self.n);
        match &self.factor {
            Factor::Symmetric(sym, f) => f.solve_in_place(sym, &mut x, self.par),
            Factor::Split(sym, f) => f.solve_in_place(sym, &mut x),
            Factor::Lu(sym, f) => f.solve_in_place(sym, &mut x, self.par),
            #[cfg(feature = "mumps")]
            Factor::Mumps(inst, generation) => {
                if let Err(e) = inst.lock().expect("MUMPS lock").solve(*generation, &mut x) {
                    // A failed solve reads as a singular system (non-finite).
                    eprintln!("MUMPS solve: {e}");
                    x.fill(f64::NAN);
                }
            }
        }
        x
    }

    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Seconds of the numeric factorization (no analysis, no check).
    pub fn numeric_seconds(&self) -> f64 {
        self.numeric_s
    }

    /// Seconds of the caller's solve of [`LinearSolver::factorize_solve`],
    /// beside the solve that tested the factorization.
    pub fn caller_solve_seconds(&self) -> f64 {
        self.caller_solve_s
    }

    /// The backward error of the check solve.
    pub fn backward_error(&self) -> f64 {
        self.backward_error
    }

    /// (negative, zero, positive) pivot counts: the inertia of a symmetric
    /// tangent; `None` after an LU.
    pub fn inertia(&self) -> Option<(usize, usize, usize)> {
        self.inertia
    }
}

#[cfg(feature = "mumps")]
mod mumps_backend {
    use super::super::mumps::Mumps;
    use super::Structure;

    /// Generation, memory figures (MB), negative pivots, factor entries.
    pub type Factored = (u64, (f64, f64, f64), usize, usize);

    /// One MUMPS instance, analysed for one pattern.
    pub struct Instance {
        mumps: Mumps,
        generation: u64,
        symmetric: bool,
    }

    impl Instance {
        /// SYM = 2 (general symmetric: the lower triangle is kept) for a
        /// symmetric matrix, 0 otherwise; the analysis of the pattern.
        pub fn new(s: &Structure, symmetric: bool) -> Result<Self, String> {
            let mut mumps = Mumps::new(if symmetric { 2 } else { 0 })?;
            let cols: Vec<usize> = (0..s.n())
                .flat_map(|c| std::iter::repeat_n(c, s.col_ptr()[c + 1] - s.col_ptr()[c]))
                .collect();
            mumps.analyse(s.n(), s.row_idx(), &cols)?;
            Ok(Self {
                mumps,
                generation: 0,
                symmetric,
            })
        }

        /// Analysed as symmetric (SYM = 2).
        pub fn symmetric(&self) -> bool {
            self.symmetric
        }

        /// Factorizes; returns the generation, the memory figures, the
        /// negative pivots and the factor entries.
        pub fn factorize(&mut self, values: &[f64]) -> Result<Factored, String> {
            self.mumps.factorize(values)?;
            self.generation += 1;
            Ok((
                self.generation,
                self.mumps.memory_mb(),
                self.mumps.negative_pivots(),
                self.mumps.factor_entries().max(0) as usize,
            ))
        }

        pub fn solve(&mut self, generation: u64, x: &mut [f64]) -> Result<(), String> {
            if generation != self.generation {
                return Err("solve with a factorization replaced by a later one".into());
            }
            self.mumps.solve(x)
        }
    }
}

/// The symmetric analyses alive in this process, by pattern: the solvers of
/// one run (the path's, its grid points', its events') factorize the same
/// pattern, and one analysis serves them all (at a million unknowns it
/// takes seconds and holds the permuted pattern, ~0.3 GB).
static ANALYSES: Analyses<SymmetricSymbolic> = Mutex::new(Vec::new());

/// The same for the split analyses.
static SPLITS: Analyses<SplitSymbolic> = Mutex::new(Vec::new());

/// The patterns whose split was refused (no separator, or too much fill),
/// while a solver holds them.
static REFUSED: Analyses<Structure> = Mutex::new(Vec::new());

type Analyses<T> = Mutex<Vec<(u64, Weak<T>)>>;

fn shared<T>(list: &Analyses<T>, s: &Structure) -> Option<Arc<T>> {
    let analyses = list.lock().ok()?;
    analyses
        .iter()
        .find(|(id, _)| *id == s.id())
        .and_then(|(_, a)| a.upgrade())
}

fn share<T>(list: &Analyses<T>, s: &Structure, analysis: &Arc<T>) {
    if let Ok(mut analyses) = list.lock() {
        analyses.retain(|(_, a)| a.strong_count() > 0);
        analyses.push((s.id(), Arc::downgrade(analysis)));
    }
}

/// (row, col) of a slot.
fn position(s: &Structure, k: usize) -> (usize, usize) {
    let c = s.col_ptr().partition_point(|&p| p <= k) - 1;
    (s.row_idx()[k], c)
}

/// Symmetric to [`SYMMETRY_TOLERANCE`]: the pattern, and every value
/// against its transpose (what the automatic choice tests).
pub fn is_symmetric(s: &Structure, values: &[f64]) -> bool {
    let Some(t) = s.transpose_slots() else {
        return false;
    };
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values.iter().zip(t).all(|(&a, &k)| {
        let b = values[k as usize];
        (a - b).abs() <= SYMMETRY_TOLERANCE * a.abs().max(b.abs()).max(1e-3 * scale)
    })
}

/// y = A x for compressed columns.
fn mul(s: &Structure, values: &[f64], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; s.n()];
    for (c, &xc) in x.iter().enumerate() {
        for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
            y[s.row_idx()[k]] += values[k] * xc;
        }
    }
    y
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// What is checked on the values of a matrix, apart from its factor.
struct Checks {
    /// The first slot holding a non-finite value.
    non_finite: Option<usize>,
    /// [`is_symmetric`].
    symmetric: bool,
    /// The right-hand side of the backward-error test, A x_ref, x_ref a
    /// fixed vector with entries in [1, 2): not the caller's, which may
    /// hide an unstable factor (a right-hand side that does not excite its
    /// lost digits; unit test `a_tiny_pivot_hands_over_to_bunch_kaufman`).
    b: Vec<f64>,
    /// max_i Σ_j |a_ij|.
    norm_inf: f64,
}

impl Checks {
    fn of(s: &Structure, values: &[f64]) -> Self {
        let non_finite = values.iter().position(|v| !v.is_finite());
        if non_finite.is_some() {
            return Self {
                non_finite,
                symmetric: false,
                b: vec![],
                norm_inf: f64::NAN,
            };
        }
        let n = s.n();
        let mut row_sums = vec![0.0; n];
        let mut b = vec![0.0; n];
        for c in 0..n {
            let xc = 1.0 + ((c * 7919) % 113) as f64 / 113.0;
            let col = s.col_ptr()[c]..s.col_ptr()[c + 1];
            for (&r, v) in s.row_idx()[col.clone()].iter().zip(&values[col]) {
                b[r] += v * xc;
                row_sums[r] += v.abs();
            }
        }
        Self {
            non_finite,
            symmetric: is_symmetric(s, values),
            b,
            norm_inf: max_abs(&row_sums),
        }
    }

    /// The normwise backward error of f's solve of A x = b (NaN when the
    /// solve is not finite).
    fn backward_error(&self, f: &Factorization, s: &Structure, values: &[f64]) -> f64 {
        let x = f.solve(&self.b);
        if !x.iter().all(|v| v.is_finite()) {
            f64::NAN
        } else {
            let ax = mul(s, values, &x);
            let r = self
                .b
                .iter()
                .zip(&ax)
                .fold(0.0f64, |m, (b, a)| m.max((b - a).abs()));
            let denominator = self.norm_inf * max_abs(&x) + max_abs(&self.b);
            if denominator == 0.0 {
                0.0
            } else {
                r / denominator
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2D 5-point Laplacian on an m × m grid (SPD), plus `shift` on the
    /// diagonal (indefinite for shift < −λ_min) and `skew` times a
    /// non-symmetric first-difference term.
    fn grid(m: usize, shift: f64, skew: f64) -> SparseMatrix {
        let n = m * m;
        let mut a = SparseMatrix::new(n);
        for i in 0..m {
            for j in 0..m {
                let k = i * m + j;
                a.add(k, k, 4.0 + shift + 1e-3 * (k % 7) as f64);
                for (di, dj) in [(0i64, 1i64), (1, 0), (0, -1), (-1, 0)] {
                    let (p, q) = (i as i64 + di, j as i64 + dj);
                    if p >= 0 && q >= 0 && (p as usize) < m && (q as usize) < m {
                        let l = p as usize * m + q as usize;
                        a.add(k, l, -1.0 + skew * (di + dj) as f64);
                    }
                }
            }
        }
        a
    }

    fn residual(a: &SparseMatrix, f: &Factorization) -> f64 {
        let n = a.n;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let x = f.solve(&b);
        let ax = a.mul_vec(&x);
        let r = max_abs(&b.iter().zip(&ax).map(|(b, a)| b - a).collect::<Vec<_>>());
        let mut rows = vec![0.0; n];
        for (i, _, v) in a.entries() {
            rows[i] += v.abs();
        }
        r / (max_abs(&rows) * max_abs(&x) + max_abs(&b))
    }

    /// Round-off sums pass the symmetry test, a real asymmetry does not:
    /// the pair measured on the 96,714-unknown sheet's tangent (entries
    /// 3.8e-15 and 4.9e-15 of max|A|) against a follower-like 1e-9 max|A|.
    #[test]
    fn symmetry_test_tells_round_off_from_asymmetry() {
        let with = |a01: f64, a10: f64| {
            let mut a = grid(3, 0.0, 0.0);
            a.add(0, 1, a01);
            a.add(1, 0, a10);
            let (s, v) = a.compressed(None).unwrap();
            is_symmetric(&s, &v)
        };
        let scale = 4.0;
        assert!(with(0.0, 0.0));
        // The Laplacian's -1 at (0, 1) and (1, 0) cancelled to round-off.
        assert!(with(1.0 + 3.818e-15 * scale, 1.0 + 4.866e-15 * scale));
        assert!(!with(1.0, 1.0 + 1e-9 * scale));
    }

    /// `a`'s entries on the pattern `s` (one structure: the solver keeps its
    /// analysis and guesses the last backend).
    fn on(s: &Arc<Structure>, a: &SparseMatrix) -> SparseMatrix {
        let mut m = SparseMatrix::with_structure(Arc::clone(s));
        for (r, c, v) in a.entries() {
            m.add(r, c, v);
        }
        m
    }

    /// The backend factorized beside the checks is the last one; when the
    /// checks choose another (the values stopped being symmetric), the
    /// choice is made again and the answer is that backend's.
    #[test]
    fn the_guessed_backend_gives_way_when_the_symmetry_changes() {
        let (s, _) = grid(12, 0.0, 0.0).compressed(None).unwrap();
        let spd = on(&s, &grid(12, 0.0, 0.0));
        let general = on(&s, &grid(12, 0.5, 0.3));
        let mut solver = LinearSolver::default();
        for (a, backend) in [
            (&spd, Backend::Ldlt),
            (&general, Backend::Lu),
            (&general, Backend::Lu),
            (&spd, Backend::Ldlt),
        ] {
            let f = solver.factorize(a).unwrap();
            assert_eq!(f.backend(), backend);
            assert!(residual(a, &f) <= 1e-14);
        }
        assert_eq!(solver.stats().analyses, 2, "one analysis per backend");
    }

    /// factorize_solve's x is its factor's solve, bit for bit, and the
    /// factorization is tested as by factorize.
    #[test]
    fn the_first_solve_is_the_factors_solve() {
        for a in [grid(15, 0.0, 0.0), grid(15, 0.5, 0.3)] {
            let n = a.n;
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();
            let (f, x) = LinearSolver::default().factorize_solve(&a, &b).unwrap();
            assert_eq!(x, f.solve(&b));
            let alone = LinearSolver::default().factorize(&a).unwrap();
            assert_eq!(f.backward_error(), alone.backward_error());
            assert!(f.backward_error() > 0.0 && f.backward_error() <= 1e-14);
        }
    }

    /// Blocks [[1e-20, 1], [1, 1]]: LDLᵀ without pivoting takes the tiny
    /// pivot and loses the 1 of the second (backward error ~0.5): the test
    /// catches it and LBLᵀ takes over, also where the caller's right-hand
    /// side (here zero on the tiny pivots) would not have shown it.
    /// On two threads a large LDLᵀ is split in two halves and a separator
    /// (split.rs): its inertia is that of the whole factorization (definite
    /// and indefinite), and on a well-conditioned matrix (eigenvalues in
    /// [1, 9]) its backward error is round-off and its solution equals the
    /// whole one to round-off.
    #[test]
    fn ldlt_split_over_two_threads_solves_as_the_whole() {
        for shift in [1.0, -0.5] {
            let a = grid(224, shift, 0.0);
            assert!(a.n >= SPLIT_MIN_UNKNOWNS);
            let b: Vec<f64> = (0..a.n).map(|i| ((i * 13) % 7) as f64 - 3.0).collect();
            let mut whole = LinearSolver::new(Choice::Only(Backend::Ldlt)).with_threads(1);
            let mut split = LinearSolver::new(Choice::Only(Backend::Ldlt)).with_threads(2);
            let (fw, fs) = (whole.factorize(&a).unwrap(), split.factorize(&a).unwrap());
            assert!(whole.stats().split_separator.is_none());
            let ns = split.stats().split_separator.expect("split");
            assert!(ns > 0 && 8 * ns <= a.n, "separator {ns}");
            assert_eq!(fs.inertia(), fw.inertia());
            if shift > 0.0 {
                assert!(fs.backward_error() <= 1e-15, "{:e}", fs.backward_error());
                let (xw, xs) = (fw.solve(&b), fs.solve(&b));
                let diff = xw
                    .iter()
                    .zip(&xs)
                    .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(diff <= 1e-14 * max_abs(&xw), "{diff:e}");
            } else {
                // Unpivoted on an indefinite matrix: 2.9e-12 whole, 2.1e-13
                // split (measured).
                assert!(fs.backward_error() <= BACKWARD_ERROR_LIMIT);
                assert!(fw.inertia().unwrap().0 > 0, "indefinite");
            }
        }
    }

    #[test]
    fn a_tiny_pivot_hands_over_to_bunch_kaufman() {
        let m = 50;
        let mut a = SparseMatrix::new(2 * m);
        for k in 0..m {
            a.add(2 * k, 2 * k, 1e-20);
            a.add(2 * k, 2 * k + 1, 1.0);
            a.add(2 * k + 1, 2 * k, 1.0);
            a.add(2 * k + 1, 2 * k + 1, 1.0);
        }
        let only_ldlt = LinearSolver::new(Choice::Only(Backend::Ldlt)).factorize(&a);
        assert!(only_ldlt.is_err(), "LDLᵀ passed the test");
        let b: Vec<f64> = (0..2 * m).map(|i| (i % 2) as f64).collect();
        let mut auto = LinearSolver::default();
        let f = auto.factorize(&a).unwrap();
        let (g, x) = auto.factorize_solve(&a, &b).unwrap();
        for f in [&f, &g] {
            assert_eq!(f.backend(), Backend::Lblt);
            assert!(residual(&a, f) <= 1e-14);
        }
        assert_eq!(auto.stats().fallbacks, 2);
        assert_eq!(x, g.solve(&b));
    }

    #[test]
    fn every_backend_solves_what_it_is_made_for() {
        let spd = grid(20, 0.0, 0.0);
        // Shifted by −4.5: eigenvalues in (−4.5, 3.5), no zero diagonal.
        let indefinite = grid(20, -4.5, 0.0);
        let general = grid(20, 0.5, 0.3);
        let cases: [(&SparseMatrix, &[Backend]); 3] = [
            (&spd, &Backend::ALL),
            (&indefinite, &[Backend::Lblt, Backend::Lu]),
            (&general, &[Backend::Lu]),
        ];
        for (a, backends) in cases {
            for &b in backends {
                let mut s = LinearSolver::new(Choice::Only(b));
                let f = s.factorize(a).unwrap();
                let eta = residual(a, &f);
                assert!(eta <= 1e-14, "{}: backward error {eta:e}", b.name());
                assert!(f.backward_error() <= 1e-14);
            }
        }
    }

    #[test]
    fn auto_choice_follows_symmetry_and_inertia_counts_negative_eigenvalues() {
        let mut s = LinearSolver::default();
        let f = s.factorize(&grid(20, 0.0, 0.0)).unwrap();
        assert_eq!(f.backend(), Backend::Ldlt);
        assert_eq!(f.inertia(), Some((0, 0, 400)));
        let f = s.factorize(&grid(20, 0.5, 0.3)).unwrap();
        assert_eq!(f.backend(), Backend::Lu);
        assert_eq!(f.inertia(), None);
        // The 1D Laplacian tridiag(−1, 2, −1) of size m has eigenvalues
        // 2 − 2 cos(k π / (m + 1)); shifted by −2 exactly half are negative.
        let m = 41;
        let mut a = SparseMatrix::new(m);
        for i in 0..m {
            a.add(i, i, 2.0 - 2.0 + 1e-3);
            if i > 0 {
                a.add(i, i - 1, -1.0);
                a.add(i - 1, i, -1.0);
            }
        }
        let eig = |k: usize| {
            2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (m + 1) as f64).cos() - 2.0 + 1e-3
        };
        let negative = (1..=m).filter(|&k| eig(k) < 0.0).count();
        for b in [Backend::Ldlt, Backend::Lblt] {
            if let Ok(f) = LinearSolver::new(Choice::Only(b)).factorize(&a) {
                assert_eq!(
                    f.inertia(),
                    Some((negative, 0, m - negative)),
                    "{}",
                    b.name()
                );
            }
        }
        let f = LinearSolver::default().factorize(&a).unwrap();
        assert_eq!(f.inertia(), Some((negative, 0, m - negative)));
    }

    #[test]
    fn a_zero_pivot_hands_over_to_bunch_kaufman_and_a_singular_matrix_fails() {
        // [[0, 1], [1, 0]]: LDLᵀ without pivoting meets a zero pivot.
        let a = SparseMatrix::from_dense(&[vec![0.0, 1.0], vec![1.0, 0.0]]);
        let mut s = LinearSolver::default();
        let f = s.factorize(&a).unwrap();
        assert_eq!(f.backend(), Backend::Lblt);
        assert_eq!(f.inertia(), Some((1, 0, 1)));
        assert_eq!(f.solve(&[2.0, 3.0]), vec![3.0, 2.0]);
        assert_eq!(s.stats().fallbacks, 1);
        let singular = SparseMatrix::from_dense(&[vec![1.0, 1.0], vec![1.0, 1.0]]);
        let e = s.factorize(&singular).err().expect("singular");
        assert!(e.contains("no factorization passed"), "{e}");
        let mut nan = SparseMatrix::new(1);
        nan.add(0, 0, f64::NAN);
        assert!(s.factorize(&nan).err().unwrap().contains("non-finite"));
        assert!(
            Backend::from_name("ldlt") == Some(Backend::Ldlt) && Backend::from_name("x").is_none()
        );
    }
}
