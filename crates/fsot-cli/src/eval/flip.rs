//! A second, differently built judge: FLIP (Andersson et al., "FLIP: A
//! Difference Evaluator for Alternating Images", HPG 2020), its LDR form. A
//! still-image metric with its own contrast sensitivity per pixels per degree:
//! the images go to the YCxCz opponent space, are filtered by the eye's
//! spatial contrast sensitivity (a Gaussian per channel, two for blue-yellow),
//! compared in CIELab with the Hunt adjustment by the HyAB distance, and the
//! colour error is raised where edges and points differ (derivatives of a
//! Gaussian of 0.082 degrees on the luminance).
//!
//! Written in f32 the way NVIDIA's reference evaluates it (its spatial filters
//! separated into passes along x and y, image edges clamped), and tested
//! against the answers of NVIDIA's `flip-evaluator` package
//! (`crates/fsot-cli/tests/data/flip-package.json`, which `bench/flip/reference.py` writes).
//! `fsot eval --flip` compares each judged frame alone and reports the mean of
//! the per-frame mean errors (0: no difference; lower is better), on the frames
//! the ColorVideoVDP judge sees (`jod::shown`), grey as three equal sRGB channels.

use std::f32::consts::PI;

use crate::eval::jod::shown;
use fsot::error::{Error, Result};

/// The colour error's exponent, and the share of the largest colour error
/// (`PC`) that maps to `PT` of the range.
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
/// The feature detectors' width in degrees, and the feature error's exponent.
const FEATURE_WIDTH: f32 = 0.082;
const QF: f32 = 0.5;
/// The contrast sensitivity per channel (achromatic, red-green, blue-yellow) as
/// a1 sqrt(pi / b1) exp(-pi^2 x^2 / b1) + a2 sqrt(pi / b2) exp(-pi^2 x^2 / b2),
/// x in degrees (the paper's constants).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: f32 = 13.5; // blue-yellow's second Gaussian (the others have none)
const B2: f32 = 0.025;
/// The D65 white in XYZ and its inverse (the reference's digits, rounded to f32 as it rounds them).
#[allow(clippy::excessive_precision)]
const WHITE: [f32; 3] = [0.950428545, 1.000000000, 1.088900371];
#[allow(clippy::excessive_precision)]
const INV_WHITE: [f32; 3] = [1.052156925, 1.000000000, 0.918357670];

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear sRGB (D65) to XYZ.
fn rgb_to_xyz([r, g, b]: [f32; 3]) -> [f32; 3] {
    let m: [[f32; 3]; 3] = [
        [10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0],
        [2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0],
        [1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0],
    ];
    m.map(|row| row[0] * r + row[1] * g + row[2] * b)
}

#[allow(clippy::excessive_precision)]
fn xyz_to_rgb([x, y, z]: [f32; 3]) -> [f32; 3] {
    let m: [[f32; 3]; 3] = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    m.map(|row| row[0] * x + row[1] * y + row[2] * z)
}

fn xyz_to_ycxcz(xyz: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [xyz[0] * INV_WHITE[0], xyz[1] * INV_WHITE[1], xyz[2] * INV_WHITE[2]];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz([l, cx, cz]: [f32; 3]) -> [f32; 3] {
    let y = (l + 16.0) / 116.0;
    let (cx, cz) = (cx / 500.0, cz / 200.0);
    [(y + cx) * WHITE[0], y * WHITE[1], (y - cz) * WHITE[2]]
}

fn xyz_to_lab(xyz: [f32; 3]) -> [f32; 3] {
    let delta = 6.0f32 / 29.0;
    let delta_square = delta * delta;
    let delta_cube = delta * delta_square;
    let factor = 1.0 / (3.0 * delta_square);
    let term = 4.0f32 / 29.0;
    let f = |v: f32| if v > delta_cube { v.powf(1.0 / 3.0) } else { factor * v + term };
    let [x, y, z] = [f(xyz[0] * INV_WHITE[0]), f(xyz[1] * INV_WHITE[1]), f(xyz[2] * INV_WHITE[2])];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// CIELab with the Hunt adjustment: chroma scaled by 0.01 L.
fn hunt([l, a, b]: [f32; 3]) -> [f32; 3] {
    [l, 0.01 * l * a, 0.01 * l * b]
}

/// HyAB: city-block distance in L, Euclidean in (a, b).
fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    (p[0] - q[0]).abs() + ((p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])).sqrt()
}

