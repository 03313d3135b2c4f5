//! Procedural test objects, each with a selectable triangle count: the paper's sphere, torus and
//! open one-sheet hyperboloid, and the parts of the assembly scenes (box, cylinder, block with a
//! through hole, open sheet with a hole, pipe).
//!
//! Every shape is consistently wound with normals pointing out of the material (up, for the open
//! sheet; away from the axis, for the hyperboloid). Closed shapes are closed: every edge is shared
//! by exactly two triangles. Axes of symmetry are along z and shapes are centred at the origin.
//! Triangles are kept close to equilateral, so a requested count is met only approximately
//! (within a few percent for counts of some hundreds and up).

mod cuboid;
mod kind;
mod mesh_builder;
mod plates;
mod resolution;
mod revolved;
mod spec;

pub use kind::{ShapeKind, UnknownShapeKind};
pub use spec::{ShapeSpec, ShapeSpecError};

use nalgebra::Vector3;

use super::mesh::TriMesh;
use revolved::build_torus;

/// The largest triangle count a shape is built with: requests above it are clamped, and
/// configuration and command-line input above it is refused.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// Smallest and largest accepted dimension, in metres: a micrometre to a kilometre.
pub(super) const DIMENSION_RANGE: (f64, f64) = (1e-6, 1e6);

/// How much thinner than the enclosing dimension a wall may get (hole radius against the block,
/// inner against outer radius): 0.1 %. Thinner walls would produce needle triangles.
pub(super) const MIN_WALL_FRACTION: f64 = 1e-3;

/// Builds the unit-size shape of `kind` (centred at the origin, inside [-1, 1]^3) with about
/// `triangles` triangles; counts above [`MAX_TRIANGLES`] are clamped. For the torus the grid keeps
/// nu / nv = 2.5, so 50,000 triangles give benchmark B1's 250 x 100 torus (scaled by 1 / 1.35).
pub fn build(kind: ShapeKind, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::unit(kind, triangles.clamp(1, MAX_TRIANGLES)))
}

/// Builds a spec that is valid by construction, naming the spec if it is not.
fn build_valid(spec: ShapeSpec) -> TriMesh {
    spec.build()
        .unwrap_or_else(|e| panic!("invalid shape dimensions in {spec}: {e}"))
}

/// A UV sphere of `radius` with about `triangles` triangles (at least 6).
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`]; scene configs are validated before building.
pub fn sphere(radius: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::Sphere { radius, triangles })
}

/// A torus around z with `nu` segments around the axis and `nv` around the tube: nu x nv quads,
/// each split into two triangles. Benchmark B1 uses R = 1, r = 0.35, nu = 250, nv = 100.
///
/// # Panics
/// If `nu` or `nv` is below 3, the mesh would exceed [`MAX_TRIANGLES`], or the radii fail
/// [`ShapeSpec::validate`].
pub fn torus(major_radius: f64, minor_radius: f64, nu: usize, nv: usize) -> TriMesh {
    assert!(
        nu >= 3 && nv >= 3 && nu.saturating_mul(nv).saturating_mul(2) <= MAX_TRIANGLES,
        "a torus needs at least 3 segments each way and at most {MAX_TRIANGLES} triangles, \
         not {nu} x {nv}"
    );
    let spec = ShapeSpec::Torus {
        major_radius,
        minor_radius,
        triangles: 2 * nu * nv,
    };
    spec.validate()
        .unwrap_or_else(|e| panic!("invalid torus {spec}: {e}"));
    build_torus(major_radius, minor_radius, nu, nv)
}

/// An open one-sheet hyperboloid of revolution around z, x² + y² - (w/c)² z² = w², with waist
/// radius w at z = 0 and `end_radius` at z = ±height / 2; no caps.
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn hyperboloid(waist_radius: f64, end_radius: f64, height: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::Hyperboloid {
        waist_radius,
        end_radius,
        height,
        triangles,
    })
}

/// A box with edge lengths `size`, its faces subdivided into near-square cells. (Named `cuboid`
/// because `box` is a Rust keyword.)
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn cuboid(size: Vector3<f64>, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::Box {
        size: size.into(),
        triangles,
    })
}

/// A closed cylinder along z: the side and two caps made of concentric rings.
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn cylinder(radius: f64, height: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::Cylinder {
        radius,
        height,
        triangles,
    })
}

/// A block with a square `width` x `width` cross-section and a round through hole of
/// `hole_radius` along z. The hole is a regular polygon with a vertex at angle 0, so a peg that
/// is a regular polygon of the same segment count fits whenever its radius is smaller.
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn box_with_hole(width: f64, height: f64, hole_radius: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::BoxWithHole {
        width,
        height,
        hole_radius,
        triangles,
    })
}

/// An open square sheet of edge `width` in the plane z = 0 (a single surface without thickness)
/// with a round hole of `hole_radius` in the middle.
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn sheet_with_hole(width: f64, hole_radius: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::SheetWithHole {
        width,
        hole_radius,
        triangles,
    })
}

/// A hollow tube along z: inner and outer walls joined by annular ends.
///
/// # Panics
/// If the dimensions fail [`ShapeSpec::validate`].
pub fn pipe(inner_radius: f64, outer_radius: f64, length: f64, triangles: usize) -> TriMesh {
    build_valid(ShapeSpec::Pipe {
        inner_radius,
        outer_radius,
        length,
        triangles,
    })
}

#[cfg(test)]
mod tests;
