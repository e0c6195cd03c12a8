//! Mask files: EXR round trips, PNG slices, and validation of what is read.

use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::atomic::AtomicFile;
use fsot::io::{exr, png as png_io};

#[test]
fn exr_round_trips_every_layout_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for (spp, dims) in [(1, 1), (1, 2), (1, 3), (1, 4), (1, 5), (2, 2), (3, 8), (16, 1)] {
        let tile = Tile::new(5, 3, 4, spp, dims).unwrap();
        let mut mask = Mask::white(tile, 99);
        mask.set_meta("kernel", "taa (sigma = 2.1, alpha = 0.1)");
        mask.set_meta("iterations", "12");
        let path = dir.path().join(format!("m{spp}_{dims}.exr"));
        exr::write(&mask, AtomicFile::create(&path).unwrap()).unwrap();
        let back = exr::read(&path).unwrap();
        assert_eq!(back.tile, tile);
        assert_eq!(bits(&back.samples), bits(&mask.samples));
        assert_eq!(back.meta("kernel"), Some("taa (sigma = 2.1, alpha = 0.1)"));
        assert_eq!(back.meta("iterations"), Some("12"));
    }
}

#[test]
fn one_mask_always_encodes_to_the_same_exr_bytes() {
    // Attributes in name order: the exr crate alone writes them in a HashMap's
    // order, which changes from one encoding to the next. Frames in several parts
    // and chunks in increasing order: compressed on several threads, they would
    // be written in the order the threads finish.
    for frames in [1, 3, 8] {
        let tile = Tile::new(4, 3, frames, 2, 3).unwrap();
        let mut mask = Mask::white(tile, 5);
        for (k, v) in
            [("kernel", "taa"), ("iterations", "7"), ("seed", "5"), ("method", "fsot"), ("slices", "9")]
        {
            mask.set_meta(k, v);
        }
        let first = exr::encode(&mask).unwrap();
        for _ in 0..32 {
            assert!(exr::encode(&mask).unwrap() == first, "{frames} frames: the bytes changed");
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.exr");
        std::fs::write(&path, &first).unwrap();
        let back = exr::read(&path).unwrap();
        assert_eq!(bits(&back.samples), bits(&mask.samples));
        assert_eq!(back.meta("slices"), Some("9"));
    }
}

#[test]
fn exr_frames_are_parts_named_in_order_with_rgba_channels() {
    let tile = Tile::new(4, 4, 3, 1, 2).unwrap();
    let mask = Mask::white(tile, 1);
    let bytes = exr::encode(&mask).unwrap();
    let meta = ::exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(&bytes), false).unwrap();
    let names: Vec<String> =
        meta.headers.iter().map(|h| h.own_attributes.layer_name.as_ref().unwrap().to_string()).collect();
    assert_eq!(names, ["frame0000", "frame0001", "frame0002"]);
    for h in &meta.headers {
        let channels: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
        assert_eq!(channels, ["G", "R"]); // EXR stores channels sorted
        assert_eq!(h.channels.list[0].sample_type, ::exr::meta::attribute::SampleType::F32);
        assert!(h.own_attributes.other.contains_key(&::exr::meta::attribute::Text::from("fsot.seed")));
    }
}

#[test]
fn png_slices_hold_16_bit_quantised_values() {
    let dir = tempfile::tempdir().unwrap();
    let tile = Tile::new(6, 5, 2, 1, 2).unwrap();
    let mask = Mask::white(tile, 4);
    let files = png_io::write(&mask, dir.path(), 16).unwrap();
    assert_eq!(files, ["frame0000.png", "frame0001.png"]);
    let decoder = ::png::Decoder::new(std::fs::File::open(dir.path().join("frame0001.png")).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (6, 5));
    assert_eq!(info.bit_depth, ::png::BitDepth::Sixteen);
    assert_eq!(info.color_type, ::png::ColorType::Rgb);
    for y in 0..5 {
        for x in 0..6 {
            let i = (y * 6 + x) * 6;
            let r = u16::from_be_bytes([buf[i], buf[i + 1]]);
            let g = u16::from_be_bytes([buf[i + 2], buf[i + 3]]);
            let b = u16::from_be_bytes([buf[i + 4], buf[i + 5]]);
            let s = mask.sample(x, y, 1, 0);
            assert_eq!(b, 0, "no third dimension");
            // Level k stands for the values in [k, k + 1) / 65536: the sample within
            // half a level of its centre.
            for (level, value) in [(r, s[0]), (g, s[1])] {
                assert!(((level as f32 + 0.5) / 65536.0 - value).abs() <= 0.5 / 65536.0 + 1e-7);
            }
        }
    }
    // Layouts beyond RGBA get one file per sample and group of four dimensions.
    let wide = Mask::white(Tile::new(2, 2, 1, 2, 5).unwrap(), 4);
    let files = png_io::write(&wide, &dir.path().join("wide"), 16).unwrap();
    assert_eq!(
        files,
        [
            "frame0000_s00_d0-3.png",
            "frame0000_s00_d4-4.png",
            "frame0000_s01_d0-3.png",
            "frame0000_s01_d4-4.png"
        ]
    );
}

