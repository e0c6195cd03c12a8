//! KTX2 output, read back by an independent reader (the `ktx2` crate): the
//! header a renderer uploads from, the data format descriptor the format calls
//! for, the provenance, and texels within half a quantisation level of the mask.

use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::ktx2::{decode, encode, format_for, Format};
use fsot::io::MaskFile;

fn mask(dims: usize, spp: usize) -> Mask {
    let mut m = Mask::white(Tile::new(5, 3, 4, spp, dims).unwrap(), 11);
    // The ends of the range, and the middle.
    m.samples[..3].copy_from_slice(&[0.0, 0.999_999_9, 0.5]);
    m.set_meta("kernel", "taa (test)");
    m
}

/// Decodes channel `c` of texel `i` of level 0 as a renderer's sampler reads it.
fn read(data: &[u8], format: Format, i: usize, c: usize) -> f64 {
    let bytes = format.bits() as usize / 8;
    let at = (i * format.channels() + c) * bytes;
    let raw = &data[at..at + bytes];
    match format.bits() {
        8 => raw[0] as f64 / 255.0,
        16 => u16::from_le_bytes([raw[0], raw[1]]) as f64 / 65535.0,
        _ => f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) as f64,
    }
}

#[test]
fn every_format_reads_back_within_half_a_level_in_an_independent_reader() {
    for format in Format::ALL {
        for dims in 1..=format.channels() {
            for spp in [1, 2] {
                let m = mask(dims, spp);
                let bytes = encode(&m, format).unwrap();
                let r = ktx2::Reader::new(&bytes[..]).unwrap();
                let h = r.header();
                assert_eq!(h.format.map(|f| f.value()), Some(format.vk_format()), "{format:?}");
                assert_eq!(h.type_size, format.bits() / 8);
                assert_eq!((h.pixel_width, h.pixel_height, h.pixel_depth), (5, 3, 0));
                assert_eq!((h.layer_count, h.face_count, h.level_count), (4 * spp as u32, 1, 1));
                assert!(h.supercompression_scheme.is_none());
                // The descriptor the format calls for, as the reader's crate builds it.
                let (want, type_size) = ktx2::dfd::Basic::from_format(h.format.unwrap()).unwrap();
                assert_eq!(type_size, h.type_size);
                assert_eq!(r.basic_dfd(), Some(&want), "{format:?}");
                let levels: Vec<_> = r.levels().collect();
                assert_eq!(levels.len(), 1);
                let data = levels[0].data;
                assert_eq!(data.len(), 5 * 3 * 4 * spp * format.texel_bytes());
                let level = if format.is_float() { 0.0 } else { 1.0 / ((1u64 << format.bits()) - 1) as f64 };
                for t in 0..4 {
                    for s in 0..spp {
                        for y in 0..3 {
                            for x in 0..5 {
                                let i = ((t * spp + s) * 3 + y) * 5 + x; // layer t * spp + s
                                let want = m.sample(x, y, t, s);
                                for c in 0..format.channels() {
                                    let got = read(data, format, i, c);
                                    let v = want.get(c).copied().unwrap_or(0.0) as f64;
                                    assert!(
                                        (got - v).abs() <= 0.5 * level + 1e-7,
                                        "{format:?} d {dims}: {got} against {v}"
                                    );
                                }
                            }
                        }
                    }
                }
                let kv: Vec<(&str, &[u8])> = r.key_value_data().collect();
                let get =
                    |k: &str| kv.iter().find(|e| e.0 == k).map(|e| e.1.strip_suffix(&[0]).unwrap_or(e.1));
                assert_eq!(get("fsot.kernel"), Some(&b"taa (test)"[..]));
                assert_eq!(get("fsot.dims"), Some(dims.to_string().as_bytes()));
                assert_eq!(get("fsot.spp"), Some(spp.to_string().as_bytes()));
                assert!(get("KTXwriter").unwrap().starts_with(b"fsot "));
                let keys: Vec<&str> = kv.iter().map(|e| e.0).collect();
                let mut sorted = keys.clone();
                sorted.sort();
                assert_eq!(keys, sorted, "KTX2 asks for keys in byte order");
                // Level data aligned to lcm(texel size, 4).
                let offset = data.as_ptr() as usize - bytes.as_ptr() as usize;
                assert_eq!(offset % format.texel_bytes().max(4), 0);
            }
        }
    }
}

#[test]
fn unorm_levels_are_the_nearest_of_two_to_the_b_minus_one() {
    use fsot::io::ktx2::quantize;
    assert_eq!(quantize(0.0, 8), 0);
    assert_eq!(quantize(0.5, 8), 128); // 127.5 rounds up
    assert_eq!(quantize(0.999_9, 8), 255);
    assert_eq!(quantize(1.0 / 255.0 * 0.49, 8), 0);
    assert_eq!(quantize(1.0 / 255.0 * 0.51, 8), 1);
    assert_eq!(quantize(0.25, 16), 16384); // 16383.75
}

