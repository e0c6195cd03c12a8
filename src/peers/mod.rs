//! The peers' methods, made by fsot on the same tile, the same way: the masks fsot
//! is measured against. `method` dispatches by name; `stbn` and `fast` are the
//! published energies; `swap` is their swap search, on the CPU and on Vulkan.
pub mod fast;
pub mod method;
pub mod stbn;
pub mod swap;
