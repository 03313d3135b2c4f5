//! The scripted hand path of B8: the right hand takes the bar with the scripted power grasp,
//! carries it across the cabin until its far end presses into the right side panel, and slides
//! it along the panel (forward, and up and down once) while pressing on.

use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use vas_testkit::script::{Keyframe, power_grasp_at, sample};

/// The bar's radius: the scripted power grasp's handle's, which the right hand's fist fits.
pub const BAR_RADIUS: f64 = 0.016;
/// The bar's length: it reaches well past the hand on both sides, so that its end meets the
/// panel while the hand stays clear of it.
pub const BAR_LENGTH: f64 = 0.4;
/// The right side panel's surface: the plane y = `PANEL_Y`.
pub const PANEL_Y: f64 = -0.85;

/// The bar's middle at the start, floating in the cabin.
const BAR_CENTRE: [f64; 3] = [-0.6, -0.35, 0.6];
/// How far the bar's axis is turned from the panel's normal about the vertical, in degrees: the
/// rim of its end meets the panel first, not the whole end face at once.
const BAR_YAW_DEG: f64 = 10.0;
/// How far past the panel's surface the hand holds the bar's end while it slides (metres):
/// the ghost stays in the panel, the visible bar on it.
const PRESS: f64 = 0.01;
/// How far the bar slides forward (metres), and how far up and down on the way.
const SLIDE_LENGTH: f64 = 0.4;
const SLIDE_WAVE: f64 = 0.05;
/// Seconds of holding still after the grasp and at the end, and of carrying the bar to the panel.
const HOLD_S: f64 = 0.1;
const CARRY_S: f64 = 0.5;
/// Seconds between the keyframes of the slide's curve.
const SLIDE_KEY_S: f64 = 0.01;
/// How far the hand reaches from its root (metres): the keep-out region's margin for the hand.
const HAND_REACH: f64 = 0.25;

/// The bar's pose at the start: its axis (its z) pointing at the right side panel, turned by
/// [`BAR_YAW_DEG`], so that the hand grasping it from above has its fingers forward.
pub fn bar_pose() -> Isometry3<f64> {
    let towards_panel =
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (BAR_YAW_DEG - 90.0).to_radians());
    let axis_along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2);
    Isometry3::from_parts(
        Translation3::from(Vector3::from(BAR_CENTRE)),
        towards_panel * axis_along_x,
    )
}

/// The hand's keyframes and where they take the bar.
#[derive(Debug, Clone)]
pub struct ScriptedPath {
    keys: Vec<Keyframe>,
    /// The bar's pose in the hand's frame once grasped.
    hand_to_bar: Isometry3<f64>,
    /// Seconds from the start to the grasp, and to the start of the slide.
    grasp_s: f64,
    slide_s: f64,
}

impl ScriptedPath {
    /// The path with a slide of `slide_seconds`.
    pub fn new(slide_seconds: f64) -> Self {
        let bar = bar_pose();
        let mut keys = power_grasp_at(&bar, BAR_RADIUS);
        let grasped = *keys.last().expect("the grasp has keyframes");
        let hand_to_bar = grasped.tracker.inverse() * bar;
        let mut then = |seconds: f64, tracker: Isometry3<f64>| {
            let last = *keys.last().expect("the grasp has keyframes");
            keys.push(Keyframe {
                time: last.time + seconds,
                tracker,
                ..last
            });
        };
        then(HOLD_S, grasped.tracker);
        // The axis's reach along y, and the end cap's radius across it.
        let axis = bar.rotation * Vector3::z();
        let reach = BAR_LENGTH / 2.0 * axis.y.abs() + BAR_RADIUS * (1.0 - axis.y.powi(2)).sqrt();
        let gap = bar.translation.y - reach - PANEL_Y;
        let pressed = Translation3::new(0.0, -(gap + PRESS), 0.0) * grasped.tracker;
        then(CARRY_S, pressed);
        let steps = (slide_seconds / SLIDE_KEY_S).ceil().max(1.0) as usize;
        let mut slid = pressed;
        for step in 1..=steps {
            let t = step as f64 / steps as f64;
            let along = Translation3::new(SLIDE_LENGTH * t, 0.0, SLIDE_WAVE * (TAU * t).sin());
            slid = along * pressed;
            then(slide_seconds / steps as f64, slid);
        }
        then(HOLD_S, slid);
        let slide_s = grasped.time + HOLD_S + CARRY_S;
        ScriptedPath {
            grasp_s: grasped.time,
            keys,
            hand_to_bar,
            slide_s,
        }
    }

