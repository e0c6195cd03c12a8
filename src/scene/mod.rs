//! A renderer's scene: the file that says what it samples and how it is seen
//! (`file`), and the plan of masks made for it (`plan`).
pub mod file;
pub mod plan;
