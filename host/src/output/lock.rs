//! One writer per folder: an exclusive OS lock (`flock` on Unix) held for as long as a
//! run writes in its output folder. Two processes writing one folder would truncate
//! each other's `NAME.tmp` files and rename the remains as finished files; with the
//! lock the second is refused (or waits) before it touches anything.
//!
//! The lock is on the folder itself, so that it adds no file to the folder (its
//! listing stays that of the run) and works in a folder that cannot be written. Where
//! the file system cannot lock a folder (some network file systems lock only files
//! open for writing), it falls back to the file `.lock` in the folder. Either way the
//! OS releases the lock when the process ends, killed included: a stale lock never
//! blocks a rerun, and the lock file is never removed (removing it would let a third
//! process lock a new file while the second still holds the old one).

use std::fmt;
use std::fs::{File, OpenOptions, TryLockError};
use std::io;
use std::path::{Path, PathBuf};

use super::name_error;

/// The lock file, where the folder itself cannot be locked.
pub const LOCK_FILE: &str = ".lock";

/// An exclusive lock on an output folder, released when dropped (or the process ends).
#[derive(Debug)]
pub struct FolderLock {
    _file: File,
}

/// The folder is locked by another process (or another run of this one).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Locked {
    /// The folder.
    pub dir: PathBuf,
}

impl fmt::Display for Locked {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: another process is writing this folder (it holds its lock); wait for it \
             to end, or write elsewhere",
            self.dir.display()
        )
    }
}

impl std::error::Error for Locked {}

/// Whether `e` says the file system cannot lock this file, rather than that it is
/// locked or missing.
fn unsupported(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::Unsupported | io::ErrorKind::InvalidInput | io::ErrorKind::PermissionDenied
    ) || e.raw_os_error().is_some_and(|c| c == 9 || c == 37) // EBADF, ENOLCK
}

impl FolderLock {
    /// Locks `dir` (which exists) without waiting: None when another holds it. A lock
    /// found held is tried twice more, 20 ms apart: a reader's [`held`](Self::held)
    /// holds it for an instant, and a writer should not skip a folder for that.
    pub fn try_take(dir: &Path) -> io::Result<Option<FolderLock>> {
        for _ in 0..2 {
            if let Some(l) = Self::try_take_once(dir)? {
                return Ok(Some(l));
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        Self::try_take_once(dir)
    }

    fn try_take_once(dir: &Path) -> io::Result<Option<FolderLock>> {
        Self::take_with(dir, |f| match f.try_lock() {
            Ok(()) => Ok(true),
            Err(TryLockError::WouldBlock) => Ok(false),
            Err(TryLockError::Error(e)) => Err(e),
        })
    }

    /// Whether a process (a live one: the OS drops a dead one's lock) holds `dir`'s
    /// lock now. Found by taking a shared lock and letting it go at once; nothing is
    /// written, not even the lock file of a folder that cannot be locked.
    pub fn held(dir: &Path) -> io::Result<bool> {
        let probe = |f: &File| match f.try_lock_shared() {
            Ok(()) => Ok(false),
            Err(TryLockError::WouldBlock) => Ok(true),
            Err(TryLockError::Error(e)) => Err(e),
        };
        #[cfg(unix)]
        if let Ok(file) = File::open(dir) {
            match probe(&file) {
                Ok(held) => return Ok(held),
                Err(e) if unsupported(&e) => {}
                Err(e) => return Err(name_error(dir, e)),
            }
        }
        let path = dir.join(LOCK_FILE);
        match File::open(&path) {
            Ok(file) => probe(&file).map_err(|e| name_error(&path, e)),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
            Err(e) => Err(name_error(&path, e)),
        }
    }

    /// Locks `dir`, waiting for the process that holds it to end or let go.
    pub fn wait(dir: &Path) -> io::Result<FolderLock> {
        Self::take_with(dir, |f| f.lock().map(|()| true))
            .map(|l| l.expect("a waited lock is taken"))
    }

    /// Locks `dir` or refuses with [`Locked`].
    pub fn take(dir: &Path) -> anyhow::Result<FolderLock> {
        match Self::try_take(dir)? {
            Some(l) => Ok(l),
            None => Err(Locked {
                dir: dir.to_path_buf(),
            }
            .into()),
        }
    }

    fn take_with(
        dir: &Path,
        lock: impl Fn(&File) -> io::Result<bool>,
    ) -> io::Result<Option<FolderLock>> {
        #[cfg(unix)]
        if let Ok(file) = File::open(dir) {
            match lock(&file) {
                Ok(true) => return Ok(Some(FolderLock { _file: file })),
                Ok(false) => return Ok(None),
                Err(e) if unsupported(&e) => {}
                Err(e) => return Err(name_error(dir, e)),
            }
        }
        let path = dir.join(LOCK_FILE);
        let file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| name_error(&path, e))?;
        match lock(&file) {
            Ok(true) => Ok(Some(FolderLock { _file: file })),
            Ok(false) => Ok(None),
            Err(e) => Err(name_error(&path, e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_taker_is_refused_until_the_first_lets_go() {
        let dir = std::env::temp_dir().join(format!("folder-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let first = FolderLock::take(&dir).unwrap();
        let e = FolderLock::take(&dir).unwrap_err();
        assert_eq!(e.downcast_ref::<Locked>().unwrap().dir, dir);
        drop(first);
        let again = FolderLock::try_take(&dir).unwrap();
        assert!(again.is_some());
        // A probe sees the holder and adds nothing to the folder either.
        assert!(FolderLock::held(&dir).unwrap());
        drop(again);
        assert!(!FolderLock::held(&dir).unwrap());
        assert!(FolderLock::try_take(&dir).unwrap().is_some());
        // Nothing was added to the folder.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
