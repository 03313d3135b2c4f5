use std::f64::consts::{PI, TAU};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::*;
use crate::scene::TrackingParams;

/// A sample with the root at `position`, turned by `rotation`, and the values `values`.
fn sample(position: Vector3<f64>, rotation: UnitQuaternion<f64>, values: [f64; 2]) -> Sample<2> {
    Sample {
        root: Isometry3::from_parts(Translation3::from(position), rotation),
        values,
    }
}

/// A sample at `x` along the x axis, unturned, both values `x`.
fn at(x: f64) -> Sample<2> {
    sample(
        Vector3::new(x, 0.0, 0.0),
        UnitQuaternion::identity(),
        [x; 2],
    )
}

/// The default filter of two values.
fn default_filter() -> StreamFilter<2> {
    StreamFilter::new(&TrackingParams::default())
}

/// Samples at 100 Hz.
const DT: f64 = 0.01;

#[test]
fn a_constant_signal_passes_unchanged() {
    let mut filter = default_filter();
    let rotation = UnitQuaternion::from_euler_angles(0.3, -1.2, 2.9);
    let constant = sample(Vector3::new(0.1, -0.2, 1.3), rotation, [0.4, -0.1]);
    for tick in 0..500 {
        let out = filter.apply(tick as f64 * DT, constant).unwrap();
        assert_eq!(out.sample.root.translation, constant.root.translation);
        assert_eq!(out.sample.values, constant.values);
        assert!(out.sample.root.rotation.angle_to(&rotation) < 1e-12);
    }
}

#[test]
fn a_step_converges_without_overshoot() {
    let mut filter = default_filter();
    filter.apply(0.0, at(0.0)).unwrap();
    let mut previous = 0.0;
    for tick in 1..=200 {
        let out = filter.apply(tick as f64 * DT, at(0.05)).unwrap();
        let x = out.sample.root.translation.x;
        assert!((previous..=0.05).contains(&x), "{x} after {previous}");
        previous = x;
    }
    assert!((0.05 - previous).abs() < 1e-4, "{previous} after 2 s");
}

/// The steady lag of a ramp at `speed` through a first-order low-pass whose cut-off the speed
/// sets: its time constant, `1 / (2π (min_cutoff + beta speed))`.
fn predicted_lag_s(min_cutoff: f64, beta: f64, speed: f64) -> f64 {
    1.0 / (TAU * (min_cutoff + beta * speed))
}

#[test]
fn a_ramp_lags_by_the_time_constant_its_speed_sets() {
    let tracking = TrackingParams::default();
    let mut filter = default_filter();
    let speed = 0.5;
    let angular = 2.0;
    let mut last = None;
    for tick in 0..300 {
        let t = tick as f64 * DT;
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angular * t);
        let raw = sample(
            Vector3::new(speed * t, 0.0, 0.0),
            rotation,
            [angular * t; 2],
        );
        last = Some((raw, filter.apply(t, raw).unwrap().sample));
    }
    let (raw, out) = last.unwrap();
    let lag_s = (raw.root.translation.x - out.root.translation.x) / speed;
    let expected = predicted_lag_s(tracking.min_cutoff, tracking.beta, speed);
    assert!(
        (lag_s / expected - 1.0).abs() < 0.02,
        "{lag_s} s, {expected} s"
    );
    let expected = predicted_lag_s(tracking.min_cutoff, tracking.beta_angular, angular);
    let turn_lag_s = out.root.rotation.angle_to(&raw.root.rotation) / angular;
    assert!(
        (turn_lag_s / expected - 1.0).abs() < 0.02,
        "{turn_lag_s} s, {expected} s"
    );
    let value_lag_s = (raw.values[0] - out.values[0]) / angular;
    assert!(
        (value_lag_s / expected - 1.0).abs() < 0.02,
        "{value_lag_s} s, {expected} s"
    );
}

