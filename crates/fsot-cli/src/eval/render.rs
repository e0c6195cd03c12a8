//! Rendering the evaluation's scenes: one sample per pixel per frame with a
//! mask's numbers, and references with many stratified samples, cached on disk.

use std::path::Path;

use rayon::prelude::*;

use crate::eval::scenes::{reference, Scene};
use fsot::core::mask::Mask;
use fsot::core::rng::{derive, seed_key, Stream};
use fsot::error::Result;
use fsot::io::atomic::AtomicFile;

/// Image size and frames of a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shot {
    pub image: usize,
    pub frames: usize,
}

/// One source of a render's numbers: the scene's dimensions `first..first + d`
/// (d the mask's dimension) read from `mask` at a pixel and frame offset, plus a
/// toroidal shift per component.
struct Source<'a> {
    mask: &'a Mask,
    first: usize,
    offset: [usize; 3],
    shift: Vec<f64>,
}

/// How a render takes its numbers from masks. With one mask (`new`), the scene's
/// dimension k is component k mod d of the mask's sample, in group k / d, and
/// every group reads the tile at its own random pixel offset and toroidal shift,
/// so groups are decorrelated. With a plan (`planned`), each decision's
/// dimensions come from the masks the plan gives it: each mask is placed once per
/// render at a random offset and shift (the renderer's placement of its tile),
/// and every read of it adds the plan's offset and shift to that placement, as
/// a renderer following `plan.json` does.
pub struct MaskSampler<'a> {
    sources: Vec<Source<'a>>,
}

/// One read of a plan: the scene's dimensions from `first` on (as many as the
/// mask has) come from `mask` at the plan's pixel and frame `offset`, with its
/// toroidal `shift`.
pub struct Read<'a> {
    pub mask: &'a Mask,
    pub first: usize,
    pub offset: [u32; 3],
    pub shift: &'a [f32],
}

/// A random placement of a mask's tile: pixel and frame offset, shift per component.
fn place(rng: &mut Stream, mask: &Mask) -> ([usize; 3], Vec<f64>) {
    let t = mask.tile;
    let offset = [
        rng.below(t.width as u32) as usize,
        rng.below(t.height as u32) as usize,
        rng.below(t.frames as u32) as usize,
    ];
    (offset, (0..t.dims).map(|_| rng.next_f64()).collect())
}

impl<'a> MaskSampler<'a> {
    pub fn new(mask: &'a Mask, scene_dims: usize, seed: u64) -> Self {
        let mut rng = Stream::new(derive(seed_key(seed), 0x5ca1));
        let d = mask.tile.dims;
        let sources = (0..scene_dims.div_ceil(d))
            .map(|g| {
                let (offset, shift) = place(&mut rng, mask);
                Source { mask, first: g * d, offset, shift }
            })
            .collect();
        Self { sources }
    }

