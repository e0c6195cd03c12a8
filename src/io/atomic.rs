//! Writing a file so that readers see either the old file or the complete new one,
//! never a half-written one: write a temporary file beside the target, flush it to
//! disk, rename it over the target.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Makes a folder (and its parents) for outputs, with a clear error.
pub fn make_folder(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::invalid(format!("{} is a file, not a folder", dir.display())));
    }
    fs::create_dir_all(dir).map_err(|e| Error::io(format!("cannot make the folder {}", dir.display()), e))
}

/// A reserved output: creating it checks that the target's folder is writable
/// (before any long work) by creating and removing the temporary file, so a run
/// killed during its long work leaves nothing behind; `commit` writes the
/// temporary file, syncs it and renames it over the target; dropping it
/// uncommitted leaves the target untouched.
pub struct AtomicFile {
    /// The path as given (what a C header is named for).
    target: PathBuf,
    /// The file replaced: the target, or where its link leads.
    dest: PathBuf,
    temp: PathBuf,
}

impl AtomicFile {
    /// Reserves `target`. A symbolic link is written through (its target is
    /// replaced, the link kept); a target that exists and is not a regular file
    /// (a folder, a device, a pipe) or a link to nothing is refused.
    pub fn create(target: &Path) -> Result<Self> {
        let named = target;
        let resolved;
        let target = match fs::symlink_metadata(named) {
            Ok(m) if m.file_type().is_symlink() => {
                resolved = fs::canonicalize(named).map_err(|e| {
                    Error::io(format!("output {} is a link to nothing that can be written", named.display()), e)
                })?;
                resolved.as_path()
            }
            _ => named,
        };
        if target.is_dir() {
            return Err(Error::invalid(format!("output {} is a directory", named.display())));
        }
        if target.exists() && !target.is_file() {
            return Err(Error::invalid(format!(
                "output {} exists and is not a regular file (a device or a pipe); it is left as it is",
                named.display()
            )));
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
        // Unique per file made, so that two reservations of one target (two
        // threads, or one path given twice) never share a temporary file.
        static MADE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = MADE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let temp = dir.join(format!(".{}.fsot-{}-{n}.tmp", name.to_string_lossy(), std::process::id()));
        File::create(&temp).map_err(|e| Error::io(format!("cannot write in {}", dir.display()), e))?;
        fs::remove_file(&temp).map_err(|e| Error::io(format!("cannot write in {}", dir.display()), e))?;
        Ok(Self { target: named.to_path_buf(), dest: target.to_path_buf(), temp })
    }

    /// The output's path as given (a link's own name, not where it leads).
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes `bytes` to the temporary file, syncs it, renames it over the target.
    pub fn commit(self, bytes: &[u8]) -> Result<()> {
        self.stage(bytes)?.commit()
    }

    /// Writes `bytes` to the temporary file and syncs it, the target untouched
    /// until `Staged::commit` (several outputs: `commit_all`). An existing
    /// target's permissions carry over to the new file.
    pub fn stage(mut self, bytes: &[u8]) -> Result<Staged> {
        let ctx = || format!("writing {}", self.temp.display());
        let mut file = File::create(&self.temp).map_err(|e| Error::io(ctx(), e))?;
        file.write_all(bytes).map_err(|e| Error::io(ctx(), e))?;
        if let Ok(old) = fs::metadata(&self.dest) {
            file.set_permissions(old.permissions()).map_err(|e| Error::io(ctx(), e))?;
        }
        file.sync_all().map_err(|e| Error::io(ctx(), e))?;
        let temp = std::mem::take(&mut self.temp);
        Ok(Staged { dest: self.dest.clone(), temp })
    }
}

/// An output written in full beside its target, waiting to be renamed over it;
/// dropped uncommitted, it goes and the target stays as it was.
pub struct Staged {
    dest: PathBuf,
    temp: PathBuf,
}

impl Staged {
    /// Renames the written file over the target.
    pub fn commit(mut self) -> Result<()> {
        fs::rename(&self.temp, &self.dest)
            .map_err(|e| Error::io(format!("renaming into {}", self.dest.display()), e))?;
        self.temp = PathBuf::new();
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.temp.as_os_str().is_empty() && self.temp.exists() {
            let _ = fs::remove_file(&self.temp); // best effort: nothing to report from drop
        }
    }
}

/// An error unless the files replace different files (links resolved): one
/// file named twice would be written twice, the last write winning.
pub fn distinct<'a>(files: impl IntoIterator<Item = &'a AtomicFile>) -> Result<()> {
    let files: Vec<&AtomicFile> = files.into_iter().collect();
    for (i, a) in files.iter().enumerate() {
        if let Some(b) = files[..i].iter().find(|b| same_file(&a.dest, &b.dest)) {
            return Err(Error::invalid(format!(
                "outputs {} and {} are one file: name each output once",
                b.target.display(),
                a.target.display()
            )));
        }
    }
    Ok(())
}

