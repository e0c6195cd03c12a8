//! `fsot stress`: the numerical stress suite.

use crate::*;

pub(crate) fn stress_command(args: StressArgs) -> Result<()> {
    use fsot_cli::stress::{run_stress, to_markdown, StressSize};
    let out = AtomicFile::create(&args.out)?;
    let ctx = if args.cpu_only {
        None
    } else {
        match super::env::context(args.device.clone()) {
            Ok(c) => Some(c),
            // A device named (the flag or FSOT_DEVICE) and not found: its
            // checks would silently not run.
            Err(e) if super::env::device(args.device.clone()).is_some() => return Err(e),
            Err(e) => {
                eprintln!("no Vulkan device, CPU checks only: {e}");
                None
            }
        }
    };
    let size = if args.quick { StressSize::quick() } else { StressSize::full() };
    let mut machine = fsot_cli::bench::machine::cpu_description();
    if let Some(c) = &ctx {
        machine += &format!("; Vulkan: {} ({})", c.info().name, c.info().driver);
    }
    eprintln!("stress suite on {machine}");
    let checks = run_stress(size, ctx.as_ref(), &mut |c| {
        let held = match c.passed {
            Some(true) => "ok",
            Some(false) => "FAILED",
            None => "not tried",
        };
        eprintln!("[{held}] {}: {}: {}", c.group, c.name, c.figure)
    })?;
    if let Some(c) = &ctx {
        let messages = c.validation_messages();
        if !messages.is_empty() {
            return Err(Error::invalid(format!("validation layer: {}", messages[0])));
        }
    }
    let table = to_markdown(&checks, &machine);
    out.commit(table.as_bytes())?;
    let failed = checks.iter().filter(|c| c.passed == Some(false)).count();
    let untried = checks.iter().filter(|c| c.passed.is_none()).count();
    outln!("{table}")?;
    if failed > 0 {
        return Err(Error::invalid(format!("{failed} of {} stress checks failed", checks.len())));
    }
    let held = checks.len() - untried;
    match untried {
        0 => eprintln!("all {held} checks held; table in {}", args.out.display()),
        n => eprintln!(
            "all {held} checks tried held ({n} not tried on this device); table in {}",
            args.out.display()
        ),
    }
    Ok(())
}
