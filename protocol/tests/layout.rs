//! Pins the size and alignment of every wire type: a layout change must fail here, so that it
//! cannot reach the wire without a new `::vN` type name.

use std::mem::{align_of, offset_of, size_of};

use vas_protocol::*;

fn assert_layout<T>(size: usize, align: usize) {
    let name = std::any::type_name::<T>();
    assert_eq!(size_of::<T>(), size, "size of {name}");
    assert_eq!(align_of::<T>(), align, "alignment of {name}");
}

#[test]
fn input_types_keep_their_layout() {
    assert_layout::<WirePose>(56, 8);
    assert_layout::<TrackerSample>(144, 8);
    assert_layout::<GloveSample>(112, 8);
    assert_layout::<JointLocation>(64, 8);
    assert_layout::<HandJointsSample>(1688, 8);
    assert_eq!(offset_of!(TrackerSample, hand), 16);
    assert_eq!(offset_of!(TrackerSample, cart), 72);
    assert_eq!(offset_of!(TrackerSample, sensor_id), 128);
    assert_eq!(offset_of!(TrackerSample, user), 132);
    assert_eq!(offset_of!(TrackerSample, side), 136);
    assert_eq!(offset_of!(GloveSample, flex), 16);
    assert_eq!(offset_of!(GloveSample, user), 104);
    assert_eq!(offset_of!(GloveSample, side), 108);
    assert_eq!(offset_of!(JointLocation, radius), 56);
    assert_eq!(offset_of!(HandJointsSample, joints), 16);
    assert_eq!(offset_of!(HandJointsSample, side), 1680);
    assert_eq!(offset_of!(HandJointsSample, user), 1684);
    assert_eq!(HAND_JOINT_COUNT, 26);
}

#[test]
fn output_types_keep_their_layout() {
    assert_layout::<InputStamp>(16, 8);
    assert_layout::<PartsFrameHeader>(72, 8);
    assert_layout::<PartState>(64, 8);
    assert_layout::<HandFrame>(1128, 8);
    assert_layout::<SimEvent>(176, 8);
    assert_layout::<ClearancePair>(80, 8);
    assert_layout::<ClearanceFrame>(80 + 80 * MAX_CLEARANCE_PAIRS, 8);
    assert_layout::<GeometryHeader>(24, 8);
    assert_layout::<ForceFrame>(120, 8);
    assert_eq!(offset_of!(PartsFrameHeader, part_count), 64);
    assert_eq!(offset_of!(PartState, position), 8);
    assert_eq!(offset_of!(HandFrame, root), 64);
    assert_eq!(offset_of!(HandFrame, flex), 120);
    assert_eq!(offset_of!(HandFrame, grasp_type), 212);
    assert_eq!(offset_of!(HandFrame, user), 228);
    assert_eq!(offset_of!(HandFrame, segments), 232);
    assert_eq!(offset_of!(SimEvent, user), 88);
    assert_eq!(offset_of!(SimEvent, point), 96);
    assert_eq!(offset_of!(SimEvent, other_point), 144);
    assert_eq!(offset_of!(SimEvent, distance), 168);
    assert_eq!(offset_of!(ClearancePair, distance), 24);
    assert_eq!(offset_of!(ClearancePair, other_point), 56);
    assert_eq!(offset_of!(ClearanceFrame, threshold), 64);
    assert_eq!(offset_of!(ClearanceFrame, pairs), 80);
    assert_eq!(MAX_CLEARANCE_PAIRS, 32);
    assert_eq!(offset_of!(ForceFrame, torque), 88);
    assert_eq!(offset_of!(ForceFrame, hand), 112);
    assert_eq!(offset_of!(ForceFrame, user), 116);
}

#[test]
fn control_types_keep_their_layout() {
    assert_layout::<WireText<MAX_NAME_BYTES>>(68, 4);
    assert_layout::<WireText<MAX_PATH_BYTES>>(516, 4);
    assert_layout::<WireText<MAX_STATUS_MESSAGE_BYTES>>(260, 4);
    assert_layout::<ControlRequest>(524, 4);
    assert_layout::<InputStats>(144, 8);
    assert_layout::<PartDescription>(728, 8);
    assert_layout::<HandDescription>(76, 4);
    assert_layout::<ControlResponse>(2744, 8);
    assert_eq!(offset_of!(HandDescription, user), 4);
    assert_eq!(offset_of!(ControlResponse, part), 600);
    assert_eq!(offset_of!(ControlResponse, stats), 1328);
    assert_eq!(offset_of!(ControlResponse, hands), 1776);
    assert_eq!(offset_of!(ControlResponse, generation), 2456);
    assert_eq!(offset_of!(ControlResponse, metaphor), 2464);
    assert_eq!(offset_of!(ControlResponse, user_count), 2468);
    assert_eq!(offset_of!(ControlResponse, users), 2472);
    assert_eq!((MAX_USERS, MAX_HANDS), (4, 8));
}

#[test]
fn string_capacities_are_pinned() {
    assert_eq!(
        (MAX_NAME_BYTES, MAX_PATH_BYTES, MAX_STATUS_MESSAGE_BYTES),
        (64, 512, 256)
    );
    assert_eq!(FLEX_COUNT, 22);
}

#[test]
fn payload_type_names_are_versioned() {
    use iceoryx2::prelude::ZeroCopySend;
    // SAFETY: `type_name` only returns the name given in the derive attribute.
    let names = unsafe {
        [
            <TrackerSample as ZeroCopySend>::type_name(),
            <GloveSample as ZeroCopySend>::type_name(),
            <HandJointsSample as ZeroCopySend>::type_name(),
            <PartsFrameHeader as ZeroCopySend>::type_name(),
            <PartState as ZeroCopySend>::type_name(),
            <HandFrame as ZeroCopySend>::type_name(),
            <SimEvent as ZeroCopySend>::type_name(),
            <ForceFrame as ZeroCopySend>::type_name(),
            <ClearancePair as ZeroCopySend>::type_name(),
            <ClearanceFrame as ZeroCopySend>::type_name(),
            <GeometryHeader as ZeroCopySend>::type_name(),
            <ControlRequest as ZeroCopySend>::type_name(),
            <ControlResponse as ZeroCopySend>::type_name(),
        ]
    };
    assert_eq!(
        names,
        [
            "vas::input::TrackerSample::v2",
            "vas::input::GloveSample::v2",
            "vas::input::HandJointsSample::v2",
            "vas::output::PartsFrameHeader::v2",
            "vas::output::PartState::v1",
            "vas::output::HandFrame::v4",
            "vas::output::SimEvent::v5",
            "vas::output::ForceFrame::v3",
            "vas::output::ClearancePair::v1",
            "vas::output::ClearanceFrame::v1",
            "vas::scene::GeometryHeader::v2",
            "vas::control::ControlRequest::v1",
            "vas::control::ControlResponse::v8",
        ]
    );
}
