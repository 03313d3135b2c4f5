//! A shape with its dimensions, as a config or the command line gives it: validated, then built.

use std::fmt;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::cuboid::build_cuboid;
use super::plates::{build_box_with_hole, build_sheet_with_hole};
use super::resolution::torus_resolution;
use super::revolved::{build_cylinder, build_hyperboloid, build_pipe, build_sphere, build_torus};
use super::{DIMENSION_RANGE, MAX_TRIANGLES, MIN_WALL_FRACTION, ShapeKind};
use crate::geometry::mesh::TriMesh;

/// A shape with its dimensions (metres) and approximate triangle count, as scene configs give it
/// (`shape = { kind = "cylinder", radius = 0.01, height = 0.08, triangles = 800 }`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// See [`sphere`](super::sphere).
    Sphere {
        /// Radius.
        radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// A torus around z; see [`torus`](super::torus).
    Torus {
        /// Distance from the axis to the centre of the tube.
        major_radius: f64,
        /// Radius of the tube.
        minor_radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`hyperboloid`](super::hyperboloid).
    Hyperboloid {
        /// Radius at the waist (z = 0).
        waist_radius: f64,
        /// Radius at both ends.
        end_radius: f64,
        /// Length along z.
        height: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`cuboid`](super::cuboid).
    Box {
        /// Edge lengths along x, y and z.
        size: [f64; 3],
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`cylinder`](super::cylinder).
    Cylinder {
        /// Radius.
        radius: f64,
        /// Length along z.
        height: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`box_with_hole`](super::box_with_hole).
    BoxWithHole {
        /// Edge length of the square cross-section (x and y).
        width: f64,
        /// Length along z, which is the hole's axis.
        height: f64,
        /// Radius of the hole.
        hole_radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`sheet_with_hole`](super::sheet_with_hole).
    SheetWithHole {
        /// Edge length of the square sheet.
        width: f64,
        /// Radius of the hole.
        hole_radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`pipe`](super::pipe).
    Pipe {
        /// Radius of the bore.
        inner_radius: f64,
        /// Outer radius.
        outer_radius: f64,
        /// Length along z.
        length: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
}

/// Why a [`ShapeSpec`] cannot be built: the field and the reason.
#[derive(Debug, Clone, Error, PartialEq)]
#[error("{field}: {reason}")]
pub struct ShapeSpecError {
    /// The offending field, as named in configs (`hole_radius`).
    pub field: &'static str,
    /// What is wrong with it.
    pub reason: String,
}

impl ShapeSpec {
    /// The unit-size shape of `kind` that [`build`](super::build) makes: centred at the origin, fitting in
    /// [-1, 1]^3. The torus has the proportions of benchmark B1 (R = 1, r = 0.35) scaled by
    /// 1 / 1.35 to fit.
    pub fn unit(kind: ShapeKind, triangles: usize) -> ShapeSpec {
        match kind {
            ShapeKind::Sphere => ShapeSpec::Sphere {
                radius: 1.0,
                triangles,
            },
            ShapeKind::Torus => ShapeSpec::Torus {
                major_radius: 1.0 / 1.35,
                minor_radius: 0.35 / 1.35,
                triangles,
            },
            ShapeKind::Hyperboloid => ShapeSpec::Hyperboloid {
                waist_radius: 0.5,
                end_radius: 1.0,
                height: 2.0,
                triangles,
            },
            ShapeKind::Box => ShapeSpec::Box {
                size: [2.0, 1.5, 1.0],
                triangles,
            },
            ShapeKind::Cylinder => ShapeSpec::Cylinder {
                radius: 0.5,
                height: 2.0,
                triangles,
            },
            ShapeKind::BoxWithHole => ShapeSpec::BoxWithHole {
                width: 2.0,
                height: 1.0,
                hole_radius: 0.5,
                triangles,
            },
            ShapeKind::SheetWithHole => ShapeSpec::SheetWithHole {
                width: 2.0,
                hole_radius: 0.5,
                triangles,
            },
            ShapeKind::Pipe => ShapeSpec::Pipe {
                inner_radius: 0.7,
                outer_radius: 1.0,
                length: 2.0,
                triangles,
            },
        }
    }

    /// The kind of shape.
    pub fn kind(&self) -> ShapeKind {
        match self {
            ShapeSpec::Sphere { .. } => ShapeKind::Sphere,
            ShapeSpec::Torus { .. } => ShapeKind::Torus,
            ShapeSpec::Hyperboloid { .. } => ShapeKind::Hyperboloid,
            ShapeSpec::Box { .. } => ShapeKind::Box,
            ShapeSpec::Cylinder { .. } => ShapeKind::Cylinder,
            ShapeSpec::BoxWithHole { .. } => ShapeKind::BoxWithHole,
            ShapeSpec::SheetWithHole { .. } => ShapeKind::SheetWithHole,
            ShapeSpec::Pipe { .. } => ShapeKind::Pipe,
        }
    }

    /// The requested triangle count.
    pub fn triangles(&self) -> usize {
        match *self {
            ShapeSpec::Sphere { triangles, .. }
            | ShapeSpec::Torus { triangles, .. }
            | ShapeSpec::Hyperboloid { triangles, .. }
            | ShapeSpec::Box { triangles, .. }
            | ShapeSpec::Cylinder { triangles, .. }
            | ShapeSpec::BoxWithHole { triangles, .. }
            | ShapeSpec::SheetWithHole { triangles, .. }
            | ShapeSpec::Pipe { triangles, .. } => triangles,
        }
    }

    /// Checks that every dimension is finite and within a micrometre to a kilometre, that holes
    /// fit inside their blocks with a wall left, and that the triangle count is in range.
    pub fn validate(&self) -> Result<(), ShapeSpecError> {
        let triangles = self.triangles();
        if !(1..=MAX_TRIANGLES).contains(&triangles) {
            return Err(ShapeSpecError {
                field: "triangles",
                reason: format!("must be between 1 and {MAX_TRIANGLES}, not {triangles}"),
            });
        }
        match *self {
            ShapeSpec::Sphere { radius, .. } => dimension("radius", radius),
            ShapeSpec::Torus {
                major_radius,
                minor_radius,
                ..
            } => {
                dimension("major_radius", major_radius)?;
                dimension("minor_radius", minor_radius)?;
                thinner("minor_radius", minor_radius, "major_radius", major_radius)
            }
            ShapeSpec::Hyperboloid {
                waist_radius,
                end_radius,
                height,
                ..
            } => {
                dimension("waist_radius", waist_radius)?;
                dimension("end_radius", end_radius)?;
                dimension("height", height)?;
                thinner("waist_radius", waist_radius, "end_radius", end_radius)
            }
            ShapeSpec::Box { size, .. } => size.iter().try_for_each(|&s| dimension("size", s)),
            ShapeSpec::Cylinder { radius, height, .. } => {
                dimension("radius", radius)?;
                dimension("height", height)
            }
            ShapeSpec::BoxWithHole {
                width,
                height,
                hole_radius,
                ..
            } => {
                dimension("width", width)?;
                dimension("height", height)?;
                dimension("hole_radius", hole_radius)?;
                thinner("hole_radius", hole_radius, "half the width", width / 2.0)
            }
            ShapeSpec::SheetWithHole {
                width, hole_radius, ..
            } => {
                dimension("width", width)?;
                dimension("hole_radius", hole_radius)?;
                thinner("hole_radius", hole_radius, "half the width", width / 2.0)
            }
            ShapeSpec::Pipe {
                inner_radius,
                outer_radius,
                length,
                ..
            } => {
                dimension("inner_radius", inner_radius)?;
                dimension("outer_radius", outer_radius)?;
                dimension("length", length)?;
                thinner("inner_radius", inner_radius, "outer_radius", outer_radius)
            }
        }
    }

    /// Validates and builds the mesh.
    pub fn build(&self) -> Result<TriMesh, ShapeSpecError> {
        self.validate()?;
        let target = self.triangles();
        Ok(match *self {
            ShapeSpec::Sphere { radius, .. } => build_sphere(radius, target),
            ShapeSpec::Torus {
                major_radius,
                minor_radius,
                ..
            } => {
                let (nu, nv) = torus_resolution(target);
                build_torus(major_radius, minor_radius, nu, nv)
            }
            ShapeSpec::Hyperboloid {
                waist_radius,
                end_radius,
                height,
                ..
            } => build_hyperboloid(waist_radius, end_radius, height, target),
            ShapeSpec::Box { size, .. } => build_cuboid(Vector3::from(size), target),
            ShapeSpec::Cylinder { radius, height, .. } => build_cylinder(radius, height, target),
            ShapeSpec::BoxWithHole {
                width,
                height,
                hole_radius,
                ..
            } => build_box_with_hole(width, height, hole_radius, target),
            ShapeSpec::SheetWithHole {
                width, hole_radius, ..
            } => build_sheet_with_hole(width, hole_radius, target),
            ShapeSpec::Pipe {
                inner_radius,
                outer_radius,
                length,
                ..
            } => build_pipe(inner_radius, outer_radius, length, target),
        })
    }
}

/// A compact description, `shape:KIND:field=value,...`, used as a part's mesh source.
impl fmt::Display for ShapeSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "shape:{}:", self.kind())?;
        match self {
            ShapeSpec::Sphere { radius, .. } => write!(f, "radius={radius}")?,
            ShapeSpec::Torus {
                major_radius,
                minor_radius,
                ..
            } => write!(f, "major_radius={major_radius},minor_radius={minor_radius}")?,
            ShapeSpec::Hyperboloid {
                waist_radius,
                end_radius,
                height,
                ..
            } => write!(
                f,
                "waist_radius={waist_radius},end_radius={end_radius},height={height}"
            )?,
            ShapeSpec::Box {
                size: [x, y, z], ..
            } => write!(f, "size={x}x{y}x{z}")?,
            ShapeSpec::Cylinder { radius, height, .. } => {
                write!(f, "radius={radius},height={height}")?
            }
            ShapeSpec::BoxWithHole {
                width,
                height,
                hole_radius,
                ..
            } => write!(f, "width={width},height={height},hole_radius={hole_radius}")?,
            ShapeSpec::SheetWithHole {
                width, hole_radius, ..
            } => write!(f, "width={width},hole_radius={hole_radius}")?,
            ShapeSpec::Pipe {
                inner_radius,
                outer_radius,
                length,
                ..
            } => write!(
                f,
                "inner_radius={inner_radius},outer_radius={outer_radius},length={length}"
            )?,
        }
        write!(f, ",triangles={}", self.triangles())
    }
}

/// Checks one dimension: finite and within [`DIMENSION_RANGE`].
pub(super) fn dimension(field: &'static str, value: f64) -> Result<(), ShapeSpecError> {
    let (lo, hi) = DIMENSION_RANGE;
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(ShapeSpecError {
            field,
            reason: format!(
                "must be a length between {lo} and {hi} metres, not {}",
                vas_protocol::Readable(value)
            ),
        })
    }
}

/// Checks that `inner` is smaller than `outer` by at least [`MIN_WALL_FRACTION`].
pub(super) fn thinner(
    field: &'static str,
    inner: f64,
    outer_name: &str,
    outer: f64,
) -> Result<(), ShapeSpecError> {
    if inner <= outer * (1.0 - MIN_WALL_FRACTION) {
        Ok(())
    } else {
        Err(ShapeSpecError {
            field,
            reason: format!(
                "must be smaller than {outer_name} ({outer}) by at least {}%, but is {inner}",
                MIN_WALL_FRACTION * 100.0
            ),
        })
    }
}
