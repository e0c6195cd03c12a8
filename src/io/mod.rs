//! Mask files: OpenEXR (the primary format), KTX2 array textures, C headers and
//! 16-bit PNG slices, all written through a temporary file renamed into place.
pub mod atomic;
pub(crate) mod c_header;
pub mod exr;
pub mod ktx2;
pub mod png;
pub mod stacked_png;

use std::path::Path;

use crate::core::mask::Mask;
use crate::error::{Error, Result};

/// What a mask file is, from its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskFile {
    Exr,
    Ktx2(ktx2::Format),
    CHeader,
}

impl MaskFile {
    /// The kind of `path` by its extension (`.exr`, `.ktx2`, `.h`); `ktx2_format`
    /// only for `.ktx2` (default: by d, see `ktx2::Format::default_for`). Checked
    /// before any work: a format that cannot hold d is an error.
    pub fn for_path(path: &Path, dims: usize, ktx2_format: Option<&str>) -> Result<Self> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        let kind = match ext.as_str() {
            "ktx2" => return Ok(MaskFile::Ktx2(ktx2::format_for(dims, ktx2_format)?)),
            "h" => MaskFile::CHeader,
            _ => MaskFile::Exr,
        };
        if let Some(f) = ktx2_format {
            return Err(Error::invalid(format!(
                "a KTX2 format ({f}) was given for {}, which is not a .ktx2 file",
                path.display()
            )));
        }
        Ok(kind)
    }

    pub fn write(self, mask: &Mask, out: atomic::AtomicFile) -> Result<()> {
        match self {
            MaskFile::Exr => exr::write(mask, out),
            MaskFile::Ktx2(f) => ktx2::write(mask, f, out),
            MaskFile::CHeader => c_header::write(mask, out),
        }
    }
}
