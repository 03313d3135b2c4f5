//! B2, random poses (FCL's procedure): mesh B at uniformly random poses against a fixed mesh A,
//! translation uniform in [-3000, 3000] x [-3000, 3000] x [0, 3000] (FCL's environment units),
//! rotation uniform; one first-hit query per pose and algorithm, in turns.

use anyhow::{Result, bail};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::args::OutputArgs;
use crate::report::{LinePlot, Series};
use crate::tumble::{
    Algo, AlgoResult, BuildResult, BuiltCollider, build_results, build_table, print_disagreements,
    results_table, run_poses,
};
use vas_server::collision::OrientationSet;
use vas_server::geometry::{TriMesh, parse_mesh_spec};

/// The default number of poses of B2.
pub const DEFAULT_POSES: usize = 10_000;

/// Parameters of B2.
#[derive(Debug, Clone)]
pub struct RandomConfig {
    /// Number of random poses.
    pub poses: usize,
    /// Seed of the pose generator.
    pub seed: u64,
    /// Algorithms to compare.
    pub algos: Vec<Algo>,
    /// Orientation set of the DOP-based algorithms.
    pub orientations: OrientationSet,
    /// Passes over the poses; each query's time is its fastest pass (see [`run_poses`]).
    pub rounds: usize,
}

/// The JSON document of B2.
#[derive(Debug, Clone, Serialize)]
pub struct RandomReport {
    /// Always "random".
    pub benchmark: &'static str,
    /// Number of poses.
    pub poses: usize,
    /// Triangles of A.
    pub triangles_a: usize,
    /// Triangles of B.
    pub triangles_b: usize,
    /// DOP orientations used.
    pub k: usize,
    /// Passes over the poses (each query's time is its fastest pass).
    pub rounds: usize,
    /// Poses where the algorithms disagreed.
    pub mismatches: usize,
    /// One entry per algorithm (`distance` is null).
    pub results: Vec<AlgoResult>,
    /// Build time and memory per algorithm.
    pub build: Vec<BuildResult>,
}

/// `count` poses with FCL's distribution, from `seed`.
pub fn random_poses(count: usize, seed: u64) -> Vec<Isometry3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let t = Vector3::new(
                rng.random_range(-3000.0..3000.0),
                rng.random_range(-3000.0..3000.0),
                rng.random_range(0.0..3000.0),
            );
            Isometry3::from_parts(Translation3::from(t), uniform_rotation(&mut rng))
        })
        .collect()
}

/// A uniformly distributed rotation (Shoemake's method from three uniform numbers).
fn uniform_rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    UnitQuaternion::from_quaternion(Quaternion::new(
        b * (tau * u3).cos(),
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
    ))
}

/// Runs B2 with `b` posed randomly against the fixed `a` (no normalisation: FCL's units).
pub fn run_random(a: &TriMesh, b: &TriMesh, config: &RandomConfig) -> Result<RandomReport> {
    if config.poses == 0 || config.algos.is_empty() {
        bail!("the random-pose benchmark needs at least one pose and one algorithm");
    }
    let colliders: Vec<BuiltCollider> = config
        .algos
        .iter()
        .map(|&algo| BuiltCollider::new(algo, a, b, &config.orientations))
        .collect();
    let poses = random_poses(config.poses, config.seed);
    let (results, mismatches) = run_poses(&colliders, &poses, None, config.rounds);
    Ok(RandomReport {
        benchmark: "random",
        poses: config.poses,
        triangles_a: a.triangles().len(),
        triangles_b: b.triangles().len(),
        k: config.orientations.k(),
        rounds: config.rounds,
        mismatches,
        results,
        build: build_results(&colliders),
    })
}

/// Command-line arguments of `vas-bench random`.
#[derive(Debug, Clone, clap::Args)]
pub struct RandomArgs {
    /// The fixed mesh A: a file or shape:KIND:TRIANGLES.
    #[arg(long, default_value = "configs/meshes/fcl_env.obj")]
    pub mesh: String,
    /// The moving mesh B.
    #[arg(long, default_value = "configs/meshes/fcl_rob.obj")]
    pub mesh_b: String,
    /// Number of random poses.
    #[arg(long, default_value_t = DEFAULT_POSES)]
    pub poses: usize,
    /// Seed of the pose generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Algorithms to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = Algo::DEFAULT)]
    pub algos: Vec<Algo>,
    /// Number of DOP orientations (6, 14, 18, 24 or 26).
    #[arg(long, default_value_t = vas_server::collision::orientation::DEFAULT_K)]
    pub k: usize,
    /// Passes over the poses; each query's time is its fastest pass (robust to preemption).
    #[arg(long, default_value_t = 3, value_parser = crate::args::pass_count())]
    pub rounds: usize,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `vas-bench random`: runs B2, prints the table, writes files.
pub fn run_cli(args: &RandomArgs) -> Result<()> {
    let a = parse_mesh_spec(&args.mesh)?;
    let b = parse_mesh_spec(&args.mesh_b)?;
    let config = RandomConfig {
        poses: args.poses,
        seed: args.seed,
        algos: args.algos.clone(),
        orientations: OrientationSet::new(args.k)?,
        rounds: args.rounds,
    };
    let report = run_random(&a, &b, &config)?;
    println!(
        "random poses: {} x {} triangles, {} poses, k = {}, fastest of {} rounds",
        report.triangles_a, report.triangles_b, report.poses, report.k, report.rounds
    );
    print!("{}", results_table(&report.results).render());
    print!("{}", build_table(&report.build).render());
    println!("mismatches: {}", report.mismatches);
    print_disagreements(&report.results);
    args.output
        .write(&report, || percentile_plot(&report.results))
}

/// Time per query by percentile (log time axis), one curve per algorithm.
fn percentile_plot(results: &[AlgoResult]) -> LinePlot {
    LinePlot {
        title: "Random poses: time per query by percentile".into(),
        x_label: "percentile".into(),
        y_label: "microseconds per query".into(),
        log_x: false,
        log_y: true,
        series: results
            .iter()
            .map(|r| Series {
                name: r.algo.clone(),
                points: r
                    .percentiles_us
                    .iter()
                    .enumerate()
                    .map(|(p, &t)| (p as f64, t.max(1e-3)))
                    .collect(),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vas_server::geometry::shapes;

    #[test]
    fn poses_follow_the_distribution() {
        let poses = random_poses(2000, 5);
        assert!(poses.iter().all(|p| {
            let t = p.translation.vector;
            t.x.abs() <= 3000.0 && t.y.abs() <= 3000.0 && (0.0..=3000.0).contains(&t.z)
        }));
        // Uniform rotations: the mean of the rotated x axis is near zero.
        let mean: Vector3<f64> = poses
            .iter()
            .map(|p| p.rotation * Vector3::x())
            .sum::<Vector3<f64>>()
            / 2000.0;
        assert!(mean.norm() < 0.1, "{mean}");
    }

    #[test]
    fn random_benchmark_agrees_across_algorithms() {
        let scale = |m: TriMesh, s: f64| m.map_vertices(|p| p * s).unwrap();
        let a = scale(shapes::torus(1.0, 0.35, 30, 12), 2500.0);
        let b = scale(shapes::torus(1.0, 0.3, 12, 8), 1000.0);
        let config = RandomConfig {
            poses: 300,
            seed: 1,
            algos: Algo::DEFAULT.to_vec(),
            orientations: OrientationSet::default(),
            rounds: 1,
        };
        let report = run_random(&a, &b, &config).unwrap();
        assert_eq!(report.mismatches, 0);
        assert!(report.results[0].hit_fraction > 0.05);
    }
}
