//! The tree cache: a folder of built trees, one file per mesh content and build parameters, so
//! that a scene started again reads its large parts' trees instead of building them. A file that
//! cannot be read, or is stale, corrupt or not a valid tree of its mesh, is logged and replaced by
//! a fresh build, never trusted. Files are written whole under a temporary name and then renamed,
//! so that servers sharing the folder never read one half-written; the temporary name is random
//! and created anew, so that a link planted in the folder is never written through.

use std::fs::OpenOptions;
use std::io::{self, BufReader, BufWriter};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};

use super::persist::{self, BuildKey, Refused};
use super::tree::DopTree;
use crate::collision::orientation::OrientationSet;
use crate::geometry::TriMesh;

/// A folder of built trees.
#[derive(Debug)]
pub struct TreeCache {
    folder: PathBuf,
}

/// Where a tree came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Provenance {
    /// Read from the cache.
    Read,
    /// Built, and stored if the folder took it.
    Built,
}

impl TreeCache {
    /// The cache in `folder`, which is made if missing.
    pub fn open(folder: &Path) -> io::Result<TreeCache> {
        std::fs::create_dir_all(folder)?;
        if !std::fs::metadata(folder)?.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::NotADirectory,
                format!("{} is not a folder", folder.display()),
            ));
        }
        Ok(TreeCache {
            folder: folder.to_owned(),
        })
    }

    /// The cache's folder.
    pub fn folder(&self) -> &Path {
        &self.folder
    }

    /// The file that keeps the tree over `mesh` with orientations `set` and at most `leaf_size`
    /// triangles a leaf.
    pub fn file_of(&self, mesh: &TriMesh, set: &OrientationSet, leaf_size: usize) -> PathBuf {
        self.folder
            .join(BuildKey::of(mesh, set, leaf_size).file_name())
    }

    /// The tree over `mesh` with orientations `set` and at most `leaf_size` triangles a leaf:
    /// the cache's if it holds a valid one, otherwise built and stored.
    pub fn tree(
        &self,
        mesh: &TriMesh,
        set: &OrientationSet,
        leaf_size: usize,
    ) -> (DopTree, Provenance) {
        let key = BuildKey::of(mesh, set, leaf_size);
        let path = self.folder.join(key.file_name());
        match read(&path, &key, mesh, set) {
            Ok(Some(tree)) => return (tree, Provenance::Read),
            Ok(None) => {}
            Err(refused) => tracing::warn!(
                file = %path.display(),
                "cached tree refused, building it again: {refused}"
            ),
        }
        let tree = DopTree::with_options(mesh, set, leaf_size);
        if let Err(error) = self.store(&path, &key, &tree) {
            tracing::warn!(file = %path.display(), %error, "cannot store the tree in the cache");
        }
        (tree, Provenance::Built)
    }

    /// Writes `tree` to `path` through a temporary file in the same folder, of a random name
    /// and created anew (`O_EXCL`, `O_NOFOLLOW`): a file or link already there, planted or
    /// left over, is never written through (another name is tried), and the name cannot be
    /// guessed in advance. The file is removed if the write or the rename fails.
    fn store(&self, path: &Path, key: &BuildKey, tree: &DopTree) -> io::Result<()> {
        let temporary = tempfile::Builder::new()
            .prefix(&format!(".{}.", key.file_name()))
            .suffix(".tmp")
            .make_in(&self.folder, |name| {
                OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .custom_flags(libc::O_NOFOLLOW)
                    .open(name)
            })?;
        let mut out = BufWriter::new(temporary);
        persist::write(tree, key, &mut out)?;
        let temporary = out.into_inner().map_err(io::IntoInnerError::into_error)?;
        temporary.persist(path).map_err(|error| error.error)?;
        Ok(())
    }
}

