//! Numbers in messages: a value received from outside (1e300, 1e-300) printed as `{}` would be
//! hundreds of digits long, so every error that quotes one prints it through [`Readable`].

use std::fmt;

/// A number as a message quotes it: in plain decimals between 1e-4 and 1e9 (and zero), in
/// scientific notation beyond (`1e300`, `-2.5e-12`), NaN and infinities as Rust spells them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readable(pub f64);

impl fmt::Display for Readable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let magnitude = self.0.abs();
        if magnitude == 0.0 || !magnitude.is_finite() || (1e-4..1e9).contains(&magnitude) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Readable;

    #[test]
    fn large_and_small_numbers_are_printed_in_scientific_notation() {
        let printed = |x: f64| Readable(x).to_string();
        assert_eq!(printed(1e300), "1e300");
        assert_eq!(printed(-2.5e-12), "-2.5e-12");
        assert_eq!(printed(1234.5), "1234.5");
        assert_eq!(printed(0.001), "0.001");
        assert_eq!(printed(0.0), "0");
        assert_eq!(printed(f64::NAN), "NaN");
        assert_eq!(printed(f64::NEG_INFINITY), "-inf");
    }
}
