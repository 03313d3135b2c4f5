//! The part of a glTF 2.0 document that geometry needs, as serde reads it.
//!
//! vas reads these few fields itself rather than through the gltf crate: that crate's
//! validation indexes a primitive's POSITION accessor before checking that it exists (a panic
//! on a bad file, gltf-json 1.4.1) and keeps transforms in single precision. Here every index is
//! checked where it is used, with a message that names it.

use std::collections::BTreeMap;

use serde::Deserialize;
use serde::de::IgnoredAny;

/// The root of a glTF document.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Document {
    pub asset: Asset,
    #[serde(default)]
    pub extensions_required: Vec<String>,
    /// The default scene.
    pub scene: Option<usize>,
    #[serde(default)]
    pub scenes: Vec<Scene>,
    #[serde(default)]
    pub nodes: Vec<Node>,
    #[serde(default)]
    pub meshes: Vec<Mesh>,
    #[serde(default)]
    pub accessors: Vec<Accessor>,
    #[serde(default)]
    pub buffer_views: Vec<BufferView>,
    #[serde(default)]
    pub buffers: Vec<Buffer>,
}

#[derive(Debug, Deserialize)]
pub(super) struct Asset {
    pub version: String,
}

#[derive(Debug, Deserialize)]
pub(super) struct Scene {
    /// The scene's root nodes.
    #[serde(default)]
    pub nodes: Vec<usize>,
}

#[derive(Debug, Deserialize)]
pub(super) struct Node {
    pub name: Option<String>,
    #[serde(default)]
    pub children: Vec<usize>,
    pub mesh: Option<usize>,
    /// Column-major; when given, it replaces translation, rotation and scale.
    pub matrix: Option<[f64; 16]>,
    pub translation: Option<[f64; 3]>,
    /// A unit quaternion, x, y, z, w.
    pub rotation: Option<[f64; 4]>,
    pub scale: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
pub(super) struct Mesh {
    pub primitives: Vec<Primitive>,
}

#[derive(Debug, Deserialize)]
pub(super) struct Primitive {
    /// Accessors by attribute name (`POSITION`, `NORMAL`, ...).
    pub attributes: BTreeMap<String, usize>,
    pub indices: Option<usize>,
    #[serde(default = "triangles_mode")]
    pub mode: u32,
}

/// The primitive modes that give triangles.
pub(super) const TRIANGLES: u32 = 4;
pub(super) const TRIANGLE_STRIP: u32 = 5;
pub(super) const TRIANGLE_FAN: u32 = 6;

fn triangles_mode() -> u32 {
    TRIANGLES
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Accessor {
    pub buffer_view: Option<usize>,
    #[serde(default)]
    pub byte_offset: u64,
    pub component_type: u32,
    pub count: u64,
    #[serde(rename = "type")]
    pub kind: String,
    /// Present for a sparse accessor, which vas does not read.
    pub sparse: Option<IgnoredAny>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct BufferView {
    pub buffer: usize,
    #[serde(default)]
    pub byte_offset: u64,
    pub byte_length: u64,
    pub byte_stride: Option<u64>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Buffer {
    /// A file relative to the `.gltf` or a `data:` URI; none for a GLB's binary chunk.
    pub uri: Option<String>,
    pub byte_length: u64,
}

impl Document {
    /// Parses the JSON of a glTF 2.0 document, refusing other versions and extensions that the
    /// file requires and that change how its geometry is stored (compression, quantisation):
    /// required extensions of appearance alone (materials, textures, lights) do not matter to
    /// vas.
    pub fn parse(json: &[u8]) -> Result<Document, String> {
        let document: Document =
            serde_json::from_slice(json).map_err(|e| format!("not a valid glTF file: {e}"))?;
        if !document.asset.version.starts_with("2.") {
            return Err(format!(
                "glTF version {}; vas reads glTF 2.0",
                document.asset.version
            ));
        }
        const APPEARANCE: [&str; 5] = [
            "KHR_materials_",
            "KHR_texture_",
            "EXT_texture_",
            "MSFT_texture_",
            "KHR_lights_punctual",
        ];
        let geometric = document
            .extensions_required
            .iter()
            .find(|name| !APPEARANCE.iter().any(|prefix| name.starts_with(prefix)));
        if let Some(name) = geometric {
            return Err(format!(
                "the file requires the extension {name}, which vas does not read"
            ));
        }
        Ok(document)
    }
}
