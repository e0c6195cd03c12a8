//! Failure injection (the one environment switch the library reads; documented in
//! the README), so that tests can see what users see when a GPU fails:
//! `FSOT_FAULT=device-lost:N` makes the N-th queue submission of the process
//! (counting from 1) fail as `VK_ERROR_DEVICE_LOST`; `FSOT_FAULT=device-memory:B`
//! makes every device-local allocation larger than B bytes fail as out of device
//! memory. Unset (always, outside tests), it does nothing.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use ash::vk;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fault {
    None,
    DeviceLost(u64),
    DeviceMemory(u64),
}

fn fault() -> Fault {
    static FAULT: OnceLock<Fault> = OnceLock::new();
    *FAULT.get_or_init(|| {
        let Ok(v) = std::env::var("FSOT_FAULT") else { return Fault::None };
        let number = |s: &str| s.trim().parse::<u64>().ok();
        match v.split_once(':') {
            Some(("device-lost", n)) => number(n).map(Fault::DeviceLost),
            Some(("device-memory", b)) => number(b).map(Fault::DeviceMemory),
            _ => None,
        }
        .unwrap_or(Fault::None)
    })
}

/// Called before each queue submission: the injected result, if any.
pub(crate) fn submission() -> Option<vk::Result> {
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let n = COUNT.fetch_add(1, Ordering::SeqCst) + 1;
    match fault() {
        Fault::DeviceLost(at) if n >= at => Some(vk::Result::ERROR_DEVICE_LOST),
        _ => None,
    }
}

/// Called before each device-local allocation of `bytes`: true to refuse it.
pub(crate) fn refuse_device_allocation(bytes: u64) -> bool {
    matches!(fault(), Fault::DeviceMemory(limit) if bytes > limit)
}
