//! Masks as OpenEXR files.
//!
//! One part (layer) per frame, named `frame0000`, `frame0001`, ... in frame order,
//! each W x H with 32-bit float channels:
//! - spp = 1 and d <= 4: channels `R`, `G`, `B`, `A` hold dimensions 0..d, so
//!   viewers and texture loaders read the mask as an ordinary image;
//! - otherwise: channel `sSS.dK` holds dimension K of sample SS (two digits), e.g.
//!   `s03.d5`.
//!
//! Every part carries the provenance as text attributes named `fsot.*` (kernel and
//! parameters, seed, iterations, fsot's version, method) plus `fsot.spp` and
//! `fsot.dims`.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use exr::block::chunk::Chunk;
use exr::block::UncompressedBlock;
use exr::meta::header::Header;
use exr::prelude::*;

use crate::core::mask::Mask;
use crate::core::tile::{Tile, MAX_DIMS, MAX_SPP};
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;

const RGBA: [&str; 4] = ["R", "G", "B", "A"];

/// Channel name of dimension `k` of sample `s` for a tile.
pub fn channel_name(tile: &Tile, s: usize, k: usize) -> String {
    if tile.spp == 1 && tile.dims <= 4 {
        RGBA[k].to_string()
    } else {
        format!("s{s:02}.d{k}")
    }
}

/// Encodes a mask as EXR bytes (an error for a mask `Mask::check` refuses).
pub fn encode(mask: &Mask) -> Result<Vec<u8>> {
    mask.check()?;
    encode_unchecked(mask)
}

/// Encodes a mask of a valid tile whatever its values: how the reader's tests
/// make files with values outside [0, 1).
#[doc(hidden)]
pub fn encode_unchecked(mask: &Mask) -> Result<Vec<u8>> {
    mask.tile.check()?;
    if mask.samples.len() != mask.tile.values() {
        return Err(Error::invalid("a mask's values do not fill its tile"));
    }
    let tile = mask.tile;
    let (w, h) = (tile.width, tile.height);
    let mut layers = Vec::with_capacity(tile.frames);
    let mut attributes: HashMap<Text, AttributeValue> = HashMap::new();
    // EXR text is Latin-1: other characters are refused, not a panic.
    let text = |t: &str| {
        Text::new_or_none(t).ok_or_else(|| {
            Error::invalid(format!("the mask's provenance {t:?} holds characters an EXR attribute cannot (Latin-1 only)"))
        })
    };
    for (k, v) in &mask.meta {
        attributes.insert(text(&format!("fsot.{k}"))?, AttributeValue::Text(text(v)?));
    }
    attributes
        .insert(Text::from("fsot.spp"), AttributeValue::Text(Text::from(tile.spp.to_string().as_str())));
    attributes
        .insert(Text::from("fsot.dims"), AttributeValue::Text(Text::from(tile.dims.to_string().as_str())));
    for t in 0..tile.frames {
        let mut channels = SmallVec::new();
        for s in 0..tile.spp {
            for k in 0..tile.dims {
                let mut data = Vec::with_capacity(w * h);
                for y in 0..h {
                    for x in 0..w {
                        data.push(mask.sample(x, y, t, s)[k]);
                    }
                }
                channels.push(AnyChannel::new(channel_name(&tile, s, k).as_str(), FlatSamples::F32(data)));
            }
        }
        let mut layer_attributes = LayerAttributes::named(format!("frame{t:04}").as_str());
        layer_attributes.other = attributes.clone();
        layers.push(Layer::new(
            (w, h),
            layer_attributes,
            // Chunks in increasing order: compressed in parallel, written in
            // the order they would be one at a time (unspecified, the file's
            // bytes depend on which thread finishes first).
            Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS },
            AnyChannels::sort(channels),
        ));
    }
    let image = Image::from_layers(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))), layers);
    let mut bytes = Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| Error::invalid(format!("EXR encoding failed: {e}")))?;
    let mut bytes = bytes.into_inner();
    sort_attributes(&mut bytes)?;
    Ok(bytes)
}

