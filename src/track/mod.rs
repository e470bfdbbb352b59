//! 2D tracking (VBA, Pan et al. "Feature tracking"): from the marks of one frame to the
//! positions of all 16 joints in every frame. Not built yet: its issue (VBA 2D tracking)
//! brings the block model, the morph-block similarity and the top-down tracker.
//!
//! Its input is [`crate::formats::Marks`], its output [`crate::formats::Tracks2d`].
