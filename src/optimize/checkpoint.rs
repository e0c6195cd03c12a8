//! Checkpoints of a long optimization: the samples and the optimizer's state after
//! some iteration, tied to the run's settings by a fingerprint, so that a resumed
//! run continues exactly where the interrupted one stopped (bit for bit on the
//! CPU path, whose every iteration is a pure function of its inputs).
//!
//! Layout (little-endian): the 8 bytes `FSOTCKP1`; a u32 length and that many bytes
//! of UTF-8 header (`key=value` lines: fingerprint, iteration, counts); the
//! samples, first and second state vectors as f32; an FNV-1a 64 checksum of
//! everything before it. Written through `AtomicFile`, so a checkpoint on disk is
//! always a complete one.

use std::path::Path;

use crate::core::step_rule::PlateauState;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;
use crate::optimize::settings::{recorded_axis_share, RunState, Settings, Start, Until};

const MAGIC: &[u8; 8] = b"FSOTCKP1";

/// What a checkpoint must match to be resumed: the tile and every setting that
/// changes the run's iterations (kernel, iterations, slices, seed, step rule,
/// the stopping rule, the axis share where it is not the default and d >= 2,
/// the start where it is not white noise: a mask records how it started).
/// The backend is not part of it: a run may resume on the other backend.
pub fn fingerprint(tile: &Tile, settings: &Settings) -> String {
    let s = settings;
    // Spelled out field by field, not by the settings' Debug, so the text stays
    // fixed; `until` is added only where the run does not end at a fixed count.
    let mut f = format!(
        "tile {}x{}x{} spp {} d {}; Settings {{ kernel: {:?}, iterations: {}, slices: {:?}, seed: {}, rule: {:?} }}",
        tile.width, tile.height, tile.frames, tile.spp, tile.dims, s.kernel, s.iterations, s.slices, s.seed, s.rule
    );
    if s.until != Until::Iterations {
        f += &format!("; until {:?}", s.until);
    }
    if let Some(share) = recorded_axis_share(tile, s) {
        f += &format!("; axis share {share}");
    }
    if s.start.animates(s.until, tile) {
        f += "; start animated";
    } else if s.start == Start::Coarse {
        f += "; start coarse";
    }
    f
}

fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

