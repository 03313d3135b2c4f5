use super::layout::{ALL, Kind, Layout};
use super::*;

/// A value whose every byte differs from its neighbours' and none is zero, and whose numbers
/// are all finite (no byte reaches an exponent of all ones): a field the layout forgot, or one
/// copied to the wrong place, changes the value.
fn patterned<T: Message>() -> T {
    let bytes: Vec<u8> = (0..size_of::<T>()).map(|i| (i % 97) as u8 + 1).collect();
    get(&bytes)
}

/// Marks the bytes of every field of `layout`, recursively, at `base`.
fn mark_fields(layout: &Layout, base: usize, covered: &mut [u8]) {
    for field in layout.fields {
        match field.kind {
            Kind::Numbers(..) => {
                for byte in &mut covered[base + field.offset..][..field.kind.size()] {
                    *byte += 1;
                }
            }
            Kind::Nested(nested, count) => {
                for index in 0..count {
                    mark_fields(nested, base + field.offset + index * nested.size, covered);
                }
            }
        }
    }
}

fn round_trip<T: Message + PartialEq + std::fmt::Debug>() {
    let value = patterned::<T>();
    let bytes = encode(&value);
    assert_eq!(bytes.len(), ENVELOPE_BYTES + size_of::<T>());
    assert_eq!(decode::<T>(&bytes), Ok(value), "{}", T::LAYOUT.name);
    // Bytes of no field are padding, sent as zeros.
    let mut covered = vec![0u8; size_of::<T>()];
    mark_fields(T::LAYOUT, 0, &mut covered);
    for (at, (&count, &byte)) in covered.iter().zip(&bytes[ENVELOPE_BYTES..]).enumerate() {
        assert!(
            count <= 1,
            "{}: byte {at} lies in two fields",
            T::LAYOUT.name
        );
        if count == 0 {
            assert_eq!(byte, 0, "{}: padding byte {at}", T::LAYOUT.name);
        }
    }
}

#[test]
fn every_message_decodes_to_what_was_encoded() {
    round_trip::<TrackerSample>();
    round_trip::<GloveSample>();
    round_trip::<HandJointsSample>();
    round_trip::<HandFrame>();
    round_trip::<SimEvent>();
    round_trip::<ForceFrame>();
    round_trip::<ClearanceFrame>();
    round_trip::<ControlRequest>();
    round_trip::<ControlResponse>();
    round_trip::<GeometryHeader>();
    round_trip::<PartsFrameHeader>();
    round_trip::<PartState>();
}

#[test]
fn fields_lie_in_order_inside_their_type() {
    for layout in ALL {
        let mut end = 0;
        for field in layout.fields {
            assert!(
                field.offset >= end,
                "{}.{} overlaps",
                layout.name,
                field.name
            );
            end = field.offset + field.kind.size();
        }
        assert!(end <= layout.size, "{} ends beyond its size", layout.name);
        assert_eq!(layout.size % layout.align, 0, "{}", layout.name);
    }
}

#[test]
fn envelopes_of_another_message_size_or_version_are_refused() {
    let sample = patterned::<HandJointsSample>();
    let bytes = encode(&sample);
    assert_eq!(
        decode::<TrackerSample>(&bytes),
        Err(Refusal::Code {
            expected: Code::Tracker as u32,
            found: Code::HandJoints as u32
        })
    );
    let mut longer = bytes.clone();
    longer.push(0);
    assert_eq!(
        decode::<HandJointsSample>(&longer),
        Err(Refusal::Size {
            expected: bytes.len(),
            found: longer.len()
        })
    );
    let mut tracker = encode(&patterned::<TrackerSample>());
    tracker[..4].copy_from_slice(&(Code::Glove as u32).to_le_bytes());
    assert!(matches!(
        decode::<TrackerSample>(&tracker),
        Err(Refusal::Code { found: 2, .. })
    ));
    let mut old = bytes.clone();
    old[4..8].copy_from_slice(&(HandJointsSample::version() - 1).to_le_bytes());
    assert!(matches!(
        decode::<HandJointsSample>(&old),
        Err(Refusal::Version { .. })
    ));
    for len in [0, 7, 8, bytes.len() - 1] {
        assert!(matches!(
            decode::<HandJointsSample>(&bytes[..len]),
            Err(Refusal::Size { .. })
        ));
    }
}

#[test]
fn versions_come_from_the_type_names() {
    assert!(HandFrame::version() >= 1);
    assert_eq!(version_of("vas::output::HandFrame::v12"), 12);
    assert_eq!(version_of("no version"), 0);
}

#[test]
fn parts_frames_round_trip_and_their_count_is_checked() {
    let mut header = patterned::<PartsFrameHeader>();
    header.part_count = 3;
    let parts = vec![patterned::<PartState>(); 3];
    let bytes = encode_parts(&header, &parts);
    assert_eq!(decode_parts(&bytes), Ok((header, parts.clone())));
    assert!(matches!(
        decode_parts(&bytes[..bytes.len() - 1]),
        Err(Refusal::Size { .. })
    ));
    header.part_count = u32::MAX;
    assert!(matches!(
        decode_parts(&encode_parts(&header, &parts)),
        Err(Refusal::Size { .. })
    ));
}

#[test]
fn geometry_round_trips_and_a_cut_one_is_refused() {
    let geometry = SceneGeometry {
        generation: 3,
        parts: vec![vas_protocol::MeshData {
            name: "peg".into(),
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: Vec::new(),
            triangles: vec![[0, 1, 2]],
        }],
        hands: Vec::new(),
    };
    let bytes = encode_geometry(&geometry);
    assert_eq!(decode_geometry(&bytes), Ok(geometry));
    assert!(decode_geometry(&bytes[..bytes.len() - 4]).is_err());
}
