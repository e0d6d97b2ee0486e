//! TOML scene files (serde, `deny_unknown_fields`), validated into models.
//!
//! Every scene starts with `[scene] kind = "..."`; the kind selects the typed
//! schema. Errors name the file, the key (`table.key`) and the problem.

mod exact;
pub mod friction;
pub mod shell;

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The kinds of scene `anm` knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Friction1d,
    FrictionPlane,
    FrictionRoller,
    Shell,
}

impl Kind {
    pub const ALL: [(&'static str, Kind); 4] = [
        ("friction-1d", Kind::Friction1d),
        ("friction-plane", Kind::FrictionPlane),
        ("friction-roller", Kind::FrictionRoller),
        ("shell", Kind::Shell),
    ];

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, k)| *k == self)
            .map(|(n, _)| *n)
            .unwrap_or("?")
    }
}

/// Reads a scene file's text.
pub fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|source| Error::Parse {
        file: path.to_path_buf(),
        message: format!("cannot read: {source}"),
    })
}

/// The `[scene] kind` of a scene file.
pub fn kind(path: &Path, text: &str) -> Result<Kind> {
    let value: toml::Table = toml::from_str(text).map_err(|e| parse_error(path, text, e))?;
    let invalid = |problem: String| Error::Invalid {
        file: path.to_path_buf(),
        key: "scene.kind".into(),
        problem,
    };
    let kind = value
        .get("scene")
        .and_then(|s| s.get("kind"))
        .ok_or_else(|| invalid("missing: every scene needs `[scene] kind = \"...\"`".into()))?;
    let name = kind
        .as_str()
        .ok_or_else(|| invalid(format!("expected a string, found {kind}")))?;
    Kind::ALL
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, k)| *k)
        .ok_or_else(|| {
            let known: Vec<&str> = Kind::ALL.iter().map(|(n, _)| *n).collect();
            let hint = if name == "plate-cylinder" {
                "; plate-cylinder is now a `shell` scene with [[fix]] and [[probe]] tables: see scenes/plate-cylinder.toml and docs/scenes.md"
            } else {
                ""
            };
            invalid(format!(
                "unknown kind `{name}` (known: {}){hint}",
                known.join(", ")
            ))
        })
}

/// Deserializes `text` into `T`, turning serde/TOML errors into an error that
/// names the file, the line and the `table.key` involved.
pub fn parse<T: serde::de::DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| parse_error(path, text, e))
}

fn parse_error(path: &Path, text: &str, e: toml::de::Error) -> Error {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return Error::Parse {
            file: path.to_path_buf(),
            message,
        };
    };
    // A table missing from the file: the error spans the whole document,
    // and its first line's table was named (review 17: "line 1: key
    // `scene`: missing field `material`").
    if span.start == 0
        && (span.end == 0 || span.end >= text.trim_end().len())
        && let Some(field) = message
            .strip_prefix("missing field `")
            .and_then(|m| m.split('`').next())
    {
        return Error::Parse {
            file: path.to_path_buf(),
            message: format!("the table [{field}] is missing (docs/scenes.md lists what it holds)"),
        };
    }
    let line_no = text[..span.start.min(text.len())].matches('\n').count() + 1;
    let key = key_at(text, span.start);
    // The parser reads a value starting with n or i as a try at nan or inf
    // (review 22: `np.float64(0.5)` gave "invalid float, expected `nan`").
    let message = if message.contains("expected `nan`") || message.contains("expected `inf`") {
        let token: String = text[span.start.min(text.len())..]
            .chars()
            .take_while(|c| !matches!(c, ',' | ']' | '}' | '\n' | '#'))
            .collect();
        format!(
            "`{}` is not a number (numbers are written 0.5, 1e-3, -2.0)",
            token.trim()
        )
    } else {
        message
    };
    Error::Parse {
        file: path.to_path_buf(),
        message: match key {
            Some(k) => format!("line {line_no}: key `{k}`: {message}"),
            None => format!("line {line_no}: {message}"),
        },
    }
}

