//! Counts that a file announces and does not hold are refused before memory is reserved for
//! them: the files of `malformed_counts/` (an 84-byte STL counting 49,999,999 triangles, a PLY
//! header counting 100 million vertices, an OBJ face naming vertex 4,000,000,000, glTF and GLB
//! accessors counting a billion vertices in a 36-byte buffer) and a tree-cache file whose header
//! counts 2^40 nodes. The test binary's allocator notes the largest block each thread asks for.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};

use vas_server::collision::dop_tree::{DEFAULT_LEAF_SIZE, Provenance, TreeCache};
use vas_server::collision::orientation::OrientationSet;
use vas_server::geometry::{GeometryError, load_mesh, shapes};

/// The system allocator, noting the largest block asked for on each thread.
struct NotingLargest;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    // Not during the thread's teardown, when the slot is gone.
    let _ = LARGEST.try_with(|largest| largest.set(largest.get().max(size)));
}

// SAFETY: every call is passed on to `System` unchanged; noting a size allocates nothing.
unsafe impl GlobalAlloc for NotingLargest {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's guarantees, passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: NotingLargest = NotingLargest;

/// What `work` returns, and the largest block it asked for on this thread.
fn largest_block<T>(work: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|largest| largest.set(0));
    let result = work();
    (result, LARGEST.with(Cell::get))
}

/// More than any of these files needs, far less than what their counts announce.
const SMALL_BLOCK: usize = 1 << 20;

fn malformed(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/loading/malformed_counts")
        .join(name)
}

#[test]
fn every_format_refuses_a_count_beyond_its_bytes_before_reserving_for_it() {
    for name in [
        "count.stl",
        "count.ply",
        "count.obj",
        "count.gltf",
        "count.glb",
    ] {
        let path = malformed(name);
        let (loaded, largest) = largest_block(|| load_mesh(&path));
        match loaded {
            Err(error @ GeometryError::Parse { .. }) => {
                assert!(error.to_string().contains(name), "{error}");
            }
            other => panic!("{name}: {other:?}"),
        }
        assert!(
            largest < SMALL_BLOCK,
            "{name}: a block of {largest} bytes asked for"
        );
    }
}

#[test]
fn a_tree_cache_file_counting_more_nodes_than_it_holds_is_rebuilt_without_reserving_for_them() {
    let folder = tempfile::tempdir().unwrap();
    let cache = TreeCache::open(folder.path()).unwrap();
    let mesh = shapes::sphere(0.05, 2_000);
    let set = OrientationSet::default();
    let (built, _) = cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE);
    let file = cache.file_of(&mesh, &set, DEFAULT_LEAF_SIZE);
    // The header's node count, after the magic, the layout and the five words of the key.
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[56..64].copy_from_slice(&(1u64 << 40).to_le_bytes());
    std::fs::write(&file, &bytes).unwrap();
    let ((tree, provenance), largest) =
        largest_block(|| cache.tree(&mesh, &set, DEFAULT_LEAF_SIZE));
    assert_eq!(provenance, Provenance::Built, "the file is refused");
    assert_eq!(tree.node_count(), built.node_count());
    assert!(
        largest < SMALL_BLOCK,
        "a block of {largest} bytes asked for"
    );
}
