//! The human model shared by every stage: the 16 joints, the bone tree rooted at the pelvis,
//! the body parts tracked as blocks, and proportions scaled to a subject.

mod bone;
mod distance;
mod joint;
mod proportions;
mod standing;

pub use bone::{BONE_COUNT, BodyPart, Bone, Breadth};
pub use distance::segment_distance;
pub use joint::{JOINT_COUNT, Joint, MarkingView, PerJoint};
pub use proportions::{DEFAULT_HEIGHT_M, Proportions, ProportionsError, SubjectModel};
pub use standing::{LimbDirections, standing_pose};
