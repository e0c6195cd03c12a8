//! Writing a file so that readers see either the old file or the complete new one,
//! never a half-written one: write a temporary file beside the target, flush it to
//! disk, rename it over the target.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Makes a folder (and its parents) for outputs, with a clear error.
pub fn make_folder(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).map_err(|e| Error::io(format!("cannot make the folder {}", dir.display()), e))
}

/// A reserved output: creating it checks that the target's folder is writable
/// (before any long work) by creating and removing the temporary file, so a run
/// killed during its long work leaves nothing behind; `commit` writes the
/// temporary file, syncs it and renames it over the target; dropping it
/// uncommitted leaves the target untouched.
pub struct AtomicFile {
    target: PathBuf,
    temp: PathBuf,
}

impl AtomicFile {
    pub fn create(target: &Path) -> Result<Self> {
        if target.is_dir() {
            return Err(Error::invalid(format!("output {} is a directory", target.display())));
        }
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            let why = if dir.exists() { "is not a folder" } else { "does not exist" };
            return Err(Error::invalid(format!("output folder {} {why}", dir.display())));
        }
        let name = target
            .file_name()
            .ok_or_else(|| Error::invalid(format!("output {} has no file name", target.display())))?;
        let temp = dir.join(format!(".{}.fsot-{}.tmp", name.to_string_lossy(), std::process::id()));
        File::create(&temp).map_err(|e| Error::io(format!("cannot write in {}", dir.display()), e))?;
        fs::remove_file(&temp).map_err(|e| Error::io(format!("cannot write in {}", dir.display()), e))?;
        Ok(Self { target: target.to_path_buf(), temp })
    }

    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes `bytes` to the temporary file, syncs it, renames it over the target.
    pub fn commit(mut self, bytes: &[u8]) -> Result<()> {
        let ctx = || format!("writing {}", self.temp.display());
        let mut file = File::create(&self.temp).map_err(|e| Error::io(ctx(), e))?;
        file.write_all(bytes).map_err(|e| Error::io(ctx(), e))?;
        file.sync_all().map_err(|e| Error::io(ctx(), e))?;
        drop(file);
        fs::rename(&self.temp, &self.target)
            .map_err(|e| Error::io(format!("renaming into {}", self.target.display()), e))?;
        self.temp = PathBuf::new();
        Ok(())
    }
}

impl Drop for AtomicFile {
    /// After a failed commit: the partial temporary file goes (the target was
    /// never touched).
    fn drop(&mut self) {
        if !self.temp.as_os_str().is_empty() && self.temp.exists() {
            let _ = fs::remove_file(&self.temp); // best effort: nothing to report from drop
        }
    }
}