#[test]
fn png_slices_hold_8_bit_values_read_at_the_centre_of_their_level() {
    let dir = tempfile::tempdir().unwrap();
    let mask = Mask::white(Tile::new(7, 3, 1, 1, 1).unwrap(), 9);
    png_io::write(&mask, dir.path(), 8).unwrap();
    let decoder = ::png::Decoder::new(std::fs::File::open(dir.path().join("frame0000.png")).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.bit_depth, info.color_type), (::png::BitDepth::Eight, ::png::ColorType::Grayscale));
    for y in 0..3 {
        for x in 0..7 {
            let v = mask.sample(x, y, 0, 0)[0] as f64;
            let read = (buf[y * 7 + x] as f64 + 0.5) / 256.0;
            assert!((read - v).abs() <= 0.5 / 256.0 + 1e-9, "{read} against {v}");
        }
    }
    assert!(png_io::write(&mask, &dir.path().join("b"), 12).is_err());
}

#[test]
fn reading_rejects_bad_masks_with_reasons() {
    let dir = tempfile::tempdir().unwrap();
    let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
    let good = exr::encode(&Mask::white(tile, 3)).unwrap();

    let missing = exr::read(&dir.path().join("nope.exr")).unwrap_err().to_string();
    assert!(missing.contains("cannot read"), "{missing}");
    let garbage = exr::decode(b"this is not an exr file").unwrap_err();
    assert!(garbage.contains("not a readable EXR"), "{garbage}");
    let truncated = exr::decode(&good[..good.len() / 2]).unwrap_err();
    assert!(truncated.contains("not a readable EXR"), "{truncated}");

    for (bad, what) in [(f32::NAN, "NaN"), (1.0, "1"), (-0.25, "-0.25"), (f32::INFINITY, "inf")] {
        let mut mask = Mask::white(tile, 3);
        mask.samples[5] = bad;
        assert!(exr::encode(&mask).is_err(), "{what} encoded");
        let err = exr::decode(&exr::encode_unchecked(&mask).unwrap()).unwrap_err();
        assert!(err.contains("outside [0, 1)") && err.contains(what), "{err}");
    }
}

/// A two-frame file of one block a frame: the byte offset of its offset tables
/// (two u64s, the first pointing just past them) and of each frame's chunk.
fn one_block_frames(bytes: &[u8]) -> (usize, [usize; 2]) {
    let u64_at = |p: usize| u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap()) as usize;
    let table = (0..bytes.len() - 16).find(|&p| u64_at(p) == p + 16).expect("the offset tables");
    (table, [u64_at(table), u64_at(table + 8)])
}

#[test]
fn a_file_that_names_one_block_twice_is_refused_not_read_with_zeros_for_the_missing_one() {
    let good = exr::encode(&Mask::white(Tile::new(4, 4, 2, 1, 2).unwrap(), 3)).unwrap();
    let (table, chunks) = one_block_frames(&good);
    assert!(exr::decode(&good).is_ok());
    // The offset table sends frame 1's entry to frame 0's chunk.
    let mut bytes = good.clone();
    bytes.copy_within(table..table + 8, table + 8);
    let reason = exr::decode(&bytes).unwrap_err();
    assert!(reason.contains("appears twice"), "{reason}");
    // Frame 1's chunk says it belongs to part 0 (a chunk starts with its part).
    let mut bytes = good.clone();
    bytes[chunks[1]..chunks[1] + 4].copy_from_slice(&0i32.to_le_bytes());
    let reason = exr::decode(&bytes).unwrap_err();
    assert!(reason.contains("frame 0") && reason.contains("appears twice"), "{reason}");
}

