//! A built tree as a file: a header naming what the tree was built from (the mesh's content hash
//! and triangle count, the orientations, the leaf size, the layout of the file) and a checksum,
//! then the arrays the build computes, as their bytes. What the mesh gives again (its triangles
//! in leaf order, their ranges, the parents, the bounding sphere) is not stored, and a tree read
//! back is checked against its mesh ([`check`](super::check)) before it is used: a stale, corrupt
//! or foreign file is refused, never trusted.

use std::hash::{Hash, Hasher};
use std::io::{self, Read, Write};

use super::check::{self, Defect};
use super::node_bounds::NodeBox;
use super::shared;
use super::tree::{Arrays, DopTree, Node};
use crate::collision::orientation::OrientationSet;
use crate::geometry::TriMesh;
use bytemuck::{Pod, Zeroable};

/// The first bytes of every tree file.
const MAGIC: u64 = u64::from_le_bytes(*b"vas-dop\0");

/// The version of the file's layout and of what its arrays mean: a file of another is stale.
const LAYOUT: u64 = 2;

#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
#[repr(C)]
struct Header {
    magic: u64,
    layout: u64,
    key: BuildKey,
    nodes: u64,
    /// Of the arrays' bytes, in the order they are stored.
    checksum: u64,
}

/// What a stored tree must have been built from to serve a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub(super) struct BuildKey {
    mesh_hash: u64,
    triangles: u64,
    /// Of the orientation set's axes.
    orientations_hash: u64,
    k: u64,
    leaf_size: u64,
}

impl BuildKey {
    /// What a tree over `mesh` with orientations `set` and `leaf_size` is built from.
    pub(super) fn of(mesh: &TriMesh, set: &OrientationSet, leaf_size: usize) -> Self {
        let mut hasher = rustc_hash::FxHasher::default();
        for axis in set.axes() {
            axis.map(f64::to_bits).as_slice().hash(&mut hasher);
        }
        BuildKey {
            mesh_hash: mesh.content_hash(),
            triangles: mesh.triangles().len() as u64,
            orientations_hash: hasher.finish(),
            k: set.k() as u64,
            leaf_size: leaf_size as u64,
        }
    }

    /// The name of the key's file in a cache folder.
    pub(super) fn file_name(&self) -> String {
        format!(
            "{:016x}-k{}-leaf{}-{:016x}-v{LAYOUT}.dop",
            self.mesh_hash, self.k, self.leaf_size, self.orientations_hash
        )
    }

    /// The bytes of a file of a tree of `nodes` nodes built from this key.
    fn file_bytes(&self, nodes: u64) -> u64 {
        let per_node = (size_of::<Node>() + size_of::<NodeBox>()) as u64 + 4 * self.k;
        size_of::<Header>() as u64 + nodes * per_node + 4 * self.triangles
    }
}