/// Puts every header's attributes in name order, so that one mask always gives
/// the same bytes: the exr crate writes a layer's other attributes from a
/// HashMap, whose order changes from run to run. A header keeps its length,
/// so the offset tables after the headers stay valid. The layout (OpenEXR file
/// layout): magic and version (8 bytes); headers, each a run of attributes
/// (name and type as null-terminated strings, a little-endian i32 size, the
/// value) ended by a null byte; in a multi-part file (version bit 12) the run
/// of headers ends with one more null byte.
fn sort_attributes(bytes: &mut [u8]) -> Result<()> {
    let bad = || Error::invalid("EXR encoding produced a header fsot cannot read back");
    let multipart = bytes.get(4..8).ok_or_else(bad)?[1] & 0x10 != 0;
    let mut at = 8;
    loop {
        let start = at;
        let mut attributes: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
        while *bytes.get(at).ok_or_else(bad)? != 0 {
            let name_end = string_end(bytes, at).ok_or_else(bad)?;
            let type_end = string_end(bytes, name_end).ok_or_else(bad)?;
            let size = bytes.get(type_end..type_end + 4).ok_or_else(bad)?;
            let size = i32::from_le_bytes([size[0], size[1], size[2], size[3]]);
            let end =
                usize::try_from(size).ok().and_then(|s| (type_end + 4).checked_add(s)).ok_or_else(bad)?;
            if end > bytes.len() {
                return Err(bad());
            }
            attributes.push((bytes[at..name_end].to_vec(), at..end));
            at = end;
        }
        attributes.sort_by(|a, b| a.0.cmp(&b.0));
        let sorted: Vec<u8> = attributes.iter().flat_map(|(_, r)| bytes[r.clone()].to_vec()).collect();
        bytes[start..at].copy_from_slice(&sorted);
        at += 1; // the header's null byte
        if !multipart || *bytes.get(at).ok_or_else(bad)? == 0 {
            return Ok(());
        }
    }
}

/// The index past the null byte that ends the string at `at`.
fn string_end(bytes: &[u8], at: usize) -> Option<usize> {
    bytes.get(at..)?.iter().position(|&b| b == 0).map(|i| at + i + 1)
}

/// Writes a mask to `out` atomically.
pub fn write(mask: &Mask, out: AtomicFile) -> Result<()> {
    let bytes = encode(mask)?;
    out.commit(&bytes)
}

/// Reads and validates a mask: parts named frame0000.. in order, one size, a
/// complete channel layout, every value finite and in [0, 1).
pub fn read(path: &Path) -> Result<Mask> {
    let bytes = crate::io::read_regular(path).map_err(|e| Error::bad_file(path, format!("cannot read: {e}")))?;
    decode(&bytes).map_err(|reason| Error::bad_file(path, reason))
}

/// How many times its own size a file may expand to. Deflate, the densest of
/// EXR's codecs, tops out near 1032:1, so a valid file stays well inside this.
const MAX_EXPANSION: usize = 4096;

/// Reads the headers alone and refuses a file whose pixels would take more memory
/// than its bytes could hold (or than the largest tile), before anything is
/// allocated for them: the exr crate sizes its buffers from the header.
fn check_promised_size(bytes: &[u8]) -> std::result::Result<(), String> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| format!("not a readable EXR file ({e})"))?;
    let mut promised = 0usize;
    for header in &meta.headers {
        let part = header
            .layer_size
            .0
            .checked_mul(header.layer_size.1)
            .and_then(|pixels| pixels.checked_mul(header.channels.bytes_per_pixel))
            .and_then(|b| promised.checked_add(b));
        promised = part.unwrap_or(usize::MAX);
    }
    let largest_tile = crate::core::tile::MAX_VALUES * 4;
    let limit = bytes.len().saturating_mul(MAX_EXPANSION).min(largest_tile);
    if promised > limit {
        return Err(format!(
            "the header promises {promised} bytes of pixels from a file of {} bytes (at most {limit} \
             accepted); refused before reading the pixels",
            bytes.len()
        ));
    }
    Ok(())
}