/// The largest colour error: green against blue, raised to `QC`.
fn max_colour_error() -> f32 {
    let lab = |rgb| hunt(xyz_to_lab(rgb_to_xyz(rgb)));
    hyab(lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])).powf(QC)
}

/// One direction's taps of the separated filters at a pixels per degree.
struct Filters {
    /// Achromatic and red-green: each channel's Gaussian, summing to 1.
    y: Vec<f32>,
    cx: Vec<f32>,
    /// Blue-yellow's two Gaussians, each the square root of its 2-D weight, so
    /// the 2-D filter (their outer products summed) sums to 1.
    cz: [Vec<f32>; 2],
    /// The feature detectors' Gaussian (sums to 1) and its first and second
    /// derivatives (positive and negative taps each summing to 1 and -1), in pixels.
    g: Vec<f32>,
    dg: Vec<f32>,
    ddg: Vec<f32>,
}

impl Filters {
    fn new(ppd: f32) -> Self {
        let pi_sq = PI * PI;
        // Wide enough for the widest Gaussian (blue-yellow's first).
        let radius = (3.0 * (B1[2] / (2.0 * pi_sq)).sqrt() * ppd).ceil() as i32;
        let gaussian = |x2: f32, a: f32, b: f32| a * (PI / b).sqrt() * (-pi_sq * x2 / b).exp();
        let root = |x2: f32, a: f32, b: f32| (a * (PI / b).sqrt()).sqrt() * (-pi_sq * x2 / b).exp();
        let x2s: Vec<f32> = (-radius..=radius)
            .map(|i| {
                let x = i as f32 * (1.0 / ppd);
                x * x
            })
            .collect();
        let normalised = |taps: Vec<f32>| {
            let norm = 1.0 / taps.iter().sum::<f32>();
            taps.into_iter().map(|t| t * norm).collect::<Vec<_>>()
        };
        let y = normalised(x2s.iter().map(|&x2| gaussian(x2, A1[0], B1[0])).collect());
        let cx = normalised(x2s.iter().map(|&x2| gaussian(x2, A1[1], B1[1])).collect());
        let cz1: Vec<f32> = x2s.iter().map(|&x2| root(x2, A1[2], B1[2])).collect();
        let cz2: Vec<f32> = x2s.iter().map(|&x2| root(x2, A2, B2)).collect();
        let (s1, s2) = (cz1.iter().sum::<f32>(), cz2.iter().sum::<f32>());
        let norm = 1.0 / (s1 * s1 + s2 * s2).sqrt();
        let cz = [cz1.iter().map(|t| t * norm).collect(), cz2.iter().map(|t| t * norm).collect()];

        let sd = 0.5 * FEATURE_WIDTH * ppd;
        let radius = (3.0 * sd).ceil() as i32;
        let g: Vec<f32> =
            (-radius..=radius).map(|i| (-(i as f32 * i as f32) / (2.0 * sd * sd)).exp()).collect();
        let dg: Vec<f32> = (-radius..=radius).zip(&g).map(|(i, g)| -(i as f32) * g).collect();
        let ddg: Vec<f32> =
            (-radius..=radius).zip(&g).map(|(i, g)| (i as f32 * i as f32 / (sd * sd) - 1.0) * g).collect();
        let signed = |taps: Vec<f32>| {
            let positive: f32 = taps.iter().filter(|&&t| t > 0.0).sum();
            let negative: f32 = -taps.iter().filter(|&&t| t <= 0.0).sum::<f32>();
            taps.into_iter().map(|t| t / if t > 0.0 { positive } else { negative }).collect::<Vec<_>>()
        };
        // Divided by the sum, where the spatial filters are multiplied by its
        // inverse: each as the reference rounds it.
        let sum: f32 = g.iter().sum();
        let g = g.into_iter().map(|t| t / sum).collect();
        Self { y, cx, cz, g, dg: signed(dg), ddg: signed(ddg) }
    }
}

