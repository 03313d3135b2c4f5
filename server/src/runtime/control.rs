//! Answers to `vas/control` requests: what they read and change of the served session, and the
//! change they send down the loops.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use vas_protocol::{
    ControlRequest, ControlRequestKind, ControlResponse, ControlStatus, HandDescription, MAX_HANDS,
    MAX_NAME_BYTES, MAX_USERS, PART_MOVABLE, PartDescription, SlidingMetaphor, WirePose, WireText,
};

use super::inputs::Inputs;
use crate::scene::{Part, Scene};
use crate::simulation::restart::{Change, HandSetupError, Restart};

/// What the I/O thread serves: the scene, the input state and the count of restarts.
pub struct Session {
    /// The scene being served.
    pub scene: Arc<Scene>,
    /// Input validation, counters and the latest targets.
    pub inputs: Inputs,
    /// Restarts so far (the first load is 1).
    pub epoch: u64,
    /// The scenes that may be loaded by name.
    pub catalogue: SceneCatalogue,
    /// The sliding metaphor in use: the scene's own until a `SetMetaphor`.
    pub metaphor: SlidingMetaphor,
}

/// The scenes the server may load by name: the `*.toml` files of one folder, named by their
/// file stem. A name is looked up in this list, never joined to a path, so a request cannot
/// reach a file outside the folder.
#[derive(Debug, Clone)]
pub struct SceneCatalogue {
    folder: PathBuf,
    names: Vec<String>,
}

impl SceneCatalogue {
    /// The scenes of `folder`, as it is now.
    pub fn of(folder: PathBuf) -> Self {
        let mut catalogue = Self {
            folder,
            names: Vec::new(),
        };
        catalogue.refresh();
        catalogue
    }

    /// Reads the folder again (a listing that fails leaves the list empty, and says why in the
    /// log).
    fn refresh(&mut self) {
        let entries = match std::fs::read_dir(&self.folder) {
            Ok(entries) => entries,
            Err(error) => {
                tracing::warn!(folder = %self.folder.display(), %error, "cannot list the scenes");
                self.names.clear();
                return;
            }
        };
        self.names = entries
            .filter_map(|entry| entry.ok()?.path().to_str().map(PathBuf::from))
            .filter(|path| path.extension().is_some_and(|e| e == "toml") && path.is_file())
            .filter_map(|path| Some(path.file_stem()?.to_str()?.to_owned()))
            .collect();
        self.names.sort();
    }

    /// The scene names, sorted.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    fn path_of(&self, name: &str) -> Option<PathBuf> {
        (self.names.iter().any(|listed| listed == name))
            .then(|| self.folder.join(format!("{name}.toml")))
    }
}

impl Session {
    /// A session on `scene`, offering the scenes of `catalogue`, and what starts the loops on
    /// it.
    pub fn start(
        scene: Scene,
        catalogue: SceneCatalogue,
    ) -> Result<(Session, Restart), HandSetupError> {
        let scene = Arc::new(scene);
        let restart = Restart::new(Arc::clone(&scene), 1)?;
        let session = Session {
            inputs: Inputs::for_hands(scene.hand_models(), scene.params.tracking),
            metaphor: scene.params.sliding.metaphor,
            scene,
            epoch: 1,
            catalogue,
        };
        Ok((session, restart))
    }

    /// Slides grasped parts with the metaphor of `code` from now on (until a load or reset
    /// brings the scene's own back).
    fn set_metaphor(&mut self, code: u32) -> Result<(PartDescription, Option<Change>), Refusal> {
        let metaphor = SlidingMetaphor::try_from(code)
            .map_err(|unknown| (ControlStatus::InvalidRequest, unknown.to_string()))?;
        tracing::info!(%metaphor, "sliding metaphor set on request");
        self.metaphor = metaphor;
        Ok((
            PartDescription::default(),
            Some(Change::SlidingMetaphor(metaphor)),
        ))
    }

    /// Starts over on `scene`: the targets are forgotten, the counters go on.
    fn restart(&mut self, scene: Arc<Scene>) -> Result<Change, Refusal> {
        let restart = Restart::new(Arc::clone(&scene), self.epoch + 1)
            .map_err(|error| (ControlStatus::SceneLoadFailed, error.to_string()))?;
        self.epoch += 1;
        self.inputs
            .restart(scene.hand_models(), scene.params.tracking);
        self.metaphor = scene.params.sliding.metaphor;
        self.scene = scene;
        Ok(restart.into_change())
    }
}

