//! B1, the tumbling pair (the paper's Figure 3), and the machinery it shares with B2: a set of
//! exact colliders built over two meshes, run on the same poses, timed per query, with their
//! answers compared at every pose.
//!
//! Procedure: both meshes are centred on their bounding-box centre and scaled to fit [-1, 1]^3.
//! A stays at the identity; B is at translation (d, 0, 0) with rotation Rz(a)·Rx(a),
//! a = 2π s / steps, for s = 0 .. steps-1, at every distance d. One first-hit query per step and
//! algorithm; the algorithms take turns at each step, so that machine noise hits them alike.

use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

use super::report::{LinePlot, Series, Table, TimingSummary, format_number};
use crate::collision::{
    DopTree, KdopBruteForceTree, MeshCollider, ObbTree, OrientationSet, ParryMesh, QueryStats,
};
use crate::geometry::TriMesh;

/// The default distances of B1.
pub const DEFAULT_DISTANCES: [f64; 9] = [3.0, 2.5, 2.0, 1.75, 1.5, 1.25, 1.0, 0.75, 0.5];

/// The default number of steps per distance.
pub const DEFAULT_STEPS: usize = 5000;

/// An exact collision algorithm that the benchmarks compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Algo {
    /// The DOP-tree with O(k) re-alignment.
    Doptree,
    /// The DOP-tree, one query's traversal split across threads.
    DoptreePar,
    /// The k-DOP tree re-aligned by brute force (QuickCD).
    KdopBruteforce,
    /// The OBB-tree (RAPID).
    Obbtree,
    /// parry3d's mesh-mesh intersection test.
    Parry,
}

impl Algo {
    /// The four algorithms of the paper's comparison plus the peer (the default of `--algos`).
    pub const DEFAULT: [Algo; 4] = [
        Algo::Doptree,
        Algo::KdopBruteforce,
        Algo::Obbtree,
        Algo::Parry,
    ];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Algo::Doptree => "doptree",
            Algo::DoptreePar => "doptree-par",
            Algo::KdopBruteforce => "kdop-bruteforce",
            Algo::Obbtree => "obbtree",
            Algo::Parry => "parry",
        }
    }
}

impl fmt::Display for Algo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Algo {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        [
            Algo::Doptree,
            Algo::DoptreePar,
            Algo::KdopBruteforce,
            Algo::Obbtree,
            Algo::Parry,
        ]
        .into_iter()
        .find(|a| a.name() == s)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "unknown algorithm '{s}': expected doptree, doptree-par, kdop-bruteforce, obbtree or parry"
            )
        })
    }
}

/// A first-hit query of one algorithm over a fixed pair of meshes.
type Query = Box<dyn Fn(&Isometry3<f64>, &mut QueryStats) -> bool + Send + Sync>;

/// One algorithm built over meshes A and B.
pub struct BuiltCollider {
    /// Which algorithm.
    pub algo: Algo,
    /// Time to build both structures.
    pub build_time: Duration,
    /// Bytes per triangle of both structures (0 where unknown, for parry).
    pub bytes_per_triangle: f64,
    query: Query,
}

