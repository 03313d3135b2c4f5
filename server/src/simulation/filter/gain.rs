//! The One Euro filter's adaptive gain: a speed estimate and the cut-off it sets.

use std::f64::consts::TAU;

use nalgebra::SVector;

/// The One Euro filter's three parameters for one kind of value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// The cut-off frequency at rest (Hz): lower holds a still signal stiller.
    pub min_cutoff_hz: f64,
    /// How much the cut-off rises per unit of speed (Hz per unit per second): higher follows a
    /// fast signal with less lag.
    pub beta: f64,
    /// The cut-off frequency of the speed estimate (Hz).
    pub derivative_cutoff_hz: f64,
}

/// The weight of a new sample, `dt` seconds after the previous one, in a first-order low-pass
/// of cut-off `cutoff_hz`: `1 / (1 + tau / dt)` with the time constant `tau = 1 / (2π f)`. On
/// a ramp the estimate then trails by exactly `tau` seconds once settled.
pub fn smoothing(cutoff_hz: f64, dt: f64) -> f64 {
    let tau = 1.0 / (TAU * cutoff_hz);
    1.0 / (1.0 + tau / dt)
}

/// The adaptive part of a One Euro filter over values with `N` components (or a rotation's
/// three of its tangent space): the low-passed velocity of the samples, whose norm sets the
/// cut-off. The norm of the whole vector, not each component's, so that the filter treats every
/// direction alike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gain<const N: usize> {
    velocity: SVector<f64, N>,
}

impl<const N: usize> Default for Gain<N> {
    fn default() -> Self {
        Gain {
            velocity: SVector::zeros(),
        }
    }
}

impl<const N: usize> Gain<N> {
    /// The fraction of its offset from the estimate by which the estimate moves toward a new
    /// sample, `dt` seconds after the previous one and `change` away from it, with the speed
    /// estimate updated. As in the paper's reference code, the velocity is the change between
    /// raw samples over `dt`, low-passed at the derivative cut-off: the change from the
    /// estimate would measure the lag, not the speed.
    pub fn step(&mut self, change: &SVector<f64, N>, dt: f64, tuning: &Tuning) -> f64 {
        let derivative = smoothing(tuning.derivative_cutoff_hz, dt);
        self.velocity += (change / dt - self.velocity) * derivative;
        smoothing(
            tuning.min_cutoff_hz + tuning.beta * self.velocity.norm(),
            dt,
        )
    }
}