/// Another tool's file: tiles of 3 x 3 with mip levels below the full
/// resolution, half floats, frames as parts named in order.
#[test]
fn a_tiled_mip_mapped_half_float_file_reads_its_full_resolution() {
    use ::exr::prelude::*;
    let (w, h, frames) = (8, 8, 2);
    let value = |x: usize, y: usize, t: usize, k: usize| ((x + w * (y + h * t)) * 2 + k) as f32 / 512.0;
    let layers: Vec<_> = (0..frames)
        .map(|t| {
            let channel = |name: &str, k: usize| {
                let full: Vec<f16> = (0..w * h).map(|i| f16::from_f32(value(i % w, i / w, t, k))).collect();
                // Smaller levels hold values no mask has: they must not be read.
                let levels = [4usize, 2, 1].map(|s| FlatSamples::F16(vec![f16::from_f32(7.0); s * s]));
                let level_data = std::iter::once(FlatSamples::F16(full)).chain(levels).collect();
                AnyChannel::new(
                    name,
                    Levels::Mip { rounding_mode: ::exr::math::RoundingMode::Down, level_data },
                )
            };
            Layer::new(
                (w, h),
                LayerAttributes::named(format!("frame{t:04}").as_str()),
                Encoding {
                    blocks: Blocks::Tiles(Vec2(3, 3)),
                    compression: Compression::ZIP1,
                    ..Encoding::default()
                },
                AnyChannels::sort(SmallVec::from_vec(vec![channel("R", 0), channel("G", 1)])),
            )
        })
        .collect();
    let image = Image::from_layers(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))), layers);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).unwrap();
    let meta = MetaData::read_from_buffered(std::io::Cursor::new(bytes.get_ref()), true).unwrap();
    assert!(meta.headers.iter().all(|h| h.blocks
        == ::exr::meta::BlockDescription::Tiles(TileDescription {
            tile_size: Vec2(3, 3),
            level_mode: ::exr::meta::attribute::LevelMode::MipMap,
            rounding_mode: ::exr::math::RoundingMode::Down,
        })));
    let mask = exr::decode(bytes.get_ref()).unwrap();
    assert_eq!((mask.tile.width, mask.tile.height, mask.tile.frames, mask.tile.dims), (w, h, frames, 2));
    for t in 0..frames {
        for y in 0..h {
            for x in 0..w {
                let want = [0, 1].map(|k| f16::from_f32(value(x, y, t, k)).to_f32());
                assert_eq!(mask.sample(x, y, t, 0), &want[..], "({x}, {y}, {t})");
            }
        }
    }
}

#[test]
fn provenance_a_format_cannot_hold_is_refused_not_a_panic_or_a_broken_file() {
    let mut mask = Mask::white(Tile::new(4, 4, 2, 1, 2).unwrap(), 3);
    mask.set_meta("note", "café");
    let back = exr::decode(&exr::encode(&mask).unwrap()).unwrap();
    assert_eq!(back.meta("note"), Some("café"), "Latin-1 reads back");
    mask.set_meta("note", "cost 5 €");
    let e = exr::encode(&mask).unwrap_err().to_string();
    assert!(e.contains("Latin-1"), "{e}");
    mask.set_meta("note", "plain");
    mask.set_meta("a\0b", "v");
    let e = fsot::io::ktx2::encode(&mask, fsot::io::ktx2::Format::R16G16Unorm).unwrap_err().to_string();
    assert!(e.contains("NUL"), "{e}");
}

#[test]
fn an_uncommitted_output_leaves_the_existing_file_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keep.exr");
    std::fs::write(&path, b"precious").unwrap();
    {
        let _reserved = AtomicFile::create(&path).unwrap();
        // dropped without commit, as when a run fails
    }
    assert_eq!(std::fs::read(&path).unwrap(), b"precious");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file left behind");
    assert!(AtomicFile::create(&dir.path().join("no/such/dir/m.exr")).is_err());
}

