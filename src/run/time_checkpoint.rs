//! checkpoint.json of a shell run in time, written when Ctrl-C or SIGTERM
//! stops it: the scene (file and text, so that a changed scene is
//! refused), the counters and wall time so far, and every output sample
//! (time, load, full dof vector, friction per node, and the DAE state that
//! a run restarts from). `anm run --resume DIR` continues from the last
//! sample's state ([`super::shell_time::resume`]).

use crate::error::{Error, Result};
use crate::scene::shell::ShellScene;
use crate::shell::time_path::{TimeRun, TimeSample, TimeStats};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The value of `run` that marks a checkpoint of a run in time.
const IN_TIME: &str = "shell_in_time";

#[derive(Serialize, Deserialize)]
pub struct TimeCheckpoint {
    run: String,
    scene_file: PathBuf,
    scene_text: String,
    /// ShellScene::mesh_digest at the start.
    #[serde(default)]
    mesh_digest: Option<String>,
    /// Seconds the run took up to its interruption.
    pub wall_s: f64,
    pub stats: TimeStats,
    /// The samples written so far.
    pub samples: Vec<TimeSample>,
}

impl TimeCheckpoint {
    /// The checkpoint of an interrupted run of `scene`.
    pub fn new(scene: &ShellScene, run: &TimeRun, wall_s: f64) -> Result<Self> {
        Ok(Self {
            run: IN_TIME.into(),
            scene_file: scene.file.clone(),
            scene_text: scene.text.clone(),
            mesh_digest: scene.mesh_digest(),
            wall_s,
            stats: run.stats.clone(),
            samples: run.samples.clone(),
        })
    }

    /// Writes `dir`/checkpoint.json (through a temporary file: a run
    /// killed while writing leaves no half checkpoint).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let file = dir.join("checkpoint.json");
        let tmp = dir.join("checkpoint.json.tmp");
        let text = serde_json::to_string(self).map_err(|e| Error::write(&file, e))?;
        std::fs::write(&tmp, text).map_err(|source| Error::Io {
            file: tmp.clone(),
            source,
        })?;
        std::fs::rename(&tmp, &file).map_err(|source| Error::Io { file, source })
    }

    /// Removes `dir`/checkpoint.json if there is one.
    pub fn remove(dir: &Path) -> Result<()> {
        let file = dir.join("checkpoint.json");
        match std::fs::remove_file(&file) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                Err(Error::Io { file, source: e })
            }
            _ => Ok(()),
        }
    }

    /// Whether `dir`/checkpoint.json is one of a run in time.
    pub fn is_in(dir: &Path) -> bool {
        let Ok(text) = std::fs::read_to_string(dir.join("checkpoint.json")) else {
            return false;
        };
        #[derive(Deserialize)]
        struct Kind {
            run: Option<String>,
        }
        serde_json::from_str::<Kind>(&text).is_ok_and(|k| k.run.as_deref() == Some(IN_TIME))
    }

    /// Reads `dir`/checkpoint.json.
    pub fn read(dir: &Path) -> Result<Self> {
        let file = dir.join("checkpoint.json");
        let text = std::fs::read_to_string(&file).map_err(|source| Error::Io {
            file: file.clone(),
            source,
        })?;
        let cp: Self = serde_json::from_str(&text).map_err(|e| Error::Parse {
            file: file.clone(),
            message: e.to_string(),
        })?;
        if cp.run != IN_TIME || cp.samples.is_empty() {
            return Err(Error::Resume {
                file,
                problem: "not the checkpoint of a shell run in time with its samples".into(),
            });
        }
        Ok(cp)
    }

    /// The scene, refused if its file changed since the run started.
    pub fn scene(&self) -> Result<ShellScene> {
        let now = crate::scene::read(&self.scene_file)?;
        if now != self.scene_text {
            return Err(Error::Invalid {
                file: self.scene_file.clone(),
                key: "scene".into(),
                problem: "changed since the interrupted run started: a resumed run must solve the same scene".into(),
            });
        }
        let scene = crate::scene::shell::load(&self.scene_file)?;
        scene.check_mesh_digest(&self.mesh_digest)?;
        Ok(scene)
    }
}