/// `taps` (odd length, centred) applied along x to every row of `plane`
/// (width `w`), the edges clamped; taps in order, as the reference sums them.
fn along_x(plane: &[f32], w: usize, taps: &[f32]) -> Vec<f32> {
    let r = taps.len() / 2;
    let mut out = vec![0.0f32; plane.len()];
    let mut padded = vec![0.0f32; w + 2 * r];
    for (row, out) in plane.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[i.saturating_sub(r).min(w - 1)];
        }
        for (t, &tap) in taps.iter().enumerate() {
            for (o, &v) in out.iter_mut().zip(&padded[t..t + w]) {
                *o += tap * v;
            }
        }
    }
    out
}

/// `taps` applied along y (height `plane.len() / w`), the edges clamped.
fn along_y(plane: &[f32], w: usize, taps: &[f32]) -> Vec<f32> {
    let (r, h) = (taps.len() as isize / 2, plane.len() / w);
    let mut out = vec![0.0f32; plane.len()];
    for (y, out) in out.chunks_exact_mut(w).enumerate() {
        for (t, &tap) in taps.iter().enumerate() {
            let yy = (y as isize + t as isize - r).clamp(0, h as isize - 1) as usize;
            for (o, &v) in out.iter_mut().zip(&plane[yy * w..(yy + 1) * w]) {
                *o += tap * v;
            }
        }
    }
    out
}

/// `v` clamped to [0, 1] as the reference clamps (NaN to 0, where `clamp` keeps it).
#[allow(clippy::manual_clamp)]
fn unit(v: f32) -> f32 {
    v.max(0.0).min(1.0)
}

/// An image in YCxCz, one plane per channel.
struct Opponent([Vec<f32>; 3]);

impl Opponent {
    /// From sRGB planes in [0, 1] (clamped in linear light).
    fn from_srgb(rgb: [&[f32]; 3]) -> Self {
        let mut planes = [(); 3].map(|_| Vec::with_capacity(rgb[0].len()));
        for ((&r, &g), &b) in rgb[0].iter().zip(rgb[1]).zip(rgb[2]) {
            let linear = [r, g, b].map(|v| unit(srgb_to_linear(v)));
            for (plane, v) in planes.iter_mut().zip(xyz_to_ycxcz(rgb_to_xyz(linear))) {
                plane.push(v);
            }
        }
        Self(planes)
    }

    /// Filtered by the eye's contrast sensitivity, back to linear RGB (clamped),
    /// then to Hunt-adjusted CIELab, per pixel.
    fn seen(&self, w: usize, f: &Filters) -> Vec<[f32; 3]> {
        let both = |plane: &[f32], taps: &[f32]| along_y(&along_x(plane, w, taps), w, taps);
        let (l, cx) = (both(&self.0[0], &f.y), both(&self.0[1], &f.cx));
        let (cz1, cz2) = (both(&self.0[2], &f.cz[0]), both(&self.0[2], &f.cz[1]));
        (0..l.len())
            .map(|i| {
                let rgb = xyz_to_rgb(ycxcz_to_xyz([l[i], cx[i], cz1[i] + cz2[i]])).map(unit);
                hunt(xyz_to_lab(rgb_to_xyz(rgb)))
            })
            .collect()
    }

    /// The edge and point strengths of the luminance (normalised to [0, 1]).
    fn features(&self, w: usize, f: &Filters) -> Vec<[f32; 2]> {
        let y: Vec<f32> = self.0[0].iter().map(|&v| v * (1.0 / 116.0) + 16.0 / 116.0).collect();
        let (dx, ddx, g) = (along_x(&y, w, &f.dg), along_x(&y, w, &f.ddg), along_x(&y, w, &f.g));
        let (dx, ddx) = (along_y(&dx, w, &f.g), along_y(&ddx, w, &f.g));
        let (dy, ddy) = (along_y(&g, w, &f.dg), along_y(&g, w, &f.ddg));
        (0..y.len())
            .map(|i| [(dx[i] * dx[i] + dy[i] * dy[i]).sqrt(), (ddx[i] * ddx[i] + ddy[i] * ddy[i]).sqrt()])
            .collect()
    }
}