impl BuiltCollider {
    /// Builds `algo` over `a` and `b`; DOP-based algorithms use `set`.
    pub fn new(algo: Algo, a: &TriMesh, b: &TriMesh, set: &OrientationSet) -> Self {
        let triangles = (a.triangles().len() + b.triangles().len()) as f64;
        let start = Instant::now();
        let (query, bytes): (Query, usize) = match algo {
            Algo::Doptree | Algo::DoptreePar => {
                let (ta, tb) = (
                    DopTree::with_orientations(a, set),
                    DopTree::with_orientations(b, set),
                );
                let bytes = ta.bytes() + tb.bytes();
                let query: Query = if algo == Algo::Doptree {
                    Box::new(move |pose, stats| ta.intersects(&tb, pose, stats))
                } else {
                    Box::new(move |pose, stats| ta.intersects_parallel(&tb, pose, stats))
                };
                (query, bytes)
            }
            Algo::KdopBruteforce => {
                let (ta, tb) = (
                    KdopBruteForceTree::with_orientations(a, set),
                    KdopBruteForceTree::with_orientations(b, set),
                );
                let bytes = ta.tree().bytes() + tb.tree().bytes();
                (
                    Box::new(move |pose, stats| ta.intersects(&tb, pose, stats)),
                    bytes,
                )
            }
            Algo::Obbtree => {
                let (ta, tb) = (ObbTree::build(a), ObbTree::build(b));
                let bytes = ta.bytes() + tb.bytes();
                (
                    Box::new(move |pose, stats| ta.intersects(&tb, pose, stats)),
                    bytes,
                )
            }
            Algo::Parry => {
                let (ta, tb) = (ParryMesh::build(a), ParryMesh::build(b));
                (
                    Box::new(move |pose, stats| ta.intersects(&tb, pose, stats)),
                    0,
                )
            }
        };
        BuiltCollider {
            algo,
            build_time: start.elapsed(),
            bytes_per_triangle: bytes as f64 / triangles,
            query,
        }
    }
}

/// Timings and counters of one algorithm over one set of poses.
#[derive(Debug, Clone, Serialize)]
pub struct AlgoResult {
    /// Algorithm name.
    pub algo: String,
    /// Distance of B1 (none for B2).
    pub distance: Option<f64>,
    /// Mean time per query, microseconds.
    pub mean_us: f64,
    /// Median time per query, microseconds.
    pub median_us: f64,
    /// Largest time of one query, microseconds.
    pub max_us: f64,
    /// Fraction of poses in collision.
    pub hit_fraction: f64,
    /// Mean bounding-volume tests per query.
    pub bv_tests: f64,
    /// Mean re-alignments per query.
    pub realignments: f64,
    /// Mean node pairs opened per query.
    pub nodes_visited: f64,
    /// Mean triangle tests per query.
    pub tri_tests: f64,
}

/// Build cost of one algorithm.
#[derive(Debug, Clone, Serialize)]
pub struct BuildResult {
    /// Algorithm name.
    pub algo: String,
    /// Time to build the structures of both meshes, milliseconds.
    pub build_ms: f64,
    /// Bytes per triangle of both structures (0 where unknown).
    pub bytes_per_triangle: f64,
}

/// Runs every collider on every pose, in turns; returns per-algorithm results and the number of
/// poses at which the algorithms did not all give the same answer.
pub fn run_poses(
    colliders: &[BuiltCollider],
    poses: &[Isometry3<f64>],
    distance: Option<f64>,
) -> (Vec<AlgoResult>, usize) {
    let mut times = vec![Vec::with_capacity(poses.len()); colliders.len()];
    let mut stats = vec![QueryStats::default(); colliders.len()];
    let mut hits = vec![0usize; colliders.len()];
    let mut mismatches = 0;
    for pose in poses {
        let mut answers = Vec::with_capacity(colliders.len());
        for (i, collider) in colliders.iter().enumerate() {
            let start = Instant::now();
            let hit = (collider.query)(pose, &mut stats[i]);
            times[i].push(start.elapsed());
            hits[i] += hit as usize;
            answers.push(hit);
        }
        mismatches += answers.iter().any(|&h| h != answers[0]) as usize;
    }
    let n = poses.len().max(1) as f64;
    let results = colliders
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let timing = TimingSummary::from_durations(&times[i]);
            AlgoResult {
                algo: c.algo.name().to_string(),
                distance,
                mean_us: timing.mean_us,
                median_us: timing.median_us,
                max_us: timing.max_us,
                hit_fraction: hits[i] as f64 / n,
                bv_tests: stats[i].bv_tests as f64 / n,
                realignments: stats[i].realignments as f64 / n,
                nodes_visited: stats[i].nodes_visited as f64 / n,
                tri_tests: stats[i].tri_tests as f64 / n,
            }
        })
        .collect();
    (results, mismatches)
}

