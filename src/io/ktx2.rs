//! Masks as KTX2 2-D array textures, the form renderers bind them in.
//!
//! One layer per frame and sample (layer `t * spp + s`), `pixelDepth` 0, one
//! level, no supercompression, a basic data format descriptor (RGBSDA, linear),
//! the mask's provenance as `fsot.*` key/value entries. Each texel holds one
//! sample's d components in its first d channels (the rest 0), so the format
//! must have at least d channels (d <= 4; a plan splits larger decisions).
//!
//! Quantisation of a value v in [0, 1) to a b-bit UNORM channel: the nearest of
//! the 2^b levels, q = round(v (2^b - 1)); a reader (`texelFetch` of a UNORM
//! image) gets q / (2^b - 1), within half a level of v. The top level reads 1.0,
//! which a sampler wraps to 0.0 (`fract`, as `glsl/include/fsot.glsl` does): the
//! mask is toroidal, so that is the value's nearest point on the circle. SFLOAT
//! formats hold v exactly.

use crate::core::mask::Mask;
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;

/// The formats fsot writes, with their Vulkan `VkFormat` numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// One 8-bit UNORM channel (`VK_FORMAT_R8_UNORM`, 9).
    R8Unorm,
    /// Two 8-bit UNORM channels (`VK_FORMAT_R8G8_UNORM`, 16).
    R8G8Unorm,
    /// Four 8-bit UNORM channels (`VK_FORMAT_R8G8B8A8_UNORM`, 37).
    R8G8B8A8Unorm,
    /// One 16-bit UNORM channel (`VK_FORMAT_R16_UNORM`, 70).
    R16Unorm,
    /// Two 16-bit UNORM channels (`VK_FORMAT_R16G16_UNORM`, 77).
    R16G16Unorm,
    /// Four 16-bit UNORM channels (`VK_FORMAT_R16G16B16A16_UNORM`, 91).
    R16G16B16A16Unorm,
    /// One 32-bit float channel (`VK_FORMAT_R32_SFLOAT`, 100).
    R32Sfloat,
    /// Two 32-bit float channels (`VK_FORMAT_R32G32_SFLOAT`, 103).
    R32G32Sfloat,
    /// Four 32-bit float channels (`VK_FORMAT_R32G32B32A32_SFLOAT`, 109).
    R32G32B32A32Sfloat,
}

impl Format {
    /// Every format fsot writes.
    pub const ALL: [Format; 9] = [
        Format::R8Unorm,
        Format::R8G8Unorm,
        Format::R8G8B8A8Unorm,
        Format::R16Unorm,
        Format::R16G16Unorm,
        Format::R16G16B16A16Unorm,
        Format::R32Sfloat,
        Format::R32G32Sfloat,
        Format::R32G32B32A32Sfloat,
    ];

