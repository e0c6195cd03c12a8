//! A display's viewing geometry, as pixels per degree of visual angle: given
//! directly, by the name of a display model, or by resolution, diagonal and
//! viewing distance. The eye's spatial filter follows from it (`csf.rs`).
//!
//! The named models carry the geometry of ColorVideoVDP's display models of
//! the same names (Mantiuk et al. 2024): resolution, diagonal and distance.

use crate::error::{Error, Result};

/// Named displays: (name, resolution, diagonal in inches, viewing distance in metres).
pub const PRESETS: [(&str, [u32; 2], f64, f64); 10] = [
    ("standard_fhd", [1920, 1080], 24.0, 0.6),
    ("standard_4k", [3840, 2160], 30.0, 0.7472),
    ("sdr_fhd_24", [1920, 1080], 24.0, 0.6),
    ("sdr_4k_30", [3840, 2160], 30.0, 0.6),
    ("standard_phone", [2400, 1080], 6.0, 0.4),
    ("iphone_12_pro", [2532, 1170], 6.1, 20.0 * 0.0254),
    ("ipad_pro_12_9", [2732, 2048], 12.9, 20.0 * 0.0254),
    ("macbook_pro_16", [3072, 1920], 16.0, 25.0 * 0.0254),
    ("lg_oled_2017_sdr", [3840, 2160], 64.5, 101.0 * 0.0254),
    ("eizo_CG3146", [4096, 2160], 31.063, 0.73406),
];

/// The display fsot plans for when a scene names none.
pub const DEFAULT_DISPLAY: &str = "standard_fhd";

/// Pixels per degree at the centre of a flat screen: the inverse of the angle
/// one pixel subtends, 2 atan(pitch / (2 distance)), in degrees.
pub fn pixels_per_degree(resolution: [u32; 2], diagonal_inches: f64, distance_m: f64) -> Result<f64> {
    let [w, h] = resolution;
    if w == 0 || h == 0 {
        return Err(Error::invalid(format!("a display resolution of {w} x {h}")));
    }
    if !(diagonal_inches.is_finite() && diagonal_inches > 0.0 && diagonal_inches <= 1000.0) {
        return Err(Error::invalid(format!(
            "a display diagonal must be in (0, 1000] inches, got {diagonal_inches:?}"
        )));
    }
    if !(distance_m.is_finite() && distance_m > 0.0 && distance_m <= 100.0) {
        return Err(Error::invalid(format!("a viewing distance must be in (0, 100] m, got {distance_m:?}")));
    }
    let (w, h) = (w as f64, h as f64);
    let pitch = diagonal_inches * 0.0254 / w.hypot(h);
    Ok(1.0 / (2.0 * (0.5 * pitch / distance_m).atan()).to_degrees())
}

/// A named display's pixels per degree, rounded to a hundredth.
pub fn preset_ppd(name: &str) -> Result<f64> {
    let (_, resolution, diagonal, distance) = PRESETS.iter().find(|p| p.0 == name).ok_or_else(|| {
        let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
        Error::invalid(format!("unknown display {name:?}; one of {}", names.join(", ")))
    })?;
    check_ppd(pixels_per_degree(*resolution, *diagonal, *distance)?)
}

/// Pixels per degree fsot accepts: from a phone at arm's length to far beyond
/// what an eye resolves.
pub const PPD_RANGE: std::ops::RangeInclusive<f64> = 5.0..=500.0;

/// Checks a pixels-per-degree figure and rounds it to a hundredth (finer than
/// any display's geometry is known; short in a mask's description).
pub fn check_ppd(ppd: f64) -> Result<f64> {
    if ppd.is_finite() && PPD_RANGE.contains(&ppd) {
        Ok((ppd * 100.0).round() / 100.0)
    } else {
        Err(Error::invalid(format!(
            "pixels per degree must be in [{}, {}], got {ppd:?}",
            PPD_RANGE.start(),
            PPD_RANGE.end()
        )))
    }
}

/// Reads `--display`: a number (pixels per degree), a display's name, or
/// `WxH:DIAGONALin:DISTANCEm` (for example `2560x1440:27in:0.7m`).
pub fn parse(text: &str) -> Result<f64> {
    let text = text.trim();
    if let Ok(ppd) = text.parse::<f64>() {
        return check_ppd(ppd);
    }
    if let Some((size, rest)) = text.split_once(':') {
        let bad = || {
            Error::invalid(format!(
                "display {text:?}: expected WxH:DIAGONALin:DISTANCEm, e.g. 2560x1440:27in:0.7m"
            ))
        };
        let (w, h) = size.split_once('x').ok_or_else(bad)?;
        let (diagonal, distance) = rest.split_once(':').ok_or_else(bad)?;
        let diagonal: f64 = diagonal.strip_suffix("in").ok_or_else(bad)?.parse().map_err(|_| bad())?;
        let distance: f64 = distance.strip_suffix('m').ok_or_else(bad)?.parse().map_err(|_| bad())?;
        let resolution = [w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?];
        return check_ppd(pixels_per_degree(resolution, diagonal, distance)?);
    }
    check_ppd(preset_ppd(text)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixel_subtends_its_pitch_over_the_distance() {
        // 1000 pixels over a diagonal of 10 m / 0.0254 (10 mm pitch) at 1 m: 0.573 degrees.
        let ppd = pixels_per_degree([600, 800], 10.0 / 0.0254, 1.0).unwrap();
        let degrees = 2.0 * (0.005f64).atan().to_degrees();
        assert!((ppd - 1.0 / degrees).abs() < 1e-12, "{ppd}");
        // Twice the distance: nearly twice the pixels per degree.
        let far = pixels_per_degree([600, 800], 10.0 / 0.0254, 2.0).unwrap();
        assert!((far / ppd - 2.0).abs() < 1e-4);
    }

    #[test]
    fn every_form_of_display_reads_and_bad_ones_are_refused() {
        assert_eq!(parse("60").unwrap(), 60.0);
        let fhd = parse("standard_fhd").unwrap();
        assert!((37.0..39.0).contains(&fhd), "{fhd}");
        let same = parse("1920x1080:24in:0.6m").unwrap();
        assert_eq!(same, fhd);
        for bad in
            ["0", "-3", "1e9", "nan", "standard_8k", "1920x1080:24:0.6m", "1920x:24in:0.6m", "x1080:24in:0m"]
        {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }
}