/// Parameters of B1.
#[derive(Debug, Clone)]
pub struct TumbleConfig {
    /// Steps per distance.
    pub steps: usize,
    /// Distances d of B's centre from A's.
    pub distances: Vec<f64>,
    /// Algorithms to compare.
    pub algos: Vec<Algo>,
    /// Orientation set of the DOP-based algorithms.
    pub orientations: OrientationSet,
}

/// The JSON document of B1.
#[derive(Debug, Clone, Serialize)]
pub struct TumbleReport {
    /// Always "tumble".
    pub benchmark: &'static str,
    /// Steps per distance.
    pub steps: usize,
    /// Triangles of A.
    pub triangles_a: usize,
    /// Triangles of B.
    pub triangles_b: usize,
    /// DOP orientations used.
    pub k: usize,
    /// Steps (over all distances) where the algorithms disagreed.
    pub mismatches: usize,
    /// One entry per algorithm and distance.
    pub results: Vec<AlgoResult>,
    /// Build time and memory per algorithm.
    pub build: Vec<BuildResult>,
}

/// B's pose at step `s` of `steps` at distance `d`.
pub fn tumble_pose(d: f64, s: usize, steps: usize) -> Isometry3<f64> {
    let a = std::f64::consts::TAU * s as f64 / steps as f64;
    let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a);
    Isometry3::from_parts(Translation3::new(d, 0.0, 0.0), rotation)
}

/// Runs B1 on meshes `a` and `b` (normalised here).
pub fn run_tumble(a: &TriMesh, b: &TriMesh, config: &TumbleConfig) -> Result<TumbleReport> {
    if config.steps == 0 || config.distances.is_empty() || config.algos.is_empty() {
        bail!("the tumbling benchmark needs at least one step, one distance and one algorithm");
    }
    let (a, b) = (a.normalized_to_unit_box(), b.normalized_to_unit_box());
    let colliders: Vec<BuiltCollider> = config
        .algos
        .iter()
        .map(|&algo| BuiltCollider::new(algo, &a, &b, &config.orientations))
        .collect();
    let mut results = Vec::new();
    let mut mismatches = 0;
    for &d in &config.distances {
        let poses: Vec<_> = (0..config.steps)
            .map(|s| tumble_pose(d, s, config.steps))
            .collect();
        let (mut r, m) = run_poses(&colliders, &poses, Some(d));
        results.append(&mut r);
        mismatches += m;
    }
    Ok(TumbleReport {
        benchmark: "tumble",
        steps: config.steps,
        triangles_a: a.triangles().len(),
        triangles_b: b.triangles().len(),
        k: config.orientations.k(),
        mismatches,
        results,
        build: build_results(&colliders),
    })
}

/// Build time and bytes per triangle of each collider.
pub fn build_results(colliders: &[BuiltCollider]) -> Vec<BuildResult> {
    colliders
        .iter()
        .map(|c| BuildResult {
            algo: c.algo.name().to_string(),
            build_ms: c.build_time.as_secs_f64() * 1e3,
            bytes_per_triangle: c.bytes_per_triangle,
        })
        .collect()
}

/// The results as a table: one row per algorithm and distance, with the DOP-tree's speed-up over
/// each other algorithm measured in the same run.
pub fn results_table(results: &[AlgoResult]) -> Table {
    let mut table = Table::new([
        "algo",
        "d",
        "mean_us",
        "median_us",
        "max_us",
        "hit",
        "bv_tests",
        "realign",
        "tri_tests",
        "doptree_x",
    ]);
    for r in results {
        let doptree = results
            .iter()
            .find(|o| o.algo == Algo::Doptree.name() && o.distance == r.distance);
        let ratio = doptree
            .map(|o| format!("{:.1}", r.mean_us / o.mean_us))
            .unwrap_or_default();
        table.push_row([
            r.algo.clone(),
            r.distance.map(|d| d.to_string()).unwrap_or_default(),
            format_number(r.mean_us),
            format_number(r.median_us),
            format_number(r.max_us),
            format!("{:.0}%", 100.0 * r.hit_fraction),
            format_number(r.bv_tests),
            format_number(r.realignments),
            format_number(r.tri_tests),
            ratio,
        ]);
    }
    table
}

