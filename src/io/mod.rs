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

/// The largest file `read_regular` reads: 4 GiB, four times the largest
/// tile's values in f32.
pub const MAX_FILE_BYTES: u64 = crate::core::tile::MAX_VALUES as u64 * 4 * 4;

/// The bytes of a regular file (through links), at most `MAX_FILE_BYTES`; a device, a pipe or a folder is
/// an error before it is opened: reading one would never end, or never begin.
pub fn read_regular(path: &Path) -> std::io::Result<Vec<u8>> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.file_type().is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a folder, a device or a pipe)",
        ));
    }
    // Nothing fsot reads is larger: a tile's values (2^28 of 4 bytes) and room
    // for headers and a format that stores them less tightly.
    if metadata.len() > MAX_FILE_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} bytes, more than any file fsot reads ({MAX_FILE_BYTES})", metadata.len()),
        ));
    }
    std::fs::read(path)
}

/// `read_regular` as UTF-8 text.
pub fn read_regular_text(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read_regular(path)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// What a mask file is, from its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskFile {
    Exr,
    Ktx2(ktx2::Format),
    CHeader,
}

impl MaskFile {
    /// The kind of `path` by its extension (`.exr`, `.ktx2`, `.h`; any other is an
    /// error); `ktx2_format` only for `.ktx2` (default: by d, see `ktx2::Format::default_for`). Checked
    /// before any work: a format that cannot hold d is an error.
    pub fn for_path(path: &Path, dims: usize, ktx2_format: Option<&str>) -> Result<Self> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        let kind = match ext.as_str() {
            "ktx2" => return Ok(MaskFile::Ktx2(ktx2::format_for(dims, ktx2_format)?)),
            "h" => MaskFile::CHeader,
            "exr" => MaskFile::Exr,
            _ if path.is_dir() => {
                return Err(Error::invalid(format!(
                    "{} is a folder: name a mask file in it, ending .exr, .ktx2 or .h \
                     (a scene's masks go into a folder with --scene)",
                    path.display()
                )))
            }
            _ => {
                return Err(Error::invalid(format!(
                    "cannot tell the format of {} by its name: give it .exr, .ktx2 or .h \
                     (PNG slices are written beside a mask by --png)",
                    path.display()
                )))
            }
        };
        if let Some(f) = ktx2_format {
            return Err(Error::invalid(format!(
                "a KTX2 format ({f}) was given for {}, which is not a .ktx2 file",
                path.display()
            )));
        }
        Ok(kind)
    }

    /// Writes `mask` in this kind of file.
    pub fn write(self, mask: &Mask, out: atomic::AtomicFile) -> Result<()> {
        let bytes = self.encode(mask, out.target())?;
        out.commit(&bytes)
    }

    /// The file's bytes; a C header's array is named for `target`'s file name.
    pub fn encode(self, mask: &Mask, target: &Path) -> Result<Vec<u8>> {
        match self {
            MaskFile::Exr => exr::encode(mask),
            MaskFile::Ktx2(f) => ktx2::encode(mask, f),
            MaskFile::CHeader => c_header::encode_for(mask, target).map(String::into_bytes),
        }
    }
}

impl Mask {
    /// Saves the mask by the file's extension: `.exr` (exact, 32-bit float),
    /// `.ktx2` (an array texture, 16-bit UNORM with the
    /// fewest channels that hold its dimensions: `Mask::ktx2` for another
    /// format) or `.h` (a C header); any other extension is an error. The
    /// file is written beside the target and renamed into place, so a failed save
    /// leaves what was there.
    ///
    /// ```
    /// let mask = fsot::Mask::white(fsot::Tile::new(8, 8, 2, 1, 2)?, 1);
    /// let dir = std::env::temp_dir().join(format!("fsot-save-{}", std::process::id()));
    /// std::fs::create_dir_all(&dir)?;
    /// mask.save(dir.join("mask.exr"))?;
    /// assert_eq!(fsot::Mask::open(dir.join("mask.exr"))?, mask);
    /// # std::fs::remove_dir_all(&dir)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let kind = MaskFile::for_path(path, self.tile.dims, None)?;
        kind.write(self, atomic::AtomicFile::create(path)?)
    }

    /// The mask as the bytes of a KTX2 array texture (layer = frame * spp +
    /// sample) in `format`, or by default the format that holds its dimensions;
    /// what an engine embeds or uploads.
    ///
    /// ```
    /// let mask = fsot::Mask::white(fsot::Tile::new(8, 8, 2, 1, 2)?, 1);
    /// let bytes = mask.ktx2(None)?;
    /// assert_eq!(&bytes[..12], b"\xABKTX 20\xBB\r\n\x1A\n");
    /// assert!(mask.ktx2(Some(fsot::TexelFormat::R8Unorm)).is_err()); // one channel cannot hold d = 2
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn ktx2(&self, format: Option<ktx2::Format>) -> Result<Vec<u8>> {
        let format = match format {
            Some(f) => {
                f.check_holds(self.tile.dims)?;
                f
            }
            None => ktx2::Format::default_for(self.tile.dims)?,
        };
        ktx2::encode(self, format)
    }

    /// Opens a mask saved as KTX2 (`.ktx2`: `ktx2::decode` says what it reads;
    /// a UNORM file gives its levels back, not the exact values it was made
    /// from) or as EXR (any other name), checking its layout and that every
    /// value is finite and in [0, 1).
    ///
    /// ```
    /// let mask = fsot::Mask::white(fsot::Tile::new(8, 8, 2, 1, 2)?, 1);
    /// let dir = std::env::temp_dir().join(format!("fsot-open-{}", std::process::id()));
    /// std::fs::create_dir_all(&dir)?;
    /// std::fs::write(dir.join("mask.ktx2"), mask.ktx2(Some(fsot::TexelFormat::R32G32Sfloat))?)?;
    /// assert_eq!(fsot::Mask::open(dir.join("mask.ktx2"))?.samples, mask.samples);
    /// # std::fs::remove_dir_all(&dir)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn open(path: impl AsRef<Path>) -> Result<Mask> {
        let path = path.as_ref();
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("ktx2") => ktx2::read(path),
            _ => exr::read(path),
        }
    }
}
