//! Fixed-capacity UTF-8 strings for the control service.

use iceoryx2::prelude::ZeroCopySend;

/// A UTF-8 string of at most `N` bytes, stored inline so that it can live in shared memory.
#[derive(Clone, Copy, PartialEq, Eq, ZeroCopySend)]
#[repr(C)]
pub struct WireText<const N: usize> {
    len: u32,
    bytes: [u8; N],
}

/// Why a [`WireText`] could not be built or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum WireTextError {
    /// The string is longer than the capacity.
    #[error("text of {len} bytes exceeds the capacity of {capacity} bytes")]
    TooLong {
        /// Length of the string in bytes.
        len: usize,
        /// Capacity of the wire field in bytes.
        capacity: usize,
    },
    /// The received bytes are not UTF-8 (a corrupt or foreign peer).
    #[error("text on the wire is not valid UTF-8")]
    InvalidUtf8,
}

impl<const N: usize> WireText<N> {
    /// The empty string.
    pub const EMPTY: Self = Self {
        len: 0,
        bytes: [0; N],
    };

    /// The wire form of `text`, or an error if it does not fit.
    pub fn new(text: &str) -> Result<Self, WireTextError> {
        if text.len() > N {
            return Err(WireTextError::TooLong {
                len: text.len(),
                capacity: N,
            });
        }
        Ok(Self::copy_prefix(text, text.len()))
    }

    /// The wire form of `text`, cut at the last character boundary that fits; the flag says
    /// whether anything was cut.
    pub fn truncated(text: &str) -> (Self, bool) {
        let mut end = text.len().min(N);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        (Self::copy_prefix(text, end), end < text.len())
    }

    fn copy_prefix(text: &str, end: usize) -> Self {
        let mut bytes = [0; N];
        bytes[..end].copy_from_slice(&text.as_bytes()[..end]);
        Self {
            len: u32::try_from(end).expect("wire text capacities are far below u32::MAX"),
            bytes,
        }
    }

    /// The string, checked: a length beyond the capacity or invalid UTF-8 is an error.
    pub fn as_str(&self) -> Result<&str, WireTextError> {
        let len = self.len as usize;
        let bytes = self
            .bytes
            .get(..len)
            .ok_or(WireTextError::TooLong { len, capacity: N })?;
        std::str::from_utf8(bytes).map_err(|_| WireTextError::InvalidUtf8)
    }
}

impl<const N: usize> Default for WireText<N> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<const N: usize> std::fmt::Debug for WireText<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.as_str() {
            Ok(text) => write!(f, "{text:?}"),
            Err(error) => write!(f, "<{error}>"),
        }
    }
}
