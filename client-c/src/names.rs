//! The wire's codes in words, as static C strings: what a renderer prints or logs.

use std::collections::HashMap;
use std::ffi::{CString, c_char};
use std::sync::{Mutex, OnceLock};

use vas_protocol::{EventKind, GraspType, HandSegment, HandSide};

use crate::status::{VasStatus, guard};

/// `name` as a NUL-terminated string that lives as long as the process: each name is made once
/// and kept, so the pointer never dangles.
fn interned(name: &'static str) -> *const c_char {
    static NAMES: OnceLock<Mutex<HashMap<&'static str, CString>>> = OnceLock::new();
    let mut names = (NAMES.get_or_init(Default::default).lock())
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let text = names
        .entry(name)
        .or_insert_with(|| CString::new(name).unwrap_or_default());
    // The CString's buffer is on the heap and the entry is never removed.
    text.as_ptr()
}

/// The name of a code, or null for a code this library does not know; a panic is null too.
fn name_or_null(name: impl FnOnce() -> Option<&'static str>) -> *const c_char {
    let mut pointer = std::ptr::null();
    guard(|| {
        pointer = name().map_or(std::ptr::null(), interned);
        Ok(VasStatus::Ok)
    });
    pointer
}

/// The hand side `code` (a `VAS_HAND_*` code) in words: `right` or `left`. Null for an unknown
/// code. The string is static: never freed, never changed.
#[unsafe(no_mangle)]
pub extern "C" fn vas_hand_side_name(code: u32) -> *const c_char {
    name_or_null(|| HandSide::try_from(code).ok().map(HandSide::name))
}

/// The grasp type `code` (`VasHandFrame::grasp_type`, `VasSimEvent::grasp_type`) in words,
/// e.g. `power` or `tip_pinch`. Null for an unknown code. The string is static.
#[unsafe(no_mangle)]
pub extern "C" fn vas_grasp_type_name(code: u32) -> *const c_char {
    name_or_null(|| GraspType::try_from(code).ok().map(GraspType::name))
}

/// The event kind `code` (`VasSimEvent::kind`) in words, e.g. `grasp` or `contact_begin`.
/// Null for an unknown code. The string is static.
#[unsafe(no_mangle)]
pub extern "C" fn vas_event_kind_name(code: u32) -> *const c_char {
    name_or_null(|| EventKind::try_from(code).ok().map(EventKind::name))
}

/// The hand segment `index` (the order of `VasHandFrame::segments` and of a hand's segment
/// meshes; also the bit of `VasHandFrame::touching`) in words, e.g. `palm` or `index_distal`.
/// Null past the last segment. The string is static.
#[unsafe(no_mangle)]
pub extern "C" fn vas_hand_segment_name(index: u32) -> *const c_char {
    name_or_null(|| {
        let segment = HandSegment::ALL.get(usize::try_from(index).ok()?)?;
        Some(segment.name())
    })
}

#[cfg(test)]
mod tests {
    use std::ffi::CStr;

    use super::*;

    fn read(pointer: *const c_char) -> Option<String> {
        // SAFETY: a static name or null.
        (!pointer.is_null()).then(|| unsafe { CStr::from_ptr(pointer) }.to_str().unwrap().into())
    }

    #[test]
    fn codes_have_their_protocol_names() {
        assert_eq!(read(vas_hand_side_name(1)).as_deref(), Some("left"));
        assert_eq!(read(vas_grasp_type_name(8)).as_deref(), Some("power"));
        assert_eq!(
            read(vas_event_kind_name(3)).as_deref(),
            Some("contact_begin")
        );
        assert_eq!(
            read(vas_hand_segment_name(6)).as_deref(),
            Some("index_distal")
        );
        assert_eq!(vas_hand_side_name(2), std::ptr::null());
        assert_eq!(vas_hand_segment_name(16), std::ptr::null());
        assert_eq!(vas_grasp_type_name(u32::MAX), std::ptr::null());
        // The same name is the same pointer: nothing is made twice.
        assert_eq!(vas_grasp_type_name(8), vas_grasp_type_name(8));
    }
}
