//! The four stages (`kinds`), their keys (`keys`), what `status` says of
//! them (`status`), the context a runner gets (`ctx`), one runner per stage
//! (`geometry`, `mesh`, `solve`, `post`) and the skip-or-run-and-commit
//! step around them (`runner`). Each stage reads exactly the inputs that go
//! into its key, writes into the store's in-progress directory, commits by
//! one rename and publishes its files under `WORK/<scene>/`.

mod bond_law;
mod ctx;
pub mod folder;
mod geometry;
mod keys;
mod kinds;
mod mesh;
pub mod post;
mod runner;
pub mod solve;
mod status;

pub use ctx::Ctx;
pub use keys::Keys;
pub use kinds::{Stage, CHECKPOINT_FILE};
pub use runner::ensure;
pub use status::{folder_report, status, StageStatus};
