//! The results folder's record, `WORK/<scene>/.ribbar-stages.json`: which
//! key each stage last published there, what each published file was when
//! ribbar wrote it, and how the last run ended. It is also ribbar's mark on
//! the folder: `clean` removes only what it lists, and a folder without it
//! is not ribbar's.

use super::base::{io_err, write_atomic, StageKey, Store, StoreError, RECORD_FILE};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::fs;
use std::time::{SystemTime, UNIX_EPOCH};

/// Version of the record's layout (format 1: a map of stage keys only).
const RECORD_FORMAT: u32 = 2;

/// What a results folder holds, by stage, and how its last run ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneRecord {
    pub format: u32,
    pub stages: BTreeMap<String, PublishedStage>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<RunRecord>,
}

impl Default for SceneRecord {
    fn default() -> Self {
        SceneRecord {
            format: RECORD_FORMAT,
            stages: BTreeMap::new(),
            run: None,
        }
    }
}

/// One stage's published files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PublishedStage {
    #[serde(flatten)]
    pub key: StageKey,
    /// Each published file, by its path in the results folder, as ribbar
    /// wrote it; `None` for a folder published by a ribbar that kept no
    /// such record (its files are then those of the stage's published
    /// names).
    #[serde(default)]
    pub files: Option<BTreeMap<String, PublishedFile>>,
}

/// A published file as ribbar wrote it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PublishedFile {
    pub size: u64,
    pub sha256: String,
    pub mtime_ns: u64,
}

/// The last run of `ribbar` on the folder's scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// The subcommand (`run`, `mesh`, ...).
    pub command: String,
    /// When it started and finished, s since the Unix epoch.
    pub started_unix_s: u64,
    #[serde(default)]
    pub finished_unix_s: Option<u64>,
    pub outcome: RunOutcome,
    /// Each stage's key under the run's spec: `clean` finds the scene's
    /// in-progress folders (a solve's checkpoint) by them.
    pub keys: BTreeMap<String, String>,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum RunOutcome {
    /// Not ended yet, or the process was killed.
    Running,
    /// Every stage asked for is done.
    Complete,
    /// Every stage ran, and the solve stopped before the end of the loading.
    Stopped { reason: String },
    /// A stage failed; the folder holds only the stages before it.
    Failed { stage: String, error: String },
}

/// Seconds since the Unix epoch, now.
pub fn unix_now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