/// The dotted key (`table.key`) whose line contains byte offset `at`: the
/// n-th table of an array of tables as `name[n]` (0-based, as the
/// validation errors name it), and inside an inline table the key that
/// holds `at` (`obstacle[0].motion.omega`).
fn key_at(text: &str, at: usize) -> Option<String> {
    let mut table = String::new();
    let mut arrays: std::collections::HashMap<String, usize> = Default::default();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim();
        if trimmed.starts_with("[[") {
            let name = trimmed.trim_matches(|c| c == '[' || c == ']').trim();
            let n = arrays.entry(name.to_string()).or_insert(0);
            table = format!("{name}[{n}]");
            *n += 1;
        } else if trimmed.starts_with('[') {
            table = trimmed
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_string();
        }
        if at < offset + line.len() {
            if trimmed.starts_with('[') {
                return Some(table);
            }
            if trimmed.starts_with('#') {
                return None;
            }
            let path = inline_key_path(line, (at - offset).min(line.len()));
            if path.is_empty() {
                return None;
            }
            return Some(if table.is_empty() {
                path
            } else {
                format!("{table}.{path}")
            });
        }
        offset += line.len();
    }
    None
}

/// The keys, outermost first and joined by dots, that byte `at` of `line`
/// (a line of TOML) lies under: in `motion = { omega = "fast" }` the value
/// is under `motion.omega`, and so is the key `omega` itself; in
/// `x = [1.0, "y"]` the "y" is under `x`.
fn inline_key_path(line: &str, at: usize) -> String {
    let prefix = &line[..at];
    let mut keys: Vec<String> = vec![];
    let mut current: Option<String> = None;
    let mut start = 0;
    let mut quote: Option<char> = None;
    // Inside an array the position is under the array's key.
    let mut in_array = 0usize;
    for (i, c) in prefix.char_indices() {
        if let Some(q) = quote {
            if c == q {
                quote = None;
            }
            continue;
        }
        match c {
            '"' | '\'' => quote = Some(c),
            '[' => in_array += 1,
            ']' => in_array = in_array.saturating_sub(1),
            _ if in_array > 0 => {}
            '=' if current.is_none() => {
                current = Some(prefix[start..i].trim().to_string());
            }
            '{' => {
                keys.extend(current.take());
                start = i + 1;
            }
            '}' => {
                keys.pop();
                current = None;
                start = i + 1;
            }
            ',' => {
                current = None;
                start = i + 1;
            }
            _ => {}
        }
    }
    // At a key (not yet followed by `=`): that key.
    let at_key = || {
        line[start..]
            .split('=')
            .next()
            .map(|k| k.trim().to_string())
    };
    keys.extend(current.or_else(at_key));
    keys.retain(|k| !k.is_empty());
    keys.join(".")
}

/// Resolves a path written in a scene relative to the scene file's folder.
pub fn relative_to(scene: &Path, file: &str) -> PathBuf {
    let p = Path::new(file);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scene.parent().unwrap_or(Path::new(".")).join(p)
    }
}

/// Validation helper: a failed check becomes `Error::Invalid` naming the key.
pub struct Checker<'a> {
    pub file: &'a Path,
}

