//! Natural grasping (the paper's section 4): a hand model driven by a tracker and a data glove
//! whose fingers close around parts without entering them, and that knows when it holds one.

pub mod analysis;
pub mod clasp;
pub mod collider;
pub mod flex;
pub mod hand;
pub mod model;
#[cfg(test)]
mod scenarios;
pub mod script;
pub mod segment_mesh;
#[cfg(test)]
pub(crate) mod testing;

pub use model::{
    FLEX_COUNT, Finger, FlexVector, HandConfigError, HandModel, JointLevel, ROOT_VARIABLE,
    SegmentId, Side, VARIABLE_COUNT, VariableSet,
};
