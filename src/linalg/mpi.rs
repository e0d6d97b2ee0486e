//! The few MPI calls the MUMPS backend needs, declared by hand against
//! OpenMPI (Debian's libopenmpi-dev; no bindgen, no libclang).
//!
//! Every rank of an `mpirun -n P anm ...` job runs the same deterministic
//! program: [`mpi_init`] once at start, the same MUMPS jobs on every rank
//! (MUMPS jobs are collective), [`broadcast`] of the results the host
//! computed, and only the root ([`is_root`]) writes files. A process started
//! without `mpirun` is an MPI singleton: one rank, rank 0.
//!
//! OpenMPI's `MPI_COMM_WORLD` and `MPI_DOUBLE` are the addresses of the
//! globals `ompi_mpi_comm_world` and `ompi_mpi_double` (its `mpi.h` defines
//! them so); `MPI_Comm` and `MPI_Datatype` are pointers. Another MPI
//! (MPICH's integer handles) would need other declarations.

use std::ffi::{c_int, c_void};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// `MPI_THREAD_SERIALIZED` in OpenMPI's mpi.h: any thread may call MPI, one
/// at a time. The wrapper holds [`MPI_LOCK`] around every MPI and MUMPS
/// call, so test harness threads are safe.
const MPI_THREAD_SERIALIZED: c_int = 2;
const MPI_SUCCESS: c_int = 0;

#[repr(C)]
struct OmpiPredefined {
    _opaque: [u8; 0],
}

#[link(name = "mpi")]
unsafe extern "C" {
    static ompi_mpi_comm_world: OmpiPredefined;
    static ompi_mpi_double: OmpiPredefined;
    fn MPI_Init_thread(
        argc: *mut c_int,
        argv: *mut *mut *mut i8,
        required: c_int,
        provided: *mut c_int,
    ) -> c_int;
    fn MPI_Initialized(flag: *mut c_int) -> c_int;
    fn MPI_Finalized(flag: *mut c_int) -> c_int;
    fn MPI_Finalize() -> c_int;
    fn MPI_Comm_rank(comm: *const c_void, rank: *mut c_int) -> c_int;
    fn MPI_Comm_size(comm: *const c_void, size: *mut c_int) -> c_int;
    fn MPI_Bcast(
        buffer: *mut c_void,
        count: c_int,
        datatype: *const c_void,
        root: c_int,
        comm: *const c_void,
    ) -> c_int;
}

/// Serializes MPI and MUMPS calls of this process (threads of one rank).
pub(crate) static MPI_LOCK: Mutex<()> = Mutex::new(());

static RANK: AtomicUsize = AtomicUsize::new(0);
static SIZE: AtomicUsize = AtomicUsize::new(1);

fn comm_world() -> *const c_void {
    (&raw const ompi_mpi_comm_world).cast()
}

fn lock() -> std::sync::MutexGuard<'static, ()> {
    MPI_LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn initialized_unlocked() -> bool {
    let mut init = 0;
    let mut fin = 0;
    // SAFETY: both calls may be made at any time, even before MPI_Init.
    unsafe {
        MPI_Initialized(&mut init);
        MPI_Finalized(&mut fin);
    }
    init != 0 && fin == 0
}

/// Initializes MPI once per process (idempotent; later calls only return).
/// Panics if MPI cannot start: nothing sensible can run after that.
pub fn mpi_init() {
    let _g = lock();
    let mut init = 0;
    // SAFETY: may be called before MPI_Init.
    unsafe { MPI_Initialized(&mut init) };
    if init == 0 {
        let mut provided = 0;
        // SAFETY: null argc/argv are allowed since MPI-2.
        let rc = unsafe {
            MPI_Init_thread(
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                MPI_THREAD_SERIALIZED,
                &mut provided,
            )
        };
        assert_eq!(rc, MPI_SUCCESS, "MPI_Init_thread failed (code {rc})");
    }
    let (mut rank, mut size) = (0, 1);
    // SAFETY: MPI is initialized; comm_world() is OpenMPI's MPI_COMM_WORLD.
    unsafe {
        MPI_Comm_rank(comm_world(), &mut rank);
        MPI_Comm_size(comm_world(), &mut size);
    }
    RANK.store(rank as usize, Ordering::Relaxed);
    SIZE.store(size as usize, Ordering::Relaxed);
}

/// Finalizes MPI if it is running (idempotent). Every [`super::mumps::Mumps`]
/// must be dropped before: their termination job communicates. A process
/// started by `mpirun` must call it before exiting, or mpirun reports the
/// job as failed.
pub fn mpi_finalize() {
    let _g = lock();
    if initialized_unlocked() {
        // SAFETY: MPI is initialized and not finalized.
        unsafe { MPI_Finalize() };
    }
}

/// True on rank 0, the rank that writes files; true too before
/// [`mpi_init`] (a process without MPI is its own root).
pub fn is_root() -> bool {
    rank() == 0
}

/// This process's rank in MPI_COMM_WORLD (0 before [`mpi_init`]).
pub fn rank() -> usize {
    RANK.load(Ordering::Relaxed)
}

/// The number of ranks in MPI_COMM_WORLD (1 before [`mpi_init`]).
pub fn ranks() -> usize {
    SIZE.load(Ordering::Relaxed)
}

/// True between [`mpi_init`] and [`mpi_finalize`].
pub fn is_initialized() -> bool {
    let _g = lock();
    initialized_unlocked()
}

/// Broadcasts `data` from rank 0 to every rank (collective: every rank
/// calls it with a slice of the same length). No-op with one rank.
pub fn broadcast(data: &mut [f64]) -> Result<(), String> {
    let _g = lock();
    broadcast_locked(data)
}

/// [`broadcast`] for a caller that already holds [`MPI_LOCK`].
pub(crate) fn broadcast_locked(data: &mut [f64]) -> Result<(), String> {
    if SIZE.load(Ordering::Relaxed) <= 1 {
        return Ok(());
    }
    for chunk in data.chunks_mut(c_int::MAX as usize) {
        // SAFETY: the buffer holds chunk.len() doubles; MPI is initialized
        // (SIZE > 1 is only set by mpi_init).
        let rc = unsafe {
            MPI_Bcast(
                chunk.as_mut_ptr().cast(),
                chunk.len() as c_int,
                (&raw const ompi_mpi_double).cast(),
                0,
                comm_world(),
            )
        };
        if rc != MPI_SUCCESS {
            return Err(format!(
                "MPI_Bcast of {} doubles failed (code {rc})",
                chunk.len()
            ));
        }
    }
    Ok(())
}