/// Decodes EXR bytes into a mask; the error is a reason for the user.
///
/// Block by block: the full-resolution blocks of every frame must each arrive
/// exactly once (a file whose offset table or chunks name a block twice, or leave
/// one out, is refused rather than read with zeros where the block was missing),
/// and only then are they decompressed into the mask.
pub fn decode(bytes: &[u8]) -> std::result::Result<Mask, String> {
    check_promised_size(bytes)?;
    let unreadable = |e: exr::error::Error| format!("not a readable EXR file ({e})");
    let reader = exr::block::read(Cursor::new(bytes), false).map_err(unreadable)?;
    let meta = reader.meta_data().clone();
    let (tile, layout) = frames_of(&meta.headers)?;
    let chunks = reader
        .filter_chunks(false, |_, block, _| block.is_largest_resolution_level())
        .map_err(unreadable)?
        .collect::<exr::error::Result<Vec<Chunk>>>()
        .map_err(unreadable)?;
    check_every_block_once(&meta.headers, &chunks)?;
    let (w, spp, dims) = (tile.width, tile.spp, tile.dims);
    let mut samples = vec![0.0f32; tile.values()];
    for chunk in chunks {
        let block = UncompressedBlock::decompress_chunk(chunk, &meta, false).map_err(unreadable)?;
        let t = block.index.layer;
        let header = &meta.headers[t];
        for line in block.lines(&header.channels) {
            let (s, k) = layout[line.location.channel];
            let name = || channel_name(&tile, s, k);
            let values: Vec<f32> = match header.channels.list[line.location.channel].sample_type {
                SampleType::F32 => line.read_samples::<f32>().collect::<exr::error::Result<_>>(),
                SampleType::F16 => line.read_samples::<f16>().map(|v| v.map(f16::to_f32)).collect(),
                SampleType::U32 => return Err(format!("channel {} holds integers, not floats", name())),
            }
            .map_err(unreadable)?;
            let Vec2(x0, y) = line.location.position;
            for (i, &v) in values.iter().enumerate() {
                let x = x0 + i;
                if x >= w || y >= tile.height {
                    return Err(format!("frame {t}: a block reaches past its {w}x{} pixels", tile.height));
                }
                if !(v.is_finite() && (0.0..1.0).contains(&v)) {
                    return Err(format!(
                        "frame {t}, pixel ({x}, {y}), channel {}: value {v} is outside [0, 1)",
                        name()
                    ));
                }
                samples[(tile.pixel_index(x, y, t) * spp + s) * dims + k] = v;
            }
        }
    }
    let mut meta: Vec<(String, String)> = meta.headers[0]
        .own_attributes
        .other
        .iter()
        .filter_map(|(k, v)| {
            let key = k.to_string();
            let key = key.strip_prefix("fsot.")?;
            if key == "spp" || key == "dims" {
                return None;
            }
            match v {
                AttributeValue::Text(t) => Some((key.to_string(), t.to_string())),
                _ => None,
            }
        })
        .collect();
    meta.sort();
    Ok(Mask { tile, samples, meta })
}

/// The tile the parts describe, and for each channel index of a part (every part
/// lists the same names, in the file's order) the (sample, dimension) it holds:
/// parts named frame0000.. in order, one size, a complete channel layout of full
/// resolution floats.
fn frames_of(headers: &[Header]) -> std::result::Result<(Tile, Vec<(usize, usize)>), String> {
    let first = headers.first().ok_or("the file holds no frames")?;
    let size = first.layer_size;
    let names: Vec<String> = first.channels.list.iter().map(|c| c.name.to_string()).collect();
    let (spp, dims) = layout_of(&names)?;
    let tile = Tile::new(size.0, size.1, headers.len(), spp, dims).map_err(|e| e.to_string())?;
    let mut layout = vec![(0, 0); names.len()];
    for s in 0..spp {
        for k in 0..dims {
            let want = channel_name(&tile, s, k);
            let at = names.iter().position(|n| *n == want).ok_or_else(|| format!("frame 0 lacks channel {want}"))?;
            layout[at] = (s, k);
        }
    }
    for (t, header) in headers.iter().enumerate() {
        let expected = format!("frame{t:04}");
        let name = header.own_attributes.layer_name.as_ref().map(|n| n.to_string()).unwrap_or_default();
        if name != expected {
            return Err(format!("part {t} is named {name:?}; expected {expected:?} (frames in order)"));
        }
        if header.layer_size != size {
            return Err(format!(
                "frame {t} is {}x{}, frame 0 is {}x{}",
                header.layer_size.0, header.layer_size.1, size.0, size.1
            ));
        }
        if header.deep {
            return Err(format!("frame {t} holds deep data"));
        }
        let list = &header.channels.list;
        if list.len() != names.len() {
            return Err(format!("frame {t} has {} channels, frame 0 has {}", list.len(), names.len()));
        }
        for (channel, want) in list.iter().zip(&names) {
            if channel.name.to_string() != *want {
                return Err(format!("frame {t} lacks channel {want}"));
            }
            if channel.sampling != Vec2(1, 1) {
                return Err(format!("channel {want} of frame {t} is subsampled"));
            }
        }
    }
    Ok((tile, layout))
}