/// What a control request needs: an answer now, or a scene loaded first.
#[expect(
    clippy::large_enum_variant,
    reason = "one per request, copied straight into the response sample"
)]
pub enum Reply {
    /// The answer, with the change for the loops, if any.
    Now(ControlResponse, Option<Change>),
    /// `LoadScene` of this file: load it apart and answer with [`loaded`].
    Load(PathBuf),
}

/// Carries out `request` and builds the answer; `loading` says whether a scene load is already
/// under way (a second one is refused).
///
/// Every answer carries the scene summary and the input counters as they are after the request;
/// a refused request changes nothing and explains itself in `message`.
pub fn answer(session: &mut Session, request: &ControlRequest, loading: bool) -> Reply {
    let mut listed = WireText::EMPTY;
    let outcome = match ControlRequestKind::try_from(request.kind) {
        Err(unknown) => Err((ControlStatus::InvalidRequest, unknown.to_string())),
        Ok(ControlRequestKind::SceneInfo) => Ok((PartDescription::default(), None)),
        Ok(ControlRequestKind::PartInfo) => {
            describe_part(&session.scene, request.argument).map(|part| (part, None))
        }
        Ok(ControlRequestKind::LoadScene) => match scene_path(request, loading) {
            Ok(path) => return Reply::Load(path),
            Err(refusal) => Err(refusal),
        },
        Ok(ControlRequestKind::LoadNamedScene) => {
            match scene_path(request, loading).and_then(|name| named(&session.catalogue, &name)) {
                Ok(path) => return Reply::Load(path),
                Err(refusal) => Err(refusal),
            }
        }
        Ok(ControlRequestKind::ListScene) => {
            if request.argument == 0 {
                session.catalogue.refresh();
            }
            list_scene(&session.catalogue, request.argument).map(|name| {
                listed = name;
                (PartDescription::default(), None)
            })
        }
        Ok(ControlRequestKind::Reset) => session
            .restart(Arc::clone(&session.scene))
            .map(|change| (PartDescription::default(), Some(change))),
        Ok(ControlRequestKind::SetMetaphor) => session.set_metaphor(request.argument),
    };
    let (mut response, change) = respond(session, request.kind, outcome);
    response.listed = listed;
    Reply::Now(response, change)
}

/// The answer to a `LoadScene` request whose scene finished loading (or failed to): a loaded
/// scene replaces the served one, a failure changes nothing and says why.
pub fn loaded(
    session: &mut Session,
    outcome: Result<Scene, String>,
) -> (ControlResponse, Option<Change>) {
    let outcome = outcome
        .map_err(|reason| (ControlStatus::SceneLoadFailed, reason))
        .and_then(|scene| {
            tracing::info!(
                scene = scene.name,
                parts = scene.parts.len(),
                source = %scene.source.display(),
                "scene loaded on request"
            );
            session.restart(Arc::new(scene))
        })
        .map(|change| (PartDescription::default(), Some(change)));
    respond(session, ControlRequestKind::LoadScene as u32, outcome)
}

