//! B14, smoothing hand tracking: the One Euro filter of the server's input on the real WebXR
//! captures of `tests/fixtures/hands/`, with tracker-like noise added.
//!
//! Procedure: each capture as a right hand, retargeted onto the shipped right hand model as the
//! server does it, sampled at `--rate` Hz, with seeded Gaussian noise on every joint of every
//! sample: positions moved by an RMS distance of `--noise-mm`, orientations turned about a random
//! axis by an RMS angle of `--noise-deg`. Each retargeted root and flex vector goes through the
//! filter with the scene's default `[params.tracking]` (`StreamFilter`, as the server's input does
//! it) and is also kept unfiltered. The palm's pose is the model's palm segment on the root.
//!
//! * At rest: the hand held still for [`REST_S`] s. From the end of the first second (the
//!   filter starts from the first noisy sample and settles), the jitter is the RMS distance of
//!   the palm from its mean position, its RMS angle from its mean rotation, and the RMS deviation
//!   of the flex values from their means.
//! * Moving: the hand still for a second, then moving at `--speed` m/s along x for
//!   [`MOVE_S`] s. The lag is the filtered palm's distance behind the noise-free palm along the
//!   motion, over the speed: its mean over the second half of the motion (the steady lag) and
//!   its largest over the whole (the start, while the speed estimate rises). Then likewise the
//!   hand turning about the vertical through its wrist at `--turn` rad/s: the filtered palm's
//!   angle from the noise-free palm's over the turn rate, mean over the second half of the turn.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use vas_protocol::HandSide;
use vas_server::grasping::model::{FLEX_COUNT, HandModel};
use vas_server::grasping::retarget::{Capture, HandJoints, Joint, Retargeter};
use vas_server::scene::TrackingParams;
use vas_server::simulation::filter::{Sample, StreamFilter};

use crate::args::{OutputArgs, finite_number};
use crate::report::{LinePlot, Series, Table, format_number};

/// How long the hand is held still (seconds), of which the first second is not measured.
pub const REST_S: f64 = 10.0;

/// How long the moving hand moves (seconds).
pub const MOVE_S: f64 = 0.5;

/// What `vas-bench filter` measures with.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FilterConfig {
    /// Samples per second.
    pub rate_hz: f64,
    /// RMS distance by which noise moves each joint (mm).
    pub noise_mm: f64,
    /// RMS angle by which noise turns each joint (degrees).
    pub noise_deg: f64,
    /// Speed of the moving hand (m/s).
    pub speed: f64,
    /// Angular speed of the turning hand (rad/s).
    pub turn_rate: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// The filter's parameters.
    pub tracking: TrackingParams,
}

/// One capture's figures.
#[derive(Debug, Clone, Serialize)]
pub struct FilterRow {
    /// The capture's file name.
    pub capture: String,
    /// The palm's RMS distance from its mean position at rest, unfiltered and filtered (mm).
    pub jitter_mm: (f64, f64),
    /// The palm's RMS angle from its mean rotation at rest, unfiltered and filtered (degrees).
    pub jitter_deg: (f64, f64),
    /// The flex values' RMS deviation from their means at rest, unfiltered and filtered
    /// (degrees).
    pub flex_jitter_deg: (f64, f64),
    /// The filtered palm's mean lag over the second half of the motion (ms).
    pub lag_ms: f64,
    /// Its largest lag over the whole motion (ms).
    pub max_lag_ms: f64,
    /// The filtered palm's mean lag over the second half of the turn (ms).
    pub turn_lag_ms: f64,
    /// The filtered palm's distance along the motion, by time (s, mm), for the figure.
    #[serde(skip)]
    pub track: Vec<(f64, f64)>,
}

impl FilterRow {
    /// How many times smaller the filtered palm's jitter is than the unfiltered, by distance
    /// and by angle.
    pub fn reduction(&self) -> (f64, f64) {
        (
            self.jitter_mm.0 / self.jitter_mm.1,
            self.jitter_deg.0 / self.jitter_deg.1,
        )
    }
}

