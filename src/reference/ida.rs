//! A safe wrapper around SUNDIALS IDA (variable-order, variable-step BDF for
//! implicit DAEs F(t, y, y') = 0), through sundials-sys.
//!
//! One [`Ida`] owns the SUNDIALS context, the serial vectors, a dense matrix
//! with its dense direct linear solver, and the IDA memory; the problem is a
//! [`Dae`] with an analytic iteration matrix J = dF/dy + cj dF/dy'
//! (IDASetJacFn). Differential and algebraic components are marked with
//! IDASetId. Every negative return flag becomes an [`IdaError`] with the flag
//! name, the time reached and the last message SUNDIALS reported; nothing
//! here panics on a solver failure. The residual and Jacobian callbacks
//! return a recoverable failure (IDA cuts the step) when they produce a
//! non-finite value, and an unrecoverable one if the model panics.

use super::dae::{Dae, Dense};
use super::error::IdaError;
use std::ffi::{CStr, c_char, c_int, c_long, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use sundials_sys as sys;

/// How [`Ida::solve`] advances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Task {
    /// IDA_NORMAL: integrate past tout and interpolate y(tout).
    Normal,
    /// IDA_ONE_STEP: take one internal step.
    OneStep,
}

/// IDA's counters.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Counters {
    pub steps: i64,
    pub residual_evals: i64,
    pub jacobian_evals: i64,
    pub linear_setups: i64,
    pub error_test_fails: i64,
    pub nonlinear_iters: i64,
    pub nonlinear_conv_fails: i64,
    /// Residual evaluations made by the linear solver module (0 with an analytic Jacobian).
    pub ls_residual_evals: i64,
}

impl Counters {
    /// Under the names every time run shares (`summary.json` `counters`,
    /// [`super::counters`]).
    pub fn common(&self) -> super::counters::Counters {
        super::counters::Counters {
            steps: self.steps as u64,
            residual_evaluations: (self.residual_evals + self.ls_residual_evals) as u64,
            jacobian_evaluations: self.jacobian_evals as u64,
            factorizations: self.linear_setups as u64,
            linear_solves: self.nonlinear_iters as u64,
            nonlinear_iterations: self.nonlinear_iters as u64,
            error_test_failures: self.error_test_fails as u64,
            convergence_failures: self.nonlinear_conv_fails as u64,
        }
    }
}

/// Data the C callbacks reach through IDA's user_data pointer.
struct Callback<'a> {
    dae: &'a dyn Dae,
    n: usize,
}

/// The last message reported through SUNDIALS' error handler.
#[derive(Default)]
struct LastMessage(Option<String>);

/// An IDA integrator over a borrowed [`Dae`].
pub struct Ida<'a> {
    ctx: sys::SUNContext,
    mem: *mut c_void,
    y: sys::N_Vector,
    yp: sys::N_Vector,
    id: sys::N_Vector,
    work: sys::N_Vector,
    mat: sys::SUNMatrix,
    ls: sys::SUNLinearSolver,
    n: usize,
    t: f64,
    // Boxed so that their addresses, handed to C, stay fixed.
    callback: Box<Callback<'a>>,
    last_message: Box<LastMessage>,
}

