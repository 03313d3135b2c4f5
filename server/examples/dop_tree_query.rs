//! How to ask the DOP-tree whether two meshes touch, and where.
//!
//! Builds two procedural tori and a DOP-tree over each, then poses the second torus in the
//! first one's frame twice: linked like two chain links without touching (their bounding boxes
//! overlap, their surfaces stay 0.2 apart), and pushed over so that the tubes cross. For each
//! pose it runs the two queries every collision structure answers through `MeshCollider`: the
//! boolean one, which stops at the first touching triangle pair, and the one that lists every
//! touching pair (what sliding contact needs). One line per result, one per pair.
//!
//! ```text
//! cargo run --release -p vas-server --example dop_tree_query
//! ```

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Isometry3, Vector3};
use vas_server::collision::{DopTree, MeshCollider, QueryStats};
use vas_server::geometry::shapes;

fn main() {
    // A ring of radius 0.5 with a tube of radius 0.15, 48 x 16 quads, around z at the origin.
    let mesh = shapes::torus(0.5, 0.15, 48, 16);
    println!("mesh torus triangles={}", mesh.triangles().len());
    // Built once per mesh; both tori share the mesh here, each still gets its own tree.
    let a = DopTree::build(&mesh);
    let b = DopTree::build(&mesh);

    // B's pose in A's frame (A sits at the origin, so that is B's pose in the world):
    // turned a quarter about x, so it stands in the xz-plane through A's hole.
    let linked = |x: f64| Isometry3::new(Vector3::new(x, 0.0, 0.0), Vector3::x() * FRAC_PI_2);
    // Centred on A's tube: every point of B's centre line is 0.5 from A's, more than 2 x 0.15.
    query(&a, &b, "apart", &linked(0.5));
    // 0.25 further along x: B's centre line comes within 0.25 of A's, so the tubes cross.
    query(&a, &b, "crossing", &linked(0.75));
}

fn query(a: &DopTree, b: &DopTree, name: &str, b_to_a: &Isometry3<f64>) {
    let mut stats = QueryStats::default();
    let touching = a.intersects(b, b_to_a, &mut stats);
    let mut pairs = Vec::new();
    a.intersecting_pairs(b, b_to_a, &mut pairs, &mut QueryStats::default());
    pairs.sort_unstable();
    println!(
        "pose name={name} intersects={touching} pairs={} bv_tests={} tri_tests={}",
        pairs.len(),
        stats.bv_tests,
        stats.tri_tests
    );
    for [triangle_a, triangle_b] in pairs {
        println!("pair a={triangle_a} b={triangle_b}");
    }
}