/// The JSON document of B14.
#[derive(Debug, Clone, Serialize)]
pub struct FilterReport {
    /// Always "filter".
    pub benchmark: &'static str,
    /// What was measured with.
    pub config: FilterConfig,
    /// One row per capture.
    pub rows: Vec<FilterRow>,
}

/// A retargeted sample: the root and the flex values.
type Fit = Sample<FLEX_COUNT>;

/// Seeded tracker-like noise on joints.
struct Noise {
    random: ChaCha8Rng,
    /// Standard deviation of each coordinate of a position offset (m).
    position_sigma: f64,
    /// Standard deviation of each component of a rotation vector (radians).
    angle_sigma: f64,
}

impl Noise {
    fn new(config: &FilterConfig) -> Self {
        // An isotropic Gaussian offset with per-axis sigma s has an RMS length of s √3.
        Noise {
            random: ChaCha8Rng::seed_from_u64(config.seed),
            position_sigma: config.noise_mm * 1e-3 / 3f64.sqrt(),
            angle_sigma: config.noise_deg.to_radians() / 3f64.sqrt(),
        }
    }

    /// A standard normal number (Box-Muller).
    fn normal(&mut self) -> f64 {
        let u: f64 = 1.0 - self.random.random::<f64>();
        let v: f64 = self.random.random();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    fn vector(&mut self, sigma: f64) -> Vector3<f64> {
        Vector3::new(self.normal(), self.normal(), self.normal()) * sigma
    }

    /// `joints` with every joint moved and turned by noise.
    fn apply(&mut self, joints: &HandJoints) -> HandJoints {
        let mut noisy = joints.clone();
        for joint in &mut noisy.joints {
            joint.position += self.vector(self.position_sigma);
            let turn = UnitQuaternion::from_scaled_axis(self.vector(self.angle_sigma));
            joint.orientation = *(turn * joint.rotation()).quaternion();
        }
        noisy
    }
}

/// The palm's pose for a retargeted sample.
fn palm(model: &HandModel, fit: &Fit) -> Isometry3<f64> {
    fit.root * model.segment_poses(&fit.values)[model.palm()]
}

/// The RMS distance of points from their mean.
fn spread(points: &[Vector3<f64>]) -> f64 {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    rms(points.iter().map(|p| (p - mean).norm()))
}

/// The RMS angle of rotations from their mean (the normalised mean of the quaternions, signs
/// aligned with the first: close to the rotations' mean for rotations this close together).
fn angular_spread(rotations: &[UnitQuaternion<f64>]) -> f64 {
    let first = rotations[0].coords;
    let sum: Vector4<f64> = (rotations.iter())
        .map(|q| q.coords * q.coords.dot(&first).signum())
        .sum();
    let mean = UnitQuaternion::from_quaternion(nalgebra::Quaternion::from(sum));
    rms(rotations.iter().map(|q| q.angle_to(&mean)))
}

/// The RMS deviation of each flex value from its mean, over all values.
fn flex_spread(fits: &[Fit]) -> f64 {
    let count = fits.len() as f64;
    let means: Vec<f64> = (0..FLEX_COUNT)
        .map(|i| fits.iter().map(|fit| fit.values[i]).sum::<f64>() / count)
        .collect();
    rms(fits
        .iter()
        .flat_map(|fit| fit.values.iter().zip(&means).map(|(v, m)| v - m)))
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, count) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    (sum / count as f64).sqrt()
}

/// The filtered and unfiltered retargeted samples of `joints` moved by `place(t)` at every
/// sample time `t` from 0 to `duration` s, with noise.
struct Run<'a> {
    retargeter: &'a Retargeter,
    config: &'a FilterConfig,
    noise: Noise,
}

