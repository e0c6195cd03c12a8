//! The eye's spatial filter at a display's pixels per degree.
//!
//! Contrast sensitivity: Barten's closed-form model (P. G. J. Barten, "Evaluation
//! of subjective image quality with the square-root integral method", JOSA A
//! 7(10), 1990; the simplified formula of his SPIE 1989 paper),
//!
//! S(u) = a u exp(-b u) sqrt(1 + c exp(b u)),
//! a = 540 (1 + 0.7 / L)^-0.2 / (1 + 12 / (w (1 + u / 3)^2)),
//! b = 0.3 (1 + 100 / L)^0.15, c = 0.06,
//!
//! u in cycles per degree, L the adapting luminance (cd/m^2), w the field size
//! (degrees). fsot takes L = 100 cd/m^2 (mid-grey of a 200 cd/m^2 display) and
//! w = 10 degrees.
//!
//! The level-set form of the objective needs a kernel that is positive in space,
//! so its frequency response is largest at DC, where the sensitivity falls
//! (the CSF is band-pass). The kernel follows the CSF's passband and its fall
//! to high frequencies and is flat below the peak: the target response at f
//! cycles per pixel is min(1, S(f ppd) / S_peak). It is fitted, by non-negative
//! least squares over the pixel grid's frequencies, as a mixture of Gaussians
//! exp(-r^2 / s^2) on a fixed ladder of widths s, each normalised on the pixel
//! grid; positive weights keep the mixture positive everywhere. On a display of
//! 75 pixels per degree the fit is close to a Gaussian of 1.8 pixels with a
//! heavier tail; at 38 it is nearly a Gaussian of 0.9 pixels.

/// The adapting luminance the sensitivity is taken at, cd/m^2.
pub const LUMINANCE: f64 = 100.0;
/// The field size the sensitivity is taken at, degrees.
pub const FIELD_DEGREES: f64 = 10.0;

/// Widths of the mixture's Gaussians, pixels (exp(-r^2 / s^2)), up to
/// `LADDER_PPD`; the narrowest is all but the centre pixel alone.
pub const LADDER: [f64; 9] = [0.3, 0.45, 0.6, 0.9, 1.3, 1.8, 2.5, 3.5, 5.0];

/// The most pixels per degree `LADDER` is made for. Above, its widths scale with
/// ppd: the eye's filter, fixed in degrees, widens in pixels, and the target is
/// a function of cycles per degree, so the fit at k times this ppd is the fit at
/// this ppd widened k times (up to the pixel grid). The widest Gaussian unscaled
/// would clip the kernel: at 500 ppd to 5 pixels of the 11.7 its fit needs.
pub const LADDER_PPD: f64 = 150.0;

/// The ladder's widths at `ppd`.
pub fn ladder(ppd: f64) -> [f64; 9] {
    let k = (ppd / LADDER_PPD).max(1.0);
    LADDER.map(|s| s * k)
}

/// A Gaussian's support: offsets with exp(-r^2 / s^2) >= this are kept.
const SUPPORT: f64 = 1e-6;

/// Barten's contrast sensitivity at `u` cycles per degree.
pub fn barten(u: f64, luminance: f64, field_degrees: f64) -> f64 {
    if u <= 0.0 {
        return 0.0;
    }
    let a =
        540.0 * (1.0 + 0.7 / luminance).powf(-0.2) / (1.0 + 12.0 / (field_degrees * (1.0 + u / 3.0).powi(2)));
    let b = 0.3 * (1.0 + 100.0 / luminance).powf(0.15);
    let c = 0.06;
    a * u * (-b * u).exp() * (1.0 + c * (b * u).exp()).sqrt()
}

/// The sensitivity's peak: (frequency in cycles per degree, sensitivity), found on
/// a 0.01 cpd grid up to 60 cpd.
pub fn peak() -> (f64, f64) {
    (1..=6000)
        .map(|k| {
            let u = k as f64 * 0.01;
            (u, barten(u, LUMINANCE, FIELD_DEGREES))
        })
        .fold((0.0, 0.0), |best, p| if p.1 > best.1 { p } else { best })
}