/// One object of the Figure 3 sweep: its family (curve) name and mesh.
pub struct FigureObject {
    /// Curve the object belongs to ("sphere", "torus", ..., or "real").
    pub family: String,
    /// Label of the object (for the table).
    pub label: String,
    /// The mesh, used as both A and B.
    pub mesh: TriMesh,
}

/// One point of Figure 3: mean time per query of one algorithm on one object, over all distances.
#[derive(Debug, Clone, Serialize)]
pub struct FigurePoint {
    /// Curve family of the object.
    pub family: String,
    /// Object label.
    pub label: String,
    /// Triangles of the object.
    pub triangles: usize,
    /// Algorithm name.
    pub algo: String,
    /// Mean time per query over every distance and step, microseconds.
    pub mean_us: f64,
    /// Steps where the algorithms disagreed.
    pub mismatches: usize,
}

/// Runs B1 on every object (both copies the same mesh) and averages over distances.
pub fn figure3(objects: &[FigureObject], config: &TumbleConfig) -> Result<Vec<FigurePoint>> {
    let mut points = Vec::new();
    for object in objects {
        let report = run_tumble(&object.mesh, &object.mesh, config)?;
        for algo in &config.algos {
            let rows: Vec<&AlgoResult> = report
                .results
                .iter()
                .filter(|r| r.algo == algo.name())
                .collect();
            let mean_us = rows.iter().map(|r| r.mean_us).sum::<f64>() / rows.len() as f64;
            points.push(FigurePoint {
                family: object.family.clone(),
                label: object.label.clone(),
                triangles: report.triangles_a,
                algo: algo.name().to_string(),
                mean_us,
                mismatches: report.mismatches,
            });
        }
    }
    Ok(points)
}

/// Figure 3 as a log-log line plot: one curve per algorithm and object family.
pub fn figure3_plot(points: &[FigurePoint]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for p in points {
        let name = format!("{} / {}", p.algo, p.family);
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push((p.triangles as f64, p.mean_us)),
            None => series.push(Series {
                name,
                points: vec![(p.triangles as f64, p.mean_us)],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    LinePlot {
        title: "Tumbling pair: mean time per query".into(),
        x_label: "triangles per object".into(),
        y_label: "microseconds per query".into(),
        log_x: true,
        log_y: true,
        series,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::oracle_tests::torus;

    #[test]
    fn tumble_runs_every_algorithm_without_mismatch() {
        let mesh = torus(0.35, 20, 10);
        let config = TumbleConfig {
            steps: 40,
            distances: vec![2.5, 1.0],
            algos: vec![
                Algo::Doptree,
                Algo::DoptreePar,
                Algo::KdopBruteforce,
                Algo::Obbtree,
                Algo::Parry,
            ],
            orientations: OrientationSet::default(),
        };
        let report = run_tumble(&mesh, &mesh, &config).unwrap();
        assert_eq!(report.mismatches, 0);
        assert_eq!(report.results.len(), 10);
        let far = &report.results[0];
        let near = report
            .results
            .iter()
            .find(|r| r.distance == Some(1.0))
            .unwrap();
        assert!(far.hit_fraction < near.hit_fraction);
        assert!(near.hit_fraction > 0.9, "a torus through a torus at d = 1");
        let json = serde_json::to_value(&report).unwrap();
        for key in [
            "algo",
            "distance",
            "mean_us",
            "max_us",
            "hit_fraction",
            "bv_tests",
            "realignments",
            "tri_tests",
        ] {
            assert!(json["results"][0].get(key).is_some(), "{key}");
        }
        assert!(
            results_table(&report.results)
                .render()
                .contains("kdop-bruteforce")
        );
    }

    #[test]
    fn algorithm_names_round_trip() {
        for algo in [
            Algo::Doptree,
            Algo::DoptreePar,
            Algo::KdopBruteforce,
            Algo::Obbtree,
            Algo::Parry,
        ] {
            assert_eq!(algo.name().parse::<Algo>().unwrap(), algo);
        }
        assert!("rapid".parse::<Algo>().is_err());
    }
}
