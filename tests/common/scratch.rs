//! Temporary files of the tests: each test writes into its own directory,
//! removed when the test is done (none left in the system's temporary
//! folder, no name shared with another test run on the same machine).

use std::path::{Path, PathBuf};
use tempfile::TempDir;

/// A fresh directory `anm-<what>-XXXXXX` under the system's temporary
/// folder, removed with its content when dropped.
pub fn scratch(what: &str) -> TempDir {
    tempfile::Builder::new()
        .prefix(&format!("anm-{what}-"))
        .tempdir()
        .expect("a temporary directory")
}

/// A path inside a directory of its own, kept while this value lives: a
/// helper that writes a file for its caller returns one (it derefs to the
/// path, so `&file` goes where a `&Path` is expected).
pub struct ScratchFile {
    _dir: TempDir,
    path: PathBuf,
}

impl ScratchFile {
    /// `name` in a fresh directory `anm-<what>-XXXXXX` (not created).
    pub fn new(what: &str, name: &str) -> Self {
        let dir = scratch(what);
        let path = dir.path().join(name);
        Self { _dir: dir, path }
    }

    /// `name` in a fresh directory, written with `text`.
    pub fn with_text(what: &str, name: &str, text: &str) -> Self {
        let f = Self::new(what, name);
        std::fs::write(&f.path, text).expect("write a temporary file");
        f
    }
}

impl std::ops::Deref for ScratchFile {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchFile {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<std::ffi::OsStr> for ScratchFile {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.path.as_os_str()
    }
}
