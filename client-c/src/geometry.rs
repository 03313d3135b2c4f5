//! The scene's render meshes as C sees them: arrays of positions, normals and triangles that
//! point into the client's copy of a geometry generation.

use std::ffi::{CString, c_char};
use std::sync::Arc;

use vas_protocol::{MeshData, SceneGeometry};

use crate::client::{VasClient, client_mut};
use crate::pointers::output;
use crate::status::{VasStatus, guard};

/// One triangle mesh: a part's in the part's own frame (its scale applied), or a hand segment's
/// in the segment's frame. Every pointer stays valid as long as the [`VasGeometry`] it came in.
#[repr(C)]
#[derive(Debug)]
pub struct VasMesh {
    /// The part's or segment's name, NUL-terminated UTF-8.
    pub name: *const c_char,
    /// `vertex_count` positions in metres, x, y, z each.
    pub positions: *const [f32; 3],
    /// `vertex_count` unit normals, one per position; null when the server sent none (compute
    /// them).
    pub normals: *const [f32; 3],
    /// Vertices.
    pub vertex_count: usize,
    /// `triangle_count` triangles, three vertex indices each. CAD meshes may be polygon soups
    /// whose winding means nothing: draw both sides.
    pub triangles: *const [u32; 3],
    /// Triangles.
    pub triangle_count: usize,
}

/// One hand's segment meshes, in segment order (`vas_hand_segment_name` names them).
#[repr(C)]
#[derive(Debug)]
pub struct VasHandGeometry {
    /// Which hand, a `VAS_HAND_*` code.
    pub side: u32,
    /// Whose hand: an index into `VasSceneInfo::users`.
    pub user: u32,
    /// The hand model's name, NUL-terminated UTF-8.
    pub model: *const c_char,
    /// `segment_count` meshes.
    pub segments: *const VasMesh,
    /// Segments.
    pub segment_count: usize,
}

/// Every mesh of one scene generation: parts by id, then each hand's segments.
#[repr(C)]
#[derive(Debug)]
pub struct VasGeometry {
    /// The scene generation: one more after every load or reset of the scene.
    pub generation: u64,
    /// `part_count` meshes, indexed by part id.
    pub parts: *const VasMesh,
    /// Parts.
    pub part_count: usize,
    /// `hand_count` hands.
    pub hands: *const VasHandGeometry,
    /// Hands.
    pub hand_count: usize,
}

/// A geometry generation kept for C: the decoded meshes, their names as C strings and the C
/// structs pointing into both. The `Vec`s are never changed after construction, so the pointers
/// into them stay put for as long as the view lives.
pub(crate) struct GeometryView {
    geometry: Arc<SceneGeometry>,
    _names: Vec<CString>,
    _parts: Vec<VasMesh>,
    _segments: Vec<Vec<VasMesh>>,
    _hands: Vec<VasHandGeometry>,
    root: VasGeometry,
}

impl GeometryView {
    fn new(geometry: Arc<SceneGeometry>) -> Self {
        let mut names = Vec::new();
        let mut name = |text: &str| {
            let owned = c_string(text);
            let pointer = owned.as_ptr();
            names.push(owned);
            pointer
        };
        let parts: Vec<VasMesh> = (geometry.parts.iter())
            .map(|mesh| mesh_of(mesh, name(&mesh.name)))
            .collect();
        let segments: Vec<Vec<VasMesh>> = (geometry.hands.iter())
            .map(|hand| {
                (hand.segments.iter())
                    .map(|mesh| mesh_of(mesh, name(&mesh.name)))
                    .collect()
            })
            .collect();
        let hands: Vec<VasHandGeometry> = (geometry.hands.iter().zip(&segments))
            .map(|(hand, meshes)| VasHandGeometry {
                side: hand.side as u32,
                user: hand.user,
                model: name(&hand.model),
                segments: meshes.as_ptr(),
                segment_count: meshes.len(),
            })
            .collect();
        let root = VasGeometry {
            generation: geometry.generation,
            parts: parts.as_ptr(),
            part_count: parts.len(),
            hands: hands.as_ptr(),
            hand_count: hands.len(),
        };
        Self {
            geometry,
            _names: names,
            _parts: parts,
            _segments: segments,
            _hands: hands,
            root,
        }
    }
}

/// `text` as a C string, cut at a NUL inside it (names on the wire are UTF-8 without NULs; a
/// corrupt one must not fail the whole geometry).
pub(crate) fn c_string(text: &str) -> CString {
    let text = text.split('\0').next().unwrap_or_default();
    CString::new(text).unwrap_or_default()
}

/// The C view of `mesh`, named by `name`.
fn mesh_of(mesh: &MeshData, name: *const c_char) -> VasMesh {
    VasMesh {
        name,
        positions: mesh.positions.as_ptr(),
        normals: match mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty() {
            true => mesh.normals.as_ptr(),
            false => std::ptr::null(),
        },
        vertex_count: mesh.positions.len(),
        triangles: mesh.triangles.as_ptr(),
        triangle_count: mesh.triangles.len(),
    }
}

/// The newest scene geometry the polls received: `*geometry` points to every part's and hand
/// segment's mesh with the scene generation. [`VasStatus::Empty`] before the first geometry (a
/// client gets the current one soon after it connects; poll first).
///
/// Everything behind `*geometry` belongs to the client and stays valid until a later call of
/// this function returns another generation (after a load or reset of the scene), or
/// `vas_client_free`: a renderer uploads the meshes when the generation
/// changes and may keep reading them until it asks again.
///
/// # Safety
/// `client` is a live handle; `geometry` points to writable memory for a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_geometry(
    client: *mut VasClient,
    geometry: *mut *const VasGeometry,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, geometry) = unsafe { (client_mut(client)?, output(geometry, "geometry")?) };
        let Some(latest) = client.client.geometry() else {
            return Ok(VasStatus::Empty);
        };
        let current =
            (client.geometry.as_ref()).is_some_and(|view| Arc::ptr_eq(&view.geometry, latest));
        if !current {
            client.geometry = Some(GeometryView::new(Arc::clone(latest)));
        }
        let view = client.geometry.as_ref().expect("kept above");
        *geometry = &view.root;
        Ok(VasStatus::Ok)
    })
}
