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

use std::path::Path;

use crate::core::mask::Mask;
use crate::core::tile::Tile;
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

/// The provenance keys `encode` writes from the tile, not from the mask's `meta`.
const STRUCTURAL_KEYS: [&str; 5] = ["fsot.tile", "fsot.spp", "fsot.dims", "fsot.layers", "fsot.quantisation"];

/// Reads a mask from a KTX2 array texture (fsot's, or one laid out the same
/// way: see `decode`).
pub fn read(path: &Path) -> Result<Mask> {
    let bytes = crate::io::read_regular(path).map_err(|e| Error::bad_file(path, format!("cannot read: {e}")))?;
    decode(&bytes).map_err(|reason| Error::bad_file(path, reason))
}

/// Decodes a KTX2 file into a mask; the error is a reason for the user. The
/// file is a 2-D array texture in one of `Format::ALL`, with no
/// supercompression; level 0 is read. Layer `t * spp + s` holds sample s of
/// frame t, spp and d from `fsot.spp` and `fsot.dims` (default 1 and the
/// format's channels); a UNORM level q reads q / (2^b - 1), the top level
/// wrapping to 0, and a float must lie in [0, 1). The `fsot.*` provenance
/// entries come back as the mask's `meta`.
pub fn decode(bytes: &[u8]) -> std::result::Result<Mask, String> {
    let file = Parsed::of(bytes).map_err(|e| format!("not a readable KTX2 file ({e})"))?;
    let vk = file.field(3);
    let format = Format::ALL.into_iter().find(|f| f.vk_format() == vk).ok_or_else(|| {
        let names: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
        format!("VkFormat {vk} is not one fsot reads ({})", names.join(", "))
    })?;
    let [type_size, width, height, depth, layer_count, faces, _, supercompression] =
        std::array::from_fn(|i| file.field(4 + i));
    if supercompression != 0 {
        return Err("its levels are supercompressed; fsot reads plain ones".into());
    }
    if height == 0 || depth != 0 || faces != 1 {
        return Err(format!("a {width}x{height}x{depth} texture of {faces} faces, not a 2-D array texture"));
    }
    if type_size != format.bits() / 8 {
        return Err(format!("typeSize {type_size} for {}, which has {}-bit channels", format.name(), format.bits()));
    }
    let entries = file.entries;
    let entry = |key: &str| entries.iter().find(|(k, _)| *k == key).map(|(_, v)| v.as_str());
    let count = |key: &str, default: usize| match entry(key) {
        None => Ok(default),
        Some(v) => v.parse::<usize>().map_err(|_| format!("{key} = {v:?} is not a count")),
    };
    let (spp, dims) = (count("fsot.spp", 1)?, count("fsot.dims", format.channels())?);
    if dims > format.channels() {
        return Err(format!("fsot.dims = {dims}, but {} has {} channels", format.name(), format.channels()));
    }
    let layers = layer_count.max(1) as usize;
    if spp == 0 || layers % spp != 0 {
        return Err(format!("{layers} layers do not split into frames of fsot.spp = {spp} samples"));
    }
    let (width, height) = (width as usize, height as usize);
    let tile = Tile::new(width, height, layers / spp, spp, dims).map_err(|e| e.to_string())?;
    let size = format!("{width}x{height}x{}", tile.frames);
    if let Some(said) = entry("fsot.tile").filter(|said| *said != size) {
        return Err(format!("fsot.tile says {said}, the texture is {size}"));
    }
    let level = file.level;
    let texel = format.texel_bytes();
    let want = tile.pixels() * spp * texel;
    if level.len() != want {
        return Err(format!(
            "level 0 holds {} bytes; {layers} layers of {width}x{height} {} texels take {want}",
            level.len(),
            format.name()
        ));
    }
    let top = ((1u64 << format.bits()) - 1) as f64;
    let channel_bytes = format.bits() as usize / 8;
    let mut samples = vec![0.0f32; tile.values()];
    for (i, texel_bytes) in level.chunks_exact(texel).enumerate() {
        let (layer, pixel) = (i / (width * height), i % (width * height));
        let (t, s, x, y) = (layer / spp, layer % spp, pixel % width, pixel / width);
        for (c, raw) in texel_bytes.chunks_exact(channel_bytes).take(dims).enumerate() {
            let v = match format.bits() {
                8 => wrap(raw[0] as f64 / top),
                16 => wrap(u16::from_le_bytes([raw[0], raw[1]]) as f64 / top),
                _ => f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]),
            };
            if !(v.is_finite() && (0.0..1.0).contains(&v)) {
                return Err(format!("frame {t}, sample {s}, pixel ({x}, {y}), channel {c}: value {v} is outside [0, 1)"));
            }
            samples[(tile.pixel_index(x, y, t) * spp + s) * dims + c] = v;
        }
    }
    let mut meta: Vec<(String, String)> = entries
        .iter()
        .filter(|(k, _)| !STRUCTURAL_KEYS.contains(&k.as_str()))
        .filter_map(|(k, v)| Some((k.strip_prefix("fsot.")?.to_string(), v.clone())))
        .collect();
    meta.sort();
    Ok(Mask { tile, samples, meta })
}

