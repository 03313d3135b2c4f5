//! The kinds of procedural shape and their names.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use thiserror::Error;

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
