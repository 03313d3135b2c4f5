//! Answers to `vas/control` requests, as a pure function of the simulation state.

use std::path::Path;

use vas_protocol::{
    ControlRequest, ControlRequestKind, ControlResponse, ControlStatus, PART_MOVABLE,
    PartDescription, SlidingMetaphor, WirePose, WireText,
};

use super::simulation::Simulation;
use crate::scene::{Part, Scene};
use crate::sliding::Metaphor;

/// Carries out `request` on the simulation and builds the answer.
///
/// Every answer carries the scene summary and the input counters as they are after the request;
/// a refused request leaves the simulation unchanged and explains itself in `message`.
/// `LoadScene` reads the file on the calling thread: the server answers nothing else meanwhile.
pub fn answer(simulation: &mut Simulation, request: &ControlRequest) -> ControlResponse {
    let outcome = match ControlRequestKind::try_from(request.kind) {
        Err(unknown) => Err((ControlStatus::InvalidRequest, unknown.to_string())),
        Ok(ControlRequestKind::SceneInfo) => Ok(PartDescription::default()),
        Ok(ControlRequestKind::PartInfo) => describe_part(simulation.scene(), request.argument),
        Ok(ControlRequestKind::LoadScene) => load_scene(simulation, request),
        Ok(ControlRequestKind::Reset) => {
            simulation.reset();
            Ok(PartDescription::default())
        }
        Ok(ControlRequestKind::SetMetaphor) => set_metaphor(simulation, request.argument),
    };
    let scene = simulation.scene();
    let (scene_name, name_cut) = WireText::truncated(&scene.name);
    let (scene_source, source_cut) = WireText::truncated(&scene.source.display().to_string());
    let mut response = ControlResponse {
        status: ControlStatus::Ok as u32,
        kind: request.kind,
        part_count: u32::try_from(scene.parts.len()).unwrap_or(u32::MAX),
        scene_truncated: u32::from(name_cut || source_cut),
        scene_name,
        scene_source,
        part: PartDescription::default(),
        stats: simulation.stats(),
        message: WireText::EMPTY,
    };
    match outcome {
        Ok(part) => response.part = part,
        Err((status, message)) => {
            response.status = status as u32;
            response.message = WireText::truncated(&message).0;
        }
    }
    response
}

type Refusal = (ControlStatus, String);

fn describe_part(scene: &Scene, id: u32) -> Result<PartDescription, Refusal> {
    let part: &Part = scene.parts.get(id as usize).ok_or_else(|| {
        (
            ControlStatus::NoSuchPart,
            format!(
                "the scene has {} parts, there is no part {id}",
                scene.parts.len()
            ),
        )
    })?;
    let (name, name_cut) = WireText::truncated(&part.name);
    let (group, group_cut) = WireText::truncated(&part.group);
    let (mesh_source, source_cut) = WireText::truncated(&part.mesh_source);
    Ok(PartDescription {
        id,
        flags: if part.movable { PART_MOVABLE } else { 0 },
        initial_pose: WirePose::from_isometry(&part.pose),
        name,
        group,
        mesh_source,
        truncated: u32::from(name_cut || group_cut || source_cut),
    })
}

fn load_scene(
    simulation: &mut Simulation,
    request: &ControlRequest,
) -> Result<PartDescription, Refusal> {
    let path = request.path.as_str().map_err(|error| {
        (
            ControlStatus::InvalidRequest,
            format!("scene path: {error}"),
        )
    })?;
    let scene = Scene::load(Path::new(path))
        .map_err(|error| (ControlStatus::SceneLoadFailed, error.to_string()))?;
    tracing::info!(
        scene = scene.name,
        parts = scene.parts.len(),
        path,
        "scene loaded on request"
    );
    simulation.replace_scene(scene);
    Ok(PartDescription::default())
}

