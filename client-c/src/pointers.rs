//! Pointer arguments from C, checked for null before they are used.

use std::ffi::{CStr, c_char};

use crate::status::Failure;

/// The value behind `pointer`, or the error naming `argument` when it is null.
///
/// # Safety
/// A non-null `pointer` must point to a valid `T` that outlives the use of the reference.
pub(crate) unsafe fn input<'a, T>(pointer: *const T, argument: &str) -> Result<&'a T, Failure> {
    // SAFETY: as the caller guarantees for a non-null pointer.
    unsafe { pointer.as_ref() }.ok_or_else(|| Failure::null(argument))
}

/// The place behind an out-pointer, or the error naming `argument` when it is null.
///
/// # Safety
/// A non-null `pointer` must point to writable memory for a `T` that no one else uses meanwhile.
pub(crate) unsafe fn output<'a, T>(pointer: *mut T, argument: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: as the caller guarantees for a non-null pointer.
    unsafe { pointer.as_mut() }.ok_or_else(|| Failure::null(argument))
}

/// The UTF-8 text of a NUL-terminated string, or the error naming `argument` when it is null or
/// not UTF-8.
///
/// # Safety
/// A non-null `pointer` must point to a NUL-terminated string that outlives the use of the text.
pub(crate) unsafe fn text<'a>(pointer: *const c_char, argument: &str) -> Result<&'a str, Failure> {
    if pointer.is_null() {
        return Err(Failure::null(argument));
    }
    // SAFETY: non-null, and NUL-terminated as the caller guarantees.
    let text = unsafe { CStr::from_ptr(pointer) };
    text.to_str()
        .map_err(|_| Failure::invalid(format!("{argument} is not UTF-8")))
}

/// Writes `value` through an out-pointer that may be null (the caller does not want it).
///
/// # Safety
/// A non-null `pointer` must point to writable memory for a `T`.
pub(crate) unsafe fn write_optional<T>(pointer: *mut T, value: T) {
    // SAFETY: as the caller guarantees for a non-null pointer.
    if let Some(place) = unsafe { pointer.as_mut() } {
        *place = value;
    }
}
