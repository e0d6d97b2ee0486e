//! One run per output directory.
//!
//! Two runs started into one directory each removed the other's files and
//! wrote their own: the survivor exited 0 with a summary.json of its scene
//! beside a history.csv and steps.csv of the other (review 23). A run
//! therefore holds `anm.lock` (its process id) while it writes; a second
//! run is refused while that process lives. A lock left by a killed run
//! (SIGKILL, a node lost) names a process that is gone, and is taken over.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const NAME: &str = "anm.lock";

/// The lock this process holds, for an exit that skips destructors (a
/// second interrupt: run::interrupt).
static HELD: std::sync::Mutex<Option<PathBuf>> = std::sync::Mutex::new(None);

/// Removes the lock this process holds (before `std::process::exit`).
pub fn remove_held() {
    if let Ok(mut held) = HELD.lock()
        && let Some(file) = held.take()
    {
        let _ = std::fs::remove_file(file);
    }
}

/// The lock of an output directory, released (its file removed) on drop.
#[derive(Debug)]
pub struct OutputLock {
    file: PathBuf,
    /// The folder, where the lock created it: removed again if the run
    /// wrote nothing (a scene refused while the model is built).
    created: Option<PathBuf>,
}

impl OutputLock {
    /// Creates `dir` if needed and takes its lock; refused while another
    /// living process holds it.
    pub fn take(dir: &Path) -> Result<Self> {
        super::folder_or_absent(dir)?;
        let created = (!dir.exists()).then(|| dir.to_path_buf());
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            file: dir.to_path_buf(),
            source,
        })?;
        let file = dir.join(NAME);
        // Two tries: the second after removing a lock whose process died.
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&file)
            {
                Ok(mut f) => {
                    writeln!(f, "{}", std::process::id()).map_err(|source| Error::Io {
                        file: file.clone(),
                        source,
                    })?;
                    if let Ok(mut held) = HELD.lock() {
                        *held = Some(file.clone());
                    }
                    return Ok(Self { file, created });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&file)
                        .ok()
                        .and_then(|t| t.trim().parse::<u32>().ok());
                    match holder {
                        Some(pid) if alive(pid) => {
                            return Err(Error::write(
                                dir,
                                format!(
                                    "another run (process {pid}) writes into this folder: two runs in one folder mix their files; give this one another -o (or remove {} if no run is going)",
                                    file.display()
                                ),
                            ));
                        }
                        _ => {
                            eprintln!(
                                "note: {} was left by a run that is gone (process {}); taking it over",
                                file.display(),
                                holder.map_or("unknown".into(), |p| p.to_string())
                            );
                            let _ = std::fs::remove_file(&file);
                        }
                    }
                }
                Err(source) => return Err(Error::Io { file, source }),
            }
        }
        Err(Error::write(
            dir,
            format!(
                "could not take {} (another run took it first)",
                file.display()
            ),
        ))
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        if let Ok(mut held) = HELD.lock()
            && held.as_ref() == Some(&self.file)
        {
            *held = None;
        }
        let _ = std::fs::remove_file(&self.file);
        if let Some(dir) = &self.created {
            // Only an empty folder goes.
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// Whether process `pid` lives (Linux /proc; elsewhere assumed alive, so
/// that a lock is never taken from a running process).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    if !proc.is_dir() {
        return true;
    }
    proc.join(pid.to_string()).exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_and_a_dead_holder_taken_over() {
        let dir = std::env::temp_dir().join(format!("anm-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let first = OutputLock::take(&dir).expect("first lock");
        let err = OutputLock::take(&dir).expect_err("a second run is refused");
        assert!(err.to_string().contains("another run"), "{err}");
        drop(first);
        assert!(
            !dir.exists(),
            "released on drop, with the empty folder it made"
        );
        std::fs::create_dir_all(&dir).unwrap();
        // A lock naming a process that does not exist (pid_max is at most
        // 2^22 on Linux) is taken over.
        std::fs::write(dir.join(NAME), "4194305\n").unwrap();
        let again = OutputLock::take(&dir).expect("a dead holder's lock is taken over");
        drop(again);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
