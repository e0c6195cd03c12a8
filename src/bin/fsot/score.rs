//! `fsot score`: the objective of a mask file.

use super::*;

pub(crate) fn score_command(args: ScoreArgs) -> Result<()> {
    let spec = args.kernel.spec()?;
    if args.slices == 0 {
        return Err(Error::invalid("--slices must be at least 1"));
    }
    let mask = fsot::io::exr::read(&args.mask)?;
    let s = score(&mask, spec, args.slices);
    println!(
        "{}: {}, kernel {}: objective {:.4e} (white noise {:.4e}; ratio {:.4})",
        args.mask.display(),
        mask.tile.describe(),
        spec.describe(),
        s.objective,
        s.white,
        s.ratio()
    );
    Ok(())
}
