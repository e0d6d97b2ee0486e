//! Shared by the shell-scene input tests: a scene file with text edits
//! applied, and the check that loading it fails naming the file and key.

use anm::scene::shell::load;
use std::path::{Path, PathBuf};

/// `base` with `edits` (old, new) applied, written as `dir/name` under the
/// temporary directory.
pub fn edited(base: &str, dir: &str, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(base).unwrap();
    for (old, new) in edits {
        assert!(text.contains(old), "edit `{old}` does not apply");
        text = text.replacen(old, new, 1);
    }
    let d = std::env::temp_dir().join(dir);
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
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
