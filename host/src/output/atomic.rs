//! Atomic files: written under a temporary name, synced, then renamed. Every error
//! names the file it is about, and a file that fails is removed: a failed run leaves no
//! `*.tmp` behind.

use serde::Serialize;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The temporary name a file is written under before it is renamed: `NAME.tmp` in the
/// same directory.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// The file [`AtomicFile::continue_from`] continues `path` from: the `NAME.tmp` a
/// stopped run left when it holds at least `keep` bytes, else `NAME`.
pub fn continued_source(path: &Path, keep: u64) -> PathBuf {
    let tmp = tmp_path(path);
    match std::fs::metadata(&tmp) {
        Ok(m) if m.is_file() && m.len() >= keep => tmp,
        _ => path.to_path_buf(),
    }
}

/// `e` with `path` in front of its message (the kind kept), so that a full disk or a
/// read-only folder says which file it stopped.
pub fn name_error(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// A file being written under its temporary name; [`AtomicFile::commit`] makes it
/// appear under its final name. Dropped without a commit, or failing to commit, the
/// temporary file is removed. Errors name the final path.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Creates (truncates) `NAME.tmp` next to `path`.
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        let tmp = tmp_path(path);
        let file = File::create(&tmp).map_err(|e| name_error(path, e))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            writer: Some(BufWriter::new(file)),
        })
    }

    /// Continues a file from its first `keep` bytes (a resumed run continues its files
    /// from a checkpoint): the `NAME.tmp` a stopped run left, cut back to `keep`, or
    /// else a copy of the first `keep` bytes of `NAME`. Stands at the end.
    pub fn continue_from(path: &Path, keep: u64) -> io::Result<AtomicFile> {
        let tmp = tmp_path(path);
        if continued_source(path, keep) == tmp {
            let mut file = std::fs::OpenOptions::new()
                .write(true)
                .open(&tmp)
                .map_err(|e| name_error(path, e))?;
            file.set_len(keep)
                .and_then(|()| file.seek(SeekFrom::End(0)))
                .map_err(|e| name_error(path, e))?;
            return Ok(AtomicFile {
                path: path.to_path_buf(),
                tmp,
                writer: Some(BufWriter::new(file)),
            });
        }
        let mut file = AtomicFile::create(path)?;
        let copied = File::open(path)
            .and_then(|src| io::copy(&mut io::Read::take(src, keep), file.writer()))
            .map_err(|e| name_error(path, e))?;
        if copied != keep {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!(
                    "{}: {copied} bytes where the checkpoint expects {keep}",
                    path.display()
                ),
            ));
        }
        Ok(file)
    }

    /// Flushes and leaves the file under its temporary name, for a run stopped on
    /// request whose checkpoint marks it: the resumed run continues it
    /// ([`continue_from`](Self::continue_from)).
    pub fn keep(mut self) -> io::Result<()> {
        match self.writer.take() {
            Some(mut w) => w.flush().map_err(|e| name_error(&self.path, e)),
            None => Ok(()),
        }
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs the data to disk and renames the file to its final name (then
    /// syncs the directory, where the platform allows it). On failure the temporary
    /// file is removed.
    pub fn commit(mut self) -> io::Result<()> {
        let Some(writer) = self.writer.take() else {
            return Ok(());
        };
        let done = writer
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|file| file.sync_all())
            .and_then(|()| std::fs::rename(&self.tmp, &self.path));
        if let Err(e) = done {
            let _ = std::fs::remove_file(&self.tmp);
            return Err(name_error(&self.path, e));
        }
        sync_parent(&self.path);
        Ok(())
    }

    fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer
            .as_mut()
            .expect("an uncommitted file has a writer")
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let path = self.path.clone();
        self.writer().write(buf).map_err(|e| name_error(&path, e))
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        let path = self.path.clone();
        self.writer()
            .write_all(buf)
            .map_err(|e| name_error(&path, e))
    }

    fn flush(&mut self) -> io::Result<()> {
        let path = self.path.clone();
        self.writer().flush().map_err(|e| name_error(&path, e))
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        let path = self.path.clone();
        self.writer().seek(pos).map_err(|e| name_error(&path, e))
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Best-effort sync of the directory holding `path`, so that a rename survives a crash.
fn sync_parent(path: &Path) {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if let Ok(dir) = File::open(parent) {
        let _ = dir.sync_all();
    }
}

/// Writes `bytes` to `path` atomically (temporary name, sync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

/// Writes `value` as pretty-printed JSON (with a final newline), atomically.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(io::Error::other)?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}
