//! Sparse factorization by MUMPS 5 (Debian's libmumps-dev, OpenMPI), behind
//! the `mumps` cargo feature: a small safe wrapper over the C interface
//! `dmumps_c` (double precision, real).
//!
//! Run model (`mpirun -n P anm ...`): every rank runs the same program and
//! assembles the same matrix; the matrix is passed centralized on the host,
//! rank 0 (ICNTL(18) = 0), which also works (PAR = 1); every MUMPS job is
//! collective, so every rank calls [`Mumps::analyse`], [`Mumps::factorize`],
//! [`Mumps::solve`] in the same order with the same arguments. MUMPS returns
//! the solution on the host only (ICNTL(21) = 0); [`Mumps::solve`] broadcasts
//! it so that every rank holds it and continues identically. Only the root
//! ([`is_root`]) writes files. Without `mpirun` the process is an MPI
//! singleton and MUMPS runs on one rank.
//!
//! `DMUMPS_STRUC_C` is declared by hand in the field order of MUMPS 5.5.1's
//! `dmumps_c.h` (32-bit MUMPS_INT, Debian's build); [`struct_layout`] lists
//! every field offset so that a test compares them with the C compiler's
//! `offsetof` on the installed header.
//!
//! Memory figures are MUMPS's own, in millions of bytes (MB = 1e6 bytes).

use std::ffi::c_char;
use std::mem::offset_of;

use super::mpi::{MPI_LOCK, broadcast_locked};
pub use super::mpi::{is_root, mpi_finalize, mpi_init};

/// MUMPS's code for "use MPI_COMM_WORLD" in the Fortran communicator field.
const USE_COMM_WORLD: i32 = -987_654;

/// `DMUMPS_STRUC_C` of dmumps_c.h (MUMPS 5.5.1), field for field.
#[repr(C)]
struct DmumpsStrucC {
    sym: i32,
    par: i32,
    job: i32,
    comm_fortran: i32,
    icntl: [i32; 60],
    keep: [i32; 500],
    cntl: [f64; 15],
    dkeep: [f64; 230],
    keep8: [i64; 150],
    n: i32,
    nblk: i32,
    nz_alloc: i32,
    // Assembled entry.
    nz: i32,
    nnz: i64,
    irn: *mut i32,
    jcn: *mut i32,
    a: *mut f64,
    // Distributed entry.
    nz_loc: i32,
    nnz_loc: i64,
    irn_loc: *mut i32,
    jcn_loc: *mut i32,
    a_loc: *mut f64,
    // Element entry.
    nelt: i32,
    eltptr: *mut i32,
    eltvar: *mut i32,
    a_elt: *mut f64,
    // Matrix by blocks.
    blkptr: *mut i32,
    blkvar: *mut i32,
    // Ordering, if given by user.
    perm_in: *mut i32,
    // Orderings returned to user.
    sym_perm: *mut i32,
    uns_perm: *mut i32,
    // Scaling.
    colsca: *mut f64,
    rowsca: *mut f64,
    colsca_from_mumps: i32,
    rowsca_from_mumps: i32,
    // RHS, solution, output data and statistics.
    rhs: *mut f64,
    redrhs: *mut f64,
    rhs_sparse: *mut f64,
    sol_loc: *mut f64,
    rhs_loc: *mut f64,
    irhs_sparse: *mut i32,
    irhs_ptr: *mut i32,
    isol_loc: *mut i32,
    irhs_loc: *mut i32,
    nrhs: i32,
    lrhs: i32,
    lredrhs: i32,
    nz_rhs: i32,
    lsol_loc: i32,
    nloc_rhs: i32,
    lrhs_loc: i32,
    schur_mloc: i32,
    schur_nloc: i32,
    schur_lld: i32,
    mblock: i32,
    nblock: i32,
    nprow: i32,
    npcol: i32,
    info: [i32; 80],
    infog: [i32; 80],
    rinfo: [f64; 40],
    rinfog: [f64; 40],
    // Null space.
    deficiency: i32,
    pivnul_list: *mut i32,
    mapping: *mut i32,
    // Schur.
    size_schur: i32,
    listvar_schur: *mut i32,
    schur: *mut f64,
    // Internal parameters.
    instance_number: i32,
    wk_user: *mut f64,
    version_number: [c_char; 32],
    ooc_tmpdir: [c_char; 256],
    ooc_prefix: [c_char; 64],
    write_problem: [c_char; 256],
    lwk_user: i32,
    save_dir: [c_char; 256],
    save_prefix: [c_char; 256],
    metis_options: [i32; 40],
}

