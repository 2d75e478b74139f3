//! Content-addressed artifact store under the work directory.
//!
//! Layout:
//! ```text
//! WORK/.store/<stage>/<key>/           finished artifacts of one stage run
//! WORK/.store/<stage>/<key>/stage.json what was hashed, and each file's
//!                                      size, time and SHA-256
//! WORK/.store/<stage>/<key>.partial/   a run in progress (never read as done)
//! WORK/.store/<stage>/<key>.lock       held while a process works on <key>
//! WORK/.store/quarantine/              folders and checkpoints that failed
//!                                      their checks, moved aside
//! WORK/<scene>/                        copies of the scene's latest results
//! WORK/<scene>/.ribbar-stages.json     which key each stage last published,
//!                                      each published file's record, and
//!                                      how the last run ended
//! ```
//! A key is the SHA-256 of the canonical JSON of exactly what the stage reads
//! (resolved spec sections, upstream keys, versions that change results);
//! never paths or times. A stage directory becomes visible under its key only
//! by one `rename` after `stage.json` is written, so an interrupted stage is
//! never taken as done. Two processes that need the same key serialise on its
//! lock file; the second then finds it done.
//!
//! "Finished" has one definition, [`Store::examine`], used by lookup and by
//! commit alike: the folder has a `stage.json` of its own key listing every
//! file with its size and digest, and every file listed is there, a regular
//! file of that size (and that digest, where checked). A folder that fails
//! it is moved to the quarantine and the stage recomputed. Artifacts are
//! read-only and published as copies, so that editing a published file
//! never changes what the store serves.

mod base;
mod digest;
mod publish;
mod record;
mod stages;

pub use base::{
    changed_keys, flatten, write_atomic, StageKey, Store, StoreError, QUARANTINE, RECORD_FILE,
    STAGE_FILE, STORE_FORMAT,
};
pub use digest::{check_cost, sha256_file, Depth, FileDigest};
pub use publish::{edited_name, publish_cost, Compare, FileState, Published};
pub use record::{
    unix_now, utc_text, PublishedFile, PublishedStage, RunOutcome, RunRecord, SceneRecord,
};
pub use stages::{Committed, Examined, KeyLock, StageRecord, Thoroughness};
