//! FLIP as `fsot eval --flip` computes it, against NVIDIA's `flip-evaluator`
//! package: `tests/data/flip-package.json` holds the package's answers (its mean
//! and its error map) for images made from integer hashes, which this test
//! makes again bit for bit (`bench/flip/reference.py` wrote the file).

use fsot_cli::eval::flip::Flip;

/// A byte from four integers, as `bench/flip/reference.py` computes it.
fn hash_byte(x: u32, y: u32, c: u32, seed: u32) -> u32 {
    let mut h = x.wrapping_mul(73856093)
        ^ y.wrapping_mul(19349663)
        ^ c.wrapping_mul(83492791)
        ^ seed.wrapping_mul(2654435761);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5BD1E995);
    h ^= h >> 15;
    h >> 24
}

/// Three sRGB planes of one image, as `reference.py`'s `image` makes them.
fn image(kind: &str, w: u32, h: u32, seed: u32) -> [Vec<f32>; 3] {
    [0, 1, 2].map(|c| {
        let mut plane = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = match kind {
                    "grey-noise" => hash_byte(x, y, 0, seed) as i64,
                    "colour-noise" => hash_byte(x, y, c, seed) as i64,
                    "gradient" => {
                        let v = (255 * (x + 2 * y) / (w - 1 + 2 * (h - 1))) as i64;
                        match seed {
                            0 => v,
                            _ => (v + (hash_byte(x, y, 0, seed) % 21) as i64 - 10).clamp(0, 255),
                        }
                    }
                    "step" => match x < w / 2 + seed {
                        true => 51,
                        false => 204,
                    },
                    other => panic!("unknown kind {other}"),
                };
                // As numpy: the byte over 255 in f64, then to f32.
                plane.push((v as f64 / 255.0) as f32);
            }
        }
        plane
    })
}

fn cases() -> Vec<serde_json::Value> {
    let text = include_str!("data/flip-package.json");
    let file: serde_json::Value = serde_json::from_str(text).unwrap();
    file["cases"].as_array().unwrap().clone()
}

fn planes(p: &[Vec<f32>; 3]) -> [&[f32]; 3] {
    [&p[0], &p[1], &p[2]]
}

#[test]
fn flip_agrees_with_nvidias_package_pixel_by_pixel_and_in_the_mean() {
    let cases = cases();
    assert!(cases.len() >= 6);
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let (w, h) = (case["width"].as_u64().unwrap() as u32, case["height"].as_u64().unwrap() as u32);
        let ppd = case["ppd"].as_f64().unwrap() as f32; // as the package takes it
        let made = |side: &str| {
            image(case[side]["kind"].as_str().unwrap(), w, h, case[side]["seed"].as_u64().unwrap() as u32)
        };
        let (reference, test) = (made("reference"), made("test"));
        let flip = Flip::at(ppd as f64).unwrap();
        let ours = flip.error_map(planes(&reference), planes(&test), w as usize).unwrap();
        let theirs: Vec<f64> = case["map"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(ours.len(), theirs.len(), "{name}");
        // f32 as the package computes: the same to an ulp or two.
        for (i, (&ours, &theirs)) in ours.iter().zip(&theirs).enumerate() {
            let (x, y) = (i % w as usize, i / w as usize);
            assert!(
                (ours as f64 - theirs).abs() <= 1e-6,
                "{name}, pixel ({x}, {y}): {ours} against {theirs}"
            );
        }
        let mean = flip.mean_error(planes(&reference), planes(&test), w as usize).unwrap() as f64;
        let package = case["mean"].as_f64().unwrap();
        assert!(
            (mean - package).abs() <= 1e-6 * package,
            "{name}: mean {mean} against the package's {package}"
        );
    }
}

#[test]
fn flip_of_equal_frames_is_zero_and_grows_with_the_noise() {
    let n = 32;
    let mut rng = fsot::core::rng::Stream::new(4);
    let reference: Vec<Vec<f64>> = (0..6).map(|_| vec![0.5; n * n]).collect();
    let mut noisy = |a: f64| -> Vec<Vec<f64>> {
        reference.iter().map(|f| f.iter().map(|v| v + a * (rng.next_f64() - 0.5)).collect()).collect()
    };
    let flip = Flip::at(60.0).unwrap();
    assert_eq!(flip.judge(&reference, &reference, 2, n).unwrap(), 0.0);
    let (weak, strong) = (noisy(0.05), noisy(0.4));
    let weak = flip.judge(&weak, &reference, 2, n).unwrap();
    let strong = flip.judge(&strong, &reference, 2, n).unwrap();
    assert!(0.0 < weak && weak < strong, "weak {weak}, strong {strong}");
}

#[test]
fn flip_refuses_what_it_cannot_judge() {
    for ppd in [0.0, 1.5, f64::NAN, f64::INFINITY, -3.0] {
        let err = Flip::at(ppd).err().unwrap();
        assert!(err.to_string().contains("pixels per degree"), "{err}");
    }
    let flip = Flip::at(60.0).unwrap();
    let frames = vec![vec![0.5; 16]; 3];
    let err = flip.judge(&frames, &frames[..2], 0, 4).unwrap_err();
    assert!(err.to_string().contains("FLIP of 3 frames against 2"), "{err}");
    assert!(flip.judge(&frames, &frames, 3, 4).is_err(), "no frame from 3 on");
    assert!(flip.judge(&frames, &frames, 0, 5).is_err(), "frames of 16 values are not 5 x 5");
    let mut holed = frames.clone();
    holed[1][7] = f64::NAN;
    assert!(flip.judge(&holed, &frames, 0, 4).is_err(), "a NaN");
    let plane = [0.5f32; 12];
    let short = [0.5f32; 11];
    assert!(flip.error_map([&plane, &plane, &plane], [&plane, &plane, &short], 4).is_err());
    assert!(
        flip.error_map([&plane, &plane, &plane], [&plane, &plane, &plane], 5).is_err(),
        "12 is not 5 wide"
    );
    assert!(flip.error_map([&plane, &plane, &plane], [&plane, &plane, &plane], 0).is_err());
    assert_eq!(flip.error_map([&plane, &plane, &plane], [&plane, &plane, &plane], 4).unwrap(), vec![0.0; 12]);
}