#[link(name = "dmumps")]
#[link(name = "mumps_common")]
unsafe extern "C" {
    fn dmumps_c(id: *mut DmumpsStrucC);
}

/// Size of `DMUMPS_STRUC_C` and the offset of every field as declared here,
/// for the layout test against the C header.
#[doc(hidden)]
pub fn struct_layout() -> (usize, Vec<(&'static str, usize)>) {
    macro_rules! fields {
        ($($f:ident),* $(,)?) => {
            vec![$((stringify!($f), offset_of!(DmumpsStrucC, $f))),*]
        };
    }
    let fields = fields!(
        sym,
        par,
        job,
        comm_fortran,
        icntl,
        keep,
        cntl,
        dkeep,
        keep8,
        n,
        nblk,
        nz_alloc,
        nz,
        nnz,
        irn,
        jcn,
        a,
        nz_loc,
        nnz_loc,
        irn_loc,
        jcn_loc,
        a_loc,
        nelt,
        eltptr,
        eltvar,
        a_elt,
        blkptr,
        blkvar,
        perm_in,
        sym_perm,
        uns_perm,
        colsca,
        rowsca,
        colsca_from_mumps,
        rowsca_from_mumps,
        rhs,
        redrhs,
        rhs_sparse,
        sol_loc,
        rhs_loc,
        irhs_sparse,
        irhs_ptr,
        isol_loc,
        irhs_loc,
        nrhs,
        lrhs,
        lredrhs,
        nz_rhs,
        lsol_loc,
        nloc_rhs,
        lrhs_loc,
        schur_mloc,
        schur_nloc,
        schur_lld,
        mblock,
        nblock,
        nprow,
        npcol,
        info,
        infog,
        rinfo,
        rinfog,
        deficiency,
        pivnul_list,
        mapping,
        size_schur,
        listvar_schur,
        schur,
        instance_number,
        wk_user,
        version_number,
        ooc_tmpdir,
        ooc_prefix,
        write_problem,
        lwk_user,
        save_dir,
        save_prefix,
        metis_options,
    );
    (size_of::<DmumpsStrucC>(), fields)
}

/// A MUMPS instance: analyse a pattern once, factorize any number of times,
/// solve many. Collective: with several ranks, every rank makes the same
/// calls in the same order.
pub struct Mumps {
    id: Box<DmumpsStrucC>,
    sym: i32,
    n: usize,
    /// Number of coordinates given to `analyse` (values must match it).
    n_input: usize,
    /// For symmetric matrices given with entries above the diagonal: the
    /// input positions kept (the lower triangle); `None` keeps all.
    kept: Option<Vec<usize>>,
    irn: Vec<i32>,
    jcn: Vec<i32>,
    values: Vec<f64>,
    rhs: Vec<f64>,
    analysed: bool,
    factorized: bool,
}

// SAFETY: the instance owns every buffer its raw pointers point to, and all
// MUMPS calls of the process are serialized by MPI_LOCK (MPI runs in
// MPI_THREAD_SERIALIZED mode), so it may move to another thread.
unsafe impl Send for Mumps {}

/// What MUMPS's INFOG(1) < 0 means (MUMPS 5 user guide, section "Error
/// diagnostics"), with INFOG(2).
fn describe_error(code: i32, info2: i32) -> String {
    match code {
        -1 => format!("an error occurred on rank {info2}"),
        -2 => format!("number of entries out of range ({info2})"),
        -3 => "job called in the wrong order (e.g. factorization before analysis)".into(),
        -5 | -7 => {
            format!("not enough memory during the analysis (allocation of {info2} entries failed)")
        }
        -6 => format!("matrix structurally singular (structural rank {info2})"),
        -8 | -9 | -14 | -15 => format!(
            "internal workspace too small (code {code}, {info2}): more memory relaxation \
             (ICNTL(14)) is needed"
        ),
        -10 => format!("matrix numerically singular ({info2} pivots eliminated)"),
        -11 | -12 => format!("internal workspace too small for the solve ({info2})"),
        -13 => format!(
            "out of memory: an allocation of {} entries failed",
            if info2 < 0 {
                format!("{} million", -info2)
            } else {
                info2.to_string()
            }
        ),
        -16 => format!("N out of range ({info2})"),
        -17 => "internal send buffer too small".into(),
        -19 => "the memory limit ICNTL(23) is too small".into(),
        -20 => "internal reception buffer too small".into(),
        -21 => "PAR = 0 with a single rank".into(),
        -40 => "the matrix was declared positive definite (SYM = 1) but a negative or null \
                pivot was met: use SYM = 2"
            .into(),
        _ => format!("MUMPS error INFOG(1) = {code}, INFOG(2) = {info2}"),
    }
}

impl Mumps {
    /// sym: 0 unsymmetric, 1 SPD, 2 general symmetric (then only the lower
    /// triangle is used: entries above the diagonal given to
    /// [`Mumps::analyse`] are dropped, so the full matrix may be passed).
    /// Initializes MPI if needed (as a singleton without `mpirun`).
    pub fn new(sym: i32) -> Result<Self, String> {
        if !(0..=2).contains(&sym) {
            return Err(format!("MUMPS: SYM must be 0, 1 or 2, not {sym}"));
        }
        mpi_init();
        // SAFETY: all-zero is a valid DMUMPS_STRUC_C (integers, floats, null
        // pointers, empty strings).
        let id: Box<DmumpsStrucC> = unsafe { Box::new_zeroed().assume_init() };
        let mut m = Self {
            id,
            sym,
            n: 0,
            n_input: 0,
            kept: None,
            irn: Vec::new(),
            jcn: Vec::new(),
            values: Vec::new(),
            rhs: Vec::new(),
            analysed: false,
            factorized: false,
        };
        m.id.sym = sym;
        m.id.par = 1;
        m.id.comm_fortran = USE_COMM_WORLD;
        m.run(-1, "initialization")?;
        let verbose = std::env::var("ANM_MUMPS_VERBOSE").is_ok_and(|v| v == "1");
        if verbose {
            m.set_icntl(1, 6);
            m.set_icntl(2, 6);
            m.set_icntl(3, 6);
            m.set_icntl(4, 2);
        } else {
            m.set_icntl(1, -1);
            m.set_icntl(2, -1);
            m.set_icntl(3, -1);
            m.set_icntl(4, 0);
        }
        m.set_icntl(5, 0); // assembled matrix
        m.set_icntl(18, 0); // centralized on the host
        m.set_icntl(20, 0); // dense right-hand side
        m.set_icntl(21, 0); // centralized solution
        if sym != 0 {
            // The root front factored by MUMPS itself rather than ScaLAPACK,
            // which does not count negative pivots: INFOG(12) is then the
            // inertia with any number of ranks.
            m.set_icntl(13, 1);
        }
        Ok(m)
    }

    /// Sets ICNTL(i) (1-based, as in the MUMPS user guide), e.g. ICNTL(7)
    /// the ordering or ICNTL(14) the memory relaxation in percent. Same
    /// value on every rank.
    pub fn set_icntl(&mut self, i: usize, value: i32) {
        assert!((1..=60).contains(&i), "ICNTL index {i} outside 1..=60");
        self.id.icntl[i - 1] = value;
    }

    /// ICNTL(i) (1-based).
    pub fn icntl(&self, i: usize) -> i32 {
        self.id.icntl[i - 1]
    }

    /// INFOG(i) (1-based), identical on every rank.
    pub fn infog(&self, i: usize) -> i32 {
        self.id.infog[i - 1]
    }

    /// RINFOG(i) (1-based), identical on every rank: e.g. after a solve
    /// with ICNTL(11) = 1, RINFOG(7), RINFOG(8) the backward errors,
    /// RINFOG(9) an upper bound of the relative forward error, RINFOG(10),
    /// RINFOG(11) condition numbers.
    pub fn rinfog(&self, i: usize) -> f64 {
        self.id.rinfog[i - 1]
    }

    /// INFO(i) (1-based), this rank's.
    pub fn info(&self, i: usize) -> i32 {
        self.id.info[i - 1]
    }

    /// Runs one MUMPS job with the current buffers.
    fn run(&mut self, job: i32, what: &str) -> Result<(), String> {
        self.id.job = job;
        self.id.irn = self.irn.as_mut_ptr();
        self.id.jcn = self.jcn.as_mut_ptr();
        self.id.a = self.values.as_mut_ptr();
        self.id.rhs = self.rhs.as_mut_ptr();
        {
            let _g = MPI_LOCK.lock().unwrap_or_else(|e| e.into_inner());
            // SAFETY: the struct was initialized by JOB = -1 (or this is
            // that call), and every pointer in it points into a buffer owned
            // by self that stays alive and unmoved during the call.
            unsafe { dmumps_c(&mut *self.id) };
        }
        let code = self.id.infog[0];
        if code < 0 {
            return Err(format!(
                "MUMPS {what} (JOB = {job}) failed: {}",
                describe_error(code, self.id.infog[1])
            ));
        }
        Ok(())
    }

    /// Analysis of a pattern (0-based row/col coordinates, duplicates
    /// allowed, summed by MUMPS). Centralized on the host: every rank
    /// passes the same arguments (they are checked everywhere, so that an
    /// error returns on every rank alike), only the host keeps a copy.
    pub fn analyse(&mut self, n: usize, rows: &[usize], cols: &[usize]) -> Result<(), String> {
        if rows.len() != cols.len() {
            return Err(format!(
                "MUMPS analysis: {} row indices but {} column indices",
                rows.len(),
                cols.len()
            ));
        }
        if n > i32::MAX as usize - 1 {
            return Err(format!("MUMPS analysis: n = {n} exceeds 32-bit MUMPS_INT"));
        }
        if let Some(k) = (0..rows.len()).find(|&k| rows[k] >= n || cols[k] >= n) {
            return Err(format!(
                "MUMPS analysis: entry ({}, {}) outside the {n} x {n} matrix",
                rows[k], cols[k]
            ));
        }
        self.analysed = false;
        self.factorized = false;
        self.n = n;
        self.n_input = rows.len();
        self.id.n = n as i32;
        if !self.is_host() {
            // With a centralized matrix (ICNTL(18) = 0) MUMPS reads the
            // entries on the host only: the other ranks keep no copy.
            self.kept = None;
            self.irn = Vec::new();
            self.jcn = Vec::new();
            self.values = Vec::new();
            self.run(1, "analysis")?;
            self.analysed = true;
            return Ok(());
        }
        let upper = self.sym != 0 && rows.iter().zip(cols).any(|(r, c)| r < c);
        self.kept = upper.then(|| (0..rows.len()).filter(|&k| rows[k] >= cols[k]).collect());
        let (irn, jcn): (Vec<i32>, Vec<i32>) = match &self.kept {
            Some(kept) => kept
                .iter()
                .map(|&k| (rows[k] as i32 + 1, cols[k] as i32 + 1))
                .unzip(),
            None => rows
                .iter()
                .zip(cols)
                .map(|(&r, &c)| (r as i32 + 1, c as i32 + 1))
                .unzip(),
        };
        self.irn = irn;
        self.jcn = jcn;
        self.values = vec![0.0; self.irn.len()];
        self.id.nnz = self.irn.len() as i64;
        self.id.nz = i32::try_from(self.irn.len()).unwrap_or(0);
        self.run(1, "analysis")?;
        self.analysed = true;
        Ok(())
    }

    /// Numeric factorization with values in the same order as the
    /// coordinates passed to [`Mumps::analyse`]. If MUMPS runs short of its
    /// estimated workspace (INFOG(1) = -8, -9, -14, -15), the memory
    /// relaxation ICNTL(14) is doubled and the factorization retried, up to
    /// four times.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), String> {
        if !self.analysed {
            return Err("MUMPS factorization called before a successful analysis".into());
        }
        if values.len() != self.n_input {
            return Err(format!(
                "MUMPS factorization: {} values for the {} coordinates of the analysis",
                values.len(),
                self.n_input
            ));
        }
        self.factorized = false;
        match &self.kept {
            _ if !self.is_host() => {}
            Some(kept) => {
                for (v, &k) in self.values.iter_mut().zip(kept) {
                    *v = values[k];
                }
            }
            None => self.values.copy_from_slice(values),
        }
        let mut tries = 0;
        loop {
            match self.run(2, "factorization") {
                Ok(()) => break,
                Err(_) if tries < 4 && [-8, -9, -14, -15].contains(&self.id.infog[0]) => {
                    tries += 1;
                    let relax = self.icntl(14).max(20);
                    self.set_icntl(14, relax * 2);
                }
                Err(e) => return Err(e),
            }
        }
        self.factorized = true;
        Ok(())
    }

    /// Solve in place; on return every rank holds the solution (computed on
    /// the host from its `b`, then broadcast).
    pub fn solve(&mut self, b: &mut [f64]) -> Result<(), String> {
        if !self.factorized {
            return Err("MUMPS solve called before a successful factorization".into());
        }
        if b.len() != self.n {
            return Err(format!(
                "MUMPS solve: right-hand side of length {} for n = {}",
                b.len(),
                self.n
            ));
        }
        self.rhs.clear();
        if self.is_host() {
            self.rhs.extend_from_slice(b);
        }
        self.id.nrhs = 1;
        self.id.lrhs = self.n as i32;
        let solved = self.run(3, "solve");
        self.id.rhs = std::ptr::null_mut();
        solved?;
        if self.is_host() {
            b.copy_from_slice(&self.rhs);
        }
        let _g = MPI_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        broadcast_locked(b)
    }

    /// Number of negative pivots (INFOG(12)) for symmetric factorizations
    /// (0 for SYM = 0, where INFOG(12) counts something else).
    pub fn negative_pivots(&self) -> usize {
        if self.sym == 0 {
            return 0;
        }
        self.id.infog[11].max(0) as usize
    }

    /// Memory (MB = 1e6 bytes) effectively used by the last factorization:
    /// on this rank (INFO(22)), the maximum over ranks (INFOG(21)) and the
    /// total over ranks (INFOG(22)).
    pub fn memory_mb(&self) -> (f64, f64, f64) {
        (
            self.id.info[21] as f64,
            self.id.infog[20] as f64,
            self.id.infog[21] as f64,
        )
    }

    /// Memory (MB) MUMPS allocated for the last factorization: on this rank
    /// (INFO(16)), maximum over ranks (INFOG(18)), total (INFOG(19)).
    pub fn memory_allocated_mb(&self) -> (f64, f64, f64) {
        (
            self.id.info[15] as f64,
            self.id.infog[17] as f64,
            self.id.infog[18] as f64,
        )
    }

    /// Entries in the factors after factorization (INFOG(29)).
    pub fn factor_entries(&self) -> i64 {
        let e = self.id.infog[28] as i64;
        // Negative values count millions of entries.
        if e < 0 { -e * 1_000_000 } else { e }
    }

    /// True on the MUMPS host (rank 0), which holds the matrix and the
    /// right-hand side.
    fn is_host(&self) -> bool {
        super::mpi::rank() == 0
    }

    pub fn rank(&self) -> usize {
        super::mpi::rank()
    }

    pub fn ranks(&self) -> usize {
        super::mpi::ranks()
    }
}

impl Drop for Mumps {
    /// JOB = -2 frees MUMPS's memory (collective). Skipped once MPI is
    /// finalized, where it can no longer run.
    fn drop(&mut self) {
        if super::mpi::is_initialized() {
            let _ = self.run(-2, "termination");
        }
    }
}
