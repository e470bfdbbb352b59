//! Exports of a reconstructed skeleton (BVH, CSV, TRC). Not built yet: its issue brings the
//! local frames, joint angles and the BVH writer; the BVH reader already lives in [`crate::bvh`].
