//! Fuzzing the EXR reader (proptest, a small fixed corpus of mutations per run):
//! whatever bytes arrive, reading gives either a valid mask (every sample in
//! [0, 1), as many as its tile holds) or an error with a reason, never a panic.
//! `FSOT_FUZZ_CASES=N` runs N cases per property instead of 300.

use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::exr;
use proptest::prelude::*;

/// The seed corpus: valid files of three layouts.
fn corpus() -> Vec<Vec<u8>> {
    [(4, 3, 2, 1, 2), (2, 2, 1, 2, 3), (3, 1, 3, 1, 1)]
        .iter()
        .map(|&(w, h, t, spp, d)| exr::encode(&Mask::white(Tile::new(w, h, t, spp, d).unwrap(), 7)).unwrap())
        .collect()
}

fn read_never_panics(bytes: &[u8]) {
    // A panic inside the decoder (ours or the exr crate's) fails the case.
    let result = std::panic::catch_unwind(|| exr::decode(bytes));
    match result {
        Ok(Ok(mask)) => {
            assert_eq!(mask.samples.len(), mask.tile.values());
            assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)), "accepted a sample outside [0, 1)");
        }
        Ok(Err(reason)) => assert!(!reason.is_empty()),
        Err(_) => panic!("decoding panicked on {} bytes", bytes.len()),
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, bits: u8 },
    Truncate { at: usize },
    Splice { at: usize, junk: Vec<u8> },
    Overwrite { at: usize, value: u32 },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1u8..=255).prop_map(|(at, bits)| Mutation::Flip { at, bits }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(at, junk)| Mutation::Splice { at, junk }),
        (
            any::<usize>(),
            prop_oneof![Just(0u32), Just(u32::MAX), Just(0x7fc0_0000), Just(0x3f80_0000), any::<u32>()]
        )
            .prop_map(|(at, value)| Mutation::Overwrite { at, value }),
    ]
}

fn apply(mut bytes: Vec<u8>, m: &Mutation) -> Vec<u8> {
    let n = bytes.len();
    match m {
        Mutation::Flip { at, bits } => bytes[at % n] ^= bits,
        Mutation::Truncate { at } => bytes.truncate(at % n),
        Mutation::Splice { at, junk } => {
            let at = at % n;
            bytes.splice(at..at, junk.iter().copied());
        }
        Mutation::Overwrite { at, value } => {
            let at = at % (n - 4);
            bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: std::env::var("FSOT_FUZZ_CASES").ok().and_then(|n| n.parse().ok()).unwrap_or(300), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_are_read_or_refused_never_a_panic(
        which in 0usize..3,
        mutations in prop::collection::vec(mutation(), 1..4),
    ) {
        let mut bytes = corpus()[which].clone();
        for m in &mutations {
            if bytes.len() < 8 {
                break;
            }
            bytes = apply(bytes, m);
        }
        read_never_panics(&bytes);
    }

    #[test]
    fn arbitrary_bytes_are_refused_never_a_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        read_never_panics(&bytes);
    }
}

#[test]
fn the_corpus_itself_reads_back() {
    for bytes in corpus() {
        assert!(exr::decode(&bytes).is_ok());
    }
}

/// The exr crate sizes its buffers from the header: a mutated file can make it ask
/// for tens of GB and abort the process. Here a data window grows to
/// 100000 x 100000 that way; the reader refuses it from the header alone.
#[test]
fn a_header_promising_more_pixels_than_the_file_holds_is_refused_before_reading() {
    let mut bytes = corpus()[0].clone();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).expect("every part has a data window");
    // box2i: size (4 bytes), then x_min, y_min, x_max, y_max.
    let corners = at + key.len() + 4;
    bytes[corners + 8..corners + 12].copy_from_slice(&99_999i32.to_le_bytes());
    bytes[corners + 12..corners + 16].copy_from_slice(&99_999i32.to_le_bytes());
    let reason = exr::decode(&bytes).expect_err("a 100000 x 100000 part from a few hundred bytes");
    assert!(reason.contains("promises"), "{reason}");
}