/// `YYYY-MM-DD HH:MM:SS UTC` of a Unix time (civil date from days,
/// proleptic Gregorian calendar).
pub fn utc_text(unix_s: u64) -> String {
    let days = (unix_s / 86_400) as i64;
    let secs = unix_s % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

/// The name a file kept as changed had (`curve.edited-2.csv` →
/// `curve.csv`, `fields.edited` → `fields`).
pub(super) fn unedited(name: &str) -> String {
    match name.find(".edited") {
        None => name.to_string(),
        Some(at) => {
            let rest = &name[at + ".edited".len()..];
            let rest = rest.trim_start_matches(|c: char| c == '-' || c.is_ascii_digit());
            format!("{}{rest}", &name[..at])
        }
    }
}

/// A record as read: this format, or format 1's map of stage keys.
fn parse(bytes: &[u8]) -> Result<SceneRecord, String> {
    let value: Value = serde_json::from_slice(bytes).map_err(|e| e.to_string())?;
    if value.get("format").is_some() {
        return serde_json::from_value(value).map_err(|e| e.to_string());
    }
    let legacy: BTreeMap<String, StageKey> =
        serde_json::from_value(value).map_err(|e| e.to_string())?;
    Ok(SceneRecord {
        stages: legacy
            .into_iter()
            .map(|(stage, key)| (stage, PublishedStage { key, files: None }))
            .collect(),
        ..SceneRecord::default()
    })
}

impl Store {
    /// The results folder's record; `None` when the folder has none.
    pub fn read_record(&self, scene: &str) -> Result<Option<SceneRecord>, StoreError> {
        let path = self.scene_dir(scene).join(RECORD_FILE);
        match geom::fsutil::read_capped(&path, geom::fsutil::MAX_RECORD_BYTES) {
            Ok(text) => parse(text.as_bytes())
                .map(Some)
                .map_err(|reason| StoreError::Corrupt { path, reason }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(StoreError::Io { path, source: e }),
        }
    }

    pub fn write_record(&self, scene: &str, record: &SceneRecord) -> Result<(), StoreError> {
        let path = self.scene_dir(scene).join(RECORD_FILE);
        write_atomic(
            &path,
            &serde_json::to_vec_pretty(record).expect("serialisable"),
        )
    }

    /// Refuses a results folder that exists and has no record, unless
    /// everything in it has one of the names ribbar publishes (`names`: a
    /// folder whose record was deleted): a folder of the user's that
    /// happens to have the scene's name. A record that cannot be read is
    /// moved aside (its name says so) and the folder taken as one without
    /// a record of its files: nothing in it is then overwritten or removed,
    /// only moved aside where a result goes. Returns what was said.
    pub fn claim_scene_dir(
        &self,
        scene: &str,
        names: &[&str],
    ) -> Result<Option<String>, StoreError> {
        let dir = self.scene_dir(scene);
        let record = dir.join(RECORD_FILE);
        if record.is_file() {
            return match self.read_record(scene) {
                Ok(_) => Ok(None),
                Err(StoreError::Corrupt { reason, .. }) => {
                    let kept = dir.join(".ribbar-stages.damaged.json");
                    fs::rename(&record, &kept).map_err(io_err(&record))?;
                    self.write_record(scene, &SceneRecord::default())?;
                    Ok(Some(format!(
                        "{}: damaged ({reason}); kept as {}: files found where results go are \
                         moved aside, not overwritten",
                        record.display(),
                        kept.display()
                    )))
                }
                Err(e) => Err(e),
            };
        }
        let entries = match fs::read_dir(&dir) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(io_err(&dir)(e)),
            Ok(entries) => entries,
        };
        for entry in entries {
            let entry = entry.map_err(io_err(&dir))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            if !(name.starts_with(".ribbar-stages") || names.contains(&unedited(&name).as_str())) {
                return Err(StoreError::NotOurs { path: dir });
            }
        }
        Ok(None)
    }

    /// Reads, changes and writes back the scene's record.
    pub fn update_record(
        &self,
        scene: &str,
        change: impl FnOnce(&mut SceneRecord),
    ) -> Result<SceneRecord, StoreError> {
        let mut record = self.read_record(scene)?.unwrap_or_default();
        change(&mut record);
        record.format = RECORD_FORMAT;
        self.write_record(scene, &record)?;
        Ok(record)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known instants print as their civil UTC time.
    #[test]
    fn unix_times_print_as_utc() {
        assert_eq!(utc_text(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc_text(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc_text(1_764_623_763), "2025-12-01 21:16:03 UTC");
    }

    /// Changed files kept aside read back as the result they stood for.
    #[test]
    fn edited_names_read_back() {
        assert_eq!(unedited("curve.edited-2.csv"), "curve.csv");
        assert_eq!(unedited("curve.edited.csv"), "curve.csv");
        assert_eq!(unedited("fields.edited"), "fields");
        assert_eq!(unedited("thesis.tex"), "thesis.tex");
    }

    /// A record of the first format (stage → key) reads as stages with no
    /// file records; this format round-trips.
    #[test]
    fn records_of_both_formats_read() {
        let key = StageKey::new("geometry", serde_json::json!({"bar": 1}));
        let legacy = serde_json::to_vec(&BTreeMap::from([("geometry", &key)])).unwrap();
        let record = parse(&legacy).unwrap();
        assert_eq!(record.stages["geometry"].key, key);
        assert_eq!(record.stages["geometry"].files, None);
        let mut now = SceneRecord::default();
        now.stages.insert(
            "geometry".into(),
            PublishedStage {
                key,
                files: Some(BTreeMap::new()),
            },
        );
        now.run = Some(RunRecord {
            command: "run".into(),
            started_unix_s: 1,
            finished_unix_s: Some(2),
            outcome: RunOutcome::Failed {
                stage: "mesh".into(),
                error: "gmsh".into(),
            },
            keys: BTreeMap::new(),
        });
        assert_eq!(parse(&serde_json::to_vec(&now).unwrap()).unwrap(), now);
    }
}
