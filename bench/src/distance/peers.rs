//! The peers of B11, coal's and FCL's mesh-mesh distance, each in its own process: the harness
//! (`bench/coal/distance.cpp`, `bench/fcl/distance.cpp`) compiled when its library was found at
//! build time reads the meshes and poses written here and prints each pose's answer and time.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use nalgebra::{Isometry3, Point3};
use serde::Serialize;
use vas_server::geometry::TriMesh;

use super::compare::Answer;

/// A peer library's distance query.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Peer {
    /// coal 3.0.3, OBBRSS trees.
    Coal,
    /// FCL 0.7, OBBRSS trees.
    Fcl,
}

impl Peer {
    /// Both peers, the reference of the comparison first.
    pub const ALL: [Peer; 2] = [Peer::Coal, Peer::Fcl];

    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Peer::Coal => "coal",
            Peer::Fcl => "fcl",
        }
    }

    /// Its harness, if it was built with this program.
    pub fn harness(self) -> Option<&'static str> {
        match self {
            Peer::Coal => option_env!("VAS_COAL_DISTANCE"),
            Peer::Fcl => option_env!("VAS_FCL_DISTANCE"),
        }
    }

    /// How to get the peer when its harness is missing.
    pub fn missing(self) -> &'static str {
        match self {
            Peer::Coal => {
                "coal: not built (pip install coal==3.0.3 in the python3 on the path, or set \
                 COAL_PREFIX to its cmeel.prefix, then rebuild vas-bench)"
            }
            Peer::Fcl => "fcl: not built (Debian: libfcl-dev, then rebuild vas-bench)",
        }
    }
}

/// Writes meshes `a` and `b` and B's `poses` in A's frame into `folder` as the harnesses read
/// them (see `bench/fcl/distance_harness.h`); returns the file.
pub fn write_input(
    folder: &Path,
    a: &TriMesh,
    b: &TriMesh,
    poses: &[Isometry3<f64>],
) -> Result<PathBuf> {
    let file = folder.join("distance-input.bin");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&file)?);
    for mesh in [a, b] {
        out.write_all(&(mesh.vertices().len() as u64).to_le_bytes())?;
        out.write_all(&(mesh.triangles().len() as u64).to_le_bytes())?;
        for x in mesh.vertices().iter().flat_map(|v| v.coords.iter()) {
            out.write_all(&x.to_le_bytes())?;
        }
        for index in mesh.triangles().iter().flatten() {
            out.write_all(&index.to_le_bytes())?;
        }
    }
    out.write_all(&(poses.len() as u64).to_le_bytes())?;
    for pose in poses {
        let rotation = pose.rotation.to_rotation_matrix();
        let m = rotation.matrix();
        for row in 0..3 {
            for column in 0..3 {
                out.write_all(&m[(row, column)].to_le_bytes())?;
            }
        }
        for x in pose.translation.vector.iter() {
            out.write_all(&x.to_le_bytes())?;
        }
    }
    out.flush()?;
    Ok(file)
}

/// One turn of the harness at `harness` over the poses in `input`: each pose's answer and its
/// time in nanoseconds.
pub fn run_turn(harness: &Path, input: &Path, poses: usize) -> Result<(Vec<Answer>, Vec<f64>)> {
    let output = Command::new(harness)
        .arg(input)
        .output()
        .with_context(|| format!("running {}", harness.display()))?;
    if !output.status.success() {
        bail!(
            "{} failed: {}",
            harness.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let text = String::from_utf8(output.stdout).context("the harness's output")?;
    let (answers, times): (Vec<Answer>, Vec<f64>) = text
        .lines()
        .map(parse_line)
        .collect::<Result<Vec<_>>>()
        .with_context(|| format!("reading the output of {}", harness.display()))?
        .into_iter()
        .unzip();
    if answers.len() != poses {
        bail!(
            "{} answered {} of {poses} poses",
            harness.display(),
            answers.len()
        );
    }
    Ok((answers, times))
}

/// One line of a harness's output: distance, the point on A, the point on B (A's frame), the
/// two triangles, nanoseconds.
fn parse_line(line: &str) -> Result<(Answer, f64)> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    if fields.len() != 10 {
        bail!("{} fields in {line:?}, not 10", fields.len());
    }
    let number = |i: usize| -> Result<f64> {
        fields[i]
            .parse()
            .with_context(|| format!("field {i} of {line:?}"))
    };
    let triangle = |i: usize| -> Result<Option<u32>> {
        let index: i64 = fields[i]
            .parse()
            .with_context(|| format!("field {i} of {line:?}"))?;
        Ok(u32::try_from(index).ok())
    };
    let answer = Answer {
        distance: number(0)?,
        on_a: Point3::new(number(1)?, number(2)?, number(3)?),
        on_b: Point3::new(number(4)?, number(5)?, number(6)?),
        triangles: [triangle(7)?, triangle(8)?],
    };
    Ok((answer, number(9)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harness_lines_parse_and_a_missing_triangle_is_none() {
        let (answer, ns) = parse_line("0.5 1 2 3 4 5 6 7 -1 1234.5").unwrap();
        assert_eq!(answer.distance, 0.5);
        assert_eq!(answer.on_b, Point3::new(4.0, 5.0, 6.0));
        assert_eq!(answer.triangles, [Some(7), None]);
        assert_eq!(ns, 1234.5);
        assert!(parse_line("0.5 1 2").is_err());
        assert!(parse_line("x 1 2 3 4 5 6 7 8 9").is_err());
    }
}
