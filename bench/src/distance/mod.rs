//! B11, distance: the DOP-tree's exact mesh-mesh distance against coal's and FCL's (OBBRSS
//! trees), same meshes, same poses, in the same run, the distances compared pose by pose.
//!
//! Procedures, per pair of meshes: *coherent*, B1's tumbling poses at each distance (both meshes
//! normalised as B1 does), the DOP-tree carrying one `DistanceMemory` from pose to pose as a
//! simulation keeps one per pair; *random*, B2's poses (two copies of one mesh normalised as in
//! B1, B2's translations over 3,000, fcl_env's half-size; a pair of two meshes as B2 takes it,
//! in its own units). The DOP-tree carries its memory from pose to pose, and at random poses
//! also runs cold (a fresh memory at every query); the peers make plain distance calls. Every method runs each sequence on its own, the
//! methods taking turns round by round as in B1, and each pose's time is its fastest round.

mod compare;
mod ours;
mod peers;
mod summary;

use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::Isometry3;
use serde::Serialize;
use vas_server::collision::{DopTree, OrientationSet};
use vas_server::geometry::{TriMesh, parse_mesh_spec};
use vas_testkit::tumble::tumble_pose;

use crate::args::OutputArgs;
use crate::random::random_poses;
use crate::report::timer_overhead;
use compare::{Row, Run};
use ours::Memory;
use peers::Peer;
use summary::Bar;

/// The default pairs: two copies of the 50k torus, two of the UR5e upper arm, FCL's env and rob.
const DEFAULT_PAIRS: [&str; 3] = [
    "shape:torus:50000",
    "configs/meshes/ur5e_upperarm.obj",
    "configs/meshes/fcl_env.obj+configs/meshes/fcl_rob.obj",
];

/// B1's distances from 3.0 to 1.0: the parts are apart at the first ones and touch at the last.
const DEFAULT_DISTANCES: [f64; 7] = [3.0, 2.5, 2.0, 1.75, 1.5, 1.25, 1.0];

/// The half-size of fcl_env, over which B2's translations range: two copies of one mesh,
/// normalised to half-size 1, take B2's translations over this.
const FCL_ENV_HALF_SIZE: f64 = 3000.0;

/// The bar's tolerance of a distance's difference from coal's, over the meshes' size.
pub const RELATIVE_TOLERANCE: f64 = 1e-6;

/// Command line of `vas-bench distance`.
#[derive(Debug, Clone, clap::Args)]
pub struct DistanceArgs {
    /// Pairs, comma-separated: one mesh (two copies of it) or A+B; each a file or
    /// shape:KIND:TRIANGLES.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_PAIRS.map(String::from))]
    pub pairs: Vec<String>,
    /// Tumbling steps per distance.
    #[arg(long, default_value_t = 300, value_parser = crate::args::pass_count())]
    pub steps: usize,
    /// Tumbling distances d, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_DISTANCES,
          value_parser = crate::args::finite_number)]
    pub distances: Vec<f64>,
    /// Random poses per pair.
    #[arg(long, default_value_t = 1000, value_parser = crate::args::pass_count())]
    pub poses: usize,
    /// Seed of the random poses.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of DOP orientations (6, 14, 18, 24 or 26).
    #[arg(long, default_value_t = vas_server::collision::orientation::DEFAULT_K)]
    pub k: usize,
    /// Passes over the poses; each query's time is its fastest pass.
    #[arg(long, default_value_t = 3, value_parser = crate::args::pass_count())]
    pub rounds: usize,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The JSON document of B11.
#[derive(Debug, Clone, Serialize)]
pub struct DistanceReport {
    /// Always "distance".
    pub benchmark: &'static str,
    /// Tumbling steps per distance.
    pub steps: usize,
    /// Random poses per pair.
    pub poses: usize,
    /// Seed of the random poses.
    pub seed: u64,
    /// DOP orientations.
    pub k: usize,
    /// Passes over the poses (each query's time is its fastest pass).
    pub rounds: usize,
    /// The peers measured in this run.
    pub peers: Vec<Peer>,
    /// One row per pair, procedure, distance and method.
    pub rows: Vec<Row>,
    /// The bars, met or not.
    pub bars: Vec<Bar>,
}

/// A method of the comparison.
#[derive(Debug, Clone, Copy)]
enum Method {
    /// The DOP-tree.
    Ours(Memory),
    /// A peer by its harness.
    Peer(Peer, &'static Path),
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Ours(Memory::Carried) => "doptree",
            Method::Ours(Memory::Cold) => "doptree-cold",
            Method::Peer(peer, _) => peer.name(),
        }
    }
}

/// Two meshes as measured, with their DOP-trees.
struct Pair {
    label: String,
    a: TriMesh,
    b: TriMesh,
    tree_a: DopTree,
    tree_b: DopTree,
    /// The bar's largest difference: the tolerance times the larger bounding-box diagonal.
    tolerance: f64,
}