/// Every full-resolution block of every part arrives exactly once.
fn check_every_block_once(headers: &[Header], chunks: &[Chunk]) -> std::result::Result<(), String> {
    let mut seen = std::collections::HashSet::new();
    let mut found = vec![0usize; headers.len()];
    for chunk in chunks {
        let t = chunk.layer_index;
        let header = headers.get(t).ok_or_else(|| format!("a block names part {t}, of {}", headers.len()))?;
        let block = header
            .get_block_data_indices(&chunk.compressed_block)
            .map_err(|e| format!("not a readable EXR file ({e})"))?;
        if !block.is_largest_resolution_level() {
            return Err(format!("frame {t}: a block of a smaller resolution level stands for a full one"));
        }
        if !seen.insert((t, block.tile_index)) {
            let Vec2(x, y) = block.tile_index;
            return Err(format!("frame {t}: block ({x}, {y}) appears twice (and another is missing)"));
        }
        found[t] += 1;
    }
    for (t, header) in headers.iter().enumerate() {
        let expected = header.blocks_increasing_y_order().filter(|b| b.location.is_largest_resolution_level()).count();
        if found[t] != expected {
            return Err(format!("frame {t} holds {} of its {expected} blocks of pixels", found[t]));
        }
    }
    Ok(())
}

/// (spp, dims) from a frame's channel names.
fn layout_of(names: &[String]) -> std::result::Result<(usize, usize), String> {
    let rgba: Vec<usize> = names.iter().filter_map(|n| RGBA.iter().position(|c| c == n)).collect();
    if !names.is_empty() && rgba.len() == names.len() {
        let dims = names.len();
        for k in 0..dims {
            if !rgba.contains(&k) {
                return Err(format!("channels {names:?}: with {dims} channels expected {:?}", &RGBA[..dims]));
            }
        }
        return Ok((1, dims));
    }
    let mut spp = 0;
    let mut dims = 0;
    for n in names {
        let parsed = n
            .strip_prefix('s')
            .and_then(|r| r.split_once(".d"))
            .and_then(|(s, k)| Some((s.parse::<usize>().ok()?, k.parse::<usize>().ok()?)));
        let (s, k) = parsed
            .ok_or_else(|| format!("channel {n:?} is neither R/G/B/A nor sSS.dK (sample SS, dimension K)"))?;
        if s >= MAX_SPP || k >= MAX_DIMS {
            return Err(format!(
                "channel {n:?}: a mask holds at most {MAX_SPP} samples of {MAX_DIMS} dimensions"
            ));
        }
        spp = spp.max(s + 1);
        dims = dims.max(k + 1);
    }
    if spp * dims != names.len() {
        return Err(format!("channels {names:?} do not cover {spp} samples x {dims} dimensions"));
    }
    Ok((spp, dims))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_names_past_the_largest_tile_are_refused_not_overflowed() {
        for names in [
            vec!["s18446744073709551615.d0"],
            vec!["s0.d18446744073709551615"],
            vec!["s9223372036854775808.d1", "s0.d0"],
            vec!["s64.d0"],
            vec!["s00.d8"],
        ] {
            let names: Vec<String> = names.into_iter().map(String::from).collect();
            let reason = layout_of(&names).unwrap_err();
            assert!(reason.contains("at most 64 samples of 8 dimensions"), "{names:?}: {reason}");
        }
        let names: Vec<String> = ["s63.d7"].into_iter().map(String::from).collect();
        assert!(layout_of(&names).unwrap_err().contains("do not cover 64 samples x 8 dimensions"));
    }
}
