//! The machinery B1 and B2 share: a set of exact colliders built over two meshes, run on the
//! same poses, timed per query, with their answers compared at every pose, and their tables.

use std::fmt;
use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use serde::Serialize;

use crate::baselines::{KdopBruteForceTree, ObbTree};
use crate::report::{Table, TimingSummary, format_number, timer_overhead};
use vas_server::collision::{DopTree, MeshCollider, OrientationSet, ParryMesh, QueryStats};
use vas_server::geometry::{TriMesh, bounding_sphere_of};

/// An exact collision algorithm that the benchmarks compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
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
    /// Mean time per query of one more pass over the poses timed as a whole, microseconds: the
    /// clock advances in steps of several nanoseconds, so per-query times of a few tens of
    /// nanoseconds are rounded by up to half their size; a whole pass is not.
    pub pass_mean_us: f64,
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
    /// Time per query at percentiles 0, 1, ..., 100, microseconds.
    pub percentiles_us: Vec<f64>,
    /// Poses at which this algorithm's answer differs from the first algorithm's.
    pub disagreements: usize,
}

/// What timing a query costs the harness itself, measured on the same poses with the same clock
/// as the algorithms: the floor under every algorithm's time per query. No algorithm's speed-up
/// over a peer can exceed the peer's time over this floor.
#[derive(Debug, Clone, Serialize)]
pub struct HarnessFloor {
    /// A query that answers at once, without reading the pose.
    pub empty_query: FloorTiming,
    /// The cheapest query that can prove a pair apart: B's bounding sphere, placed by the pose,
    /// against A's (what every algorithm does first, or an equivalent bounding test).
    pub sphere_test: FloorTiming,
}

/// The time per query of one reference query, taken both ways the algorithms' are.
#[derive(Debug, Clone, Serialize)]
pub struct FloorTiming {
    /// Mean over the poses of each query timed alone, as [`AlgoResult::mean_us`], microseconds.
    pub mean_us: f64,
    /// Mean of one pass timed as a whole, as [`AlgoResult::pass_mean_us`], microseconds.
    pub pass_mean_us: f64,
}

impl HarnessFloor {
    /// Times the two reference queries over `poses` of B against A, fastest of `rounds` turns.
    pub fn measure(a: &TriMesh, b: &TriMesh, poses: &[Isometry3<f64>], rounds: usize) -> Self {
        let (centre_a, radius_a) = bounding_sphere_of(a.vertices());
        let (centre_b, radius_b) = bounding_sphere_of(b.vertices());
        let reach_squared = (radius_a + radius_b).powi(2);
        let empty: Query = Box::new(|_, _| false);
        let sphere_test: Query =
            Box::new(move |pose, _| (pose * centre_b - centre_a).norm_squared() <= reach_squared);
        let overhead = timer_overhead();
        let time = |query: &Query| {
            let mut times = vec![Duration::MAX; poses.len()];
            for _ in 0..rounds.max(1) {
                run_turn(query, poses, overhead, &mut times);
            }
            FloorTiming {
                mean_us: TimingSummary::from_durations(&times).mean_us,
                pass_mean_us: pass_mean_us(query, poses),
            }
        };
        HarnessFloor {
            empty_query: time(&empty),
            sphere_test: time(&sphere_test),
        }
    }
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

/// Runs every collider on every pose; returns per-algorithm results and the number of poses at
/// which the algorithms did not all give the same answer.
///
/// Each collider runs the whole pose sequence on its own, as a user of one library would and as
/// the peers' figures were measured (each peer on the same procedure): a collider's queries
/// follow one another, so an algorithm that carries memory from one query to the next finds it
/// in the caches, and none of them finds the caches filled by another algorithm's queries (run
/// pose by pose in turns, a slow peer's queries between two DOP-tree queries evict the DOP-tree's
/// memory and trees).
///
/// The sequences are run `rounds` times, the colliders taking turns round by round in rotated
/// order, and each pose's time is its fastest round: on a shared machine a query preempted by
/// another process costs milliseconds, which would swamp means of microseconds; a preemption
/// rarely hits the same query in every round, and the rotation spreads the machine's slow
/// phases over the colliders. Replaying the sequence (rather than repeating a query at once)
/// keeps the caches and the temporal coherence the same as in one pass. Each turn starts with
/// one untimed query (see [`run_turn`]). Answers and counters come from the first round. Times
/// exclude the cost of reading the clock (see [`timer_overhead`]). One more pass per algorithm,
/// timed as a whole, gives the mean exactly where queries are as short as the clock's steps.
pub fn run_poses(
    colliders: &[BuiltCollider],
    poses: &[Isometry3<f64>],
    distance: Option<f64>,
    rounds: usize,
) -> (Vec<AlgoResult>, usize) {
    let mut times = vec![vec![Duration::MAX; poses.len()]; colliders.len()];
    let mut stats = vec![QueryStats::default(); colliders.len()];
    let mut answers = vec![Vec::new(); colliders.len()];
    let overhead = timer_overhead();
    for round in 0..rounds.max(1) {
        for turn in 0..colliders.len() {
            let i = (turn + round) % colliders.len();
            let (turn_answers, turn_stats) =
                run_turn(&colliders[i].query, poses, overhead, &mut times[i]);
            if round == 0 {
                answers[i] = turn_answers;
                stats[i] = turn_stats;
            }
        }
    }
    let hits: Vec<usize> = answers
        .iter()
        .map(|answers| answers.iter().filter(|&&hit| hit).count())
        .collect();
    let disagreements: Vec<usize> = answers
        .iter()
        .map(|own| own.iter().zip(&answers[0]).filter(|(a, b)| a != b).count())
        .collect();
    let mismatches = (0..poses.len())
        .filter(|&p| answers.iter().any(|own| own[p] != answers[0][p]))
        .count();
    let n = poses.len().max(1) as f64;
    let pass_means: Vec<f64> = colliders
        .iter()
        .map(|collider| pass_mean_us(&collider.query, poses))
        .collect();
    let results = colliders
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let timing = TimingSummary::from_durations(&times[i]);
            let mut sorted: Vec<f64> = times[i].iter().map(|t| t.as_secs_f64() * 1e6).collect();
            sorted.sort_by(f64::total_cmp);
            let percentiles_us = (0..=100)
                .map(|p| sorted[(p * (sorted.len() - 1)) / 100])
                .collect();
            AlgoResult {
                algo: c.algo.name().to_string(),
                distance,
                mean_us: timing.mean_us,
                pass_mean_us: pass_means[i],
                median_us: timing.median_us,
                max_us: timing.max_us,
                hit_fraction: hits[i] as f64 / n,
                bv_tests: stats[i].bv_tests as f64 / n,
                realignments: stats[i].realignments as f64 / n,
                nodes_visited: stats[i].nodes_visited as f64 / n,
                tri_tests: stats[i].tri_tests as f64 / n,
                percentiles_us,
                disagreements: disagreements[i],
            }
        })
        .collect();
    (results, mismatches)
}

