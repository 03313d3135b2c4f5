//! One input stream's filter: a root pose and `F` scalar values, timed by the samples.

use nalgebra::{Isometry3, Translation3, Vector1};

use super::clock::{SampleClock, TimeFault};
use super::gain::{Gain, Tuning};
use super::rotation;
use crate::scene::TrackingParams;

/// A stream's sample: a root pose and `F` values (radians, as a hand's flex values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<const F: usize> {
    /// The root pose.
    pub root: Isometry3<f64>,
    /// The values.
    pub values: [f64; F],
}

impl<const F: usize> Sample<F> {
    fn is_finite(&self) -> bool {
        let root = &self.root;
        (root.translation.vector.iter())
            .chain(root.rotation.coords.iter())
            .chain(&self.values)
            .all(|value| value.is_finite())
    }
}

/// A sample refused because a value or its timestamp is NaN or infinite; the filter's state
/// is left as it was.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("a sample to filter has a NaN or infinite value or timestamp")]
pub struct NonFiniteSample;

/// How a sample went through the filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Passage {
    /// The filter is off: the sample as it came.
    Unfiltered,
    /// The first sample, after a reset or after a gap longer than the scene's
    /// `params.tracking.lost_after` (tracking was lost): the filter starts from it.
    Started,
    /// Smoothed against the samples before.
    Smoothed,
    /// Its timestamp was not after the previous sample's: the filter starts again from it
    /// rather than take a step back in time, which would turn the speed estimate and the
    /// smoothing weights negative. Counted by the caller as faulty input.
    Restarted(TimeFault),
}

/// A sample after the filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filtered<const F: usize> {
    /// The smoothed sample.
    pub sample: Sample<F>,
    /// How it came about.
    pub passage: Passage,
}

/// The filter's parameters, from the scene's `[params.tracking]`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Settings {
    /// For the root's position (speed in m/s).
    position: Tuning,
    /// For the root's rotation and the values (speed in rad/s).
    angular: Tuning,
    /// The longest gap between samples that the filter bridges (seconds).
    restart_after_s: f64,
}

/// The estimate and the speed estimates of a running filter.
#[derive(Debug, Clone, Copy)]
struct Estimate<const F: usize> {
    sample: Sample<F>,
    /// The latest raw sample, from which the next one's change is measured.
    latest: Sample<F>,
    position: Gain<3>,
    rotation: Gain<3>,
    values: [Gain<1>; F],
}

impl<const F: usize> Estimate<F> {
    fn start(sample: Sample<F>) -> Self {
        Estimate {
            sample,
            latest: sample,
            position: Gain::default(),
            rotation: Gain::default(),
            values: [Gain::default(); F],
        }
    }

    /// Moves the estimate toward `sample`, `dt` seconds after the previous one.
    fn smooth(&mut self, sample: &Sample<F>, dt: f64, settings: &Settings) {
        let (root, latest) = (&mut self.sample.root, &self.latest.root);
        let position = sample.root.translation.vector;
        let change = position - latest.translation.vector;
        let fraction = self.position.step(&change, dt, &settings.position);
        let offset = position - root.translation.vector;
        root.translation = Translation3::from(root.translation.vector + offset * fraction);
        let change = rotation::offset(&latest.rotation, &sample.root.rotation);
        let fraction = self.rotation.step(&change, dt, &settings.angular);
        let offset = rotation::offset(&root.rotation, &sample.root.rotation);
        root.rotation = rotation::moved(&root.rotation, &offset, fraction);
        for (((estimate, gain), value), latest) in (self.sample.values.iter_mut())
            .zip(&mut self.values)
            .zip(&sample.values)
            .zip(&self.latest.values)
        {
            let fraction = gain.step(&Vector1::new(value - latest), dt, &settings.angular);
            *estimate += (value - *estimate) * fraction;
        }
        self.latest = *sample;
    }
}

/// The One Euro filter of one stream (a tracker's hand root, or one hand's retargeted root and
/// flex values), or a pass-through where the scene turns filtering off (as is the default
/// value, a filter of no scene).
#[derive(Debug, Clone, Default)]
pub struct StreamFilter<const F: usize> {
    settings: Option<Settings>,
    clock: SampleClock,
    estimate: Option<Estimate<F>>,
    /// The stream's first timestamp, which [`StreamFilter::apply_stamped`] times from.
    origin_ns: Option<u64>,
}

impl<const F: usize> StreamFilter<F> {
    /// A filter tuned by the scene's `tracking` parameters (a pass-through if they turn it off).
    pub fn new(tracking: &TrackingParams) -> Self {
        let tuning = |beta| Tuning {
            min_cutoff_hz: tracking.min_cutoff,
            beta,
            derivative_cutoff_hz: tracking.d_cutoff,
        };
        StreamFilter {
            settings: tracking.filter.then(|| Settings {
                position: tuning(tracking.beta),
                angular: tuning(tracking.beta_angular),
                restart_after_s: tracking.lost_after,
            }),
            clock: SampleClock::default(),
            estimate: None,
            origin_ns: None,
        }
    }

    /// [`StreamFilter::apply`] to a sample stamped `timestamp_ns` (nanoseconds), timed from the
    /// stream's first stamp: the seconds, and so the output, depend on the samples' spacing only,
    /// not on when a replay began (an absolute stamp in f64 seconds rounds to about 0.2 us, and
    /// differently for every start).
    pub fn apply_stamped(
        &mut self,
        timestamp_ns: u64,
        sample: Sample<F>,
    ) -> Result<Filtered<F>, NonFiniteSample> {
        let origin_ns = *self.origin_ns.get_or_insert(timestamp_ns);
        let at_s = (i128::from(timestamp_ns) - i128::from(origin_ns)) as f64 * 1e-9;
        self.apply(at_s, sample)
    }

    /// Forgets the samples so far: tracking was lost, or the hand reset.
    pub fn restart(&mut self) {
        self.clock.restart();
        self.estimate = None;
    }

    /// Filters `sample`, stamped `at_s` seconds on the stream's clock.
    pub fn apply(&mut self, at_s: f64, sample: Sample<F>) -> Result<Filtered<F>, NonFiniteSample> {
        if !sample.is_finite() || !at_s.is_finite() {
            return Err(NonFiniteSample);
        }
        let Some(settings) = self.settings else {
            return Ok(Filtered {
                sample,
                passage: Passage::Unfiltered,
            });
        };
        let passage = match (self.clock.advance(at_s), &mut self.estimate) {
            (Ok(Some(dt)), Some(estimate)) if dt <= settings.restart_after_s => {
                estimate.smooth(&sample, dt, &settings);
                Passage::Smoothed
            }
            (Ok(_), _) => Passage::Started,
            (Err(fault), _) => {
                self.clock.restart();
                self.clock
                    .advance(at_s)
                    .expect("a restarted clock takes any finite time");
                Passage::Restarted(fault)
            }
        };
        if passage != Passage::Smoothed {
            self.estimate = Some(Estimate::start(sample));
        }
        let sample = self.estimate.map_or(sample, |estimate| estimate.sample);
        Ok(Filtered { sample, passage })
    }
}
