//! Procedural test objects, each with a selectable triangle count: the paper's sphere, torus and
//! open one-sheet hyperboloid, and the parts of the assembly scenes (box, cylinder, block with a
//! through hole, open sheet with a hole, pipe).
//!
//! Every shape is consistently wound with normals pointing out of the material (up, for the open
//! sheet; away from the axis, for the hyperboloid). Closed shapes are closed: every edge is shared
//! by exactly two triangles. Axes of symmetry are along z and shapes are centred at the origin.
//! Triangles are kept close to equilateral, so a requested count is met only approximately
//! (within a few percent for counts of some hundreds and up).

use std::f64::consts::{FRAC_PI_4, PI, TAU};
use std::fmt;
use std::str::FromStr;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::mesh::{Point, TriMesh};
use super::weld::weld;

/// The largest triangle count a shape is built with: requests above it are clamped, and
/// configuration and command-line input above it is refused.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// Smallest and largest accepted dimension, in metres: a micrometre to a kilometre.
const DIMENSION_RANGE: (f64, f64) = (1e-6, 1e6);

/// How much thinner than the enclosing dimension a wall may get (hole radius against the block,
/// inner against outer radius): 0.1 %. Thinner walls would produce needle triangles.
const MIN_WALL_FRACTION: f64 = 1e-3;

/// The kinds of procedural shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// A UV sphere (closed).
    Sphere,
    /// A ring torus (closed).
    Torus,
    /// An open one-sheet hyperboloid without caps.
    Hyperboloid,
    /// A rectangular box with subdivided faces (closed).
    Box,
    /// A capped cylinder (closed).
    Cylinder,
    /// A square block with a round through hole along z: the peg-in-hole socket (closed).
    BoxWithHole,
    /// An open square sheet (one surface, no thickness) with a round hole.
    SheetWithHole,
    /// A hollow tube with inner and outer walls and annular ends (closed).
    Pipe,
}

/// A name that is not a [`ShapeKind`].
#[derive(Debug, Clone, Error, PartialEq, Eq)]
#[error("unknown shape {name:?}; expected one of: {}", ShapeKind::names().join(", "))]
pub struct UnknownShapeKind {
    /// The name given.
    pub name: String,
}

impl ShapeKind {
    /// Every kind.
    pub const ALL: [ShapeKind; 8] = [
        ShapeKind::Sphere,
        ShapeKind::Torus,
        ShapeKind::Hyperboloid,
        ShapeKind::Box,
        ShapeKind::Cylinder,
        ShapeKind::BoxWithHole,
        ShapeKind::SheetWithHole,
        ShapeKind::Pipe,
    ];

    /// The name used on the command line, in configs and in [`fmt::Display`] (kebab-case).
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Torus => "torus",
            ShapeKind::Hyperboloid => "hyperboloid",
            ShapeKind::Box => "box",
            ShapeKind::Cylinder => "cylinder",
            ShapeKind::BoxWithHole => "box-with-hole",
            ShapeKind::SheetWithHole => "sheet-with-hole",
            ShapeKind::Pipe => "pipe",
        }
    }

    /// Every kind's name, for error messages and command-line help.
    pub fn names() -> [&'static str; 8] {
        Self::ALL.map(Self::name)
    }
}

impl fmt::Display for ShapeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ShapeKind {
    type Err = UnknownShapeKind;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| UnknownShapeKind { name: s.to_owned() })
    }
}

/// A shape with its dimensions (metres) and approximate triangle count, as scene configs give it
/// (`shape = { kind = "cylinder", radius = 0.01, height = 0.08, triangles = 800 }`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// See [`sphere`].
    Sphere {
        /// Radius.
        radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// A torus around z; see [`torus`].
    Torus {
        /// Distance from the axis to the centre of the tube.
        major_radius: f64,
        /// Radius of the tube.
        minor_radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`hyperboloid`].
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
    /// See [`cuboid`].
    Box {
        /// Edge lengths along x, y and z.
        size: [f64; 3],
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`cylinder`].
    Cylinder {
        /// Radius.
        radius: f64,
        /// Length along z.
        height: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`box_with_hole`].
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
    /// See [`sheet_with_hole`].
    SheetWithHole {
        /// Edge length of the square sheet.
        width: f64,
        /// Radius of the hole.
        hole_radius: f64,
        /// Approximate triangle count.
        triangles: usize,
    },
    /// See [`pipe`].
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
    /// The unit-size shape of `kind` that [`build`] makes: centred at the origin, fitting in
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
fn dimension(field: &'static str, value: f64) -> Result<(), ShapeSpecError> {
    let (lo, hi) = DIMENSION_RANGE;
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(ShapeSpecError {
            field,
            reason: format!("must be a length between {lo} and {hi} metres, not {value}"),
        })
    }
}

