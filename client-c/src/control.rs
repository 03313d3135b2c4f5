//! Control requests: the scene's description, reset, loading a scene by name, the sliding
//! metaphor.

use std::ffi::{CString, c_char};

use vas_client_rs::SceneInfo;
use vas_protocol::{InputStats, SlidingMetaphor, WirePose};

use crate::client::{VasClient, client_mut, millis};
use crate::geometry::c_string;
use crate::pointers::{output, text};
use crate::status::{Failure, VasStatus, guard};

/// One part of the scene, as the control service describes it.
#[repr(C)]
#[derive(Debug)]
pub struct VasPartInfo {
    /// The id of the part in parts frames and geometry.
    pub id: u32,
    /// Whether a hand can grasp and move it.
    pub movable: bool,
    /// Whether a name or path was cut to fit the wire.
    pub truncated: bool,
    /// The part's name, NUL-terminated UTF-8.
    pub name: *const c_char,
    /// Its collision group, NUL-terminated UTF-8.
    pub group: *const c_char,
    /// The mesh file the server resolved, or a procedural shape's description.
    pub mesh_source: *const c_char,
    /// Its pose when the scene was loaded.
    pub initial_pose: WirePose,
    /// The scale applied to its mesh (the geometry's meshes have it applied already).
    pub scale: f64,
}

/// One hand of the scene.
#[repr(C)]
#[derive(Debug)]
pub struct VasHandInfo {
    /// Which hand, a `VAS_HAND_*` code.
    pub side: u32,
    /// Whose hand: an index into `VasSceneInfo::users`.
    pub user: u32,
    /// The hand model's name, NUL-terminated UTF-8.
    pub model: *const c_char,
}

/// The server's scene: its name, parts, hands and generation.
#[repr(C)]
#[derive(Debug)]
pub struct VasSceneInfo {
    /// The scene's name, NUL-terminated UTF-8.
    pub name: *const c_char,
    /// The file the server loaded it from, NUL-terminated UTF-8.
    pub source: *const c_char,
    /// The scene generation, the same number as its geometry's.
    pub generation: u64,
    /// `part_count` parts, indexed by id.
    pub parts: *const VasPartInfo,
    /// Parts.
    pub part_count: usize,
    /// `hand_count` hands.
    pub hands: *const VasHandInfo,
    /// Hands.
    pub hand_count: usize,
    /// The world's up direction (vas: z up).
    pub up: [f64; 3],
    /// Metres per unit of every length (vas: 1).
    pub metres_per_unit: f64,
    /// How many scenes the server offers to load by name.
    pub scenes_offered: u32,
    /// The sliding metaphor in use, a `VAS_METAPHOR_*` code: the scene's own, or the one a
    /// client set since the last load or reset.
    pub metaphor: u32,
    /// The server's input counters at the time of the answer.
    pub stats: InputStats,
    /// `user_count` users' names, NUL-terminated UTF-8, by the index that samples, frames,
    /// events and hands name them with.
    pub users: *const *const c_char,
    /// Users: 1 for a scene of one user (named "user" unless the scene names its users).
    pub user_count: usize,
}

/// A scene description kept for C: its strings and the C structs pointing into them.
pub(crate) struct SceneView {
    _strings: Vec<CString>,
    _parts: Vec<VasPartInfo>,
    _hands: Vec<VasHandInfo>,
    _users: Vec<*const c_char>,
    root: VasSceneInfo,
}

impl SceneView {
    fn new(scene: &SceneInfo) -> Self {
        let mut strings = Vec::new();
        let mut keep = |text: &str| {
            let owned = c_string(text);
            let pointer = owned.as_ptr();
            strings.push(owned);
            pointer
        };
        let parts: Vec<VasPartInfo> = (scene.parts.iter())
            .map(|part| VasPartInfo {
                id: part.id,
                movable: part.movable,
                truncated: part.truncated,
                name: keep(&part.name),
                group: keep(&part.group),
                mesh_source: keep(&part.mesh_source),
                initial_pose: part.initial_pose,
                scale: part.scale,
            })
            .collect();
        let hands: Vec<VasHandInfo> = (scene.hands.iter())
            .map(|hand| VasHandInfo {
                side: hand.side as u32,
                user: hand.user,
                model: keep(&hand.model),
            })
            .collect();
        let users: Vec<*const c_char> = scene.users.iter().map(|user| keep(user)).collect();
        let root = VasSceneInfo {
            name: keep(&scene.name),
            source: keep(&scene.source),
            generation: scene.generation,
            parts: parts.as_ptr(),
            part_count: parts.len(),
            hands: hands.as_ptr(),
            hand_count: hands.len(),
            up: scene.up,
            metres_per_unit: scene.metres_per_unit,
            scenes_offered: scene.scenes_offered,
            metaphor: scene.metaphor as u32,
            stats: scene.stats,
            users: users.as_ptr(),
            user_count: users.len(),
        };
        Self {
            _strings: strings,
            _parts: parts,
            _hands: hands,
            _users: users,
            root,
        }
    }
}

/// Asks the server for its scene and waits up to `timeout_ms` for the whole answer: `*scene`
/// points to the description.
///
/// Everything behind `*scene` belongs to the client and stays valid until the next call of this
/// function or `vas_client_free`.
///
/// # Safety
/// `client` is a live handle; `scene` points to writable memory for a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_scene_info(
    client: *mut VasClient,
    timeout_ms: u64,
    scene: *mut *const VasSceneInfo,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, scene) = unsafe { (client_mut(client)?, output(scene, "scene")?) };
        let info = client.client.scene_info(millis(timeout_ms))?;
        let view = client.scene.insert(SceneView::new(&info));
        *scene = &view.root;
        Ok(VasStatus::Ok)
    })
}

/// Asks the server to put the scene back to its initial state, and waits up to `timeout_ms` for
/// its answer. A new geometry generation follows.
///
/// # Safety
/// `client` is a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_reset(client: *mut VasClient, timeout_ms: u64) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        client.client.reset(millis(timeout_ms))?;
        Ok(VasStatus::Ok)
    })
}

/// Asks the server to load the scene it offers as `name` (NUL-terminated UTF-8; `vas-client
/// scenes` lists them), and waits up to `timeout_ms` for its answer: [`VasStatus::Refused`] for a
/// name it does not offer. A new geometry generation follows.
///
/// # Safety
/// `client` is a live handle; `name` is a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_load_named_scene(
    client: *mut VasClient,
    name: *const c_char,
    timeout_ms: u64,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, name) = unsafe { (client_mut(client)?, text(name, "name")?) };
        let answer = client.client.load_named_scene(name, millis(timeout_ms));
        match answer {
            Err(vas_client_rs::ClientError::WireText(error)) => {
                Err(Failure::invalid(error.to_string()))
            }
            other => other.map(drop).map_err(Failure::from),
        }?;
        Ok(VasStatus::Ok)
    })
}

/// Asks the server to slide grasped parts with `metaphor` (a `VAS_METAPHOR_*` code), and waits
/// up to `timeout_ms` for its answer.
///
/// # Safety
/// `client` is a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_set_metaphor(
    client: *mut VasClient,
    metaphor: u32,
    timeout_ms: u64,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        let metaphor = SlidingMetaphor::try_from(metaphor)
            .map_err(|_| Failure::invalid(format!("unknown sliding metaphor {metaphor}")))?;
        client.client.set_metaphor(metaphor, millis(timeout_ms))?;
        Ok(VasStatus::Ok)
    })
}