impl Run<'_> {
    /// Per sample: its time, the noise-free fit, the noisy fit, the filtered noisy fit.
    fn samples(
        &mut self,
        joints: &HandJoints,
        duration: f64,
        place: impl Fn(f64) -> Isometry3<f64>,
    ) -> Result<Vec<(f64, Fit, Fit, Fit)>> {
        let mut filter = StreamFilter::<FLEX_COUNT>::new(&self.config.tracking);
        let ticks = (duration * self.config.rate_hz).round() as usize;
        (0..=ticks)
            .map(|tick| {
                let t = tick as f64 / self.config.rate_hz;
                let moved = joints.transformed(&place(t));
                let fit = |joints: &HandJoints| {
                    let fit = self
                        .retargeter
                        .fit(joints)
                        .context("retargeting a sample")?;
                    anyhow::Ok(Sample {
                        root: fit.root,
                        values: fit.flex,
                    })
                };
                let truth = fit(&moved)?;
                let noisy = fit(&self.noise.apply(&moved))?;
                let filtered = filter.apply(t, noisy)?.sample;
                Ok((t, truth, noisy, filtered))
            })
            .collect()
    }
}

/// Measures one capture.
pub fn measure(model: &HandModel, capture: &Path, config: &FilterConfig) -> Result<FilterRow> {
    let joints = Capture::read(capture)?.joints_of(HandSide::Right);
    let retargeter = Retargeter::new(model.clone())?;
    let mut run = Run {
        retargeter: &retargeter,
        config,
        noise: Noise::new(config),
    };
    let rest = run.samples(&joints, REST_S, |_| Isometry3::identity())?;
    let settled: Vec<_> = rest.iter().filter(|(t, ..)| *t >= 1.0).collect();
    let palms = |pick: fn(&(f64, Fit, Fit, Fit)) -> &Fit| -> Vec<Isometry3<f64>> {
        settled.iter().map(|s| palm(model, pick(s))).collect()
    };
    let (raw, filtered) = (palms(|s| &s.2), palms(|s| &s.3));
    let positions = |poses: &[Isometry3<f64>]| -> Vec<Vector3<f64>> {
        poses.iter().map(|p| p.translation.vector).collect()
    };
    let rotations = |poses: &[Isometry3<f64>]| -> Vec<UnitQuaternion<f64>> {
        poses.iter().map(|p| p.rotation).collect()
    };
    let fits = |pick: fn(&(f64, Fit, Fit, Fit)) -> &Fit| -> Vec<Fit> {
        settled.iter().map(|s| *pick(s)).collect()
    };

    let speed = config.speed;
    let moving = run.samples(&joints, 1.0 + MOVE_S, |t| {
        Isometry3::translation(speed * (t - 1.0).max(0.0), 0.0, 0.0)
    })?;
    let lags: Vec<(f64, f64)> = (moving.iter())
        .filter(|(t, ..)| *t > 1.0)
        .map(|(t, truth, _, filtered)| {
            let behind = palm(model, truth).translation.x - palm(model, filtered).translation.x;
            (*t, behind / speed * 1e3)
        })
        .collect();
    let steady = |lags: &[(f64, f64)]| -> f64 {
        let late: Vec<f64> = (lags.iter())
            .filter(|(t, _)| *t >= 1.0 + MOVE_S / 2.0)
            .map(|(_, lag)| *lag)
            .collect();
        late.iter().sum::<f64>() / late.len() as f64
    };
    let wrist = Translation3::from(joints.get(Joint::Wrist).position.coords);
    let rate = config.turn_rate;
    let turning = run.samples(&joints, 1.0 + MOVE_S, |t| {
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rate * (t - 1.0).max(0.0));
        wrist * turn * wrist.inverse()
    })?;
    let turn_lags: Vec<(f64, f64)> = (turning.iter())
        .filter(|(t, ..)| *t > 1.0)
        .map(|(t, truth, _, filtered)| {
            let behind = palm(model, truth)
                .rotation
                .angle_to(&palm(model, filtered).rotation);
            (*t, behind / rate * 1e3)
        })
        .collect();
    Ok(FilterRow {
        capture: (capture.file_name())
            .map_or_else(String::new, |name| name.to_string_lossy().into_owned()),
        jitter_mm: (
            spread(&positions(&raw)) * 1e3,
            spread(&positions(&filtered)) * 1e3,
        ),
        jitter_deg: (
            angular_spread(&rotations(&raw)).to_degrees(),
            angular_spread(&rotations(&filtered)).to_degrees(),
        ),
        flex_jitter_deg: (
            flex_spread(&fits(|s| &s.2)).to_degrees(),
            flex_spread(&fits(|s| &s.3)).to_degrees(),
        ),
        lag_ms: steady(&lags),
        max_lag_ms: lags.iter().map(|(_, lag)| *lag).fold(0.0, f64::max),
        turn_lag_ms: steady(&turn_lags),
        track: (moving.iter())
            .map(|(t, _, _, filtered)| (*t, palm(model, filtered).translation.x * 1e3))
            .collect(),
    })
}

