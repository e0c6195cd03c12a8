//! The environment variables the command line reads: `FSOT_DEVICE` and
//! `FSOT_VALIDATION` (the library reads only the documented `FSOT_FAULT` test
//! switch).

use fsot::vk::{Context, ContextOptions};

use crate::{Error, Result};

/// The Vulkan device: the flag, else `FSOT_DEVICE`.
pub(crate) fn device(flag: Option<String>) -> Option<String> {
    flag.or_else(|| std::env::var("FSOT_DEVICE").ok()).filter(|d| !d.is_empty())
}

/// `FSOT_VALIDATION=1`: the Vulkan validation layer on.
pub(crate) fn validation() -> bool {
    std::env::var("FSOT_VALIDATION").map(|v| v == "1").unwrap_or(false)
}

/// A Vulkan context on the device the flag or the environment names.
pub(crate) fn context(flag: Option<String>) -> Result<Context> {
    Ok(Context::new(&ContextOptions { validation: validation(), device: device(flag) })?)
}

/// A second interrupt sooner than this after the first is the same one again.
const REPEAT: std::time::Duration = std::time::Duration::from_secs(1);

/// A cancel flag that Ctrl-C (SIGINT) and SIGTERM set: the run stops between
/// iterations (and saves its checkpoint). A second signal, a second or more
/// after the first, ends the process at once, exit status 130: outputs are
/// renamed into place whole, so what was there stays (a signal while one is
/// written may leave its `.tmp` file beside it). Once per process.
pub fn interrupt_flag() -> Result<fsot::optimize::run::CancelFlag> {
    let flag = fsot::optimize::run::CancelFlag::new();
    let set = flag.clone();
    let first = std::sync::OnceLock::new();
    ctrlc::set_handler(move || {
        if let Some(t) = first.get() {
            // The same signal sent again to the process group (as `timeout` and
            // some shells do) within the second is not a second request.
            if std::time::Instant::elapsed(t) < REPEAT {
                return;
            }
            eprintln!("\nquit at once: what the run did since its last checkpoint is not saved");
            std::process::exit(130);
        }
        let _ = first.set(std::time::Instant::now());
        set.cancel();
        eprintln!("\ninterrupted: the run stops between iterations (again, a second or more later, to quit at once)");
    })
    .map_err(|e| Error::invalid(format!("cannot catch interrupts: {e}")))?;
    Ok(flag)
}