impl Pair {
    fn new(label: &str, a: TriMesh, b: TriMesh, set: &OrientationSet) -> Self {
        let diagonal = |mesh: &TriMesh| {
            let (low, high) = mesh.bounding_box();
            (high - low).norm()
        };
        Pair {
            label: label.to_owned(),
            tolerance: RELATIVE_TOLERANCE * diagonal(&a).max(diagonal(&b)),
            tree_a: DopTree::with_orientations(&a, set),
            tree_b: DopTree::with_orientations(&b, set),
            a,
            b,
        }
    }
}

/// `vas-bench distance`: runs B11, prints the table and the bars, writes files.
pub fn run_cli(args: &DistanceArgs) -> Result<()> {
    let set = OrientationSet::new(args.k)?;
    let mut peers = Vec::new();
    for peer in Peer::ALL {
        match peer.harness() {
            Some(harness) => peers.push((peer, Path::new(harness))),
            None => println!("{}", peer.missing()),
        }
    }
    // Cold queries only at random poses: on the tumbling path they would only repeat what a
    // cold query costs, at the price of the slowest runs of the benchmark.
    let with_peers = |ours: &[Memory]| -> Vec<Method> {
        ours.iter()
            .map(|&memory| Method::Ours(memory))
            .chain(
                peers
                    .iter()
                    .map(|&(peer, harness)| Method::Peer(peer, harness)),
            )
            .collect()
    };
    let coherent = with_peers(&[Memory::Carried]);
    let random = with_peers(&[Memory::Carried, Memory::Cold]);
    let mut rows = Vec::new();
    for spec in &args.pairs {
        let (label, a, b) = parse_pair(spec)?;
        let copies = b.is_none();
        let b = b.unwrap_or_else(|| a.clone());
        let normalised = Pair::new(
            &label,
            a.normalized_to_unit_box(),
            b.normalized_to_unit_box(),
            &set,
        );
        for &d in &args.distances {
            let poses: Vec<_> = (0..args.steps)
                .map(|s| tumble_pose(d, s, args.steps))
                .collect();
            rows.extend(measure(
                &normalised,
                &poses,
                ("coherent", Some(d)),
                &coherent,
                args.rounds,
            )?);
        }
        let mut poses = random_poses(args.poses, args.seed);
        let random_pair = if copies {
            for pose in &mut poses {
                pose.translation.vector /= FCL_ENV_HALF_SIZE;
            }
            normalised
        } else {
            Pair::new(&label, a, b, &set)
        };
        rows.extend(measure(
            &random_pair,
            &poses,
            ("random", None),
            &random,
            args.rounds,
        )?);
    }
    let bars = summary::bars(&rows);
    println!(
        "distance: {} tumbling steps a distance, {} random poses, k = {}, fastest of {} rounds",
        args.steps, args.poses, args.k, args.rounds
    );
    print!("{}", summary::table(&rows).render());
    for bar in &bars {
        println!("{bar}");
    }
    let report = DistanceReport {
        benchmark: "distance",
        steps: args.steps,
        poses: args.poses,
        seed: args.seed,
        k: args.k,
        rounds: args.rounds,
        peers: peers.iter().map(|&(peer, _)| peer).collect(),
        rows,
        bars,
    };
    args.output.write(&report, || summary::plot(&report.rows))
}

/// A pair of the command line: its label, mesh A, and mesh B unless it is two copies of A.
fn parse_pair(spec: &str) -> Result<(String, TriMesh, Option<TriMesh>)> {
    let label = |spec: &str| match spec.strip_prefix("shape:") {
        Some(shape) => shape.to_owned(),
        None => Path::new(spec)
            .file_stem()
            .map_or(spec.to_owned(), |s| s.to_string_lossy().into_owned()),
    };
    let load = |spec: &str| parse_mesh_spec(spec).with_context(|| format!("mesh {spec}"));
    Ok(match spec.split_once('+') {
        Some((a, b)) => (
            format!("{}+{}", label(a), label(b)),
            load(a)?,
            Some(load(b)?),
        ),
        None => (label(spec), load(spec)?, None),
    })
}