impl Checker<'_> {
    pub fn fail(&self, key: &str, problem: impl Into<String>) -> Error {
        Error::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            problem: problem.into(),
        }
    }

    pub fn finite(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be a finite number, got {v}")))
        }
    }

    pub fn positive(&self, key: &str, v: f64) -> Result<f64> {
        self.finite(key, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be > 0, got {v}")))
        }
    }

    pub fn non_negative(&self, key: &str, v: f64) -> Result<f64> {
        self.finite(key, v)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be >= 0, got {v}")))
        }
    }

    pub fn within(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
        self.finite(key, v)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must lie in [{lo}, {hi}], got {v}")))
        }
    }

    /// The friction law's speeds must stay representable where the law
    /// squares and raises them (contact::friction): (ω Vc)² and Vc^q in
    /// f64, else its forces and derivatives are 0 · ∞ at the first step.
    pub fn slip_speeds(&self, vc: f64, omega: f64, q: f64) -> Result<()> {
        let w2 = (omega * vc).powi(2);
        if !w2.is_finite() || (omega > 0.0 && w2 == 0.0) {
            // The key of the factor farther from 1 (review 12: omega =
            // 1e-300 was blamed on friction.Vc).
            let key = if omega.log10().abs() > vc.log10().abs() {
                "friction.omega"
            } else {
                "friction.Vc"
            };
            return Err(self.fail(
                key,
                format!(
                    "omega Vc = {omega:e} × {vc:e} = {:e}: its square is out of the range of a double (about 1e-150 < omega Vc < 1e150 in the scene's length unit per second)",
                    omega * vc
                ),
            ));
        }
        let vq = vc.powf(q);
        if !vq.is_finite() || vq == 0.0 {
            return Err(self.fail(
                "friction.Vc",
                format!("Vc^q = {vc:e}^{q} is out of the range of a double"),
            ));
        }
        Ok(())
    }

    /// A key that this kind of scene does not use must be absent.
    pub fn unused<T>(&self, key: &str, v: &Option<T>, kind: Kind) -> Result<()> {
        match v {
            Some(_) => Err(self.fail(
                key,
                format!("not used by a `{}` scene; remove it", kind.name()),
            )),
            None => Ok(()),
        }
    }

    pub fn required<T: Copy>(&self, key: &str, v: Option<T>, kind: Kind) -> Result<T> {
        v.ok_or_else(|| {
            self.fail(
                key,
                format!("missing: required by a `{}` scene", kind.name()),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{Path, key_at, parse};

    /// The key of the byte where `needle` starts in `text`.
    fn key_of(text: &str, needle: &str) -> Option<String> {
        key_at(text, text.find(needle).expect("needle"))
    }

    #[test]
    fn parse_errors_name_the_key_inside_inline_tables_and_arrays_of_tables() {
        let text = "[scene]\nkind = \"shell\"\n\n[[obstacle]]\nname = \"a\"\n\n[[obstacle]]\nname = \"b\"\nmotion = { type = \"rotate\", omega = \"fast\" }\nx = [1.0, \"y\"]\n\n[solver]\n# eps = 1\norder = \"ten\"\n";
        assert_eq!(
            key_of(text, "\"fast\"").as_deref(),
            Some("obstacle[1].motion.omega")
        );
        assert_eq!(
            key_of(text, "\"rotate\"").as_deref(),
            Some("obstacle[1].motion.type")
        );
        assert_eq!(key_of(text, "\"y\"").as_deref(), Some("obstacle[1].x"));
        assert_eq!(key_of(text, "\"b\"").as_deref(), Some("obstacle[1].name"));
        assert_eq!(key_of(text, "\"a\"").as_deref(), Some("obstacle[0].name"));
        assert_eq!(key_of(text, "\"ten\"").as_deref(), Some("solver.order"));
        assert_eq!(key_of(text, "\"shell\"").as_deref(), Some("scene.kind"));
        assert_eq!(key_of(text, "# eps"), None);
        // Unknown-field errors point at the key itself.
        assert_eq!(
            key_of(text, "omega =").as_deref(),
            Some("obstacle[1].motion.omega")
        );
        assert_eq!(key_of(text, "order =").as_deref(), Some("solver.order"));
    }

    /// Review 17: a table missing from the file was reported at line 1
    /// under the first table's name.
    #[test]
    fn a_missing_table_is_named_as_a_table() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct Scene {
            scene: toml::Value,
            material: toml::Value,
        }
        let e = parse::<Scene>(Path::new("s.toml"), "[scene]\nkind = \"shell\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("the table [material] is missing"), "{e}");
        assert!(!e.contains("key `scene`"), "{e}");
    }
}
