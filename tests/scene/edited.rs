//! Shared by the shell-scene input tests: a scene file with text edits
//! applied, and the check that loading it fails naming the file and key.

use crate::scratch::ScratchFile;
use anm::scene::shell::load;
use std::path::Path;

/// `base` with `edits` (old, new) applied, written as `name` in a fresh
/// temporary directory `anm-<what>-XXXXXX` (removed with the value).
pub fn edited(base: &str, what: &str, name: &str, edits: &[(&str, &str)]) -> ScratchFile {
    let mut text = std::fs::read_to_string(base).unwrap();
    for (old, new) in edits {
        assert!(text.contains(old), "edit `{old}` does not apply");
        text = text.replacen(old, new, 1);
    }
    ScratchFile::with_text(what, name, &text)
}

/// Loading `path` fails as invalid input, naming the file, `key` and `part`.
#[track_caller]
pub fn expect_invalid(path: &Path, key: &str, part: &str) {
    let e = match load(path) {
        Ok(_) => panic!("{}: expected an error on {key}", path.display()),
        Err(e) => e,
    };
    let msg = e.to_string();
    println!("{msg}");
    assert_eq!(e.kind(), "invalid_input", "{msg}");
    for p in [&path.file_name().unwrap().to_string_lossy(), key, part] {
        assert!(msg.contains(p), "message `{msg}` lacks `{p}`");
    }
}