/// The SUNDIALS version string (e.g. "7.1.1").
pub fn sundials_version() -> String {
    let mut buf = [0 as c_char; 64];
    // SAFETY: the buffer is writable for its length, which is passed.
    let rc = unsafe { sys::SUNDIALSGetVersion(buf.as_mut_ptr(), buf.len() as c_int) };
    if rc != 0 {
        return "unknown".into();
    }
    // SAFETY: SUNDIALSGetVersion wrote a NUL-terminated string within the buffer.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

/// The name of an IDA return flag.
pub fn flag_name(flag: c_int) -> String {
    // SAFETY: IDAGetReturnFlagName returns a malloc'ed NUL-terminated string
    // (or NULL), which we copy and free.
    unsafe {
        let p = sys::IDAGetReturnFlagName(flag as c_long);
        if p.is_null() {
            return format!("flag {flag}");
        }
        let s = CStr::from_ptr(p).to_string_lossy().into_owned();
        libc_free(p as *mut c_void);
        s
    }
}

unsafe extern "C" {
    #[link_name = "free"]
    fn libc_free(p: *mut c_void);
}

unsafe extern "C" fn error_handler(
    _line: c_int,
    func: *const c_char,
    _file: *const c_char,
    msg: *const c_char,
    _code: sys::SUNErrCode,
    data: *mut c_void,
    _ctx: sys::SUNContext,
) {
    let text = |p: *const c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: SUNDIALS passes NUL-terminated strings.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    // SAFETY: data is the Box<LastMessage> registered in Ida::new, alive while the context is.
    let last = unsafe { &mut *(data as *mut LastMessage) };
    last.0 = Some(format!("{}: {}", text(func), text(msg)));
}

/// The slice of a serial N_Vector.
///
/// # Safety
/// v must be a valid serial N_Vector of length n, not aliased mutably elsewhere.
unsafe fn slice<'v>(v: sys::N_Vector, n: usize) -> &'v [f64] {
    unsafe { std::slice::from_raw_parts(sys::N_VGetArrayPointer(v), n) }
}

/// # Safety
/// As [`slice`], and no other reference to v's data may be live.
unsafe fn slice_mut<'v>(v: sys::N_Vector, n: usize) -> &'v mut [f64] {
    unsafe { std::slice::from_raw_parts_mut(sys::N_VGetArrayPointer(v), n) }
}

unsafe extern "C" fn residual_cb(
    t: f64,
    y: sys::N_Vector,
    yp: sys::N_Vector,
    r: sys::N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: data is the Box<Callback> registered in Ida::new; the vectors are
    // IDA's serial vectors of length n, r distinct from y and yp.
    let cb = unsafe { &*(data as *const Callback) };
    let (y, yp, r) = unsafe { (slice(y, cb.n), slice(yp, cb.n), slice_mut(r, cb.n)) };
    match catch_unwind(AssertUnwindSafe(|| cb.dae.residual(t, y, yp, r))) {
        Ok(()) if r.iter().all(|v| v.is_finite()) => 0,
        Ok(()) => 1, // recoverable: IDA retries with a smaller step
        Err(_) => -1,
    }
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn jacobian_cb(
    t: f64,
    cj: f64,
    y: sys::N_Vector,
    yp: sys::N_Vector,
    _r: sys::N_Vector,
    jac: sys::SUNMatrix,
    data: *mut c_void,
    _t1: sys::N_Vector,
    _t2: sys::N_Vector,
    _t3: sys::N_Vector,
) -> c_int {
    // SAFETY: as in residual_cb; jac is the n x n dense matrix given to IDA.
    let cb = unsafe { &*(data as *const Callback) };
    let n = cb.n;
    let (y, yp) = unsafe { (slice(y, n), slice(yp, n)) };
    let data = unsafe { std::slice::from_raw_parts_mut(sys::SUNDenseMatrix_Data(jac), n * n) };
    data.fill(0.0);
    let mut dense = Dense { n, data };
    match catch_unwind(AssertUnwindSafe(|| {
        cb.dae.jacobian(t, cj, y, yp, &mut dense)
    })) {
        Ok(()) if dense.data.iter().all(|v| v.is_finite()) => 0,
        Ok(()) => 1,
        Err(_) => -1,
    }
}

impl<'a> Ida<'a> {
    /// Sets up IDA for `dae` at t0 with initial values (y0, yp0) (guesses for
    /// what [`Ida::calc_ic`] will correct), scalar tolerances, dense linear
    /// algebra with the analytic Jacobian, and the differential/algebraic ids.
    pub fn new(
        dae: &'a dyn Dae,
        t0: f64,
        y0: &[f64],
        yp0: &[f64],
        rtol: f64,
        atol: f64,
    ) -> Result<Self, IdaError> {
        let n = dae.dim();
        if y0.len() != n || yp0.len() != n {
            return Err(IdaError::Input(format!(
                "initial vectors have lengths {} and {}, the DAE has {n} unknowns",
                y0.len(),
                yp0.len()
            )));
        }
        if !(rtol > 0.0 && atol > 0.0 && rtol.is_finite() && atol.is_finite()) {
            return Err(IdaError::Input(format!(
                "tolerances must be positive and finite, got rtol = {rtol:e}, atol = {atol:e}"
            )));
        }
        let mut ctx: sys::SUNContext = std::ptr::null_mut();
        // SAFETY: creates a context into ctx; no MPI communicator.
        let rc = unsafe { sys::SUNContext_Create(sys::comm_no_mpi(), &mut ctx) };
        if rc != 0 || ctx.is_null() {
            return Err(IdaError::Null {
                function: "SUNContext_Create",
            });
        }
        let mut ida = Ida {
            ctx,
            mem: std::ptr::null_mut(),
            y: std::ptr::null_mut(),
            yp: std::ptr::null_mut(),
            id: std::ptr::null_mut(),
            work: std::ptr::null_mut(),
            mat: std::ptr::null_mut(),
            ls: std::ptr::null_mut(),
            n,
            t: t0,
            callback: Box::new(Callback { dae, n }),
            last_message: Box::default(),
        };
        // From here on, Drop frees whatever has been created.
        // SAFETY: ctx is valid; the handler's data is the boxed LastMessage
        // owned by `ida`, freed after the context (see Drop).
        let last = &mut *ida.last_message as *mut LastMessage as *mut c_void;
        unsafe {
            let rc = sys::SUNContext_ClearErrHandlers(ctx);
            ida.check_code("SUNContext_ClearErrHandlers", rc)?;
            let rc = sys::SUNContext_PushErrHandler(ctx, Some(error_handler), last);
            ida.check_code("SUNContext_PushErrHandler", rc)?;
        }
        let len = n as sys::sunindextype;
        // SAFETY: plain constructors on a valid context; results checked for NULL.
        unsafe {
            ida.y = non_null("N_VNew_Serial", sys::N_VNew_Serial(len, ctx))?;
            ida.yp = non_null("N_VNew_Serial", sys::N_VNew_Serial(len, ctx))?;
            ida.id = non_null("N_VNew_Serial", sys::N_VNew_Serial(len, ctx))?;
            ida.work = non_null("N_VNew_Serial", sys::N_VNew_Serial(len, ctx))?;
            slice_mut(ida.y, n).copy_from_slice(y0);
            slice_mut(ida.yp, n).copy_from_slice(yp0);
            for (dst, d) in slice_mut(ida.id, n).iter_mut().zip(dae.differential()) {
                *dst = if d { 1.0 } else { 0.0 };
            }
            ida.mem = non_null("IDACreate", sys::IDACreate(ctx))?;
            ida.check(
                "IDAInit",
                sys::IDAInit(ida.mem, Some(residual_cb), t0, ida.y, ida.yp),
            )?;
            ida.check("IDASStolerances", sys::IDASStolerances(ida.mem, rtol, atol))?;
            let user = &*ida.callback as *const Callback as *mut c_void;
            let rc = sys::IDASetUserData(ida.mem, user);
            ida.check("IDASetUserData", rc)?;
            ida.mat = non_null("SUNDenseMatrix", sys::SUNDenseMatrix(len, len, ctx))?;
            ida.ls = non_null("SUNLinSol_Dense", sys::SUNLinSol_Dense(ida.y, ida.mat, ctx))?;
            ida.check(
                "IDASetLinearSolver",
                sys::IDASetLinearSolver(ida.mem, ida.ls, ida.mat),
            )?;
            ida.check("IDASetJacFn", sys::IDASetJacFn(ida.mem, Some(jacobian_cb)))?;
            ida.check("IDASetId", sys::IDASetId(ida.mem, ida.id))?;
        }
        Ok(ida)
    }

    /// IDASetMaxNumSteps: the most internal steps per call to [`Ida::solve`].
    pub fn set_max_num_steps(&mut self, steps: i64) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetMaxNumSteps(self.mem, steps as c_long) };
        self.check("IDASetMaxNumSteps", rc)
    }

    /// IDASetMaxNonlinIters: Newton iterations per step attempt (IDA's default 4).
    pub fn set_max_nonlin_iters(&mut self, iters: i32) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetMaxNonlinIters(self.mem, iters as c_int) };
        self.check("IDASetMaxNonlinIters", rc)
    }

    /// IDASetMaxConvFails: Newton convergence failures allowed in one step
    /// (IDA's default 10).
    pub fn set_max_conv_fails(&mut self, fails: i32) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetMaxConvFails(self.mem, fails as c_int) };
        self.check("IDASetMaxConvFails", rc)
    }

    /// IDASetNonlinConvCoef: the Newton iteration stops when its estimated
    /// error is below this fraction of the error-test tolerance (IDA's
    /// default 0.33).
    pub fn set_nonlin_conv_coef(&mut self, coef: f64) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetNonlinConvCoef(self.mem, coef) };
        self.check("IDASetNonlinConvCoef", rc)
    }

    /// IDASetStopTime: IDA will not step past tstop.
    pub fn set_stop_time(&mut self, tstop: f64) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetStopTime(self.mem, tstop) };
        self.check("IDASetStopTime", rc)
    }

    /// IDACalcIC with IDA_YA_YDP_INIT: given the differential components of y,
    /// computes the algebraic components of y and the derivatives y' so that
    /// F(t0, y, y') = 0. `tout1` is the first output time (sets the scale).
    /// Returns the consistent (y0, y0').
    pub fn calc_ic(&mut self, tout1: f64) -> Result<(Vec<f64>, Vec<f64>), IdaError> {
        // SAFETY: mem is valid; y and yp are our vectors of length n.
        unsafe {
            let rc = sys::IDACalcIC(self.mem, sys::IDA_YA_YDP_INIT as c_int, tout1);
            self.check("IDACalcIC", rc)?;
            let rc = sys::IDAGetConsistentIC(self.mem, self.y, self.yp);
            self.check("IDAGetConsistentIC", rc)?;
        }
        let (y, yp) = (self.y().to_vec(), self.yp().to_vec());
        self.finite("consistent initial values", &y)?;
        self.finite("consistent initial derivatives", &yp)?;
        Ok((y, yp))
    }

    /// IDASolve toward tout; returns the time reached (tout in
    /// [`Task::Normal`] mode, the end of the internal step in
    /// [`Task::OneStep`] mode, or the stop time if one was set and reached).
    pub fn solve(&mut self, tout: f64, task: Task) -> Result<f64, IdaError> {
        let itask = match task {
            Task::Normal => sys::IDA_NORMAL,
            Task::OneStep => sys::IDA_ONE_STEP,
        } as c_int;
        let mut tret = self.t;
        // SAFETY: mem, y, yp are valid; tret is a local.
        let rc = unsafe { sys::IDASolve(self.mem, tout, &mut tret, self.y, self.yp, itask) };
        if rc >= 0 {
            self.t = tret;
        } else {
            // On failure IDA leaves tret at the last time reached.
            self.t = self.current_time().unwrap_or(tret);
        }
        self.check("IDASolve", rc)?;
        let y = self.y();
        if let Some(i) = y.iter().position(|v| !v.is_finite()) {
            return Err(IdaError::NonFinite {
                what: format!("y[{i}]"),
                t: tret,
            });
        }
        Ok(tret)
    }

    /// y at the time last returned by [`Ida::solve`].
    pub fn y(&self) -> &[f64] {
        // SAFETY: y is our vector of length n; IDA writes it only inside solve.
        unsafe { slice(self.y, self.n) }
    }

    /// y' at the time last returned by [`Ida::solve`].
    pub fn yp(&self) -> &[f64] {
        // SAFETY: as for y.
        unsafe { slice(self.yp, self.n) }
    }

    /// The time last returned by [`Ida::solve`].
    pub fn t(&self) -> f64 {
        self.t
    }

    /// IDAGetDky: the k-th derivative of the interpolating polynomial at t,
    /// which must lie within the last internal step.
    pub fn dky(&mut self, t: f64, k: i32) -> Result<Vec<f64>, IdaError> {
        // SAFETY: mem and the work vector are valid.
        let rc = unsafe { sys::IDAGetDky(self.mem, t, k as c_int, self.work) };
        let prev = self.t;
        self.t = t;
        let res = self.check("IDAGetDky", rc);
        self.t = prev;
        res?;
        // SAFETY: work is our vector of length n.
        let v = unsafe { slice(self.work, self.n) }.to_vec();
        self.finite("IDAGetDky output", &v)?;
        Ok(v)
    }

    /// IDAGetLastStep: the size of the last internal step taken.
    pub fn last_step(&self) -> f64 {
        self.get_real(sys::IDAGetLastStep)
    }

    /// IDAGetCurrentStep: the step size IDA will try next.
    pub fn current_step(&self) -> f64 {
        self.get_real(sys::IDAGetCurrentStep)
    }

    /// IDAGetLastOrder: the BDF order of the last internal step.
    pub fn last_order(&self) -> i32 {
        let mut k: c_int = 0;
        // SAFETY: mem is valid; k is a local.
        unsafe { sys::IDAGetLastOrder(self.mem, &mut k) };
        k
    }

    /// IDAGetCurrentTime: the internal time reached (the end of the last step).
    pub fn current_time(&self) -> Option<f64> {
        let mut t = f64::NAN;
        // SAFETY: mem is valid; t is a local.
        let rc = unsafe { sys::IDAGetCurrentTime(self.mem, &mut t) };
        (rc == 0).then_some(t)
    }

    /// IDASVtolerances: rtol and one atol per unknown.
    pub fn set_vector_tolerances(&mut self, rtol: f64, atol: &[f64]) -> Result<(), IdaError> {
        if atol.len() != self.n {
            return Err(IdaError::Input(format!(
                "{} absolute tolerances for {} unknowns",
                atol.len(),
                self.n
            )));
        }
        // SAFETY: work is our vector of length n; IDASVtolerances copies it.
        unsafe {
            slice_mut(self.work, self.n).copy_from_slice(atol);
            let rc = sys::IDASVtolerances(self.mem, rtol, self.work);
            self.check("IDASVtolerances", rc)
        }
    }

    /// IDASetSuppressAlg: exclude the algebraic components (id = 0) from the
    /// local error test (see [`super::ida_run`] for why the reference does).
    pub fn set_suppress_alg(&mut self, suppress: bool) -> Result<(), IdaError> {
        // SAFETY: mem is valid.
        let rc = unsafe { sys::IDASetSuppressAlg(self.mem, suppress as c_int) };
        self.check("IDASetSuppressAlg", rc)
    }

    /// IDAGetEstLocalErrors times IDAGetErrWeights: each component's share of
    /// the weighted local error estimate of the last step (> 1 fails the test
    /// in the weighted RMS norm).
    pub fn weighted_local_errors(&mut self) -> Result<Vec<f64>, IdaError> {
        // SAFETY: mem and the work vectors are valid; each call writes its vector.
        let w = unsafe {
            let rc = sys::IDAGetErrWeights(self.mem, self.work);
            self.check("IDAGetErrWeights", rc)?;
            slice(self.work, self.n).to_vec()
        };
        let e = unsafe {
            let rc = sys::IDAGetEstLocalErrors(self.mem, self.work);
            self.check("IDAGetEstLocalErrors", rc)?;
            slice(self.work, self.n).to_vec()
        };
        Ok(w.iter().zip(&e).map(|(w, e)| w * e).collect())
    }

    /// The counters so far.
    pub fn counters(&self) -> Counters {
        let get = |f: unsafe extern "C" fn(*mut c_void, *mut c_long) -> c_int| {
            let mut v: c_long = 0;
            // SAFETY: mem is valid; v is a local.
            unsafe { f(self.mem, &mut v) };
            v as i64
        };
        Counters {
            steps: get(sys::IDAGetNumSteps),
            residual_evals: get(sys::IDAGetNumResEvals),
            jacobian_evals: get(sys::IDAGetNumJacEvals),
            linear_setups: get(sys::IDAGetNumLinSolvSetups),
            error_test_fails: get(sys::IDAGetNumErrTestFails),
            nonlinear_iters: get(sys::IDAGetNumNonlinSolvIters),
            nonlinear_conv_fails: get(sys::IDAGetNumNonlinSolvConvFails),
            ls_residual_evals: get(sys::IDAGetNumLinResEvals),
        }
    }

    fn get_real(&self, f: unsafe extern "C" fn(*mut c_void, *mut f64) -> c_int) -> f64 {
        let mut v = f64::NAN;
        // SAFETY: mem is valid; v is a local.
        unsafe { f(self.mem, &mut v) };
        v
    }

    fn check(&mut self, function: &'static str, rc: c_int) -> Result<(), IdaError> {
        if rc >= 0 {
            return Ok(());
        }
        Err(IdaError::Flag {
            function,
            flag: rc,
            name: flag_name(rc),
            t: self.t,
            message: self.last_message.0.take(),
        })
    }

    /// For SUNErrCode-returning calls (0 is success).
    fn check_code(&mut self, function: &'static str, rc: sys::SUNErrCode) -> Result<(), IdaError> {
        if rc == 0 {
            return Ok(());
        }
        Err(IdaError::Flag {
            function,
            flag: rc,
            name: format!("SUNErrCode {rc}"),
            t: self.t,
            message: self.last_message.0.take(),
        })
    }

    fn finite(&self, what: &str, v: &[f64]) -> Result<(), IdaError> {
        match v.iter().position(|x| !x.is_finite()) {
            None => Ok(()),
            Some(i) => Err(IdaError::NonFinite {
                what: format!("{what}[{i}]"),
                t: self.t,
            }),
        }
    }
}

fn non_null<T>(function: &'static str, p: *mut T) -> Result<*mut T, IdaError> {
    if p.is_null() {
        Err(IdaError::Null { function })
    } else {
        Ok(p)
    }
}

impl Drop for Ida<'_> {
    fn drop(&mut self) {
        // SAFETY: each pointer is either NULL or owned by us; freed once, IDA
        // memory before the linear solver and matrix it references, the
        // context last.
        unsafe {
            if !self.mem.is_null() {
                sys::IDAFree(&mut self.mem);
            }
            if !self.ls.is_null() {
                sys::SUNLinSolFree(self.ls);
            }
            if !self.mat.is_null() {
                sys::SUNMatDestroy(self.mat);
            }
            for v in [self.y, self.yp, self.id, self.work] {
                if !v.is_null() {
                    sys::N_VDestroy(v);
                }
            }
            if !self.ctx.is_null() {
                sys::SUNContext_Free(&mut self.ctx);
            }
        }
    }
}
