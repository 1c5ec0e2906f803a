//! A file read in checked pieces ([`ByteSource`]): the readers that keep a file open (frame
//! sources, trajectories) read each piece when they need it, and every piece is checked against
//! the file's length before anything is allocated.

use super::binary::cut_short;
use crate::error::{PgtError, Result};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A seekable byte stream (a file, or bytes in memory for tests and fuzzing).
pub trait ReadSeek: Read + Seek + Send {}
impl<T: Read + Seek + Send> ReadSeek for T {}

/// A file read in pieces: every read names its offset and is checked against the length before
/// anything is allocated. The handle sits behind a mutex so that sources are `Sync`.
pub struct ByteSource {
    path: PathBuf,
    len: u64,
    inner: Mutex<Box<dyn ReadSeek>>,
}

impl std::fmt::Debug for ByteSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ByteSource")
            .field("path", &self.path)
            .field("len", &self.len)
            .finish()
    }
}

impl ByteSource {
    /// Opens a file (a directory is refused).
    pub fn open(path: &Path) -> Result<ByteSource> {
        let file = std::fs::File::open(path).map_err(|e| PgtError::io(path, e))?;
        let meta = file.metadata().map_err(|e| PgtError::io(path, e))?;
        if meta.is_dir() {
            return Err(PgtError::in_file(
                path,
                "is a directory, not a particle file",
            ));
        }
        Ok(ByteSource {
            path: path.to_path_buf(),
            len: meta.len(),
            inner: Mutex::new(Box::new(file)),
        })
    }

    /// Any seekable stream of `len` bytes, named `path` in messages.
    pub fn from_reader(path: &Path, len: u64, reader: Box<dyn ReadSeek>) -> ByteSource {
        ByteSource {
            path: path.to_path_buf(),
            len,
            inner: Mutex::new(reader),
        }
    }

    /// Bytes in memory, named `path` in messages.
    pub fn from_bytes(path: &Path, bytes: Vec<u8>) -> ByteSource {
        ByteSource {
            path: path.to_path_buf(),
            len: bytes.len() as u64,
            inner: Mutex::new(Box::new(std::io::Cursor::new(bytes))),
        }
    }

    /// The file's name for messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Length in bytes.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the file is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// `len` bytes from `offset`; past the end of the file it is an error naming `what` (and the
    /// caller's context, such as the frame) at that offset.
    pub fn read_at(&self, offset: u64, len: u64, what: &str) -> Result<Vec<u8>> {
        let end = offset.checked_add(len).filter(|&e| e <= self.len);
        if end.is_none() {
            return Err(cut_short(&self.path, offset, what, len, "file", self.len));
        }
        let mut buf = vec![0u8; len as usize];
        let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        inner
            .seek(SeekFrom::Start(offset))
            .and_then(|_| inner.read_exact(&mut buf))
            .map_err(|e| PgtError::io(&self.path, e))?;
        Ok(buf)
    }

    /// The whole file (for formats parsed whole at open).
    pub fn read_all(&self, what: &str) -> Result<Vec<u8>> {
        if self.len > crate::formats::MAX_FILE_BYTES {
            return Err(PgtError::in_file(
                &self.path,
                format!(
                    "the file is {} bytes; pgt reads particle files of at most {} bytes",
                    self.len,
                    crate::formats::MAX_FILE_BYTES
                ),
            ));
        }
        self.read_at(0, self.len, what)
    }
}
