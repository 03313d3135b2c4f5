//! The bytes on zenoh: every message is an 8-byte envelope (which message, which version of its
//! layout) and then the wire type's fields at the offsets `docs/wire.md` gives, little-endian.
//!
//! The layout is the `#[repr(C)]` layout the types have in iceoryx2's shared memory, so that the
//! bridge copies fields and never converts numbers, and a client in any language reads the
//! same tables whichever transport brought the bytes. Padding goes out as zeros.

pub mod layout;

use iceoryx2::prelude::ZeroCopySend;
use vas_protocol::{
    ClearanceFrame, ControlRequest, ControlResponse, ForceFrame, GeometryDecodeError,
    GeometryHeader, GloveSample, HandFrame, HandJointsSample, PartState, PartsFrameHeader,
    SceneGeometry, SimEvent, TrackerSample,
};

use layout::Layout;

// The fields are copied as the host holds them, and the wire is little-endian.
#[cfg(not(target_endian = "little"))]
compile_error!(
    "vas-bridge copies the wire types' bytes as they are: it needs a little-endian host"
);

/// Bytes of the envelope before every message: `code: u32` then `version: u32`.
pub const ENVELOPE_BYTES: usize = 8;

/// Which message an envelope announces (its first `u32`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum Code {
    /// A [`TrackerSample`].
    Tracker = 1,
    /// A [`GloveSample`].
    Glove = 2,
    /// A [`HandJointsSample`].
    HandJoints = 3,
    /// A [`GeometryHeader`] and the geometry payload it describes.
    Geometry = 10,
    /// A [`PartsFrameHeader`] and its `part_count` [`PartState`]s.
    Parts = 11,
    /// A [`HandFrame`].
    Hand = 12,
    /// A [`SimEvent`].
    Event = 13,
    /// A [`ForceFrame`].
    Force = 14,
    /// A [`ClearanceFrame`].
    Clearance = 15,
    /// A [`ControlRequest`].
    ControlRequest = 20,
    /// A [`ControlResponse`].
    ControlResponse = 21,
}

/// A wire type the bridge copies whole.
///
/// # Safety
/// Every pattern of `size_of::<Self>()` bytes must be a valid value (the type holds numbers and
/// arrays of numbers only, however nested), and [`Message::LAYOUT`] must list every field.
pub unsafe trait Message: Copy + ZeroCopySend {
    /// The envelope's code.
    const CODE: Code;
    /// The fields.
    const LAYOUT: &'static Layout;

    /// The layout's version: the `N` of the type's `::vN` name, which changes with its layout.
    fn version() -> u32 {
        // SAFETY: reading the name the type was declared with has no precondition.
        version_of(unsafe { <Self as ZeroCopySend>::type_name() })
    }
}

/// The `N` of a type name ending in `::vN` (0 for none: every vas wire type has one).
fn version_of(type_name: &str) -> u32 {
    (type_name.rsplit_once("::v")).map_or(0, |(_, version)| version.parse().unwrap_or(0))
}

macro_rules! messages {
    ($($ty:ty => $code:ident, $layout:ident;)*) => {$(
        // SAFETY: numbers and arrays of numbers only; the layout lists every field (the
        // round-trip test fails otherwise).
        unsafe impl Message for $ty {
            const CODE: Code = Code::$code;
            const LAYOUT: &'static Layout = &layout::$layout;
        }
    )*};
}

messages! {
    TrackerSample => Tracker, TRACKER_SAMPLE;
    GloveSample => Glove, GLOVE_SAMPLE;
    HandJointsSample => HandJoints, HAND_JOINTS_SAMPLE;
    HandFrame => Hand, HAND_FRAME;
    SimEvent => Event, SIM_EVENT;
    ForceFrame => Force, FORCE_FRAME;
    ClearanceFrame => Clearance, CLEARANCE_FRAME;
    ControlRequest => ControlRequest, CONTROL_REQUEST;
    ControlResponse => ControlResponse, CONTROL_RESPONSE;
    GeometryHeader => Geometry, GEOMETRY_HEADER;
    PartsFrameHeader => Parts, PARTS_FRAME_HEADER;
    PartState => Parts, PART_STATE;
}

/// Why received bytes are not the message their key carries.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    /// Not as many bytes as the message has.
    #[error("{found} bytes where the message has {expected}")]
    Size {
        /// Bytes the message has (envelope included).
        expected: usize,
        /// Bytes received.
        found: usize,
    },
    /// The envelope announces another message.
    #[error("the envelope announces message {found}, not {expected}")]
    Code {
        /// The code this key carries.
        expected: u32,
        /// The code received.
        found: u32,
    },
    /// The envelope announces another version of the layout.
    #[error("layout version {found}, where this build speaks {expected}")]
    Version {
        /// The version this build speaks.
        expected: u32,
        /// The version received.
        found: u32,
    },
    /// A geometry payload that does not decode.
    #[error(transparent)]
    Geometry(#[from] GeometryDecodeError),
}

/// A zeroed buffer of `len` bytes that starts with `T`'s envelope.
fn with_envelope<T: Message>(len: usize) -> Vec<u8> {
    let mut bytes = vec![0; len];
    bytes[..4].copy_from_slice(&(T::CODE as u32).to_le_bytes());
    bytes[4..8].copy_from_slice(&T::version().to_le_bytes());
    bytes
}