/// The response to a request of `kind` with `outcome`, summarising the session as it is now.
fn respond(
    session: &Session,
    kind: u32,
    outcome: Result<(PartDescription, Option<Change>), Refusal>,
) -> (ControlResponse, Option<Change>) {
    let scene = &session.scene;
    let (scene_name, name_cut) = WireText::truncated(&scene.name);
    let (scene_source, source_cut) = WireText::truncated(&scene.source.display().to_string());
    let mut hands = [HandDescription::default(); MAX_HANDS];
    // A scene has at most MAX_USERS users of at most one hand of each side: MAX_HANDS.
    for (described, hand) in hands.iter_mut().zip(&scene.hands) {
        *described = HandDescription {
            side: hand.model.side() as u32,
            user: hand.user,
            model: WireText::truncated(hand.model.name()).0,
        };
    }
    let mut users = [WireText::EMPTY; MAX_USERS];
    // The scene refuses more users and longer names, so nothing is cut here.
    for (described, name) in users.iter_mut().zip(&scene.users) {
        *described = WireText::truncated(name).0;
    }
    let mut response = ControlResponse {
        status: ControlStatus::Ok as u32,
        kind,
        part_count: u32::try_from(scene.parts.len()).unwrap_or(u32::MAX),
        scene_truncated: u32::from(name_cut || source_cut),
        scene_name,
        scene_source,
        part: PartDescription::default(),
        stats: session.inputs.stats(),
        message: WireText::EMPTY,
        up: [0.0, 0.0, 1.0],
        metres_per_unit: 1.0,
        hand_count: u32::try_from(scene.hands.len().min(MAX_HANDS)).expect("at most eight"),
        listed_count: u32::try_from(session.catalogue.names().len()).unwrap_or(u32::MAX),
        hands,
        listed: WireText::EMPTY,
        generation: session.epoch,
        metaphor: session.metaphor as u32,
        user_count: u32::try_from(scene.users.len().min(MAX_USERS)).expect("at most four"),
        users,
    };
    match outcome {
        Ok((part, change)) => {
            response.part = part;
            (response, change)
        }
        Err((status, message)) => {
            response.status = status as u32;
            response.message = WireText::truncated(&message).0;
            (response, None)
        }
    }
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
        scale: part.scale,
    })
}

fn named(catalogue: &SceneCatalogue, name: &Path) -> Result<PathBuf, Refusal> {
    let name = name.to_string_lossy();
    catalogue.path_of(&name).ok_or_else(|| {
        (
            ControlStatus::SceneLoadFailed,
            format!(
                "no scene is named {name:?}; the server offers {}",
                catalogue.names().join(", ")
            ),
        )
    })
}

fn list_scene(catalogue: &SceneCatalogue, index: u32) -> Result<WireText<MAX_NAME_BYTES>, Refusal> {
    let name = catalogue.names().get(index as usize).ok_or_else(|| {
        (
            ControlStatus::SceneLoadFailed,
            format!(
                "the server offers {} scenes, there is no scene {index}",
                catalogue.names().len()
            ),
        )
    })?;
    WireText::new(name).map_err(|error| {
        (
            ControlStatus::SceneLoadFailed,
            format!("scene {index}'s name: {error}"),
        )
    })
}