/// The response the kernel aims at, `f` cycles per pixel at `ppd` pixels per degree.
pub fn target(f: f64, ppd: f64) -> f64 {
    let (u_peak, s_peak) = peak();
    let u = f * ppd;
    if u <= u_peak {
        1.0
    } else {
        barten(u, LUMINANCE, FIELD_DEGREES) / s_peak
    }
}

/// The 1-D profile of exp(-k^2 / s^2) on the pixel grid, normalised to sum 1:
/// weights for k = -r..=r.
pub fn profile(s: f64) -> Vec<f64> {
    let r = (s * (1.0 / SUPPORT).ln().sqrt()).ceil().max(1.0) as i64;
    let raw: Vec<f64> = (-r..=r).map(|k| (-((k * k) as f64) / (s * s)).exp()).collect();
    let sum: f64 = raw.iter().sum();
    raw.iter().map(|v| v / sum).collect()
}

/// The frequency response of a profile at `f` cycles per pixel.
fn profile_response(p: &[f64], f: f64) -> f64 {
    let r = (p.len() / 2) as f64;
    p.iter().enumerate().map(|(i, w)| w * (std::f64::consts::TAU * f * (i as f64 - r)).cos()).sum()
}

/// The mixture's weights on `ladder(ppd)` (summing to 1) for a display of `ppd`
/// pixels per degree (`fit`), fitted once per `ppd` in a process: a kernel's
/// construction asks for it several times.
pub fn mixture(ppd: f64) -> Vec<(f64, f64)> {
    type Fitted = Vec<(u64, Vec<(f64, f64)>)>;
    static FITTED: std::sync::Mutex<Fitted> = std::sync::Mutex::new(Vec::new());
    let key = ppd.to_bits();
    if let Some((_, m)) = FITTED.lock().unwrap_or_else(|e| e.into_inner()).iter().find(|(k, _)| *k == key) {
        return m.clone();
    }
    let m = fit(ppd);
    FITTED.lock().unwrap_or_else(|e| e.into_inner()).push((key, m.clone()));
    m
}

/// Non-negative least squares of the separable responses of `ladder(ppd)`'s
/// profiles against `target` at `ppd` on a 33 x 33 grid of frequencies in
/// [0, 0.5]^2 cycles per pixel; weights summing to 1.
fn fit(ppd: f64) -> Vec<(f64, f64)> {
    let n = 33;
    let freqs: Vec<f64> = (0..n).map(|k| 0.5 * k as f64 / (n - 1) as f64).collect();
    let widths = ladder(ppd);
    let responses: Vec<Vec<f64>> =
        widths.iter().map(|&s| freqs.iter().map(|&f| profile_response(&profile(s), f)).collect()).collect();
    // Rows: grid points; columns: ladder entries.
    let mut a = Vec::with_capacity(n * n);
    let mut b = Vec::with_capacity(n * n);
    for (i, fx) in freqs.iter().enumerate() {
        for (j, fy) in freqs.iter().enumerate() {
            a.push(responses.iter().map(|r| r[i] * r[j]).collect::<Vec<f64>>());
            b.push(target(fx.hypot(*fy), ppd));
        }
    }
    let w = nnls(&a, &b);
    let sum: f64 = w.iter().sum();
    widths.iter().zip(&w).filter(|(_, &w)| w > 0.0).map(|(&s, &w)| (w / sum, s)).collect()
}

