//! A minimal line plot as PNG (no text): series of (x, y) on a log-x, linear-y
//! frame, each in its own colour; the caller documents axes and colours.

use fsot::error::{Error, Result};

/// Colours of the series, in order (RGB).
pub const COLOURS: [[u8; 3]; 6] =
    [[31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [148, 103, 189], [140, 86, 75]];

/// Plots the series on a `width` x `height` canvas: x on a log scale over the
/// data's positive range, y linear from 0 to the data's maximum. Grid lines at
/// each power of ten in x and each 0.1 in y.
pub fn line_plot(series: &[Vec<(f64, f64)>], width: usize, height: usize) -> Result<Vec<u8>> {
    let points: Vec<(f64, f64)> =
        series.iter().flatten().copied().filter(|p| p.0 > 0.0 && p.1.is_finite()).collect();
    if points.is_empty() {
        return Err(Error::invalid("nothing to plot"));
    }
    let (x0, x1) =
        points.iter().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0.log10()), a.1.max(p.0.log10())));
    let (x0, x1) = (x0.floor(), x1.ceil().max(x0.floor() + 1.0));
    let y1 = points.iter().fold(0.0f64, |a, p| a.max(p.1)).max(1e-12) * 1.05;
    let m = 20usize;
    let (pw, ph) = (width - 2 * m, height - 2 * m);
    let mut rgb = vec![255u8; width * height * 3];
    let put = |x: usize, y: usize, c: [u8; 3], rgb: &mut Vec<u8>| {
        if x < width && y < height {
            rgb[(y * width + x) * 3..(y * width + x) * 3 + 3].copy_from_slice(&c);
        }
    };
    let to_px = |x: f64, y: f64| -> (f64, f64) {
        let u = (x.log10() - x0) / (x1 - x0);
        let v = y / y1;
        (m as f64 + u * pw as f64, (m + ph) as f64 - v * ph as f64)
    };
    // Grid.
    for d in x0 as i64..=x1 as i64 {
        let (px, _) = to_px(10f64.powi(d as i32), 0.0);
        for y in m..m + ph {
            put(px as usize, y, [210, 210, 210], &mut rgb);
        }
    }
    let mut g = 0.0;
    while g <= y1 {
        let (_, py) = to_px(10f64.powf(x0), g);
        for x in m..m + pw {
            put(x, py as usize, if g == 0.0 { [0, 0, 0] } else { [230, 230, 230] }, &mut rgb);
        }
        g += 0.1;
    }
    // Series: segments drawn by small steps, points as 3 x 3 squares.
    for (k, s) in series.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        let pts: Vec<(f64, f64)> = s.iter().filter(|p| p.0 > 0.0).map(|p| to_px(p.0, p.1)).collect();
        for w in pts.windows(2) {
            let steps = ((w[1].0 - w[0].0).abs().max((w[1].1 - w[0].1).abs()) as usize).max(1);
            for i in 0..=steps {
                let t = i as f64 / steps as f64;
                put(
                    (w[0].0 + t * (w[1].0 - w[0].0)) as usize,
                    (w[0].1 + t * (w[1].1 - w[0].1)) as usize,
                    c,
                    &mut rgb,
                );
            }
        }
        for &(x, y) in &pts {
            for dy in 0..3 {
                for dx in 0..3 {
                    put(
                        (x as usize + dx).saturating_sub(1),
                        (y as usize + dy).saturating_sub(1),
                        c,
                        &mut rgb,
                    );
                }
            }
        }
    }
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| Error::invalid(format!("PNG: {e}")))?;
        writer.write_image_data(&rgb).map_err(|e| Error::invalid(format!("PNG: {e}")))?;
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_series_lands_in_its_colour_and_empty_input_is_refused() {
        let bytes = line_plot(&[vec![(1.0, 1.0), (10.0, 0.5), (100.0, 0.2)]], 200, 120).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        reader.next_frame(&mut buf).unwrap();
        let coloured = buf.chunks(3).filter(|c| c == &COLOURS[0]).count();
        assert!(coloured > 100, "{coloured}");
        assert!(line_plot(&[vec![]], 200, 120).is_err());
    }
}
