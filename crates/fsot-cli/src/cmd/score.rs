//! `fsot score`: the objective of a mask file.

use crate::*;

pub(crate) fn score_command(args: ScoreArgs) -> Result<()> {
    if !(1..=fsot::optimize::settings::MAX_SLICES).contains(&args.slices) {
        return Err(Error::invalid(format!(
            "--slices must be 1 to {}, got {}",
            fsot::optimize::settings::MAX_SLICES,
            args.slices
        )));
    }
    let mask = fsot::Mask::open(&args.mask)?;
    let chosen = args.kernel.is_some()
        || args.display.is_some()
        || args.sigma.is_some()
        || args.sigma_t.is_some()
        || args.alpha.is_some()
        || args.fps.is_some();
    let (spec, whence) = match chosen {
        true => {
            kernel_flags_apply(
                args.kernel,
                args.sigma_t.is_some(),
                args.alpha.is_some(),
                args.fps.is_some(),
            )?;
            let name = args.kernel.map(|k| k.as_str()).unwrap_or("perceptual-taa");
            let spec = kernel_spec(
                name,
                args.display.as_deref(),
                args.sigma,
                args.sigma_t,
                args.alpha.unwrap_or(DEFAULT_ALPHA),
                args.fps.unwrap_or(DEFAULT_FPS),
            )?;
            (spec, "as asked")
        }
        false => {
            let recorded = mask.meta("kernel").unwrap_or("none");
            let spec = KernelSpec::from_description(recorded).ok_or_else(|| {
                Error::invalid(format!(
                    "{}: its recorded kernel ({recorded:?}) is not one of fsot's; give --kernel (and its parameters)",
                    args.mask.display()
                ))
            })?;
            (spec, "recorded in the mask")
        }
    };
    let s = score(&mask, spec, args.slices);
    outln!(
        "{}: {}, kernel {} ({whence}): objective {:.4e} (white noise {:.4e}; ratio {:.4})",
        args.mask.display(),
        mask.tile.describe(),
        spec.describe(),
        s.objective,
        s.white,
        s.ratio()
    )?;
    Ok(())
}
