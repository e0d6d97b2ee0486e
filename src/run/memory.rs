//! Memory a shell run will need, against what the machine gives it: a mesh
//! too large for the machine is refused before anything is built, with the
//! figures, instead of aborting mid-run on a failed allocation.
//!
//! The per-unknown figures are measured peaks (VmHWM of `anm run`, README
//! "Step cost and scaling" and the closing notes of issue 17):
//! - continuation in λ (LDLᵀ): 7.0–7.3 kB per unknown from 25,200 to
//!   1,005,480 unknowns (the element series, the tangent and its factor);
//!   on the 200×20 strip (25,326 unknowns) 6.8 kB with the ANM, 7.9 kB
//!   with Newton, 5.0 kB for one linear solve (`solver.method`);
//! - in time with friction (LU): 18, 32 and 39 kB per unknown at 2,819,
//!   8,459 and 15,979 unknowns (`scenes/strip-conveying.toml`, 2, 8 and 16
//!   elements across), rising with the factor's fill.
//!
//! A run is refused only when a lower bound (4 and 15 kB per unknown,
//! below every measured peak) exceeds the memory available; it is warned
//! about when the typical figure does.

use crate::error::{Error, Result};
use crate::scene::shell::ShellScene;

/// Lower bounds and typical peaks per unknown, bytes.
const LOW_STATIC: f64 = 4e3;
const TYPICAL_STATIC: f64 = 7.3e3;
const LOW_FRICTION: f64 = 15e3;
const TYPICAL_FRICTION: f64 = 40e3;

/// What a run of the scene is expected to need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// Unknowns before the fixes (6 per node).
    pub unknowns: usize,
    /// Bytes no run of this kind has needed less of.
    pub low: f64,
    /// Bytes runs of this kind have typically needed.
    pub typical: f64,
}

/// The estimate for `scene` (its mesh and whether it runs in time).
pub fn estimate(scene: &ShellScene) -> MemoryEstimate {
    let unknowns = 6 * scene.mesh.nodes.len();
    let (low, typical) = if scene.friction.is_some() {
        (LOW_FRICTION, TYPICAL_FRICTION)
    } else {
        (LOW_STATIC, TYPICAL_STATIC)
    };
    MemoryEstimate {
        unknowns,
        low: low * unknowns as f64,
        typical: typical * unknowns as f64,
    }
}

/// Memory this process may use, bytes, with where the limit comes from:
/// the smaller of the machine's available memory (MemAvailable of
/// /proc/meminfo) and the address-space limit (`ulimit -v`). None where
/// neither is known.
pub fn available() -> Option<(f64, &'static str)> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        let line = t.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some((kb * 1024.0, "available memory (MemAvailable)"))
    });
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given and nothing else.
    let ulimit = (unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } == 0
        && limit.rlim_cur != libc::RLIM_INFINITY)
        .then_some((limit.rlim_cur as f64, "address-space limit (ulimit -v)"));
    match (meminfo, ulimit) {
        (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
        (a, b) => a.or(b),
    }
}

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// Refuses a scene whose lower bound exceeds `available` (the error names
/// the scene, its size, the figures and the way around); a warning when
/// the typical figure does.
pub fn check(scene: &ShellScene, available: Option<(f64, &str)>) -> Result<Option<String>> {
    let Some((bytes, source)) = available else {
        return Ok(None);
    };
    let e = estimate(scene);
    let kind = if scene.friction.is_some() {
        "in time with friction"
    } else {
        "in lambda"
    };
    if e.low > bytes {
        return Err(Error::Invalid {
            file: scene.file.clone(),
            key: "mesh".into(),
            problem: format!(
                "{} nodes give {} unknowns: a run {kind} needs at least {:.1} GiB ({:.0} kB per unknown; typically {:.1} GiB), more than the {:.1} GiB of {source}: coarsen the mesh or use a larger machine (--ignore-memory tries anyway)",
                scene.mesh.nodes.len(),
                e.unknowns,
                e.low / GIB,
                e.low / e.unknowns as f64 / 1e3,
                e.typical / GIB,
                bytes / GIB
            ),
        });
    }
    Ok((e.typical > bytes).then(|| {
        format!(
            "{} unknowns: runs {kind} of this size have typically needed {:.1} GiB, more than the {:.1} GiB of {source}",
            e.unknowns,
            e.typical / GIB,
            bytes / GIB
        )
    }))
}

/// One line for `anm check`: the expected peak against what is available.
pub fn summary(scene: &ShellScene, available: Option<(f64, &str)>) -> String {
    let e = estimate(scene);
    let have = available.map_or(String::new(), |(bytes, source)| {
        format!("; {:.1} GiB of {source}", bytes / GIB)
    });
    format!(
        "memory: {} unknowns (6 per node, before the fixes), a run typically needs {:.2} GiB (at least {:.2}){have}",
        e.unknowns,
        e.typical / GIB,
        e.low / GIB
    )
}
