//! The store's per-key lock, for processes on one host or on several
//! sharing the work directory over a network file system
//! (docs/src/explanation/cluster-store.md).
//!
//! Across processes and hosts it is a POSIX record lock (`fcntl(F_SETLKW)`
//! on the whole lock file): the lock that NFS (v3 through its lock manager,
//! v4 in the protocol), Lustre (mounted with `flock`), GPFS, BeeGFS (with
//! global file locks), CephFS and GFS2 hold across clients, and that the
//! kernel, or the NFS server when a client's lease expires, releases when
//! its holder dies, so no stale lock outlives a killed job. POSIX locks
//! belong to a process, not to a file descriptor: two threads of one
//! process would both get one, and closing any descriptor of the file would
//! drop it. So within a process a table of held paths serialises the
//! threads first, the file is opened only by the thread that holds its
//! entry, and it is read and written only through the descriptor that holds
//! the lock.

use std::collections::HashSet;
use std::fs::File;
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::{Condvar, Mutex};

static HELD: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);
static RELEASED: Condvar = Condvar::new();

/// An exclusive lock on one lock file, released on drop (the record lock
/// with the file's descriptor, then this process's entry).
pub struct FileLock {
    file: Option<File>,
    path: PathBuf,
}

/// Why a lock could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path}: `{holder}` took this lock while this process held it: the file system \
         grants record locks per host only, so jobs on different hosts may compute one stage \
         at once; nothing was committed (docs/src/explanation/cluster-store.md)"
    )]
    Broken { path: PathBuf, holder: String },
    #[error(
        "{path}: the file system refuses record locks ({source}); on Lustre mount it with \
         `-o flock`, on NFS without `nolock` and with lockd (NFSv3) or NFSv4; a store shared \
         by several hosts needs them (docs/src/explanation/cluster-store.md)"
    )]
    Unsupported {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Blocks until this thread holds `path` in this process, then until this
/// process holds the record lock on it; writes `host pid` into the file
/// (who holds it, for a person looking at a lock that waits).
pub fn lock_exclusive(path: &Path) -> Result<FileLock, LockError> {
    Ok(take(path, true)?.expect("a waiting lock is always taken"))
}

/// The lock on `path` if no thread or process holds it now, `None` if one
/// does: for `ribbar clean` and `ribbar verify`, which skip a key that a
/// running stage works on rather than wait for it.
pub fn try_lock_exclusive(path: &Path) -> Result<Option<FileLock>, LockError> {
    take(path, false)
}

/// Takes the lock on `path`, waiting for it if `wait`, else `None` when
/// another thread or process holds it.
fn take(path: &Path, wait: bool) -> Result<Option<FileLock>, LockError> {
    {
        let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
        while held.get_or_insert_with(HashSet::new).contains(path) {
            if !wait {
                return Ok(None);
            }
            held = RELEASED.wait(held).unwrap_or_else(|e| e.into_inner());
        }
        held.get_or_insert_with(HashSet::new)
            .insert(path.to_path_buf());
    }
    // From here on the entry is released by FileLock's drop, on every path.
    let mut lock = FileLock {
        file: None,
        path: path.to_path_buf(),
    };
    let io = |source| LockError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::options()
        .create(true)
        .truncate(false)
        .read(true)
        .write(true)
        .open(path)
        .map_err(io)?;
    match record_lock(&file, wait) {
        Ok(true) => {}
        Ok(false) => return Ok(None),
        Err(source) => {
            return Err(match source.raw_os_error() {
                Some(libc::ENOLCK | libc::ENOSYS | libc::EOPNOTSUPP | libc::EINVAL) => {
                    LockError::Unsupported {
                        path: path.to_path_buf(),
                        source,
                    }
                }
                _ => io(source),
            })
        }
    }
    let holder = format!("{} {}\n", hostname(), std::process::id());
    // Who holds it is a courtesy: a failure to say so does not matter.
    let _ = file
        .set_len(0)
        .and_then(|()| (&file).write_all(holder.as_bytes()));
    lock.file = Some(file);
    Ok(Some(lock))
}

impl FileLock {
    /// `Err` naming the other holder when the lock file no longer names
    /// this process: another process took the lock while this one held it,
    /// which happens only where the file system grants record locks per
    /// host (Lustre's `localflock`, NFS's `nolock`).
    pub fn verify(&self) -> Result<(), LockError> {
        let ours = format!("{} {}\n", hostname(), std::process::id());
        // Read through the descriptor that holds the lock: opening and
        // closing another one of the same file would release it (POSIX).
        let Some(file) = &self.file else {
            return Ok(());
        };
        let mut buf = vec![0u8; 512];
        let n = file.read_at(&mut buf, 0).map_err(|source| LockError::Io {
            path: self.path.clone(),
            source,
        })?;
        let holder = String::from_utf8_lossy(&buf[..n]);
        if holder == ours {
            Ok(())
        } else {
            Err(LockError::Broken {
                path: self.path.clone(),
                holder: holder.trim().to_string(),
            })
        }
    }
}

/// `fcntl` on the whole file: `F_SETLKW` (waits) when `wait`, else
/// `F_SETLK`, whose `Ok(false)` is another process holding it. Retried when
/// a signal interrupts it.
fn record_lock(file: &File, wait: bool) -> std::io::Result<bool> {
    let mut request: libc::flock = unsafe { std::mem::zeroed() };
    request.l_type = libc::F_WRLCK as libc::c_short;
    request.l_whence = libc::SEEK_SET as libc::c_short;
    request.l_start = 0;
    request.l_len = 0; // to the end of the file, however long it grows
    let command = if wait { libc::F_SETLKW } else { libc::F_SETLK };
    loop {
        if unsafe { libc::fcntl(file.as_raw_fd(), command, &request) } == 0 {
            return Ok(true);
        }
        let e = std::io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EAGAIN | libc::EACCES) if !wait => return Ok(false),
            _ if e.kind() == std::io::ErrorKind::Interrupted => {}
            _ => return Err(e),
        }
    }
}

