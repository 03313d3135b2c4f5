//! Sliding contact (the paper's §3): a grasped part slides along what it touches and never passes
//! through it.
//!
//! * `machine`: the ghost, the visible part and the collision copy, driven by the finite state
//!   machine of the paper's Figure 6 under one of three metaphors.
//! * `advance`: conservative advancement, the first stage of contact approximation: the free
//!   end moves towards the colliding one by the distance measured to the obstacles.
//! * `bisection`: contact approximation between the last free and the first colliding pose.
//! * `contact`: contact classification from intersecting triangle pairs, with normals found
//!   from the geometry and oriented against the approach.
//! * `direction`: the remaining motion projected onto the free space the contacts leave.
//! * `force`: the spring-damper wrench a force-feedback device renders.
//! * `allowance`: slide-in units, whose parts may interfere up to a configured depth.
//! * [`motion`]: rigid motions of the part's pivot and their interpolation.
//! * `params`: a scene's `[params.sliding]` table (every key defaulted; a bad value is refused
//!   as `params.sliding.<key>`).
//! * [`world`]: the part's collision copy against the obstacles, queried pair by pair.
//!
//! # Model
//!
//! * **Ghost, visible part, collision copy.** [`SlideMachine::set_ghost`] takes the pose where
//!   the hand holds the part (the ghost, which may penetrate). Trial poses are tried on the
//!   collision copy; the visible pose only ever changes to a pose the copy found free.
//! * **Metaphors** (`[params.sliding] metaphor`, switchable at run time): `rubber-band` pulls the
//!   position towards the ghost and leaves the orientation alone; `spiral-spring` pulls position
//!   and orientation; `incremental` repeats each motion of the ghost from where the part is,
//!   dropping what a frame could not achieve.
//! * **One query per step**, so the runtime can interleave steps with its rendezvous:
//!   `Resting → Validating → Redirecting → Moving → (free) Redirecting … | (colliding)
//!   Advancing → Approximating → Classifying → Lifting → Redirecting`, back to `Resting` when the target is
//!   reached, the contacts block the rest of the motion, progress stalls, or the frame's
//!   iterations are used up.
//! * **Contact approximation**: optionally (`conservative_advancement`, off by default) and for a
//!   part arriving from free space, conservative advancement by
//!   the distance to the obstacles (the paper's future work: a measure of separation to find
//!   contacts faster) until it is within the tolerance of one or the steps stall (a part pressed
//!   on remembered contacts is within the tolerance already); then bisection to the tolerance (the
//!   distance of two poses is the pivot's travel plus the arc a point at the part's radius
//!   travels; no point of the part moves farther).
//! * **Classification**: the paper's counts of adjacent touching triangles decide vertex/face,
//!   face/vertex and edge/edge; rims of open meshes and shallow touches are decided by which
//!   triangle's edges cross the other; an edge between coplanar triangles is not a feature. Normals
//!   come from cross products, oriented against the approach, so inconsistent winding and sheets
//!   touched from either side need no special case.
//! * **New directions**: each contact forbids motions pushing its point into the obstacle; the rest
//!   of the motion is projected onto that cone by a small non-negative least-squares solve (one
//!   contact leaves a plane, two a crease line, three or more a stop). Contacts are remembered while
//!   the part presses on them and probed once per frame (a part slid past a table's edge falls).
//!   After each new contact the part is lifted off by half the tolerance, so visible poses keep a
//!   clearance.
//!
//! # Tests
//!
//! Scripted ghost paths (the scenes of benchmark B5), checked after every step that moved the
//! visible part with parry3d's intersection test: a block into a plane, a crease and a corner
//! under each metaphor, a peg into a blind hole with 1 % clearance, a pipe through an open sheet
//! with scrambled winding, a slide-in unit with and without its allowance. Time per contact point
//! and frame rates: benchmark B5 in `BENCHMARKS.md`.

pub(crate) mod advance;
pub(crate) mod allowance;
pub(crate) mod bisection;
pub(crate) mod contact;
pub(crate) mod direction;
pub(crate) mod force;
pub(crate) mod machine;
pub mod motion;
pub(crate) mod params;
pub mod world;

pub use contact::{Contact, ContactKind};
pub use direction::FreeSpace;
pub use force::{ForceModel, ForceParams, Wrench};
pub use machine::{Event, RestReason, SlideMachine, SlideState, SlideStats, SlideWorld};
pub use motion::{Motion, Pose};
pub use params::{Allowance, ParamError, SlideParams};
pub use vas_protocol::SlidingMetaphor;