/// Checks that `inner` is smaller than `outer` by at least [`MIN_WALL_FRACTION`].
fn thinner(
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

/// The resolution whose triangle count is closest to `target`; on a tie, the earlier candidate.
/// Candidates come as (resolution, triangle count); the search stops at the first candidate past
/// twice the target (counts grow with the resolution).
fn closest_resolution<R: Copy>(target: usize, candidates: impl Iterator<Item = (R, usize)>) -> R {
    let mut best: Option<(usize, R)> = None;
    for (resolution, count) in candidates {
        let error = count.abs_diff(target);
        if best.is_none_or(|(e, _)| error < e) {
            best = Some((error, resolution));
        }
        if count > target.saturating_mul(2) {
            break;
        }
    }
    best.expect("every shape offers at least one resolution").1
}

/// Number of equal steps of about `spacing` along `length`: at least 1, at most `cap` (which
/// bounds the mesh size whatever the proportions).
fn steps(length: f64, spacing: f64, cap: usize) -> usize {
    ((length / spacing).round() as usize).clamp(1, cap.max(1))
}

/// (segments around, stacks from pole to pole) of a UV sphere: 2 * segments * (stacks - 1)
/// triangles. Segments stay between 1.5 and 2.5 times the stacks (2 gives square cells at the
/// equator), which lets most counts be met exactly, such as the paper's 132 and 2,652.
fn sphere_resolution(target: usize) -> (usize, usize) {
    let count = |n: usize, s: usize| 2 * n * (s - 1);
    closest_resolution(
        target,
        (2usize..).flat_map(|s| {
            let (lo, hi) = ((3 * s).div_ceil(2).max(3), (5 * s) / 2);
            let ideal = target / (2 * (s - 1));
            [ideal, ideal + 1]
                .into_iter()
                .map(move |n| n.clamp(lo, hi.max(lo)))
                .map(move |n| ((n, s), count(n, s)))
        }),
    )
}

/// (nu, nv) of a torus with nu / nv = 2.5: 2 * nu * nv triangles.
fn torus_resolution(target: usize) -> (usize, usize) {
    closest_resolution(
        target,
        (3usize..).map(|nu| {
            let nv = ((nu as f64 / 2.5).round() as usize).max(3);
            ((nu, nv), 2 * nu * nv)
        }),
    )
}

fn build_sphere(radius: f64, target: usize) -> TriMesh {
    let (segments, stacks) = sphere_resolution(target);
    let profile: Vec<[f64; 2]> = (0..=stacks)
        .map(|k| {
            let latitude = -PI / 2.0 + PI * k as f64 / stacks as f64;
            // The poles lie exactly on the axis, so that they become single vertices.
            let r = if k == 0 || k == stacks {
                0.0
            } else {
                radius * latitude.cos()
            };
            [r, radius * latitude.sin()]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

fn build_torus(major_radius: f64, minor_radius: f64, nu: usize, nv: usize) -> TriMesh {
    let profile: Vec<[f64; 2]> = (0..nv)
        .map(|k| {
            let v = TAU * k as f64 / nv as f64;
            [
                major_radius + minor_radius * v.cos(),
                minor_radius * v.sin(),
            ]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, true, nu);
    builder.finish()
}

fn build_hyperboloid(waist_radius: f64, end_radius: f64, height: f64, target: usize) -> TriMesh {
    let half = height / 2.0;
    // r(z) = w * sqrt(1 + (z / c)^2), with c chosen so that r(±h/2) is the end radius.
    let c = half / ((end_radius / waist_radius).powi(2) - 1.0).sqrt();
    let radius_at = |z: f64| waist_radius * (1.0 + (z / c).powi(2)).sqrt();
    // The profile's length, estimated by the polyline through the ends and the waist.
    let profile_length = 2.0 * half.hypot(end_radius - waist_radius);
    let mean_circumference = PI * (waist_radius + end_radius);
    let bands =
        |segments: usize| steps(profile_length, mean_circumference / segments as f64, target);
    let segments = closest_resolution(target, (3usize..).map(|n| (n, 2 * n * bands(n))));
    let rings = bands(segments);
    let profile: Vec<[f64; 2]> = (0..=rings)
        .map(|k| {
            let z = -half + height * k as f64 / rings as f64;
            [radius_at(z), z]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

fn build_cuboid(size: Vector3<f64>, target: usize) -> TriMesh {
    // Cells along the longest edge; the other edges get about as many per length, rounded down
    // or up (both are candidates, which lets the count come close to any target).
    let longest = size.imax();
    let cells = move |n: usize| {
        let spacing = size[longest] / n as f64;
        let per_axis = size.map(|s| {
            let exact = (s / spacing).clamp(1.0, target.max(1) as f64);
            [exact.floor() as usize, exact.ceil() as usize]
        });
        (0..4).map(move |choice| {
            let mut c = Vector3::new(per_axis.x[0], per_axis.y[0], per_axis.z[0]);
            let others = [(longest + 1) % 3, (longest + 2) % 3];
            c[others[0]] = per_axis[others[0]][choice & 1];
            c[others[1]] = per_axis[others[1]][choice >> 1];
            c[longest] = n;
            c
        })
    };
    let count = |c: Vector3<usize>| 4 * (c.x * c.y + c.y * c.z + c.z * c.x);
    let c = closest_resolution(
        target,
        (1usize..).flat_map(|n| cells(n).map(move |c| (c, count(c)))),
    );
    let h = size / 2.0;
    let (ex, ey, ez) = (
        Vector3::x() * size.x,
        Vector3::y() * size.y,
        Vector3::z() * size.z,
    );
    let corner = Point::from(-h);
    // Each face as (origin, u, v, cells along u, cells along v), with u x v pointing outwards.
    let faces = [
        (corner + ez, ex, ey, c.x, c.y),
        (corner, ey, ex, c.y, c.x),
        (corner + ex, ey, ez, c.y, c.z),
        (corner, ez, ey, c.z, c.y),
        (corner + ey, ez, ex, c.z, c.x),
        (corner, ex, ez, c.x, c.z),
    ];
    let mut builder = MeshBuilder::default();
    for (origin, u, v, nu, nv) in faces {
        let rows: Vec<Vec<u32>> = (0..=nv)
            .map(|j| {
                builder.row(
                    (0..=nu)
                        .map(|i| origin + u * (i as f64 / nu as f64) + v * (j as f64 / nv as f64)),
                )
            })
            .collect();
        for pair in rows.windows(2) {
            builder.strip(&pair[0], &pair[1], false);
        }
    }
    // The faces were built apart; welding joins them along the box's edges.
    builder.finish_welded(size.max() * 1e-9)
}

fn build_cylinder(radius: f64, height: f64, target: usize) -> TriMesh {
    let resolution = |segments: usize| {
        let spacing = TAU * radius / segments as f64;
        (
            steps(radius, spacing, target),
            steps(height, spacing, target),
        )
    };
    // Each cap: a fan and (rings - 1) bands; the side: `bands` bands.
    let count = |n: usize, (rings, bands): (usize, usize)| n * (2 * (2 * rings - 1) + 2 * bands);
    let segments = closest_resolution(target, (3usize..).map(|n| (n, count(n, resolution(n)))));
    let (rings, bands) = resolution(segments);
    let half = height / 2.0;
    let mut profile = Vec::with_capacity(2 * rings + bands + 1);
    profile.extend((0..=rings).map(|k| [radius * k as f64 / rings as f64, -half]));
    profile.extend((1..=bands).map(|k| [radius, -half + height * k as f64 / bands as f64]));
    profile.extend((1..=rings).map(|k| [radius * (rings - k) as f64 / rings as f64, half]));
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

fn build_pipe(inner_radius: f64, outer_radius: f64, length: f64, target: usize) -> TriMesh {
    let resolution = |segments: usize| {
        let spacing = TAU * outer_radius / segments as f64;
        (
            steps(length, spacing, target),
            steps(outer_radius - inner_radius, spacing, target),
        )
    };
    let segments = closest_resolution(
        target,
        (3usize..).map(|n| {
            let (bands, rings) = resolution(n);
            (n, 4 * n * (bands + rings))
        }),
    );
    let (bands, rings) = resolution(segments);
    let half = length / 2.0;
    let wall = outer_radius - inner_radius;
    // A closed loop in the (r, z) half-plane, counter-clockwise so that normals point out of the
    // material: up the outer wall, in across the top, down the bore, out across the bottom.
    let mut profile = Vec::with_capacity(2 * (bands + rings));
    profile.extend((0..bands).map(|k| [outer_radius, -half + length * k as f64 / bands as f64]));
    profile.extend((0..rings).map(|k| [outer_radius - wall * k as f64 / rings as f64, half]));
    profile.extend((0..bands).map(|k| [inner_radius, half - length * k as f64 / bands as f64]));
    profile.extend((0..rings).map(|k| [inner_radius + wall * k as f64 / rings as f64, -half]));
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, true, segments);
    builder.finish()
}

/// Resolution of a square plate with a round hole: `sides` segments per edge of the square
/// (4 * sides around the hole) and `rings` rings between the hole and the square.
#[derive(Debug, Clone, Copy)]
struct PlateResolution {
    sides: usize,
    rings: usize,
}

impl PlateResolution {
    fn new(width: f64, hole_radius: f64, sides: usize, cap: usize) -> Self {
        let spacing = width / sides as f64;
        // Mean distance from the hole to the square, between the edge midpoints and the corners.
        let gap = width / 2.0 * (1.0 + std::f64::consts::SQRT_2) / 2.0 - hole_radius;
        PlateResolution {
            sides,
            rings: steps(gap, spacing, cap),
        }
    }

    fn segments(self) -> usize {
        4 * self.sides
    }

    /// The square's boundary, counter-clockwise from the corner (w/2, -w/2), `sides` points per
    /// edge, and the hole's boundary: a regular polygon at matching angles (vertex k at
    /// -45° + 360° k / segments, so one vertex lies at 0°).
    fn outlines(self, width: f64, hole_radius: f64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        let h = width / 2.0;
        let corners = [[h, -h], [h, h], [-h, h], [-h, -h], [h, -h]];
        let square = (0..self.segments())
            .map(|k| {
                let (edge, t) = (k / self.sides, (k % self.sides) as f64 / self.sides as f64);
                let [a, b] = [corners[edge], corners[edge + 1]];
                [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
            })
            .collect();
        let hole = (0..self.segments())
            .map(|k| {
                let angle = -FRAC_PI_4 + TAU * k as f64 / self.segments() as f64;
                [hole_radius * angle.cos(), hole_radius * angle.sin()]
            })
            .collect();
        (square, hole)
    }
}

/// Adds the flat ring between `square` and `hole` at height `z` to `builder`, reusing the given
/// boundary rows (so that the plate joins the walls built on them). Normals point up (+z) when
/// `up`, else down.
fn plate(
    builder: &mut MeshBuilder,
    (square, hole): (&[[f64; 2]], &[[f64; 2]]),
    (square_row, hole_row): (&[u32], &[u32]),
    z: f64,
    rings: usize,
    up: bool,
) {
    let mut rows = vec![square_row.to_vec()];
    for k in 1..rings {
        let t = k as f64 / rings as f64;
        rows.push(
            builder.row(
                square.iter().zip(hole).map(|(s, c)| {
                    Point::new(s[0] + (c[0] - s[0]) * t, s[1] + (c[1] - s[1]) * t, z)
                }),
            ),
        );
    }
    rows.push(hole_row.to_vec());
    for pair in rows.windows(2) {
        // Rows run outside-in: a counter-clockwise row followed by the next one inwards faces up.
        if up {
            builder.strip(&pair[0], &pair[1], true);
        } else {
            builder.strip(&pair[1], &pair[0], true);
        }
    }
}

fn build_sheet_with_hole(width: f64, hole_radius: f64, target: usize) -> TriMesh {
    let resolution = closest_resolution(
        target,
        (1usize..).map(|sides| {
            let r = PlateResolution::new(width, hole_radius, sides, target);
            (r, 2 * r.segments() * r.rings)
        }),
    );
    let (square, hole) = resolution.outlines(width, hole_radius);
    let mut builder = MeshBuilder::default();
    let at_zero = |o: &[f64; 2]| Point::new(o[0], o[1], 0.0);
    let square_row = builder.row(square.iter().map(at_zero));
    let hole_row = builder.row(hole.iter().map(at_zero));
    plate(
        &mut builder,
        (&square, &hole),
        (&square_row, &hole_row),
        0.0,
        resolution.rings,
        true,
    );
    builder.finish()
}

fn build_box_with_hole(width: f64, height: f64, hole_radius: f64, target: usize) -> TriMesh {
    // Rows of the side walls (spacing of the square's edge) and of the bore (spacing of the hole).
    let wall_bands = |r: PlateResolution| {
        (
            steps(height, width / r.sides as f64, target),
            steps(height, TAU * hole_radius / r.segments() as f64, target),
        )
    };
    let resolution = closest_resolution(
        target,
        (1usize..).map(|sides| {
            let r = PlateResolution::new(width, hole_radius, sides, target);
            let (outer, bore) = wall_bands(r);
            (r, 2 * r.segments() * (2 * r.rings + outer + bore))
        }),
    );
    let (outer_bands, bore_bands) = wall_bands(resolution);
    let (square, hole) = resolution.outlines(width, hole_radius);
    let half = height / 2.0;
    let mut builder = MeshBuilder::default();
    let level = |builder: &mut MeshBuilder, outline: &[[f64; 2]], t: f64| {
        builder.row(
            outline
                .iter()
                .map(|o| Point::new(o[0], o[1], -half + height * t)),
        )
    };
    // Outer walls bottom-up (counter-clockwise outline going up faces outwards).
    let outer: Vec<Vec<u32>> = (0..=outer_bands)
        .map(|k| level(&mut builder, &square, k as f64 / outer_bands as f64))
        .collect();
    for pair in outer.windows(2) {
        builder.strip(&pair[0], &pair[1], true);
    }
    // The bore top-down, which faces into the hole.
    let bore: Vec<Vec<u32>> = (0..=bore_bands)
        .map(|k| level(&mut builder, &hole, 1.0 - k as f64 / bore_bands as f64))
        .collect();
    for pair in bore.windows(2) {
        builder.strip(&pair[0], &pair[1], true);
    }
    let outlines = (square.as_slice(), hole.as_slice());
    let top = (outer[outer_bands].as_slice(), bore[0].as_slice());
    plate(&mut builder, outlines, top, half, resolution.rings, true);
    let bottom = (outer[0].as_slice(), bore[bore_bands].as_slice());
    plate(
        &mut builder,
        outlines,
        bottom,
        -half,
        resolution.rings,
        false,
    );
    builder.finish()
}

/// Accumulates vertices and triangles; shapes are made of rows of vertices joined by strips.
#[derive(Default)]
struct MeshBuilder {
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
}

impl MeshBuilder {
    /// Adds the points as new vertices and returns their indices.
    fn row(&mut self, points: impl IntoIterator<Item = Point>) -> Vec<u32> {
        points
            .into_iter()
            .map(|p| {
                self.vertices.push(p);
                (self.vertices.len() - 1) as u32
            })
            .collect()
    }

    /// Joins two rows of equal length with quads (a[j], a[j+1], b[j+1], b[j]), each split into
    /// two triangles; `closed` also joins the last column to the first. The normal is
    /// (a[j+1] - a[j]) x (b[j] - a[j]). Triangles with a repeated vertex (where a row collapses to
    /// a pole) are skipped.
    fn strip(&mut self, a: &[u32], b: &[u32], closed: bool) {
        let n = a.len();
        let columns = if closed { n } else { n - 1 };
        for j in 0..columns {
            let k = (j + 1) % n;
            for t in [[a[j], a[k], b[k]], [a[j], b[k], b[j]]] {
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    self.triangles.push(t);
                }
            }
        }
    }

    /// Revolves a profile of (r, z) points around z with `segments` segments (vertex j at angle
    /// 360° j / segments). Points with r = 0 become single pole vertices; `closed` joins the last
    /// profile point back to the first. Normals point to the right of the profile's direction
    /// in the (r, z) plane, i.e. outwards for a counter-clockwise profile.
    fn revolve(&mut self, profile: &[[f64; 2]], closed: bool, segments: usize) {
        let rows: Vec<Vec<u32>> = profile
            .iter()
            .map(|&[r, z]| {
                if r == 0.0 {
                    let pole = self.row([Point::new(0.0, 0.0, z)])[0];
                    vec![pole; segments]
                } else {
                    self.row((0..segments).map(|j| {
                        let angle = TAU * j as f64 / segments as f64;
                        Point::new(r * angle.cos(), r * angle.sin(), z)
                    }))
                }
            })
            .collect();
        for pair in rows.windows(2) {
            self.strip(&pair[0], &pair[1], true);
        }
        if closed {
            self.strip(&rows[rows.len() - 1], &rows[0], true);
        }
    }

    fn finish(self) -> TriMesh {
        TriMesh::new(self.vertices, self.triangles)
            .expect("procedural shapes with validated dimensions are valid meshes")
            .0
    }

    /// Finishes and merges vertices closer than `tolerance`, for shapes built from separate
    /// pieces.
    fn finish_welded(self, tolerance: f64) -> TriMesh {
        weld(&self.finish(), tolerance)
    }
}

#[cfg(test)]
mod tests;