/// Masks whose public fields were set out of range by hand: a NaN, a value
/// of 1, too few values, a tile `Tile::new` refuses.
fn masks_set_out_of_range_by_hand() -> Vec<(&'static str, Mask)> {
    let good = || Mask::white(Tile::new(4, 3, 2, 1, 2).unwrap(), 3);
    let mut nan = good();
    nan.samples[5] = f32::NAN;
    let mut one = good();
    one.samples[0] = 1.0;
    let mut short = good();
    short.samples.truncate(7);
    let mut empty = good();
    empty.samples.clear();
    let mut wide = good();
    wide.tile.dims = 9;
    vec![
        ("a NaN", nan),
        ("a value of 1", one),
        ("too few values", short),
        ("no values", empty),
        ("d = 9", wide),
    ]
}

#[test]
fn every_writer_refuses_a_mask_set_out_of_range_by_hand_and_leaves_the_file_that_was_there() {
    use fsot::TexelFormat;
    let dir = tempfile::tempdir().unwrap();
    for (what, mask) in masks_set_out_of_range_by_hand() {
        assert!(mask.check().is_err(), "{what}: check");
        for name in ["m.exr", "m.ktx2", "m.h"] {
            let path = dir.path().join(name);
            std::fs::write(&path, b"what the user had").unwrap();
            assert!(mask.save(&path).is_err(), "{what}: {name} was written");
            assert_eq!(std::fs::read(&path).unwrap(), b"what the user had", "{what}: {name} was touched");
        }
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 3, "{what}: a temporary file stayed: {names:?}");
        assert!(mask.ktx2(None).is_err(), "{what}: KTX2 bytes");
        assert!(mask.ktx2(Some(TexelFormat::R32G32Sfloat)).is_err(), "{what}: float KTX2 bytes");
        assert!(exr::encode(&mask).is_err(), "{what}: EXR bytes");
        assert!(png_io::write(&mask, &dir.path().join("png"), 16).is_err(), "{what}: PNG slices");
        assert!(!dir.path().join("png").exists(), "{what}: a PNG folder was made");
        let kernel = fsot::KernelSpec::named("taa").unwrap();
        assert!(mask.score(kernel).is_err(), "{what}: score");
    }
}

#[test]
fn a_mask_reads_a_sample_only_inside_its_tile() {
    let mask = Mask::white(Tile::new(4, 3, 2, 1, 2).unwrap(), 3);
    assert_eq!(mask.sample(3, 2, 1, 0), &mask.samples[mask.samples.len() - 2..]);
    for (x, y, t, s) in [(4, 0, 0, 0), (0, 3, 0, 0), (0, 0, 2, 0), (0, 0, 0, 1)] {
        let read = std::panic::catch_unwind(|| mask.sample(x, y, t, s).to_vec());
        assert!(read.is_err(), "({x}, {y}, {t}, {s}) read {read:?}");
    }
}

#[cfg(unix)]
#[test]
fn a_device_or_a_pipe_given_as_a_file_to_read_is_refused_before_it_is_opened() {
    use std::path::Path;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.exr");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    // /dev/zero never ends and a pipe with no writer never begins: either would hang.
    for path in [Path::new("/dev/zero"), fifo.as_path(), dir.path()] {
        let says = |e: fsot::Error| e.to_string().contains("not a regular file");
        assert!(exr::read(path).is_err_and(says), "{}: EXR", path.display());
        assert!(fsot::Scene::read(path).is_err_and(says), "{}: scene", path.display());
        assert!(fsot::io::stacked_png::read(path).is_err_and(says), "{}: PNG", path.display());
    }
    assert!(fsot::SamplerPlan::load(Path::new("/dev/zero")).is_err(), "a plan from /dev/zero");
    std::fs::remove_file(dir.path().join("pipe.exr")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("plan.json")).unwrap();
    assert!(fsot::SamplerPlan::read(dir.path()).is_err(), "a plan.json linked to /dev/zero");
}

/// The samples' bit patterns: equal only when every value is the same bits.
fn bits(samples: &[f32]) -> Vec<u32> {
    samples.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn a_file_larger_than_any_fsot_reads_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.exr");
    // Sparse: its length past the cap, no blocks written.
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(fsot::io::MAX_FILE_BYTES + 1).unwrap();
    drop(file);
    let err = exr::read(&path).unwrap_err().to_string();
    assert!(err.contains("more than any file fsot reads"), "{err}");
}