#[test]
fn rotations_stay_unit_and_go_the_short_way() {
    let mut filter = default_filter();
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        (state >> 11) as f64 / (1u64 << 53) as f64 * TAU - PI
    };
    for tick in 0..2000 {
        let rotation = UnitQuaternion::from_euler_angles(next(), next() / 2.0, next());
        let out = filter.apply(
            tick as f64 * DT,
            sample(Vector3::zeros(), rotation, [0.0; 2]),
        );
        let norm = out.unwrap().sample.root.rotation.into_inner().norm();
        assert!((norm - 1.0).abs() < 1e-12, "{norm}");
    }
    // q and -q are one rotation: a stream flipping sign between them holds still.
    let mut filter = default_filter();
    let turned = UnitQuaternion::from_euler_angles(0.2, 0.4, 2.0);
    let flipped = UnitQuaternion::new_unchecked(-turned.into_inner());
    for tick in 0..100 {
        let rotation = if tick % 2 == 0 { turned } else { flipped };
        let out = filter.apply(
            tick as f64 * DT,
            sample(Vector3::zeros(), rotation, [0.0; 2]),
        );
        assert!(out.unwrap().sample.root.rotation.angle_to(&turned) < 1e-9);
    }
    // Across half a turn the estimate takes the shorter arc: the other is 3.4 rad.
    let mut filter = default_filter();
    let start = UnitQuaternion::identity();
    let end = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 2.9);
    filter
        .apply(0.0, sample(Vector3::zeros(), start, [0.0; 2]))
        .unwrap();
    let out = filter
        .apply(DT, sample(Vector3::zeros(), end, [0.0; 2]))
        .unwrap();
    let rotation = out.sample.root.rotation;
    assert!(rotation.angle_to(&start) + rotation.angle_to(&end) < 2.9 + 1e-9);
}

#[test]
fn non_finite_input_is_refused_and_leaves_the_filter_as_it_was() {
    let at = |x: f64| {
        sample(
            Vector3::new(x, 0.0, 0.0),
            UnitQuaternion::identity(),
            [0.0; 2],
        )
    };
    let mut clean = default_filter();
    let mut fed = default_filter();
    for tick in 0..50 {
        let t = tick as f64 * DT;
        let expected = clean.apply(t, at(t)).unwrap();
        assert_eq!(fed.apply(t, at(f64::NAN)), Err(NonFiniteSample));
        assert_eq!(fed.apply(f64::INFINITY, at(t)), Err(NonFiniteSample));
        assert_eq!(fed.apply(f64::NAN, at(t)), Err(NonFiniteSample));
        assert_eq!(fed.apply(t, at(t)), Ok(expected));
    }
}

#[test]
fn a_timestamp_not_after_the_last_restarts_from_its_sample() {
    let mut filter = default_filter();
    filter.apply(1.0, at(0.0)).unwrap();
    assert_eq!(
        filter.apply(1.01, at(0.01)).unwrap().passage,
        Passage::Smoothed
    );
    for time in [1.01, 0.5] {
        let out = filter.apply(time, at(0.2)).unwrap();
        assert!(matches!(
            out.passage,
            Passage::Restarted(TimeFault::NotAfter { .. })
        ));
        assert_eq!(out.sample, at(0.2));
    }
    assert_eq!(
        filter.apply(0.51, at(0.2)).unwrap().passage,
        Passage::Smoothed
    );
}

#[test]
fn tracking_lost_or_reset_starts_afresh_and_off_passes_through() {
    let tracking = TrackingParams::default();
    let mut filter = default_filter();
    filter.apply(0.0, at(0.0)).unwrap();
    let after_gap = filter.apply(tracking.lost_after + 0.01, at(0.3)).unwrap();
    assert_eq!(
        (after_gap.passage, after_gap.sample),
        (Passage::Started, at(0.3))
    );
    filter.restart();
    let out = filter.apply(0.0, at(0.1)).unwrap();
    assert_eq!((out.passage, out.sample), (Passage::Started, at(0.1)));

    let mut off = StreamFilter::<2>::new(&TrackingParams {
        filter: false,
        ..tracking
    });
    for tick in 0..10 {
        let out = off.apply(tick as f64 * DT, at(tick as f64)).unwrap();
        assert_eq!(
            (out.passage, out.sample),
            (Passage::Unfiltered, at(tick as f64))
        );
    }
}