#[test]
fn a_format_that_cannot_hold_the_mask_is_refused_before_any_work() {
    let e = format_for(2, Some("r8_unorm")).unwrap_err().to_string();
    assert!(e.contains("r8_unorm") && e.contains("d = 2"), "{e}");
    assert!(format_for(3, Some("r16g16_unorm")).is_err());
    assert!(format_for(5, None).unwrap_err().to_string().contains("at most 4"));
    assert!(format_for(2, Some("rgb9e5")).unwrap_err().to_string().contains("r16g16_unorm"));
    assert_eq!(format_for(2, None).unwrap(), Format::R16G16Unorm, "the default for d = 2");
    assert_eq!(format_for(1, Some("auto")).unwrap(), Format::R16Unorm);
    assert_eq!(format_for(3, None).unwrap(), Format::R16G16B16A16Unorm);
    assert!(encode(&mask(2, 1), Format::R32Sfloat).is_err());
    let p = std::path::Path::new;
    assert!(MaskFile::for_path(p("m.exr"), 2, Some("r16_unorm")).is_err(), "a KTX2 format for an EXR");
    assert_eq!(MaskFile::for_path(p("m.h"), 2, None).unwrap(), MaskFile::CHeader);
    assert_eq!(MaskFile::for_path(p("m.KTX2"), 1, None).unwrap(), MaskFile::Ktx2(Format::R16Unorm));
}

#[test]
fn a_ktx2_file_reads_back_as_the_mask_within_half_a_level_with_its_provenance() {
    for format in Format::ALL {
        for dims in 1..=format.channels() {
            for spp in [1, 2] {
                let m = mask(dims, spp);
                let back = decode(&encode(&m, format).unwrap()).unwrap();
                assert_eq!(back.tile, m.tile, "{format:?}");
                let mut meta = m.meta.clone();
                meta.sort();
                assert_eq!(back.meta, meta, "{format:?}: the provenance");
                let level = if format.is_float() { 0.0 } else { 1.0 / ((1u64 << format.bits()) - 1) as f64 };
                for (&got, &want) in back.samples.iter().zip(&m.samples) {
                    // On the torus: the top level reads 0.
                    let apart = (got as f64 - want as f64).abs();
                    assert!(apart.min(1.0 - apart) <= 0.5 * level + 1e-7, "{format:?}: {got} against {want}");
                }
                if format.is_float() {
                    assert_eq!(back.samples, m.samples, "a float texture holds the values exactly");
                }
            }
        }
    }
}

#[test]
fn a_shipped_ktx2_mask_agrees_with_its_png_slices_texel_by_texel() {
    // Two files of one mask written by different paths, read by different
    // readers (the PNG by the `png` crate): layers, rows and channels must
    // line up, each value within the two roundings (KTX2: q / 255; PNG: the
    // level's centre (p + 0.5) / 256), on the torus.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("masks");
    let m = fsot::Mask::open(root.join("rg-64x64x32-taa.ktx2")).unwrap();
    assert_eq!((m.tile.width, m.tile.height, m.tile.frames, m.tile.spp, m.tile.dims), (64, 64, 32, 1, 2));
    assert_eq!(m.meta("kernel").map(|k| k.starts_with("perceptual-taa")), Some(true), "{:?}", m.meta);
    let mut worst = 0.0f64;
    for t in 0..32 {
        let file = std::fs::File::open(root.join(format!("rg-64x64x32-taa/frame{t:04}.png"))).unwrap();
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height, info.bit_depth), (64, 64, png::BitDepth::Eight));
        let channels = info.color_type.samples();
        for y in 0..64 {
            for x in 0..64 {
                for c in 0..2 {
                    let p = buf[(y * 64 + x) * channels + c] as f64;
                    let apart = (m.sample(x, y, t, 0)[c] as f64 - (p + 0.5) / 256.0).abs();
                    worst = worst.max(apart.min(1.0 - apart));
                }
            }
        }
    }
    assert!(worst <= 0.5 / 255.0 + 0.5 / 256.0 + 1e-6, "largest difference {worst}");
}

#[test]
fn a_ktx2_file_fsot_cannot_read_is_refused_with_its_reason_and_no_byte_change_panics() {
    let good = encode(&mask(2, 1), Format::R16G16Unorm).unwrap();
    let refused = |bytes: &[u8], says: &str| {
        let e = decode(bytes).expect_err(says);
        assert!(e.contains(says), "{e:?} should say {says:?}");
    };
    refused(&good[..100], "not a readable KTX2 file");
    refused(&good[..good.len() - 1], "not a readable KTX2 file");
    let mut other = good.clone();
    other[12..16].copy_from_slice(&44u32.to_le_bytes()); // VK_FORMAT_B8G8R8A8_UNORM
    refused(&other, "VkFormat 44");
    let mut volume = good.clone();
    volume[28..32].copy_from_slice(&2u32.to_le_bytes()); // pixelDepth
    refused(&volume, "not a 2-D array texture");
    // A float texture holding 1.0, and one whose provenance contradicts its size.
    let mut m = mask(1, 1);
    m.samples[4] = 0.75;
    let mut float = encode(&m, Format::R32Sfloat).unwrap();
    let at = float.windows(4).rposition(|w| w == 0.75f32.to_le_bytes()).unwrap();
    float[at..at + 4].copy_from_slice(&1.0f32.to_le_bytes());
    refused(&float, "outside [0, 1)");
    let mut tiled = encode(&m, Format::R32Sfloat).unwrap();
    let at = tiled.windows(5).position(|w| w == b"5x3x4").unwrap();
    tiled[at..at + 5].copy_from_slice(b"5x3x2");
    refused(&tiled, "fsot.tile says 5x3x2");
    // Every single-byte change of a small file decodes or is refused; none panics.
    let small = encode(&mask(2, 2), Format::R8G8Unorm).unwrap();
    for i in 0..small.len() {
        for v in [0u8, 1, 0x7f, 0xff, small[i] ^ 0x10] {
            let mut b = small.clone();
            b[i] = v;
            let _ = decode(&b);
        }
    }
}