/// Writes every output in full before any target is replaced: one that cannot be
/// written (a full disk) leaves every target as it was. Two outputs that replace
/// one file are refused before anything is written (`distinct`).
pub fn commit_all(outputs: Vec<(AtomicFile, Vec<u8>)>) -> Result<()> {
    distinct(outputs.iter().map(|(file, _)| file))?;
    let staged = outputs.into_iter().map(|(file, bytes)| file.stage(&bytes)).collect::<Result<Vec<_>>>()?;
    staged.into_iter().try_for_each(Staged::commit)
}

/// Whether two paths name one file: the same text, or the same file once links
/// are followed (a link at the file itself, as a write through it replaces what
/// it leads to, and links to folders), or the same file name in one folder.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| {
        if let Ok(file) = fs::canonicalize(p) {
            return Some(file);
        }
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(fs::canonicalize(dir).ok()?.join(p.file_name()?))
    };
    a == b || resolved(a).is_some_and(|r| Some(r) == resolved(b))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("fsot-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_commit_replaces_a_regular_file() {
        let dir = scratch("regular");
        let p = dir.join("m.exr");
        fs::write(&p, b"old").unwrap();
        AtomicFile::create(&p).unwrap().commit(b"new").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1, "no temporary file left");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn outputs_committed_together_replace_nothing_unless_every_one_is_written() {
        let dir = scratch("together");
        let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
        fs::write(&a, b"old a").unwrap();
        fs::write(&b, b"old b").unwrap();
        // c's temporary file cannot be made once its folder is gone.
        let sub = dir.join("sub");
        fs::create_dir(&sub).unwrap();
        let lost = AtomicFile::create(&sub.join("c.exr")).unwrap();
        fs::remove_dir(&sub).unwrap();
        let failing = vec![(AtomicFile::create(&a).unwrap(), b"new a".to_vec()), (lost, b"new c".to_vec())];
        assert!(commit_all(failing).is_err());
        assert_eq!(fs::read(&a).unwrap(), b"old a", "a stays as it was");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 2, "no temporary file left");
        let both = vec![(AtomicFile::create(&a).unwrap(), b"new a".to_vec()), (AtomicFile::create(&b).unwrap(), b"new b".to_vec())];
        commit_all(both).unwrap();
        assert_eq!((fs::read(&a).unwrap(), fs::read(&b).unwrap()), (b"new a".to_vec(), b"new b".to_vec()));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn one_file_named_twice_is_refused_before_anything_is_written() {
        let dir = scratch("twice");
        let p = dir.join("m.exr");
        fs::write(&p, b"old").unwrap();
        let (a, b) = (AtomicFile::create(&p).unwrap(), AtomicFile::create(&dir.join(".").join("m.exr")).unwrap());
        assert_ne!(a.temp, b.temp, "each reservation has a temporary file of its own");
        let err = commit_all(vec![(a, b"one".to_vec()), (b, b"two".to_vec())]).unwrap_err();
        assert!(err.to_string().contains("are one file"), "{err}");
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1, "no temporary file left");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let p = dir.join("m.exr");
        fs::write(&p, b"old").unwrap();
        fs::set_permissions(&p, fs::Permissions::from_mode(0o600)).unwrap();
        AtomicFile::create(&p).unwrap().commit(b"new").unwrap();
        assert_eq!(fs::metadata(&p).unwrap().permissions().mode() & 0o777, 0o600);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_link_and_the_file_it_leads_to_are_one_file() {
        let dir = scratch("same");
        let (real, link, other) = (dir.join("state.ckpt"), dir.join("m.exr"), dir.join("other.exr"));
        fs::write(&real, b"state").unwrap();
        std::os::unix::fs::symlink(&real, &link).unwrap();
        assert!(same_file(&link, &real) && same_file(&real, &link));
        assert!(same_file(&dir.join("./m.exr"), &link), "one folder, one name");
        assert!(!same_file(&link, &other) && !same_file(&real, &other));
        assert!(same_file(&other, &dir.join("other.exr")), "a file yet to be made");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_written_through_and_kept() {
        let dir = scratch("link");
        let real = dir.join("real.exr");
        let link = dir.join("link.exr");
        fs::write(&real, b"old").unwrap();
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let out = AtomicFile::create(&link).unwrap();
        assert_eq!(out.target(), link.as_path(), "named as given");
        out.commit(b"new").unwrap();
        assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays a link");
        assert_eq!(fs::read(&real).unwrap(), b"new", "its target holds the new bytes");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_dangling_link_a_device_and_a_folder_are_refused() {
        let dir = scratch("refused");
        let dangling = dir.join("dangling.exr");
        std::os::unix::fs::symlink(dir.join("nowhere/x.exr"), &dangling).unwrap();
        assert!(AtomicFile::create(&dangling).is_err());
        let err = AtomicFile::create(Path::new("/dev/null")).err().expect("a device is refused");
        assert!(err.to_string().contains("not a regular file"), "{err}");
        assert!(AtomicFile::create(&dir).is_err());
        fs::remove_dir_all(&dir).unwrap();
    }
}