fn scene_path(request: &ControlRequest, loading: bool) -> Result<PathBuf, Refusal> {
    if loading {
        return Err((
            ControlStatus::Busy,
            "another scene is loading; ask again once that request is answered".to_owned(),
        ));
    }
    let path = request.path.as_str().map_err(|error| {
        (
            ControlStatus::InvalidRequest,
            format!("scene path: {error}"),
        )
    })?;
    Ok(PathBuf::from(path))
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

    fn session() -> Session {
        let scene = Scene::load(&config("default.toml")).expect("the demo scene loads");
        let catalogue = SceneCatalogue::of(config(""));
        Session::start(scene, catalogue).expect("its hand builds").0
    }

    fn status(response: &ControlResponse) -> ControlStatus {
        ControlStatus::try_from(response.status).expect("known status")
    }

    /// The answer to a request that needs no scene loaded.
    fn now(session: &mut Session, request: &ControlRequest) -> (ControlResponse, Option<Change>) {
        match answer(session, request, false) {
            Reply::Now(response, change) => (response, change),
            Reply::Load(path) => panic!("expected an answer, got a load of {path:?}"),
        }
    }

    /// Asks to load `file` and answers as the I/O thread does once the loader finishes.
    fn load(session: &mut Session, file: &Path) -> (ControlResponse, Option<Change>) {
        let path = WireText::<MAX_PATH_BYTES>::new(&file.display().to_string()).expect("fits");
        let Reply::Load(path) = answer(session, &ControlRequest::load_scene(path), false) else {
            panic!("a load-scene request asks for a load");
        };
        assert_eq!(path, file);
        loaded(
            session,
            Scene::load(&path).map_err(|error| error.to_string()),
        )
    }

    fn restart_epoch(change: Option<Change>) -> u64 {
        match change {
            Some(Change::Restart(restart)) => restart.epoch,
            other => panic!("expected a restart, got {other:?}"),
        }
    }

    #[test]
    fn scene_info_summarises_the_scene_and_the_counters() {
        let mut session = session();
        let mut nan = TrackerSample {
            seq: 1,
            timestamp_ns: 1,
            hand: WirePose::IDENTITY,
            cart: WirePose::IDENTITY,
            sensor_id: 0,
            user: 0,
            side: 0,
            reserved: 0,
        };
        nan.hand.position[0] = f64::NAN;
        assert!(session.inputs.apply_tracker(&nan).is_err());

        let (response, change) = now(&mut session, &ControlRequest::scene_info());
        assert!(change.is_none());
        let scene = &session.scene;
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
        let mut session = session();
        let count = session.scene.parts.len();
        for id in 0..count {
            let (response, _) = now(&mut session, &ControlRequest::part_info(id as u32));
            let part = &session.scene.parts[id];
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
        let (response, change) = now(&mut session, &ControlRequest::part_info(count as u32));
        assert!(change.is_none());
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
    fn unknown_requests_and_codes_are_invalid_and_change_nothing() {
        let mut session = session();
        let mut request = ControlRequest::scene_info();
        request.kind = 99;
        let (response, change) = now(&mut session, &request);
        assert_eq!(status(&response), ControlStatus::InvalidRequest);
        assert!(change.is_none());
        let mut request = ControlRequest::set_metaphor(SlidingMetaphor::RubberBand);
        request.argument = 0;
        let (response, change) = now(&mut session, &request);
        assert_eq!(status(&response), ControlStatus::InvalidRequest);
        assert!(change.is_none());
    }

    #[test]
    fn a_scene_that_fails_to_load_leaves_the_session_unchanged() {
        let mut session = session();
        let before = session.scene.name.clone();
        let (response, change) = load(&mut session, &config("no_such_scene.toml"));
        assert_eq!(status(&response), ControlStatus::SceneLoadFailed);
        assert!(change.is_none());
        assert!(
            response
                .message
                .as_str()
                .expect("utf-8")
                .contains("no_such_scene.toml"),
            "{:?}",
            response.message
        );
        assert_eq!(session.scene.name, before);
        assert_eq!(session.epoch, 1);
    }

    #[test]
    fn a_loaded_scene_replaces_the_current_one_and_restarts_the_loops() {
        let mut session = session();
        let file = config("peg_in_hole.toml");
        let expected = Scene::load(&file).expect("loads");
        let (response, change) = load(&mut session, &file);
        assert_eq!(status(&response), ControlStatus::Ok);
        assert_eq!(response.scene_name.as_str(), Ok(expected.name.as_str()));
        assert_eq!(response.part_count as usize, expected.parts.len());
        assert_eq!(restart_epoch(change), 2);
        assert_eq!(session.epoch, 2);
    }

    #[test]
    fn a_second_load_while_one_is_under_way_is_refused_as_busy() {
        let mut session = session();
        let path = WireText::<MAX_PATH_BYTES>::new("peg_in_hole.toml").expect("fits");
        let Reply::Now(response, change) =
            answer(&mut session, &ControlRequest::load_scene(path), true)
        else {
            panic!("a load while loading is answered at once");
        };
        assert_eq!(status(&response), ControlStatus::Busy);
        assert!(change.is_none());
        assert_eq!(session.epoch, 1);
    }

    #[test]
    fn reset_restarts_the_same_scene_and_brings_its_own_metaphor_back() {
        let mut session = session();
        let own = session.scene.params.sliding.metaphor;
        let (response, _) = now(&mut session, &ControlRequest::scene_info());
        assert_eq!(
            response.metaphor, own as u32,
            "answers name the metaphor in use"
        );
        let other = SlidingMetaphor::ALL
            .into_iter()
            .find(|metaphor| *metaphor != own)
            .expect("three metaphors");
        let request = ControlRequest::set_metaphor(other);
        let (response, change) = now(&mut session, &request);
        assert_eq!(status(&response), ControlStatus::Ok);
        assert_eq!(response.metaphor, other as u32);
        assert!(matches!(change, Some(Change::SlidingMetaphor(set)) if set == other));
        let name = session.scene.name.clone();
        let (response, change) = now(&mut session, &ControlRequest::reset());
        assert_eq!(status(&response), ControlStatus::Ok);
        assert_eq!(restart_epoch(change), 2);
        assert_eq!(session.scene.name, name);
        assert_eq!(response.metaphor, own as u32);
    }
}