/// FLIP seen from one distance: its filters at a number of pixels per degree.
pub struct Flip {
    filters: Filters,
    /// The largest colour error.
    cmax: f32,
}

impl Flip {
    /// FLIP at `ppd` pixels per degree, 2 to 10000 (below 2 the feature
    /// detectors' taps vanish in f32).
    pub fn at(ppd: f64) -> Result<Self> {
        if !(2.0..=1e4).contains(&ppd) {
            return Err(Error::invalid(format!("FLIP at {ppd} pixels per degree: give 2 to 10000")));
        }
        Ok(Self { filters: Filters::new(ppd as f32), cmax: max_colour_error() })
    }

    /// The error map (row-major, width `w`) of `test` against `reference`, each
    /// three sRGB planes of the same size with values in [0, 1].
    pub fn error_map(&self, reference: [&[f32]; 3], test: [&[f32]; 3], w: usize) -> Result<Vec<f32>> {
        let len = reference[0].len();
        if w == 0 || len == 0 || len % w != 0 || reference.iter().chain(&test).any(|p| p.len() != len) {
            return Err(Error::invalid(format!(
                "FLIP of planes of {:?} values against {:?}, {w} wide",
                test.map(|p| p.len()),
                reference.map(|p| p.len())
            )));
        }
        let (f, cmax) = (&self.filters, self.cmax);
        let (r, t) = (Opponent::from_srgb(reference), Opponent::from_srgb(test));
        let pccmax = PC * cmax;
        let colour = r.seen(w, f).into_iter().zip(t.seen(w, f)).map(|(p, q)| {
            let e = hyab(p, q).powf(QC);
            // Up to PC of the largest error maps to [0, PT]; the rest to (PT, 1].
            if e < pccmax {
                e * (PT / pccmax)
            } else {
                PT + ((e - pccmax) / (cmax - pccmax)) * (1.0 - PT)
            }
        });
        let features = r.features(w, f).into_iter().zip(t.features(w, f));
        Ok(colour
            .zip(features)
            .map(|(e, (p, q))| {
                let edge = (p[0] - q[0]).abs();
                let point = (p[1] - q[1]).abs();
                let feature = ((1.0 / 2.0f32.sqrt()) * edge.max(point)).powf(QF);
                e.powf(1.0 - feature)
            })
            .collect())
    }

    /// The mean of the error map, summed in order as the reference does.
    pub fn mean_error(&self, reference: [&[f32]; 3], test: [&[f32]; 3], w: usize) -> Result<f32> {
        let map = self.error_map(reference, test, w)?;
        Ok(map.iter().fold(0.0f32, |s, &v| s + v) / map.len() as f32)
    }

    /// The mean over frames of the mean error of `render` against `reference`
    /// (n x n grey frames, from `start`), as `fsot eval` judges.
    pub fn judge(&self, render: &[Vec<f64>], reference: &[Vec<f64>], start: usize, n: usize) -> Result<f64> {
        let sized = |seq: &[Vec<f64>]| seq.iter().all(|f| f.len() == n * n);
        if render.len() != reference.len() || start >= render.len() || !sized(render) || !sized(reference) {
            return Err(Error::invalid(format!(
                "FLIP of {} frames against {}, from frame {start}, each {n} x {n}",
                render.len(),
                reference.len()
            )));
        }
        if render.iter().chain(reference).flatten().any(|v| !v.is_finite()) {
            return Err(Error::invalid("FLIP of frames that hold values that are not finite"));
        }
        let [test, refs] = shown(render, reference, start);
        let mut total = 0.0;
        for (t, r) in test.iter().zip(&refs) {
            total += self.mean_error([r, r, r], [t, t, t], n)? as f64;
        }
        Ok(total / test.len() as f64)
    }
}