    /// The format's name as options and errors spell it, e.g. "r16g16_unorm".
    pub fn name(self) -> &'static str {
        match self {
            Format::R8Unorm => "r8_unorm",
            Format::R8G8Unorm => "r8g8_unorm",
            Format::R8G8B8A8Unorm => "r8g8b8a8_unorm",
            Format::R16Unorm => "r16_unorm",
            Format::R16G16Unorm => "r16g16_unorm",
            Format::R16G16B16A16Unorm => "r16g16b16a16_unorm",
            Format::R32Sfloat => "r32_sfloat",
            Format::R32G32Sfloat => "r32g32_sfloat",
            Format::R32G32B32A32Sfloat => "r32g32b32a32_sfloat",
        }
    }

    /// The format of that name (see `name`); an error lists the names.
    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Self::ALL.iter().map(|f| f.name()).collect();
            Error::invalid(format!("unknown KTX2 format {name:?}; one of {}", names.join(", ")))
        })
    }

    /// The `VkFormat` value.
    pub fn vk_format(self) -> u32 {
        match self {
            Format::R8Unorm => 9,
            Format::R8G8Unorm => 16,
            Format::R8G8B8A8Unorm => 37,
            Format::R16Unorm => 70,
            Format::R16G16Unorm => 77,
            Format::R16G16B16A16Unorm => 91,
            Format::R32Sfloat => 100,
            Format::R32G32Sfloat => 103,
            Format::R32G32B32A32Sfloat => 109,
        }
    }

    /// Channels per texel: 1, 2 or 4.
    pub fn channels(self) -> usize {
        match self {
            Format::R8Unorm | Format::R16Unorm | Format::R32Sfloat => 1,
            Format::R8G8Unorm | Format::R16G16Unorm | Format::R32G32Sfloat => 2,
            _ => 4,
        }
    }

    /// Bits per channel.
    pub fn bits(self) -> u32 {
        match self {
            Format::R8Unorm | Format::R8G8Unorm | Format::R8G8B8A8Unorm => 8,
            Format::R16Unorm | Format::R16G16Unorm | Format::R16G16B16A16Unorm => 16,
            _ => 32,
        }
    }

    /// True for the 32-bit SFLOAT formats, which hold values exactly.
    pub fn is_float(self) -> bool {
        self.bits() == 32
    }

    /// Bytes per texel.
    pub fn texel_bytes(self) -> usize {
        self.channels() * self.bits() as usize / 8
    }

    /// The default for d components: 16-bit UNORM with the fewest channels that
    /// hold them (r16g16_unorm for d = 2).
    pub fn default_for(dims: usize) -> Result<Self> {
        match dims {
            1 => Ok(Format::R16Unorm),
            2 => Ok(Format::R16G16Unorm),
            3 | 4 => Ok(Format::R16G16B16A16Unorm),
            d => Err(Error::invalid(format!(
                "a texel holds at most 4 components, the mask has d = {d}: split it (a scene plan does)"
            ))),
        }
    }

    /// Checks that a texel of this format holds `dims` components.
    pub fn check_holds(self, dims: usize) -> Result<()> {
        if dims > self.channels() {
            return Err(Error::invalid(format!(
                "KTX2 format {} has {} channel{}, the mask has d = {dims}",
                self.name(),
                self.channels(),
                if self.channels() == 1 { "" } else { "s" }
            )));
        }
        Ok(())
    }

    /// Encodes one value into its channel's little-endian bytes.
    pub fn encode(self, v: f32, out: &mut Vec<u8>) {
        match self.bits() {
            8 => out.push(quantize(v, 8) as u8),
            16 => out.extend_from_slice(&(quantize(v, 16) as u16).to_le_bytes()),
            _ => out.extend_from_slice(&v.to_le_bytes()),
        }
    }
}

/// The UNORM level of v with b bits: round(v (2^b - 1)), v clamped to [0, 1].
pub fn quantize(v: f32, bits: u32) -> u32 {
    let top = ((1u64 << bits) - 1) as f64;
    (v.clamp(0.0, 1.0) as f64 * top).round() as u32
}

/// The texels of a mask in a format: layer (frame, sample) by layer, row by
/// row, each texel's channels in order.
pub fn texels(mask: &Mask, format: Format) -> Result<Vec<u8>> {
    mask.check()?;
    let t = mask.tile;
    format.check_holds(t.dims)?;
    let mut out = Vec::with_capacity(t.width * t.height * t.frames * t.spp * format.texel_bytes());
    for frame in 0..t.frames {
        for s in 0..t.spp {
            for y in 0..t.height {
                for x in 0..t.width {
                    let sample = mask.sample(x, y, frame, s);
                    for c in 0..format.channels() {
                        format.encode(sample.get(c).copied().unwrap_or(0.0), &mut out);
                    }
                }
            }
        }
    }
    Ok(out)
}

const IDENTIFIER: [u8; 12] = [0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A];
const HEADER_BYTES: usize = 80;
const LEVEL_INDEX_BYTES: usize = 24;

/// The basic data format descriptor of `format` (with its total-size word).
fn descriptor(format: Format) -> Vec<u8> {
    let channels = format.channels();
    let block = 24 + 16 * channels;
    let mut d = Vec::with_capacity(4 + block);
    d.extend_from_slice(&(4 + block as u32).to_le_bytes()); // dfdTotalSize
    d.extend_from_slice(&0u32.to_le_bytes()); // vendorId 0 (Khronos), descriptorType 0 (basic)
    d.extend_from_slice(&2u16.to_le_bytes()); // versionNumber (KDFS 1.3)
    d.extend_from_slice(&(block as u16).to_le_bytes()); // descriptorBlockSize
    d.extend_from_slice(&[1, 1, 1, 0]); // colorModel RGBSDA, primaries BT709, transfer LINEAR, flags
    d.extend_from_slice(&[0, 0, 0, 0]); // texelBlockDimension0..3: 1 x 1 x 1 x 1
    d.push(format.texel_bytes() as u8); // bytesPlane0
    d.extend_from_slice(&[0; 7]); // bytesPlane1..7
    let bits = format.bits();
    for c in 0..channels {
        let channel_id: u8 = if c == 3 { 15 } else { c as u8 }; // R, G, B, A
        let qualifiers: u8 = if format.is_float() { 0x80 | 0x40 } else { 0 }; // FLOAT | SIGNED
        d.extend_from_slice(&((c as u32 * bits) as u16).to_le_bytes()); // bitOffset
        d.push((bits - 1) as u8); // bitLength - 1
        d.push(channel_id | qualifiers);
        d.extend_from_slice(&[0, 0, 0, 0]); // samplePosition0..3
        let (lower, upper) = if format.is_float() {
            (0xBF80_0000u32, 0x3F80_0000u32)
        } else {
            (0, ((1u64 << bits) - 1) as u32)
        };
        d.extend_from_slice(&lower.to_le_bytes());
        d.extend_from_slice(&upper.to_le_bytes());
    }
    d
}

