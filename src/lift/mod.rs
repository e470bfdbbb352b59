//! 3D reconstruction (VBA, Pan et al. "Reconstruction of 3D human motion skeleton"): from
//! 2D tracks to a metric skeleton per frame. Not built yet: its issue brings the key-triangle
//! calibration (eqs. 6–9) and the frame-to-frame propagation (eqs. 10–11).
//!
//! Its input is [`crate::formats::Tracks2d`], its output [`crate::formats::Skeleton3d`].