/// The bars: filtered jitter at most a fifth of unfiltered, lag at 1 m/s at most 15 ms.
pub const JITTER_REDUCTION_BAR: f64 = 5.0;
/// See [`JITTER_REDUCTION_BAR`].
pub const LAG_BAR_MS: f64 = 15.0;

/// The table of B14.
fn filter_table(rows: &[FilterRow]) -> Table {
    let mut table = Table::new([
        "capture",
        "jitter_mm",
        "filtered_mm",
        "reduction_x",
        "jitter_deg",
        "filtered_deg",
        "reduction_deg_x",
        "flex_deg",
        "filtered_flex_deg",
        "lag_ms",
        "max_lag_ms",
        "turn_lag_ms",
    ]);
    for row in rows {
        let (by_distance, by_angle) = row.reduction();
        table.push_row(
            [row.capture.clone()].into_iter().chain(
                [
                    row.jitter_mm.0,
                    row.jitter_mm.1,
                    by_distance,
                    row.jitter_deg.0,
                    row.jitter_deg.1,
                    by_angle,
                    row.flex_jitter_deg.0,
                    row.flex_jitter_deg.1,
                    row.lag_ms,
                    row.max_lag_ms,
                    row.turn_lag_ms,
                ]
                .map(format_number),
            ),
        );
    }
    table
}

/// Arguments of `vas-bench filter`.
#[derive(Debug, Clone, clap::Args)]
pub struct FilterArgs {
    /// The hand model.
    #[arg(long, default_value = "configs/hands/right.toml")]
    pub hand: PathBuf,
    /// The WebXR captures, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "tests/fixtures/hands/webxr_pinch.json,tests/fixtures/hands/webxr_relaxed.json"
    )]
    pub captures: Vec<PathBuf>,
    /// Samples per second (a headset's hand tracking: 50 to 90).
    #[arg(long, default_value_t = 50.0, value_parser = positive_number)]
    pub rate: f64,
    /// RMS distance by which noise moves each joint (mm).
    #[arg(long, default_value_t = 1.5, value_parser = finite_number)]
    pub noise_mm: f64,
    /// RMS angle by which noise turns each joint (degrees).
    #[arg(long, default_value_t = 1.0, value_parser = finite_number)]
    pub noise_deg: f64,
    /// Speed of the moving hand (m/s).
    #[arg(long, default_value_t = 1.0, value_parser = positive_number)]
    pub speed: f64,
    /// Angular speed of the turning hand (rad/s).
    #[arg(long, default_value_t = 2.0, value_parser = positive_number)]
    pub turn: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The filter's cut-off at rest (Hz); default: the scene default's.
    #[arg(long, value_parser = positive_number)]
    pub min_cutoff: Option<f64>,
    /// The rise of the cut-off with speed (Hz per m/s); default: the scene default's.
    #[arg(long, value_parser = finite_number)]
    pub beta: Option<f64>,
    /// The rise of the cut-off with angular speed (Hz per rad/s); default: the scene default's.
    #[arg(long, value_parser = finite_number)]
    pub beta_angular: Option<f64>,
    /// The cut-off of the speed estimate (Hz); default: the scene default's.
    #[arg(long, value_parser = positive_number)]
    pub d_cutoff: Option<f64>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Parses a finite number above zero (a rate or a speed).
fn positive_number(text: &str) -> Result<f64, String> {
    let value = finite_number(text)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(format!("{text} is not above zero"))
    }
}