/// Key/value data: entries sorted by key, each padded to 4 bytes; a NUL in a
/// key or value (which ends it in the file) is refused.
fn key_values(entries: &[(String, String)]) -> Result<Vec<u8>> {
    if let Some((k, v)) = entries.iter().find(|(k, v)| k.contains('\0') || v.contains('\0')) {
        return Err(Error::invalid(format!("the mask's provenance {k:?} = {v:?} holds a NUL, which KTX2 cannot")));
    }
    let mut sorted: Vec<&(String, String)> = entries.iter().collect();
    sorted.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let mut out = Vec::new();
    for (k, v) in sorted {
        let length = k.len() + 1 + v.len() + 1;
        out.extend_from_slice(&(length as u32).to_le_bytes());
        out.extend_from_slice(k.as_bytes());
        out.push(0);
        out.extend_from_slice(v.as_bytes());
        out.push(0);
        while out.len() % 4 != 0 {
            out.push(0);
        }
    }
    Ok(out)
}

/// The mask as a KTX2 file in `format`.
pub fn encode(mask: &Mask, format: Format) -> Result<Vec<u8>> {
    let t = mask.tile;
    let data = texels(mask, format)?;
    let layers = t.frames * t.spp;
    let mut kv: Vec<(String, String)> =
        vec![("KTXwriter".into(), format!("fsot {}", env!("CARGO_PKG_VERSION")))];
    kv.push(("fsot.tile".into(), format!("{}x{}x{}", t.width, t.height, t.frames)));
    kv.push(("fsot.spp".into(), t.spp.to_string()));
    kv.push(("fsot.dims".into(), t.dims.to_string()));
    kv.push(("fsot.layers".into(), "layer = frame * spp + sample".into()));
    kv.push((
        "fsot.quantisation".into(),
        if format.is_float() {
            "exact".into()
        } else {
            format!("round(v * {}), read as q / {0}, 1.0 wraps to 0.0", (1u64 << format.bits()) - 1)
        },
    ));
    for (k, v) in &mask.meta {
        kv.push((format!("fsot.{k}"), v.clone()));
    }
    let dfd = descriptor(format);
    let kvd = key_values(&kv)?;
    let dfd_offset = HEADER_BYTES + LEVEL_INDEX_BYTES;
    let kvd_offset = dfd_offset + dfd.len();
    // Level data aligned to lcm(texel bytes, 4).
    let align = match format.texel_bytes() {
        b if b % 4 == 0 => b,
        _ => 4,
    };
    let data_offset = (kvd_offset + kvd.len()).div_ceil(align) * align;
    let mut out = Vec::with_capacity(data_offset + data.len());
    out.extend_from_slice(&IDENTIFIER);
    for v in [
        format.vk_format(),
        format.bits() / 8, // typeSize
        t.width as u32,
        t.height as u32,
        0, // pixelDepth
        layers as u32,
        1, // faceCount
        1, // levelCount
        0, // supercompressionScheme
        dfd_offset as u32,
        dfd.len() as u32,
        kvd_offset as u32,
        kvd.len() as u32,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteOffset
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteLength
    debug_assert_eq!(out.len(), HEADER_BYTES);
    for v in [data_offset as u64, data.len() as u64, data.len() as u64] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    out.resize(data_offset, 0);
    out.extend_from_slice(&data);
    Ok(out)
}

/// Writes the mask as KTX2 through an atomic file.
pub fn write(mask: &Mask, format: Format, out: AtomicFile) -> Result<()> {
    out.commit(&encode(mask, format)?)
}

/// The format asked for (`None` or `auto`: the default for d), checked to hold d.
pub fn format_for(dims: usize, format: Option<&str>) -> Result<Format> {
    let f = match format {
        Some(name) if name != "auto" => Format::parse(name)?,
        _ => Format::default_for(dims)?,
    };
    f.check_holds(dims)?;
    Ok(f)
}