    /// The keyframes sampled at `rate_hz`.
    pub fn samples(&self, rate_hz: f64) -> Vec<Keyframe> {
        sample(&self.keys, rate_hz)
    }

    /// Seconds from the start to the grasp.
    pub fn grasp_s(&self) -> f64 {
        self.grasp_s
    }

    /// Seconds from the start to the start of the slide.
    pub fn slide_s(&self) -> f64 {
        self.slide_s
    }

    /// Where the bar's middle goes: at its start pose until the grasp, then where the hand
    /// holds it.
    fn bar_centres(&self) -> impl Iterator<Item = Point3<f64>> + '_ {
        let start = bar_pose();
        self.keys.iter().map(move |key| {
            let pose = if key.time <= self.grasp_s {
                start
            } else {
                key.tracker * self.hand_to_bar
            };
            Point3::from(pose.translation.vector)
        })
    }

    /// The box the bar sweeps, grown by `margin` (metres).
    pub fn bar_region(&self, margin: f64) -> (Point3<f64>, Point3<f64>) {
        bounding_box(self.bar_centres(), BAR_LENGTH / 2.0 + margin)
    }

    /// The box the bar and the hand sweep, with room for the hand's reach: other parts kept out
    /// of it leave the path to the panel alone.
    pub fn keep_out(&self) -> (Point3<f64>, Point3<f64>) {
        let hand = self
            .keys
            .iter()
            .map(|key| Point3::from(key.tracker.translation.vector));
        bounding_box(
            self.bar_centres().chain(hand),
            BAR_LENGTH / 2.0 + HAND_REACH,
        )
    }
}

/// The box around `points`, grown by `margin` on every side.
fn bounding_box(
    points: impl Iterator<Item = Point3<f64>>,
    margin: f64,
) -> (Point3<f64>, Point3<f64>) {
    let (lo, hi) = points.fold(
        (Point3::from([f64::MAX; 3]), Point3::from([f64::MIN; 3])),
        |(lo, hi), p| (lo.inf(&p), hi.sup(&p)),
    );
    (lo - Vector3::repeat(margin), hi + Vector3::repeat(margin))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ghost_ends_in_the_panel_and_the_hand_stays_clear_of_it() {
        let path = ScriptedPath::new(1.0);
        let samples = path.samples(1000.0);
        let slide_s = path.slide_s();
        let axis = bar_pose().rotation * Vector3::z();
        for key in samples.iter().filter(|key| key.time >= slide_s) {
            let bar = key.tracker * path.hand_to_bar;
            let end = bar * Point3::new(0.0, 0.0, BAR_LENGTH / 2.0);
            let rim_y = end.y - BAR_RADIUS * (1.0 - axis.y.powi(2)).sqrt();
            assert!(
                (rim_y - (PANEL_Y - PRESS)).abs() < 1e-9,
                "at {} s the bar's rim is at y = {rim_y}",
                key.time
            );
            assert!(
                key.tracker.translation.y > PANEL_Y + 0.1,
                "the hand nears the panel"
            );
        }
        let last = samples.last().expect("samples");
        assert!((last.time - (slide_s + 1.0 + HOLD_S)).abs() < 1e-9);
        let (lo, hi) = path.keep_out();
        assert!(lo.y < PANEL_Y && hi.x > BAR_CENTRE[0] + SLIDE_LENGTH);
    }
}