/// `vas-bench filter`: runs B14, prints the table and the bars, writes files.
pub fn run(args: &FilterArgs) -> Result<()> {
    let model = HandModel::load(&args.hand)?;
    let defaults = TrackingParams::default();
    let config = FilterConfig {
        rate_hz: args.rate,
        noise_mm: args.noise_mm,
        noise_deg: args.noise_deg,
        speed: args.speed,
        turn_rate: args.turn,
        seed: args.seed,
        tracking: TrackingParams {
            min_cutoff: args.min_cutoff.unwrap_or(defaults.min_cutoff),
            beta: args.beta.unwrap_or(defaults.beta),
            beta_angular: args.beta_angular.unwrap_or(defaults.beta_angular),
            d_cutoff: args.d_cutoff.unwrap_or(defaults.d_cutoff),
            ..defaults
        },
    };
    let rows = (args.captures.iter())
        .map(|capture| measure(&model, capture, &config))
        .collect::<Result<Vec<_>>>()?;
    let tracking = &config.tracking;
    println!(
        "filter: {} Hz, noise {} mm and {} deg RMS a joint, seed {}, moving at {} m/s, turning \
         at {} rad/s; min_cutoff {} Hz, beta {}, beta_angular {}, d_cutoff {} Hz",
        config.rate_hz,
        config.noise_mm,
        config.noise_deg,
        config.seed,
        config.speed,
        config.turn_rate,
        tracking.min_cutoff,
        tracking.beta,
        tracking.beta_angular,
        tracking.d_cutoff
    );
    print!("{}", filter_table(&rows).render());
    for row in &rows {
        let met = |ok: bool| if ok { "met" } else { "missed" };
        let (by_distance, by_angle) = row.reduction();
        println!(
            "{}: jitter reduced at least {JITTER_REDUCTION_BAR}x: {}; lag at most {LAG_BAR_MS} ms: {}",
            row.capture,
            met(by_distance.min(by_angle) >= JITTER_REDUCTION_BAR),
            met(row.lag_ms <= LAG_BAR_MS),
        );
    }
    let report = FilterReport {
        benchmark: "filter",
        config,
        rows,
    };
    args.output.write(&report, || LinePlot {
        title: format!("Filtered palm moving at {} m/s", report.config.speed),
        x_label: "time (s)".to_owned(),
        y_label: "palm along the motion (mm)".to_owned(),
        log_x: false,
        log_y: false,
        series: (report.rows.iter())
            .map(|row| Series {
                name: row.capture.clone(),
                points: row.track.clone(),
            })
            .chain([Series {
                name: "noise-free".to_owned(),
                points: (report
                    .rows
                    .first()
                    .map_or(&[][..], |row| &row.track[..])
                    .iter())
                .map(|(t, _)| (*t, (t - 1.0).max(0.0) * report.config.speed * 1e3))
                .collect(),
            }])
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The repository's file at `path`.
    fn repository(path: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
    }

    #[test]
    fn the_default_filter_meets_its_bars_on_both_captures() {
        let model = HandModel::load(&repository("configs/hands/right.toml")).unwrap();
        let config = FilterConfig {
            rate_hz: 50.0,
            noise_mm: 1.5,
            noise_deg: 1.0,
            speed: 1.0,
            turn_rate: 2.0,
            seed: 1,
            tracking: TrackingParams::default(),
        };
        for capture in ["webxr_pinch.json", "webxr_relaxed.json"] {
            let path = repository("tests/fixtures/hands").join(capture);
            let row = measure(&model, &path, &config).unwrap();
            let (by_distance, by_angle) = row.reduction();
            // The unfiltered palm trembles about as much as the noise on the wrist.
            assert!((0.5..3.0).contains(&row.jitter_mm.0), "{row:?}");
            assert!(by_distance >= JITTER_REDUCTION_BAR, "{row:?}");
            assert!(by_angle >= JITTER_REDUCTION_BAR, "{row:?}");
            assert!(row.flex_jitter_deg.1 < row.flex_jitter_deg.0, "{row:?}");
            // Behind, but by less than the bar.
            assert!(row.lag_ms > 0.0 && row.lag_ms <= LAG_BAR_MS, "{row:?}");
            assert!(row.turn_lag_ms > 0.0, "{row:?}");
        }
    }
}