/// Non-negative least squares, min |A w - b| with w >= 0, by cyclic coordinate
/// descent on the normal equations until no weight moves by 1e-13.
fn nnls(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let m = a[0].len();
    let gram: Vec<Vec<f64>> =
        (0..m).map(|i| (0..m).map(|j| a.iter().map(|row| row[i] * row[j]).sum()).collect()).collect();
    let atb: Vec<f64> = (0..m).map(|i| a.iter().zip(b).map(|(row, y)| row[i] * y).sum()).collect();
    let mut w = vec![0.0; m];
    for _ in 0..200_000 {
        let mut moved = 0.0f64;
        for i in 0..m {
            let g: f64 = (0..m).map(|j| gram[i][j] * w[j]).sum::<f64>() - atb[i];
            let next = (w[i] - g / gram[i][i]).max(0.0);
            moved = moved.max((next - w[i]).abs());
            w[i] = next;
        }
        if moved < 1e-13 {
            break;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barten_peaks_at_a_few_cycles_per_degree_and_resolves_about_fifty() {
        // The human CSF at photopic luminance: a peak of a few hundred near 3 to 5 cpd,
        // and a resolution limit (sensitivity 1) of about 50 to 60 cpd.
        let (u, s) = peak();
        assert!((3.0..=5.0).contains(&u), "peak at {u} cpd");
        assert!((300.0..=700.0).contains(&s), "peak sensitivity {s}");
        let limit =
            (1..6000).map(|k| k as f64 * 0.01 + 10.0).find(|&u| barten(u, LUMINANCE, FIELD_DEGREES) < 1.0);
        assert!(matches!(limit, Some(l) if (45.0..=60.0).contains(&l)), "{limit:?}");
        // Dimmer light: less sensitivity, the peak lower.
        assert!(barten(4.0, 10.0, 10.0) < barten(4.0, 100.0, 10.0));
    }

    #[test]
    fn barten_matches_its_closed_form_evaluated_outside_fsot() {
        // S(u) at L = 100 cd/m^2, w = 10 degrees, from the formula in this
        // module's notes evaluated by Python 3's math module.
        let pinned = [
            (0.5, 125.54761130002423),
            (1.0, 240.24990574665966),
            (3.0, 494.35574645014714),
            (4.0, 517.0641608859086),
            (10.0, 297.05508947442365),
            (30.0, 26.63213012140464),
        ];
        for (u, want) in pinned {
            let got = barten(u, LUMINANCE, FIELD_DEGREES);
            assert!((got - want).abs() < 1e-12 * want, "S({u}) = {got}, not {want}");
        }
    }

    #[test]
    fn the_fit_follows_the_target_at_high_pixels_per_degree_and_widens_with_them() {
        // The mixture's own response (its Gaussians' sums on the pixel grid, in
        // f64) against the target, over the grid of frequencies the fit uses.
        let response = |ppd: f64, f: f64| {
            mixture(ppd).iter().map(|&(w, s)| w * profile_response(&profile(s), f)).sum::<f64>()
        };
        let rms = |ppd: f64| {
            let freqs: Vec<f64> = (0..33).map(|k| 0.5 * k as f64 / 32.0).collect();
            let mut sum = 0.0;
            for fx in &freqs {
                for fy in &freqs {
                    let got = response(ppd, *fx) * response(ppd, *fy);
                    sum += (got - target(fx.hypot(*fy), ppd)).powi(2);
                }
            }
            (sum / (33.0 * 33.0)).sqrt()
        };
        let width = |ppd: f64| mixture(ppd).iter().map(|(w, s)| w * s).sum::<f64>();
        // No worse past the ladder's own ppd than at it (an unscaled ladder's
        // widest Gaussian clips the fit there: rms 0.026 at 300 against 0.018
        // at 150).
        let at_ladder = rms(LADDER_PPD);
        for ppd in [200.0, 300.0, 500.0] {
            let e = rms(ppd);
            assert!(e <= at_ladder, "{ppd} ppd: rms {e} against {at_ladder} at {LADDER_PPD}");
        }
        // Past the ladder's ppd the kernel widens nearly in proportion.
        let ratio = width(500.0) / width(250.0);
        assert!((1.8..=2.0).contains(&ratio), "{ratio}");
        // Up to it, the ladder is the unscaled one.
        assert_eq!(ladder(LADDER_PPD), LADDER);
        assert_eq!(ladder(37.84), LADDER);
    }

    #[test]
    fn the_fit_is_a_positive_mixture_summing_to_one_and_narrower_for_coarser_pixels() {
        let fine = mixture(75.0);
        let coarse = mixture(38.0);
        for m in [&fine, &coarse] {
            assert!(m.iter().all(|&(w, _)| w > 0.0));
            assert!((m.iter().map(|p| p.0).sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // The mean width: pixels of a coarser display are seen sharper.
        let width = |m: &[(f64, f64)]| m.iter().map(|(w, s)| w * s).sum::<f64>();
        assert!(width(&coarse) < 0.8 * width(&fine), "{coarse:?} against {fine:?}");
    }
}