/// Copies `value`'s fields into `out` (as long as the type).
fn put<T: Message>(value: &T, out: &mut [u8]) {
    // SAFETY: `value` is an initialised `T`, and `T::LAYOUT` describes `T`.
    unsafe { T::LAYOUT.copy_fields((value as *const T).cast(), out) }
}

/// Reads a `T` from the first `size_of::<T>()` bytes of `bytes`.
fn get<T: Message>(bytes: &[u8]) -> T {
    assert!(
        bytes.len() >= size_of::<T>(),
        "a {} needs its bytes",
        T::LAYOUT.name
    );
    // SAFETY: the bytes are there, and every pattern of them is a `T` (`Message`'s contract).
    unsafe { bytes.as_ptr().cast::<T>().read_unaligned() }
}

/// Checks `bytes`' envelope against `T`'s and that at least `min_len` bytes follow it.
fn check_envelope<T: Message>(bytes: &[u8], min_len: usize) -> Result<&[u8], Refusal> {
    if bytes.len() < ENVELOPE_BYTES + min_len {
        return Err(Refusal::Size {
            expected: ENVELOPE_BYTES + min_len,
            found: bytes.len(),
        });
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let (code, version) = (word(0), word(4));
    if code != T::CODE as u32 {
        return Err(Refusal::Code {
            expected: T::CODE as u32,
            found: code,
        });
    }
    if version != T::version() {
        return Err(Refusal::Version {
            expected: T::version(),
            found: version,
        });
    }
    Ok(&bytes[ENVELOPE_BYTES..])
}

/// The envelope and fields of one message.
pub fn encode<T: Message>(value: &T) -> Vec<u8> {
    let mut bytes = with_envelope::<T>(ENVELOPE_BYTES + size_of::<T>());
    put(value, &mut bytes[ENVELOPE_BYTES..]);
    bytes
}

/// The message in `bytes`: its envelope checked, and exactly its size.
pub fn decode<T: Message>(bytes: &[u8]) -> Result<T, Refusal> {
    let body = check_envelope::<T>(bytes, size_of::<T>())?;
    if body.len() != size_of::<T>() {
        return Err(Refusal::Size {
            expected: ENVELOPE_BYTES + size_of::<T>(),
            found: bytes.len(),
        });
    }
    Ok(get(body))
}

/// A parts frame: the envelope, its header, then `part_count` part states.
pub fn encode_parts(header: &PartsFrameHeader, parts: &[PartState]) -> Vec<u8> {
    let (header_len, part_len) = (size_of::<PartsFrameHeader>(), size_of::<PartState>());
    let mut bytes =
        with_envelope::<PartsFrameHeader>(ENVELOPE_BYTES + header_len + part_len * parts.len());
    let (head, states) = bytes[ENVELOPE_BYTES..].split_at_mut(header_len);
    put(header, head);
    for (part, out) in parts.iter().zip(states.chunks_exact_mut(part_len)) {
        put(part, out);
    }
    bytes
}

/// The parts frame in `bytes`, its length checked against its `part_count`.
pub fn decode_parts(bytes: &[u8]) -> Result<(PartsFrameHeader, Vec<PartState>), Refusal> {
    let (header_len, part_len) = (size_of::<PartsFrameHeader>(), size_of::<PartState>());
    let body = check_envelope::<PartsFrameHeader>(bytes, header_len)?;
    let header: PartsFrameHeader = get(body);
    let expected = (header.part_count as usize)
        .checked_mul(part_len)
        .and_then(|parts| parts.checked_add(ENVELOPE_BYTES + header_len));
    if expected != Some(bytes.len()) {
        return Err(Refusal::Size {
            expected: expected.unwrap_or(usize::MAX),
            found: bytes.len(),
        });
    }
    let parts = body[header_len..].chunks_exact(part_len).map(get).collect();
    Ok((header, parts))
}

/// A scene's geometry: the envelope, its header, then the payload the header describes.
pub fn encode_geometry(geometry: &SceneGeometry) -> Vec<u8> {
    let header = geometry.header();
    let header_len = size_of::<GeometryHeader>();
    let mut bytes =
        with_envelope::<GeometryHeader>(ENVELOPE_BYTES + header_len + header.byte_len as usize);
    let (head, payload) = bytes[ENVELOPE_BYTES..].split_at_mut(header_len);
    put(&header, head);
    geometry.encode_into(payload);
    bytes
}

/// The geometry in `bytes`, every count checked against the bytes there are.
pub fn decode_geometry(bytes: &[u8]) -> Result<SceneGeometry, Refusal> {
    let header_len = size_of::<GeometryHeader>();
    let body = check_envelope::<GeometryHeader>(bytes, header_len)?;
    let header: GeometryHeader = get(body);
    let payload = &body[header_len..];
    if header.byte_len != payload.len() as u64 {
        return Err(Refusal::Size {
            expected: (ENVELOPE_BYTES + header_len).saturating_add(header.byte_len as usize),
            found: bytes.len(),
        });
    }
    Ok(SceneGeometry::decode(&header, payload)?)
}

#[cfg(test)]
mod tests;