    /// Numbers from a plan's reads (see the type).
    pub fn planned(reads: &[Read<'a>], seed: u64) -> Self {
        let mut rng = Stream::new(derive(seed_key(seed), 0x5ca1));
        let mut placed: Vec<(&Mask, [usize; 3], Vec<f64>)> = Vec::new();
        let sources = reads
            .iter()
            .map(|r| {
                // Drawn for every read, so that a plan's masks of their own are
                // placed the same whether or not other reads share.
                let drawn = place(&mut rng, r.mask);
                let (base, base_shift) = match placed.iter().find(|p| std::ptr::eq(p.0, r.mask)) {
                    Some(p) => (p.1, p.2.clone()),
                    None => {
                        placed.push((r.mask, drawn.0, drawn.1.clone()));
                        drawn
                    }
                };
                let t = r.mask.tile;
                let size = [t.width, t.height, t.frames];
                let offset: [usize; 3] = std::array::from_fn(|j| (base[j] + r.offset[j] as usize) % size[j]);
                let shift = base_shift
                    .iter()
                    .enumerate()
                    .map(|(j, &b)| {
                        let v = b + r.shift.get(j).copied().unwrap_or(0.0) as f64;
                        v - v.floor()
                    })
                    .collect();
                Source { mask: r.mask, first: r.first, offset, shift }
            })
            .collect();
        Self { sources }
    }

    /// The numbers of pixel (x, y) in frame f, into u (the scene's dimension).
    pub fn numbers(&self, x: usize, y: usize, f: usize, u: &mut [f64]) {
        for src in &self.sources {
            let t = src.mask.tile;
            let s = src.mask.sample(
                (x + src.offset[0]) % t.width,
                (y + src.offset[1]) % t.height,
                (f + src.offset[2]) % t.frames,
                0,
            );
            for (j, (&v, shift)) in s.iter().zip(&src.shift).enumerate() {
                if let Some(slot) = u.get_mut(src.first + j) {
                    let v = v as f64 + shift;
                    *slot = v - v.floor();
                }
            }
        }
    }
}

/// Frames of an n x n render at 1 sample per pixel, numbers from `sampler`.
pub fn render(scene: Scene, shot: Shot, sampler: &MaskSampler) -> Vec<Vec<f64>> {
    let n = shot.image;
    let dims = scene.dims();
    (0..shot.frames)
        .map(|f| {
            (0..n * n)
                .into_par_iter()
                .map(|i| {
                    let (x, y) = (i % n, i / n);
                    let mut u = [0.0f64; 4];
                    sampler.numbers(x, y, f, &mut u[..dims]);
                    scene.shade(
                        (x as f64 + 0.5) / n as f64,
                        (y as f64 + 0.5) / n as f64,
                        f as f64,
                        &u[..dims],
                    )
                })
                .collect()
        })
        .collect()
}

/// The reference frames: `samples` stratified samples per pixel (see
/// `scenes::reference`), read from `cache` when a file for the same scene, shot
/// and sample count is there, else rendered and written there.
pub fn references(scene: Scene, shot: Shot, samples: usize, cache: Option<&Path>) -> Result<Vec<Vec<f64>>> {
    let n = shot.image;
    let name = format!("ref-{}-{}x{}-m{}.f32", scene.name(), n, shot.frames, samples);
    let path = cache.map(|c| c.join(&name));
    if let Some(path) = &path {
        if let Ok(bytes) = std::fs::read(path) {
            if bytes.len() == n * n * shot.frames * 4 {
                let values: Vec<f64> = bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
                    .collect();
                return Ok(values.chunks(n * n).map(|c| c.to_vec()).collect());
            }
        }
    }
    let key = derive(seed_key(0x2ef), scene.dims() as u32);
    let frames: Vec<Vec<f64>> = (0..shot.frames)
        .map(|f| {
            (0..n * n)
                .into_par_iter()
                .map(|i| {
                    let mut stream = Stream::new(derive(derive(key, f as u32), i as u32));
                    let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
                    // Kept at the cache's precision, so a cached run gives the
                    // same figures as a fresh one.
                    reference(scene, x / n as f64, y / n as f64, f as f64, samples, &mut stream) as f32 as f64
                })
                .collect()
        })
        .collect();
    if let Some(path) = &path {
        if let Some(dir) = path.parent() {
            fsot::io::atomic::make_folder(dir)?;
        }
        let bytes: Vec<u8> = frames.iter().flatten().flat_map(|&v| (v as f32).to_le_bytes()).collect();
        AtomicFile::create(path)?.commit(&bytes)?;
    }
    Ok(frames)
}

/// The display's temporal antialiasing: an exponential moving average with the
/// current frame's weight alpha, history starting at the first frame.
pub fn taa(frames: &[Vec<f64>], alpha: f64) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(frames.len());
    for (f, frame) in frames.iter().enumerate() {
        let next = match f {
            0 => frame.clone(),
            _ => frame.iter().zip(&out[f - 1]).map(|(c, h)| alpha * c + (1.0 - alpha) * h).collect(),
        };
        out.push(next);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use fsot::core::tile::Tile;

    #[test]
    fn groups_read_the_mask_at_their_own_offset_and_shift() {
        let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
        let mask = Mask::white(tile, 1);
        let s = MaskSampler::new(&mask, 4, 9);
        let mut u = [0.0; 4];
        s.numbers(1, 2, 1, &mut u);
        for (k, &got) in u.iter().enumerate() {
            let src = &s.sources[k / 2];
            let o = src.offset;
            assert_eq!(src.first, 2 * (k / 2));
            let v = mask.sample((1 + o[0]) % 4, (2 + o[1]) % 4, (1 + o[2]) % 2, 0)[k % 2] as f64
                + src.shift[k % 2];
            assert_eq!(got, v - v.floor());
            assert!((0.0..1.0).contains(&got));
        }
        assert_ne!(s.sources[0].shift, s.sources[1].shift);
    }

    #[test]
    fn a_plan_gives_each_decision_its_own_mask() {
        let one = Mask::white(Tile::new(4, 4, 2, 1, 1).unwrap(), 1);
        let two = Mask::white(Tile::new(4, 4, 2, 1, 2).unwrap(), 2);
        // A 2-D decision then a 1-D one (defocus-motion's lens, then time).
        let read = |mask, first| Read { mask, first, offset: [0; 3], shift: &[] };
        let s = MaskSampler::planned(&[read(&two, 0), read(&one, 2)], 5);
        let mut u = [0.0; 3];
        s.numbers(3, 0, 1, &mut u);
        let at = |src: &Source, m: &Mask, j: usize| {
            let o = src.offset;
            let v = m.sample((3 + o[0]) % 4, o[1] % 4, (1 + o[2]) % 2, 0)[j] as f64 + src.shift[j];
            v - v.floor()
        };
        assert_eq!(u[0], at(&s.sources[0], &two, 0));
        assert_eq!(u[1], at(&s.sources[0], &two, 1));
        assert_eq!(u[2], at(&s.sources[1], &one, 0));
    }

    #[test]
    fn reads_of_a_shared_mask_keep_the_plans_offset_and_shift_between_them() {
        let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
        let mask = Mask::white(tile, 3);
        let shift = [0.25f32, 0.75];
        let reads = [
            Read { mask: &mask, first: 0, offset: [0; 3], shift: &[0.0, 0.0] },
            Read { mask: &mask, first: 2, offset: [3, 1, 1], shift: &shift },
        ];
        for seed in 0..8 {
            let s = MaskSampler::planned(&reads, seed);
            let (a, b) = (&s.sources[0], &s.sources[1]);
            for j in 0..3 {
                let n = [4, 4, 2][j];
                assert_eq!(b.offset[j], (a.offset[j] + reads[1].offset[j] as usize) % n);
            }
            for ((&got, &from), &plan) in b.shift.iter().zip(&a.shift).zip(&shift) {
                let want = (from + plan as f64).fract();
                assert!((got - want).abs() < 1e-12, "{got} against {want}");
            }
        }
    }

    #[test]
    fn taa_is_an_exponential_moving_average() {
        let frames = vec![vec![1.0], vec![0.0], vec![0.0]];
        let out = taa(&frames, 0.25);
        assert_eq!(out, vec![vec![1.0], vec![0.75], vec![0.5625]]);
    }

    #[test]
    fn references_are_cached_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let shot = Shot { image: 6, frames: 2 };
        let a = references(Scene::SoftShadow, shot, 16, Some(dir.path())).unwrap();
        let files: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().path()).collect();
        assert_eq!(files.len(), 1);
        let fresh = references(Scene::SoftShadow, shot, 16, None).unwrap();
        assert_eq!(a, fresh, "the cached run's figures are a fresh run's");
        // Known values in the cache file come back: the second run reads it.
        let known: Vec<f32> = (0..6 * 6 * 2).map(|i| i as f32 / 128.0).collect();
        std::fs::write(&files[0], known.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
        let b = references(Scene::SoftShadow, shot, 16, Some(dir.path())).unwrap();
        let read: Vec<f32> = b.iter().flatten().map(|&v| v as f32).collect();
        assert_eq!(read, known);
    }
}