pub fn encode(fingerprint: &str, state: &RunState) -> Vec<u8> {
    let mut header = format!(
        "fingerprint={fingerprint}\niteration={}\nsamples={}\nfirst={}\nsecond={}\n",
        state.iteration,
        state.samples.len(),
        state.first.len(),
        state.second.len()
    );
    if let Some(p) = &state.plateau {
        // Bit patterns: the schedule resumes exactly.
        header += &format!(
            "plateau={:08x},{:016x},{:016x},{}\n",
            p.scale.to_bits(),
            p.previous.to_bits(),
            p.sum.to_bits(),
            p.count
        );
    }
    let mut out = Vec::with_capacity(
        20 + header.len() + 4 * (state.samples.len() + state.first.len() + state.second.len()),
    );
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in [&state.samples, &state.first, &state.second] {
        for x in v.iter() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    let sum = fnv1a(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Decodes a checkpoint and checks it against the run it should continue: the
/// fingerprint, the lengths, the checksum, samples in [0, 1) and a finite state.
pub fn decode(bytes: &[u8], expected: &str, tile: &Tile) -> std::result::Result<RunState, String> {
    if bytes.len() < 20 || &bytes[..8] != MAGIC {
        return Err("not an fsot checkpoint".into());
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().map_err(|_| "truncated")?);
    if fnv1a(body) != stored {
        return Err("damaged or truncated (checksum mismatch)".into());
    }
    let header_len = u32::from_le_bytes(body[8..12].try_into().map_err(|_| "truncated")?) as usize;
    let header = body.get(12..12 + header_len).ok_or("truncated header")?;
    if header.len() as u64 > MAX_HEADER {
        return Err("header longer than any checkpoint's".into());
    }
    let header = std::str::from_utf8(header).map_err(|_| "header is not UTF-8")?;
    let field = |key: &str| -> std::result::Result<&str, String> {
        header
            .lines()
            .find_map(|l| l.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
            .ok_or_else(|| format!("header lacks {key}"))
    };
    let count = |key: &str| -> std::result::Result<usize, String> {
        field(key)?.parse::<usize>().map_err(|_| format!("bad {key} in header"))
    };
    let found = field("fingerprint")?;
    if found != expected {
        return Err(format!(
            "it was made by a different run.\n  checkpoint: {found}\n  this run:   {expected}\n\
             Resume with the same size, kernel, iterations, slices, seed, step rule, stopping rule, axis share and start as the run that wrote it"
        ));
    }
    let iteration: u32 = field("iteration")?.parse().map_err(|_| "bad iteration in header")?;
    let (ns, nf, n2) = (count("samples")?, count("first")?, count("second")?);
    let values = tile.values();
    if ns != values || nf != values || (n2 != values && n2 != 0) {
        return Err(format!("holds {ns} samples, {nf} + {n2} state values; the tile has {values}"));
    }
    let data = &body[12 + header_len..];
    if data.len() != 4 * (ns + nf + n2) {
        return Err("payload length does not match its header".into());
    }
    let floats: Vec<f32> =
        data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    let samples = floats[..ns].to_vec();
    let first = floats[ns..ns + nf].to_vec();
    let second = floats[ns + nf..].to_vec();
    if let Some(bad) = samples.iter().find(|v| !(0.0..1.0).contains(*v)) {
        return Err(format!("holds a sample outside [0, 1): {bad}"));
    }
    if first.iter().chain(&second).any(|v| !v.is_finite()) {
        return Err("holds a non-finite optimizer state".into());
    }
    if second.iter().any(|v| *v < 0.0) {
        return Err("holds a negative second moment".into());
    }
    let plateau = match header.lines().find_map(|l| l.strip_prefix("plateau=")) {
        Some(p) => Some(parse_plateau(p).ok_or("bad plateau in header")?),
        None => None,
    };
    Ok(RunState { iteration, samples, first, second, plateau })
}

fn parse_plateau(text: &str) -> Option<PlateauState> {
    let f: Vec<&str> = text.split(',').collect();
    let [scale, previous, sum, count] = f[..] else { return None };
    Some(PlateauState {
        scale: f32::from_bits(u32::from_str_radix(scale, 16).ok()?),
        previous: f64::from_bits(u64::from_str_radix(previous, 16).ok()?),
        sum: f64::from_bits(u64::from_str_radix(sum, 16).ok()?),
        count: count.parse().ok()?,
    })
}

/// Writes a checkpoint atomically (the previous one stays until the new one is
/// complete).
pub fn write(path: &Path, fingerprint: &str, state: &RunState) -> Result<()> {
    AtomicFile::create(path)?.commit(&encode(fingerprint, state))
}

/// The most header bytes a checkpoint carries (its own are a few hundred).
const MAX_HEADER: u64 = 1 << 16;

pub fn read(path: &Path, fingerprint: &str, tile: &Tile) -> Result<RunState> {
    // A checkpoint's size follows from the tile: a larger file is refused before
    // it is read into memory.
    let most = 20 + MAX_HEADER + 12 * tile.values() as u64;
    if let Ok(len) = std::fs::metadata(path).map(|m| m.len()) {
        if len > most {
            return Err(Error::bad_file(
                path,
                format!("cannot resume: {len} bytes, more than a checkpoint of this tile holds ({most})"),
            ));
        }
    }
    let bytes = crate::io::read_regular(path)
        .map_err(|e| Error::io(format!("cannot read the checkpoint {}", path.display()), e))?;
    decode(&bytes, fingerprint, tile).map_err(|why| Error::bad_file(path, format!("cannot resume: {why}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::kernel::KernelSpec;

    fn setup() -> (Tile, String, RunState) {
        let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
        let settings = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 3);
        let n = tile.values();
        let state = RunState {
            iteration: 17,
            samples: (0..n).map(|i| i as f32 / n as f32).collect(),
            first: (0..n).map(|i| i as f32 * -1e-3).collect(),
            second: Vec::new(),
            plateau: None,
        };
        (tile, fingerprint(&tile, &settings), state)
    }

    #[test]
    fn a_checkpoint_round_trips_bit_for_bit() {
        let (tile, fp, mut state) = setup();
        let back = decode(&encode(&fp, &state), &fp, &tile).unwrap();
        assert_eq!(back, state);
        state.plateau = Some(PlateauState { scale: 0.125, previous: 1.0 / 3.0, sum: 0.1 + 0.2, count: 7 });
        let back = decode(&encode(&fp, &state), &fp, &tile).unwrap();
        assert_eq!(back, state);
    }

    #[test]
    fn a_fixed_run_keeps_the_fingerprint_it_had_before_stopping_rules() {
        let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
        let s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 3);
        let fp = fingerprint(&tile, &s);
        assert!(fp.starts_with("tile 4x4x2 spp 1 d 2; Settings { kernel: "), "{fp}");
        assert!(
            fp.ends_with(
                ", iterations: 1000, slices: None, seed: 3, rule: Momentum { step: 2.0, beta: 0.8 } }"
            ),
            "{fp}"
        );
        let until = Settings { until: Until::Plateau(crate::core::step_rule::Plateau::DEFAULT), ..s };
        assert_ne!(fingerprint(&tile, &until), fp);
        // Another axis share draws other slices: another run.
        assert_ne!(fingerprint(&tile, &s.axis_share(0.85)), fp);
        // An animated start is another run too (its mask says how it started);
        // a white one keeps the fingerprint above.
        assert_eq!(fingerprint(&tile, &Settings { start: Start::White, ..s }), fp);
        assert_ne!(fingerprint(&tile, &Settings { start: Start::Animated, ..s }), fp);
    }

    #[test]
    fn damaged_truncated_or_foreign_checkpoints_are_refused_with_reasons() {
        let (tile, fp, state) = setup();
        let good = encode(&fp, &state);
        let mut flipped = good.clone();
        flipped[40] ^= 1;
        assert!(decode(&flipped, &fp, &tile).unwrap_err().contains("checksum"));
        for cut in [0, 7, 19, good.len() / 2, good.len() - 1] {
            assert!(decode(&good[..cut], &fp, &tile).is_err(), "cut at {cut}");
        }
        let other = fp.replace("seed: 3", "seed: 4");
        assert_ne!(other, fp);
        assert!(decode(&good, &other, &tile).unwrap_err().contains("different run"));
        let bigger = Tile::new(8, 4, 2, 1, 2).unwrap();
        assert!(decode(&good, &fp, &bigger).unwrap_err().contains("the tile has"));
        let mut outside = state.clone();
        outside.samples[3] = 1.0;
        assert!(decode(&encode(&fp, &outside), &fp, &tile).unwrap_err().contains("outside"));
        let mut nan = state.clone();
        nan.first[0] = f32::NAN;
        assert!(decode(&encode(&fp, &nan), &fp, &tile).unwrap_err().contains("non-finite"));
        let mut negative = state;
        negative.second = vec![0.0; tile.values()];
        assert!(decode(&encode(&fp, &negative), &fp, &tile).is_ok());
        negative.second[5] = -1e-9;
        assert!(decode(&encode(&fp, &negative), &fp, &tile).unwrap_err().contains("negative second moment"));
    }

    #[test]
    fn a_file_larger_than_a_checkpoint_of_the_tile_is_refused_before_it_is_read() {
        let (tile, fp, state) = setup();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.ckpt");
        write(&path, &fp, &state).unwrap();
        assert_eq!(read(&path, &fp, &tile).unwrap(), state);
        // Sparse: its length is all that is looked at.
        std::fs::File::options().write(true).open(&path).unwrap().set_len(1 << 30).unwrap();
        let e = read(&path, &fp, &tile).unwrap_err().to_string();
        assert!(e.contains("more than a checkpoint of this tile holds"), "{e}");
    }
}