/// Why a stored tree was not used.
#[derive(Debug, thiserror::Error)]
pub(super) enum Refused {
    /// The file could not be read.
    #[error("cannot read it: {0}")]
    Io(#[from] io::Error),
    /// Not a tree file, or one of another layout.
    #[error("not a tree file of this version")]
    Format,
    /// A tree of another mesh or other build parameters.
    #[error("built from another mesh or with other parameters")]
    Stale,
    /// The file is shorter or longer than its header says.
    #[error("{actual} bytes where its header announces {expected}")]
    Size {
        /// What the header announces.
        expected: u64,
        /// What the file has.
        actual: u64,
    },
    /// The arrays are not those the checksum was taken of.
    #[error("its checksum does not match: the file is corrupt")]
    Checksum,
    /// The tree does not bound its mesh or is not laid out as a tree.
    #[error("it is not a valid tree of its mesh: {0}")]
    Defect(#[from] Defect),
}

/// The stored arrays as bytes, in the order they are stored.
fn payload<'a>(
    nodes: &'a [Node],
    offsets: &'a [f32],
    boxes: &'a [NodeBox],
    triangle_ids: &'a [u32],
) -> [&'a [u8]; 4] {
    [
        bytemuck::cast_slice(nodes),
        bytemuck::cast_slice(offsets),
        bytemuck::cast_slice(boxes),
        bytemuck::cast_slice(triangle_ids),
    ]
}

fn checksum(parts: [&[u8]; 4]) -> u64 {
    let mut hasher = rustc_hash::FxHasher::default();
    for part in parts {
        hasher.write(part);
    }
    hasher.finish()
}

/// Writes `tree`, built from `key`, to `out`.
pub(super) fn write(tree: &DopTree, key: &BuildKey, out: &mut impl Write) -> io::Result<()> {
    let parts = payload(&tree.nodes, &tree.offsets, &tree.boxes, &tree.triangle_ids);
    let header = Header {
        magic: MAGIC,
        layout: LAYOUT,
        key: *key,
        nodes: tree.nodes.len() as u64,
        checksum: checksum(parts),
    };
    out.write_all(bytemuck::bytes_of(&header))?;
    for part in parts {
        out.write_all(part)?;
    }
    Ok(())
}

/// Sets the checksum in the header of the tree file `bytes` to that of its arrays, so that
/// damage to them reaches the checks of the structure and the bounds (fuzzing, tests); false,
/// and nothing changed, if the arrays the header announces do not fit in `bytes`.
pub fn reseal(bytes: &mut [u8]) -> bool {
    let Some((header, arrays)) = bytes.split_at_mut_checked(size_of::<Header>()) else {
        return false;
    };
    let mut sealed: Header = bytemuck::pod_read_unaligned(header);
    let lengths = [
        Some(size_of::<Node>() as u64),
        sealed.key.k.checked_mul(4),
        Some(size_of::<NodeBox>() as u64),
    ]
    .map(|each| (each?.checked_mul(sealed.nodes)).and_then(|length| usize::try_from(length).ok()));
    let mut parts: [&[u8]; 4] = [&[]; 4];
    let mut rest: &[u8] = arrays;
    for (part, length) in parts.iter_mut().zip(lengths) {
        let Some((head, tail)) = length.and_then(|n| rest.split_at_checked(n)) else {
            return false;
        };
        (*part, rest) = (head, tail);
    }
    parts[3] = rest;
    sealed.checksum = checksum(parts);
    header.copy_from_slice(bytemuck::bytes_of(&sealed));
    true
}

/// Reads the tree of `length` bytes from `input`, if it was built from `key` for `mesh` with
/// `set` and bounds `mesh`'s triangles. Nothing is allocated before the header and the length
/// agree with `key`.
pub(super) fn read(
    input: &mut impl Read,
    length: u64,
    key: &BuildKey,
    mesh: &TriMesh,
    set: &OrientationSet,
) -> Result<DopTree, Refused> {
    let mut header = Header::zeroed();
    if length < size_of::<Header>() as u64 {
        return Err(Refused::Format);
    }
    input.read_exact(bytemuck::bytes_of_mut(&mut header))?;
    if header.magic != MAGIC || header.layout != LAYOUT {
        return Err(Refused::Format);
    }
    if header.key != *key {
        return Err(Refused::Stale);
    }
    // A tree has fewer nodes than twice its triangles.
    let nodes = header.nodes.min(2 * key.triangles);
    let expected = key.file_bytes(nodes);
    if header.nodes != nodes || length != expected {
        return Err(Refused::Size {
            expected,
            actual: length,
        });
    }
    let (nodes, k, triangles) = (nodes as usize, key.k as usize, key.triangles as usize);
    let mut stored_nodes = shared::zeroed::<Node>(nodes);
    let mut offsets = shared::zeroed::<f32>(nodes * k);
    let mut boxes = shared::zeroed::<NodeBox>(nodes);
    let mut triangle_ids = shared::zeroed::<u32>(triangles);
    input.read_exact(bytemuck::cast_slice_mut(shared::unshared(
        &mut stored_nodes,
    )))?;
    input.read_exact(bytemuck::cast_slice_mut(shared::unshared(&mut offsets)))?;
    input.read_exact(bytemuck::cast_slice_mut(shared::unshared(&mut boxes)))?;
    input.read_exact(bytemuck::cast_slice_mut(shared::unshared(
        &mut triangle_ids,
    )))?;
    if checksum(payload(&stored_nodes, &offsets, &boxes, &triangle_ids)) != header.checksum {
        return Err(Refused::Checksum);
    }
    // Ids in range before the triangles are looked up by them.
    check::permutation(&triangle_ids, triangles)?;
    let (parents, triangle_ranges) = check::structure(&stored_nodes, triangles)?;
    let triangles = shared::from_fn(triangles, |i| mesh.triangle(triangle_ids[i] as usize));
    let arrays = Arrays {
        set: set.clone(),
        nodes: stored_nodes,
        parents,
        triangle_ranges,
        offsets,
        boxes,
        triangle_ids,
    };
    let tree = DopTree::assemble(arrays, triangles);
    check::bounds(&tree)?;
    Ok(tree)
}