/// This host's name, or `?` where it cannot be read.
fn hostname() -> String {
    let mut buf = [0u8; 256];
    if unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } != 0 {
        return "?".into();
    }
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..end]).into_owned()
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // Closing the descriptor releases the record lock.
        drop(self.file.take());
        let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(set) = held.as_mut() {
            set.remove(&self.path);
        }
        RELEASED.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;

    /// Threads of one process exclude each other on one path (a POSIX
    /// record lock alone would let them all in), and the lock file names
    /// its holder.
    #[test]
    fn threads_of_one_process_take_the_lock_in_turn() {
        let dir = std::env::temp_dir().join(format!("ribbar-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("k.lock");
        let inside = Arc::new(AtomicUsize::new(0));
        let most = Arc::new(AtomicUsize::new(0));
        std::thread::scope(|s| {
            for _ in 0..4 {
                let (path, inside, most) = (&path, inside.clone(), most.clone());
                s.spawn(move || {
                    for _ in 0..5 {
                        let _lock = lock_exclusive(path).unwrap();
                        let n = inside.fetch_add(1, Ordering::SeqCst) + 1;
                        most.fetch_max(n, Ordering::SeqCst);
                        std::thread::sleep(std::time::Duration::from_millis(2));
                        inside.fetch_sub(1, Ordering::SeqCst);
                    }
                });
            }
        });
        assert_eq!(most.load(Ordering::SeqCst), 1);
        let holder = std::fs::read_to_string(&path).unwrap();
        assert!(
            holder.ends_with(&format!(" {}\n", std::process::id())),
            "{holder}"
        );
        // Another holder's name in the file while this one holds the lock
        // is what a lock that does not hold across hosts leaves.
        let lock = lock_exclusive(&path).unwrap();
        lock.verify().unwrap();
        std::fs::write(&path, "elsewhere 1\n").unwrap();
        let err = lock.verify().unwrap_err().to_string();
        assert!(err.contains("`elsewhere 1` took this lock"), "{err}");
        drop(lock);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A key held by this process is not taken again by a non-waiting
    /// lock, and is taken once released.
    #[test]
    fn a_held_lock_is_not_taken_without_waiting() {
        let dir = std::env::temp_dir().join(format!("ribbar-trylock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("k.lock");
        let held = lock_exclusive(&path).unwrap();
        assert!(try_lock_exclusive(&path).unwrap().is_none());
        drop(held);
        let again = try_lock_exclusive(&path).unwrap();
        assert!(again.is_some());
        again.unwrap().verify().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