/// The parts of a KTX2 file `decode` reads, bounds-checked: the header's
/// 32-bit fields, level 0's bytes and the key/value entries (values without
/// their closing NUL).
struct Parsed<'a> {
    bytes: &'a [u8],
    level: &'a [u8],
    entries: Vec<(String, String)>,
}

impl<'a> Parsed<'a> {
    fn of(bytes: &'a [u8]) -> std::result::Result<Self, &'static str> {
        if bytes.len() < HEADER_BYTES + LEVEL_INDEX_BYTES || bytes[..12] != IDENTIFIER {
            return Err("no KTX 20 identifier and header");
        }
        let mut file = Self { bytes, level: &[], entries: Vec::new() };
        let u64_at = |at: usize| u64::from_le_bytes(std::array::from_fn(|i| bytes[at + i]));
        let range = |offset: u64, length: u64| -> std::result::Result<&'a [u8], &'static str> {
            let end = offset.checked_add(length).filter(|&e| e <= bytes.len() as u64).ok_or("a part past its end")?;
            Ok(&bytes[offset as usize..end as usize])
        };
        // Level 0's index entry follows the header, whatever the level count.
        file.level = range(u64_at(HEADER_BYTES), u64_at(HEADER_BYTES + 8))?;
        let mut kvd = range(file.field(14) as u64, file.field(15) as u64)?;
        while kvd.len() >= 4 {
            let length = u32::from_le_bytes(std::array::from_fn(|i| kvd[i])) as usize;
            let end = length.checked_add(4).ok_or("a key/value entry past its data")?;
            let entry = kvd.get(4..end).ok_or("a key/value entry past its data")?;
            let nul = entry.iter().position(|&b| b == 0).ok_or("a key without its NUL")?;
            let value = &entry[nul + 1..];
            let value = value.strip_suffix(&[0]).unwrap_or(value);
            let key = std::str::from_utf8(&entry[..nul]).map_err(|_| "a key that is not UTF-8")?;
            file.entries.push((key.to_string(), String::from_utf8_lossy(value).into_owned()));
            kvd = kvd.get(end.div_ceil(4) * 4..).unwrap_or(&[]);
        }
        Ok(file)
    }

    /// The header's 32-bit field `i` (0: the identifier's first word; 3: vkFormat).
    fn field(&self, i: usize) -> u32 {
        u32::from_le_bytes(std::array::from_fn(|k| self.bytes[4 * i + k]))
    }
}

/// A UNORM value in [0, 1] as a point of [0, 1): the top level, 1.0, is 0.0 on the torus.
fn wrap(v: f64) -> f32 {
    let v = v as f32;
    if v >= 1.0 {
        0.0
    } else {
        v
    }
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