/// The valid tree stored at `path`, `None` if there is none, or why the one there is refused.
/// Anything but a regular file is refused unopened (a FIFO would block the reader).
fn read(
    path: &Path,
    key: &BuildKey,
    mesh: &TriMesh,
    set: &OrientationSet,
) -> Result<Option<DopTree>, Refused> {
    let metadata = match std::fs::metadata(path) {
        Ok(metadata) => metadata,
        Err(error) if error.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(error) => return Err(error.into()),
    };
    if !metadata.is_file() {
        return Err(Refused::Io(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    let mut input = BufReader::new(std::fs::File::open(path)?);
    persist::read(&mut input, metadata.len(), key, mesh, set).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::MeshCollider;
    use crate::collision::dop_tree::DEFAULT_LEAF_SIZE;
    use crate::collision::oracle_tests::torus;

    /// Every array the traversal reads, compared exactly.
    fn assert_same(a: &DopTree, b: &DopTree) {
        let bits = |t: &DopTree| {
            (
                bytemuck::cast_slice::<_, u8>(&t.nodes).to_vec(),
                t.offsets.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                bytemuck::cast_slice::<_, u8>(&t.boxes).to_vec(),
                t.triangle_ids.to_vec(),
                t.parents.to_vec(),
                t.triangle_ranges.to_vec(),
                t.triangles.to_vec(),
                (t.max_abs_offset, t.bounding_centre, t.bounding_radius),
            )
        };
        assert!(bits(a) == bits(b), "the trees differ");
    }

    #[test]
    fn a_stored_tree_is_read_back_as_built() {
        let folder = tempfile::tempdir().unwrap();
        let cache = TreeCache::open(&folder.path().join("trees")).unwrap();
        let mesh = torus(0.3, 40, 20);
        let set = OrientationSet::default();
        let (built, provenance) = cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE);
        assert_eq!(provenance, Provenance::Built);
        assert_same(&built, &DopTree::build(&mesh));
        let (read, provenance) = cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE);
        assert_eq!(provenance, Provenance::Read);
        assert_same(&read, &built);
        assert_ne!(read.id, built.id, "another tree for the pair memory");
        // Other parameters, another file.
        let (_, provenance) = cache.tree(&mesh, &set, 1);
        assert_eq!(provenance, Provenance::Built);
        let (_, provenance) = cache.tree(&mesh, &OrientationSet::new(14).unwrap(), 1);
        assert_eq!(provenance, Provenance::Built);
        let names = std::fs::read_dir(cache.folder()).unwrap().count();
        assert_eq!(names, 3, "three trees, no temporary file left");
    }

    #[test]
    fn links_planted_at_temporary_names_are_never_written_through() {
        let folder = tempfile::tempdir().unwrap();
        let cache = TreeCache::open(&folder.path().join("trees")).unwrap();
        let target = folder.path().join("target.txt");
        std::fs::write(&target, "not a tree").unwrap();
        let mesh = torus(0.3, 24, 12);
        let set = OrientationSet::default();
        let name = BuildKey::of(&mesh, &set, DEFAULT_LEAF_SIZE).file_name();
        // Every name of the old scheme, `.{name}.{pid}.{n}.tmp`, for this process's first writes.
        for n in 0..1024 {
            let link = format!(".{name}.{}.{n}.tmp", std::process::id());
            std::os::unix::fs::symlink(&target, cache.folder().join(link)).unwrap();
        }
        let (_, provenance) = cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE);
        assert_eq!(provenance, Provenance::Built);
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "not a tree");
        let (_, provenance) = cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE);
        assert_eq!(provenance, Provenance::Read, "stored beside the links");
        let names = std::fs::read_dir(cache.folder()).unwrap().count();
        assert_eq!(
            names,
            1024 + 1,
            "the links and the tree, no temporary file left"
        );
    }

    #[test]
    fn bad_files_are_refused_and_replaced() {
        let folder = tempfile::tempdir().unwrap();
        let cache = TreeCache::open(folder.path()).unwrap();
        let mesh = torus(0.3, 24, 12);
        let set = OrientationSet::default();
        let key = BuildKey::of(&mesh, &set, 1);
        let path = folder.path().join(key.file_name());
        let (built, _) = cache.tree(&mesh, &set, 1);
        let good = std::fs::read(&path).unwrap();
        let refusal = |bytes: &[u8]| {
            std::fs::write(&path, bytes).unwrap();
            let refused = read(&path, &key, &mesh, &set).expect_err("refused");
            // The cache builds the tree again and stores a good file.
            let (tree, provenance) = cache.tree(&mesh, &set, 1);
            assert_eq!(provenance, Provenance::Built);
            assert_same(&tree, &built);
            assert_eq!(std::fs::read(&path).unwrap(), good);
            refused
        };
        let flipped = |at: usize| {
            let mut bytes = good.clone();
            bytes[at] ^= 0x10;
            bytes
        };
        assert!(matches!(
            refusal(&good[..good.len() - 1]),
            Refused::Size { .. }
        ));
        assert!(matches!(refusal(&good[..10]), Refused::Format));
        assert!(matches!(refusal(&flipped(0)), Refused::Format));
        assert!(matches!(refusal(&flipped(8 * 2)), Refused::Stale));
        assert!(matches!(
            refusal(&flipped(good.len() / 2)),
            Refused::Checksum
        ));
        assert!(matches!(
            refusal(&flipped(good.len() - 3)),
            Refused::Checksum
        ));
        // A file whose checksum was made to match damage: refused as no valid tree.
        let mut shrunk = built.clone();
        let mut offsets = shrunk.offsets.to_vec();
        offsets[0] -= 0.01;
        shrunk.offsets = offsets.into();
        let mut bytes = Vec::new();
        persist::write(&shrunk, &key, &mut bytes).unwrap();
        assert!(matches!(refusal(&bytes), Refused::Defect(_)));
        // Another mesh's tree under this mesh's name.
        let other = torus(0.3, 24, 13);
        let mut bytes = Vec::new();
        persist::write(&DopTree::build(&other), &key, &mut bytes).unwrap();
        assert!(matches!(
            refusal(&bytes),
            Refused::Size { .. } | Refused::Defect(_)
        ));
        // Not a regular file.
        std::fs::remove_file(&path).unwrap();
        std::fs::create_dir(&path).unwrap();
        assert!(matches!(
            read(&path, &key, &mesh, &set),
            Err(Refused::Io(_))
        ));
        let (tree, provenance) = cache.tree(&mesh, &set, 1);
        assert_eq!(provenance, Provenance::Built, "built, though not stored");
        assert_same(&tree, &built);
    }
}