/// One turn of a query over the poses: each pose is timed alone (the clock's `overhead`
/// subtracted) and `times` keeps each pose's fastest time so far; returns the answers and the
/// summed counters.
///
/// The turn starts with one untimed query at the last pose, which on the closed tumbling path is
/// the one just before the first: the first timed query then finds the caches and the query's
/// own memory as in the middle of a continuous run. Without it, every turn's first query would
/// pay for caches emptied by the other algorithms' turns, a cost of the benchmark taking turns,
/// not of the algorithm. On random poses (B2) it is one more random query.
fn run_turn(
    query: &Query,
    poses: &[Isometry3<f64>],
    overhead: Duration,
    times: &mut [Duration],
) -> (Vec<bool>, QueryStats) {
    let mut stats = QueryStats::default();
    if let Some(last) = poses.last() {
        std::hint::black_box(query(last, &mut QueryStats::default()));
    }
    let answers = poses
        .iter()
        .zip(times.iter_mut())
        .map(|(pose, fastest)| {
            let start = Instant::now();
            let hit = query(pose, &mut stats);
            *fastest = (*fastest).min(start.elapsed().saturating_sub(overhead));
            hit
        })
        .collect();
    (answers, stats)
}

/// The mean time per query of one pass over the poses timed as a whole, microseconds.
fn pass_mean_us(query: &Query, poses: &[Isometry3<f64>]) -> f64 {
    let mut unused = QueryStats::default();
    let start = Instant::now();
    for pose in poses {
        std::hint::black_box(query(pose, &mut unused));
    }
    start.elapsed().as_secs_f64() * 1e6 / poses.len().max(1) as f64
}

impl fmt::Display for Algo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
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
        "pass_us",
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
            format_number(r.pass_mean_us),
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

/// Names the algorithms that disagreed with the first one, and at how many poses.
pub fn print_disagreements(results: &[AlgoResult]) {
    for r in results.iter().filter(|r| r.disagreements > 0) {
        let at = r
            .distance
            .map(|d| format!(" at d = {d}"))
            .unwrap_or_default();
        println!(
            "  {} disagreed with {} at {} poses{at}",
            r.algo, results[0].algo, r.disagreements
        );
    }
}

/// Build time and memory as a table.
pub fn build_table(build: &[BuildResult]) -> Table {
    let mut table = Table::new(["algo", "build_ms", "bytes_per_triangle"]);
    for b in build {
        table.push_row([
            b.algo.clone(),
            format_number(b.build_ms),
            format_number(b.bytes_per_triangle),
        ]);
    }
    table
}
