//! Mask files: OpenEXR (the primary format) and 16-bit PNG slices, both written
//! through a temporary file renamed into place.
pub mod atomic;
pub mod exr;
pub mod png;
pub mod stacked_png;