fn set_metaphor(simulation: &mut Simulation, code: u32) -> Result<PartDescription, Refusal> {
    let metaphor = match SlidingMetaphor::try_from(code) {
        Ok(SlidingMetaphor::RubberBand) => Metaphor::RubberBand,
        Ok(SlidingMetaphor::RubberBandSpiralSpring) => Metaphor::SpiralSpring,
        Ok(SlidingMetaphor::IncrementalMotion) => Metaphor::Incremental,
        Err(unknown) => return Err((ControlStatus::InvalidRequest, unknown.to_string())),
    };
    tracing::info!(%metaphor, "sliding metaphor set on request");
    simulation.set_sliding_metaphor(metaphor);
    Ok(PartDescription::default())
}

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use vas_protocol::{ControlRequest, MAX_PATH_BYTES, TrackerSample};

    use super::*;

    fn config(file: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../configs")
            .join(file)
    }

    fn simulation() -> Simulation {
        Simulation::new(Scene::load(&config("default.toml")).expect("the demo scene loads"))
    }

    fn status(response: &ControlResponse) -> ControlStatus {
        ControlStatus::try_from(response.status).expect("known status")
    }

    #[test]
    fn scene_info_summarises_the_scene_and_the_counters() {
        let mut simulation = simulation();
        let mut nan = TrackerSample {
            seq: 1,
            timestamp_ns: 1,
            hand: WirePose::IDENTITY,
            cart: WirePose::IDENTITY,
            sensor_id: 0,
        };
        nan.hand.position[0] = f64::NAN;
        assert!(simulation.apply_tracker(&nan).is_err());

        let response = answer(&mut simulation, &ControlRequest::scene_info());
        let scene = simulation.scene();
        assert_eq!(status(&response), ControlStatus::Ok);
        assert_eq!(response.kind, ControlRequestKind::SceneInfo as u32);
        assert_eq!(response.part_count as usize, scene.parts.len());
        assert_eq!(response.scene_name.as_str(), Ok(scene.name.as_str()));
        assert_eq!(
            response.scene_source.as_str(),
            Ok(scene.source.display().to_string().as_str())
        );
        assert_eq!(response.scene_truncated, 0);
        assert_eq!(response.stats.tracker_rejected_non_finite, 1);
    }

    #[test]
    fn part_info_describes_each_part_and_refuses_unknown_ids() {
        let mut simulation = simulation();
        let count = simulation.scene().parts.len();
        for id in 0..count {
            let response = answer(&mut simulation, &ControlRequest::part_info(id as u32));
            let part = &simulation.scene().parts[id];
            assert_eq!(status(&response), ControlStatus::Ok);
            assert_eq!(response.part.id as usize, id);
            assert_eq!(response.part.name.as_str(), Ok(part.name.as_str()));
            assert_eq!(response.part.group.as_str(), Ok(part.group.as_str()));
            assert_eq!(
                response.part.mesh_source.as_str(),
                Ok(part.mesh_source.as_str())
            );
            assert_eq!(response.part.flags & PART_MOVABLE != 0, part.movable);
            assert_eq!(
                response.part.initial_pose,
                WirePose::from_isometry(&part.pose)
            );
        }
        let response = answer(&mut simulation, &ControlRequest::part_info(count as u32));
        assert_eq!(status(&response), ControlStatus::NoSuchPart);
        assert!(
            response
                .message
                .as_str()
                .expect("utf-8")
                .contains(&count.to_string())
        );
    }

    #[test]
    fn unknown_requests_and_codes_are_invalid() {
        let mut simulation = simulation();
        let mut request = ControlRequest::scene_info();
        request.kind = 99;
        assert_eq!(
            status(&answer(&mut simulation, &request)),
            ControlStatus::InvalidRequest
        );
        let mut request = ControlRequest::set_metaphor(SlidingMetaphor::RubberBand);
        request.argument = 0;
        assert_eq!(
            status(&answer(&mut simulation, &request)),
            ControlStatus::InvalidRequest
        );
    }

    #[test]
    fn a_scene_that_fails_to_load_leaves_the_scene_unchanged() {
        let mut simulation = simulation();
        let before = simulation.scene().name.clone();
        let missing = config("no_such_scene.toml").display().to_string();
        let path = WireText::<MAX_PATH_BYTES>::new(&missing).expect("fits");
        let response = answer(&mut simulation, &ControlRequest::load_scene(path));
        assert_eq!(status(&response), ControlStatus::SceneLoadFailed);
        assert!(
            response
                .message
                .as_str()
                .expect("utf-8")
                .contains("no_such_scene.toml"),
            "{:?}",
            response.message
        );
        assert_eq!(simulation.scene().name, before);
    }

    #[test]
    fn a_loaded_scene_replaces_the_current_one() {
        let mut simulation = simulation();
        let file = config("peg_in_hole.toml");
        let expected = Scene::load(&file).expect("loads");
        let path = WireText::<MAX_PATH_BYTES>::new(&file.display().to_string()).expect("fits");
        let response = answer(&mut simulation, &ControlRequest::load_scene(path));
        assert_eq!(status(&response), ControlStatus::Ok);
        assert_eq!(response.scene_name.as_str(), Ok(expected.name.as_str()));
        assert_eq!(response.part_count as usize, expected.parts.len());
    }

    #[test]
    fn the_sliding_metaphor_and_reset_are_applied() {
        let mut simulation = simulation();
        let request = ControlRequest::set_metaphor(SlidingMetaphor::IncrementalMotion);
        assert_eq!(
            status(&answer(&mut simulation, &request)),
            ControlStatus::Ok
        );
        assert_eq!(
            simulation.scene().params.sliding.metaphor,
            Metaphor::Incremental
        );
        assert_eq!(
            status(&answer(&mut simulation, &ControlRequest::reset())),
            ControlStatus::Ok
        );
    }
}