/// Every method over `poses` of `pair`, in turns over `rounds`; one row per method.
fn measure(
    pair: &Pair,
    poses: &[Isometry3<f64>],
    (procedure, distance): (&'static str, Option<f64>),
    methods: &[Method],
    rounds: usize,
) -> Result<Vec<Row>> {
    let folder = tempfile::tempdir()?;
    let input = peers::write_input(folder.path(), &pair.a, &pair.b, poses)?;
    let overhead = timer_overhead();
    let mut runs: Vec<Run> = methods
        .iter()
        .map(|method| Run {
            method: method.name(),
            answers: Vec::new(),
            nanoseconds: vec![f64::INFINITY; poses.len()],
            stats: None,
        })
        .collect();
    for round in 0..rounds {
        for turn in 0..methods.len() {
            let i = (turn + round) % methods.len();
            let (answers, nanoseconds, stats) = match methods[i] {
                Method::Ours(memory) => {
                    let (answers, nanoseconds, stats) =
                        ours::run_turn(&pair.tree_a, &pair.tree_b, poses, memory, overhead);
                    (answers, nanoseconds, Some(stats))
                }
                Method::Peer(_, harness) => {
                    let (answers, nanoseconds) = peers::run_turn(harness, &input, poses.len())?;
                    (answers, nanoseconds, None)
                }
            };
            let run = &mut runs[i];
            for (fastest, time) in run.nanoseconds.iter_mut().zip(nanoseconds) {
                *fastest = fastest.min(time);
            }
            if round == 0 {
                run.answers = answers;
                run.stats = stats;
            }
        }
    }
    let reference = runs.iter().find(|run| run.method == Peer::Coal.name());
    let rows: Vec<Row> = runs
        .iter()
        .map(|run| {
            compare::summarise(
                run,
                reference,
                (&pair.a, &pair.b),
                poses,
                (&pair.label, procedure, distance),
                pair.tolerance,
            )
        })
        .collect();
    let means: Vec<String> = rows
        .iter()
        .map(|r| format!("{} {:.3} us", r.method, r.mean_us))
        .collect();
    let at = distance.map(|d| format!(" d = {d}")).unwrap_or_default();
    println!("{} {procedure}{at}: {}", pair.label, means.join(", "));
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use vas_server::collision::distance::brute_force_distance;
    use vas_server::geometry::shapes;

    /// Two small normalised tori.
    fn small_pair() -> Pair {
        let mesh = shapes::torus(1.0, 0.35, 16, 8).normalized_to_unit_box();
        Pair::new("torus", mesh.clone(), mesh, &OrientationSet::default())
    }

    #[test]
    fn every_method_gets_a_row_and_the_answers_are_the_exact_ones() {
        let pair = small_pair();
        let mut methods = vec![Method::Ours(Memory::Carried), Method::Ours(Memory::Cold)];
        methods.extend(
            Peer::ALL
                .into_iter()
                .filter_map(|peer| Some(Method::Peer(peer, Path::new(peer.harness()?)))),
        );
        for (d, touching) in [(3.0, 0.0..=0.0), (1.0, 0.5..=1.0)] {
            let poses: Vec<_> = (0..24).map(|s| tumble_pose(d, s, 24)).collect();
            let rows = measure(&pair, &poses, ("coherent", Some(d)), &methods, 2).unwrap();
            assert_eq!(rows.len(), methods.len());
            for row in &rows {
                assert!(touching.contains(&row.touching), "{} at {d}", row.method);
                assert_eq!(row.touching, rows[0].touching, "{} at {d}", row.method);
                assert!(row.point_error < 1e-9, "{} at {d}", row.method);
                if let Some(difference) = row.max_difference {
                    assert!(difference <= row.tolerance, "{} at {d}", row.method);
                }
            }
            let (answers, _, stats) = ours::run_turn(
                &pair.tree_a,
                &pair.tree_b,
                &poses,
                Memory::Carried,
                Duration::ZERO,
            );
            assert!(stats.tri_tests > 0);
            for (answer, pose) in answers.iter().zip(&poses) {
                let exact = brute_force_distance(&pair.a, &pair.b, pose).unwrap();
                assert!((answer.distance - exact.distance).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn without_coal_the_bars_are_not_judged_but_the_memory_is() {
        let pair = small_pair();
        let poses: Vec<_> = random_poses(40, 3)
            .into_iter()
            .map(|mut pose| {
                pose.translation.vector /= FCL_ENV_HALF_SIZE;
                pose
            })
            .collect();
        let methods = [Method::Ours(Memory::Carried), Method::Ours(Memory::Cold)];
        let rows = measure(&pair, &poses, ("random", None), &methods, 1).unwrap();
        assert!(rows.iter().all(|r| r.max_difference.is_none()));
        let bars = summary::bars(&rows);
        assert_eq!(bars.len(), 4);
        assert!(bars[..3].iter().all(|bar| bar.met.is_none()), "{bars:?}");
        assert!(bars[3].met.is_some(), "{:?}", bars[3]);
        assert!(summary::table(&rows).render().contains("doptree-cold"));
    }

    #[test]
    fn pairs_are_one_mesh_or_two() {
        let (label, _, b) = parse_pair("shape:sphere:200").unwrap();
        assert_eq!((label.as_str(), b.is_none()), ("sphere:200", true));
        let (label, _, b) = parse_pair("shape:sphere:200+shape:torus:400").unwrap();
        assert_eq!(
            (label.as_str(), b.is_some()),
            ("sphere:200+torus:400", true)
        );
        assert!(parse_pair("shape:cube:0").is_err());
    }
}
