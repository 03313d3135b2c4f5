//! B4, bouncing objects in a cube (the paper's Figure 5): the whole collision pipeline per frame,
//! against the number of threads of its parallel back end.
//!
//! N rigid objects (spheres, boxes and cylinders of about the requested triangle count, unit size)
//! fly and spin inside a cube sized so that their bounding spheres fill a given fraction of it.
//! They bounce off the walls, and off each other whenever the pipeline reports a colliding pair
//! (equal masses: the velocity components along the line between the centres are exchanged).
//! Every object moves every frame, so every frame runs the front-end queue, the broad phase, the
//! interest matrix, the separating-plane pre-check and the DOP-tree exact test over the whole
//! scene. Each thread count has its own pipeline on its own rayon pool, and they take turns in
//! blocks of [`BLOCK_FRAMES`] frames: the block's leader (rotating from block to block) runs the
//! scene live, and the others replay the same poses and must report the same colliding pairs.
//! Within a block a pipeline runs frame after frame, as the paper's benchmark does; across blocks,
//! slow phases of the machine hit every thread count alike instead of whichever happened to run
//! during them.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, ensure};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::args::OutputArgs;
use crate::report::{self, LinePlot, Series, Table};
use vas_server::collision::pipeline::interest::GroupId;
use vas_server::collision::pipeline::{
    CollisionModel, CollisionPipeline, Detail, FrameStats, ObjectDesc, ObjectId, PipelineConfig,
    SPLIT_MIN_BV_TESTS,
};
use vas_server::collision::{DopTree, MeshCollider};
use vas_server::geometry::ConvexHull;
use vas_server::geometry::shapes::{self, ShapeKind};

/// Command-line arguments of `vas-bench bounce`.
#[derive(Debug, Clone, clap::Args)]
pub struct BounceArgs {
    /// Number of objects.
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u32).range(2..))]
    pub objects: u32,
    /// Frames timed per thread count.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Thread counts to compare (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2])]
    pub threads: Vec<usize>,
    /// About how many triangles each object has.
    #[arg(long, default_value_t = 1000)]
    pub triangles: usize,
    /// Fraction of the cube's volume filled by the objects' bounding spheres. Denser scenes send
    /// more pairs to the parallel back end (the paper: speed-ups need a dense enough scene).
    #[arg(long, default_value_t = 0.1)]
    pub fill: f64,
    /// Seed of the scene.
    #[arg(long, default_value_t = 5)]
    pub seed: u64,
    /// Frames run before timing starts (the first frame tests every pair from cold).
    #[arg(long, default_value_t = 10)]
    pub warmup: u32,
    /// Run without the separating-plane stage (pairs go from the boxes to the exact test).
    #[arg(long)]
    pub no_separating_plane: bool,
    /// Split a pair's exact test across the threads when its previous one ran at least this many
    /// bounding-volume tests (the pipeline's fine-grain threshold).
    #[arg(long, default_value_t = SPLIT_MIN_BV_TESTS)]
    pub split_min_bv_tests: u64,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// One thread count of B4.
#[derive(Debug, Clone, Serialize)]
pub struct BounceRow {
    /// Threads of the pipeline's pool.
    pub threads: usize,
    /// Objects in the cube.
    pub objects: u32,
    /// Mean wall time of a frame, microseconds.
    pub mean_frame_us: f64,
    /// 99th percentile of the frame times, microseconds.
    pub p99_frame_us: f64,
    /// Mean frame time of the first row divided by this row's.
    pub speedup: f64,
    /// Per-frame means of what went through the stages.
    pub stages: StageMeans,
}

/// Mean pairs and times per frame, by stage.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageMeans {
    /// Pairs whose boxes overlap (out of the broad phase).
    pub box_pairs: f64,
    /// Pairs of interest.
    pub interesting_pairs: f64,
    /// Pairs left for the exact test by the separating-plane stage.
    pub unseparated_pairs: f64,
    /// Colliding pairs.
    pub colliding_pairs: f64,
    /// Exact tests split across the threads.
    pub split_tests: f64,
    /// Broad-phase time, microseconds.
    pub broad_phase_us: f64,
    /// Separating-plane stage time, microseconds.
    pub separating_plane_us: f64,
    /// Exact-test stage time, microseconds.
    pub exact_us: f64,
}

/// The JSON document of B4.
#[derive(Debug, Clone, Serialize)]
pub struct BounceReport {
    /// Always "bounce".
    pub benchmark: &'static str,
    /// Frames timed per thread count.
    pub frames: u32,
    /// Triangles per object (mean over the objects).
    pub triangles_per_object: f64,
    /// Side of the cube (objects have unit half-size).
    pub cube_side: f64,
    /// One row per thread count.
    pub rows: Vec<BounceRow>,
}

/// The objects' state, advanced by [`Scene::step`].
struct Scene {
    poses: Vec<Isometry3<f64>>,
    velocities: Vec<Vector3<f64>>,
    spins: Vec<UnitQuaternion<f64>>,
    radii: Vec<f64>,
    side: f64,
}

impl Scene {
    /// `count` objects at random places (a jittered grid, so that they start apart) with random
    /// velocities and spins.
    fn new(count: usize, radii: Vec<f64>, side: f64, seed: u64) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let per_side = (count as f64).cbrt().ceil() as usize;
        let cell = side / per_side as f64;
        let mut poses = Vec::with_capacity(count);
        for i in 0..count {
            let grid = Vector3::new(
                i % per_side,
                (i / per_side) % per_side,
                i / per_side / per_side,
            );
            let jitter = Vector3::from_fn(|_, _| rng.random_range(0.3..0.7));
            let rotation = UnitQuaternion::from_euler_angles(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            );
            poses.push(Isometry3::from_parts(
                Translation3::from((grid.cast::<f64>() + jitter) * cell),
                rotation,
            ));
        }
        // About a twentieth of an object size per frame, and a few degrees of spin.
        let velocities = (0..count)
            .map(|_| Vector3::from_fn(|_, _| rng.random_range(-0.05..0.05)))
            .collect();
        let spins = (0..count)
            .map(|_| {
                UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| {
                    rng.random_range(-0.05..0.05)
                }))
            })
            .collect();
        Scene {
            poses,
            velocities,
            spins,
            radii,
            side,
        }
    }

    /// Bounces the colliding pairs off each other, then moves every object one frame, reflecting
    /// it off the walls.
    fn step(&mut self, colliding: impl Iterator<Item = (usize, usize)>) {
        for (a, b) in colliding {
            let axis = self.poses[b].translation.vector - self.poses[a].translation.vector;
            let Some(axis) = axis.try_normalize(1e-12) else {
                continue;
            };
            let approach = (self.velocities[a] - self.velocities[b]).dot(&axis);
            if approach > 0.0 {
                self.velocities[a] -= axis * approach;
                self.velocities[b] += axis * approach;
            }
        }
        for i in 0..self.poses.len() {
            let mut position = self.poses[i].translation.vector + self.velocities[i];
            for k in 0..3 {
                let (lo, hi) = (self.radii[i], self.side - self.radii[i]);
                if position[k] < lo || position[k] > hi {
                    self.velocities[i][k] = -self.velocities[i][k];
                    position[k] = position[k].clamp(lo, hi);
                }
            }
            self.poses[i] = Isometry3::from_parts(
                Translation3::from(position),
                self.spins[i] * self.poses[i].rotation,
            );
        }
    }
}

/// What one thread count's pipeline records of its timed frames.
#[derive(Default)]
struct SceneRun {
    times: Vec<Duration>,
    stats: Vec<FrameStats>,
}

/// The shared models: one per shape kind, unit half-size.
fn models(triangles: usize) -> Vec<Arc<CollisionModel<DopTree>>> {
    [ShapeKind::Sphere, ShapeKind::Box, ShapeKind::Cylinder]
        .into_iter()
        .map(|kind| {
            let mesh = shapes::build(kind, triangles);
            Arc::new(CollisionModel::new(
                DopTree::build(&mesh),
                ConvexHull::of(&mesh),
            ))
        })
        .collect()
}

/// One thread count's pipeline over the scene, on its own pool.
///
/// A block of frames runs inside the pool (`ThreadPool::install` around the whole block), so the
/// thread that queues the moves and runs each frame is one of the pool's workers, as the
/// server's collision loop is. Handing every frame to the pool from outside would add to each
/// frame the hand-over to a pool thread, which is not the pipeline's work.
struct Contender {
    threads: usize,
    pool: rayon::ThreadPool,
    lane: Lane,
}

/// A pipeline over the scene, and what its timed frames recorded.
struct Lane {
    pipeline: CollisionPipeline<DopTree>,
    ids: Vec<ObjectId>,
    run: SceneRun,
}

impl Contender {
    fn new(
        args: &BounceArgs,
        models: &[Arc<CollisionModel<DopTree>>],
        poses: &[Isometry3<f64>],
        threads: usize,
    ) -> Result<Contender> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("building the thread pool")?;
        let mut pipeline = CollisionPipeline::new(PipelineConfig {
            separating_plane: !args.no_separating_plane,
            split_min_bv_tests: args.split_min_bv_tests,
            ..PipelineConfig::default()
        });
        let ids = poses
            .iter()
            .enumerate()
            .map(|(i, pose)| {
                pipeline.add(ObjectDesc {
                    model: Arc::clone(&models[i % models.len()]),
                    pose: *pose,
                    group: GroupId::default(),
                    is_static: false,
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(Contender {
            threads,
            pool,
            lane: Lane {
                pipeline,
                ids,
                run: SceneRun::default(),
            },
        })
    }
}

impl Lane {
    /// Moves every object to `poses`, runs a frame and returns its colliding pairs (object
    /// indices), recording the frame's time and counters when `timed`.
    fn frame(&mut self, poses: &[Isometry3<f64>], timed: bool) -> Result<Vec<(usize, usize)>> {
        let start = Instant::now();
        for (id, pose) in self.ids.iter().zip(poses) {
            self.pipeline.queue_move(*id, *pose)?;
        }
        let report = self.pipeline.run_frame(Detail::Pairs);
        let elapsed = start.elapsed();
        if timed {
            self.run.times.push(elapsed);
            self.run.stats.push(report.stats);
        }
        // Ids are added in order into an empty pipeline, so an object's slot is its index.
        Ok(report
            .colliding
            .iter()
            .map(|pair| (pair.a.index() as usize, pair.b.index() as usize))
            .collect())
    }
}

/// Frames a thread count runs back to back before the next one takes its turn.
pub const BLOCK_FRAMES: u32 = 50;

/// Runs the scene for `warmup + frames` frames, the thread counts taking turns block by block,
/// and returns what each recorded of the timed frames.
fn run_scene(
    args: &BounceArgs,
    models: &[Arc<CollisionModel<DopTree>>],
    side: f64,
) -> Result<Vec<Contender>> {
    let count = args.objects as usize;
    let radii = (0..count)
        .map(|i| models[i % models.len()].hull().radius())
        .collect();
    let mut scene = Scene::new(count, radii, side, args.seed);
    let mut contenders = args
        .threads
        .iter()
        .map(|&threads| Contender::new(args, models, &scene.poses, threads))
        .collect::<Result<Vec<_>>>()?;
    let total = args.warmup + args.frames;
    let mut colliding = Vec::new();
    for block_start in (0..total).step_by(BLOCK_FRAMES as usize) {
        let frames = block_start..(block_start + BLOCK_FRAMES).min(total);
        let leader = (block_start / BLOCK_FRAMES) as usize % contenders.len();
        let mut block = Vec::with_capacity(BLOCK_FRAMES as usize);
        let Contender {
            threads: leader_threads,
            pool,
            lane,
        } = &mut contenders[leader];
        let leader_threads = *leader_threads;
        pool.install(|| -> Result<()> {
            for frame in frames.clone() {
                scene.step(colliding.iter().copied());
                colliding = lane.frame(&scene.poses, frame >= args.warmup)?;
                block.push((scene.poses.clone(), colliding.clone()));
            }
            Ok(())
        })?;
        for (index, contender) in contenders.iter_mut().enumerate() {
            if index == leader {
                continue;
            }
            let Contender {
                threads,
                pool,
                lane,
            } = contender;
            pool.install(|| -> Result<()> {
                for (frame, (poses, expected)) in frames.clone().zip(&block) {
                    let found = lane.frame(poses, frame >= args.warmup)?;
                    ensure!(
                        found == *expected,
                        "frame {frame}: {threads} threads found other colliding pairs than \
                         {leader_threads} threads"
                    );
                }
                Ok(())
            })?;
        }
    }
    Ok(contenders)
}

fn stage_means(stats: &[FrameStats]) -> StageMeans {
    let n = stats.len() as f64;
    let mean = |f: &dyn Fn(&FrameStats) -> f64| stats.iter().map(f).sum::<f64>() / n;
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    StageMeans {
        box_pairs: mean(&|s| s.broad_phase.pairs_out as f64),
        interesting_pairs: mean(&|s| s.interest.pairs_out as f64),
        unseparated_pairs: mean(&|s| s.separating_plane.pairs_out as f64),
        colliding_pairs: mean(&|s| s.exact.pairs_out as f64),
        split_tests: mean(&|s| s.split_tests as f64),
        broad_phase_us: mean(&|s| us(s.broad_phase.time)),
        separating_plane_us: mean(&|s| us(s.separating_plane.time)),
        exact_us: mean(&|s| us(s.exact.time)),
    }
}

/// Runs B4 for every thread count.
pub fn run_bounce(args: &BounceArgs) -> Result<BounceReport> {
    ensure!(
        !args.threads.is_empty(),
        "--threads needs at least one count"
    );
    ensure!(
        args.threads.iter().all(|&t| t >= 1),
        "--threads: every count must be at least 1"
    );
    ensure!(
        args.fill > 0.0 && args.fill < 0.5,
        "--fill must be in (0, 0.5), not {}",
        args.fill
    );
    let models = models(args.triangles);
    let ball_volume: f64 = models
        .iter()
        .map(|m| 4.0 / 3.0 * std::f64::consts::PI * m.hull().radius().powi(3))
        .sum::<f64>()
        / models.len() as f64;
    let side = (f64::from(args.objects) * ball_volume / args.fill).cbrt();
    let mut rows: Vec<BounceRow> = Vec::new();
    for contender in run_scene(args, &models, side)? {
        let SceneRun { times, stats } = contender.lane.run;
        let mut micros: Vec<f64> = times.iter().map(|t| t.as_secs_f64() * 1e6).collect();
        let mean = micros.iter().sum::<f64>() / micros.len() as f64;
        micros.sort_by(f64::total_cmp);
        let p99 = micros[((micros.len() as f64 * 0.99).ceil() as usize).clamp(1, micros.len()) - 1];
        let speedup = rows.first().map_or(1.0, |first| first.mean_frame_us / mean);
        rows.push(BounceRow {
            threads: contender.threads,
            objects: args.objects,
            mean_frame_us: mean,
            p99_frame_us: p99,
            speedup,
            stages: stage_means(&stats),
        });
    }
    let triangles_per_object = models
        .iter()
        .map(|m| m.exact().triangle_count() as f64)
        .sum::<f64>()
        / models.len() as f64;
    Ok(BounceReport {
        benchmark: "bounce",
        frames: args.frames,
        triangles_per_object,
        cube_side: side,
        rows,
    })
}

/// The rows as a text table.
pub fn bounce_table(rows: &[BounceRow]) -> Table {
    let mut table = Table::new([
        "threads",
        "objects",
        "mean_frame_us",
        "p99_frame_us",
        "speedup",
        "box_pairs",
        "unseparated",
        "colliding",
        "split",
        "broad_us",
        "plane_us",
        "exact_us",
    ]);
    for r in rows {
        let s = &r.stages;
        table.push_row([
            r.threads.to_string(),
            r.objects.to_string(),
            report::format_number(r.mean_frame_us),
            report::format_number(r.p99_frame_us),
            report::format_number(r.speedup),
            report::format_number(s.box_pairs),
            report::format_number(s.unseparated_pairs),
            report::format_number(s.colliding_pairs),
            report::format_number(s.split_tests),
            report::format_number(s.broad_phase_us),
            report::format_number(s.separating_plane_us),
            report::format_number(s.exact_us),
        ]);
    }
    table
}

/// Speed-up against thread count, beside the ideal.
pub fn bounce_plot(rows: &[BounceRow]) -> LinePlot {
    let measured = rows.iter().map(|r| (r.threads as f64, r.speedup)).collect();
    let ideal = rows
        .iter()
        .map(|r| (r.threads as f64, r.threads as f64 / rows[0].threads as f64))
        .collect();
    LinePlot {
        title: format!(
            "B4 bouncing objects: speed-up of the pipeline ({} objects)",
            rows[0].objects
        ),
        x_label: "threads".into(),
        y_label: "speed-up".into(),
        log_x: false,
        log_y: false,
        series: vec![
            Series {
                name: "measured".into(),
                points: measured,
            },
            Series {
                name: "ideal".into(),
                points: ideal,
            },
        ],
    }
}

/// `vas-bench bounce`: runs B4, prints the table, writes JSON (and SVG).
pub fn run_cli(args: &BounceArgs) -> Result<()> {
    let report = run_bounce(args)?;
    println!(
        "{} objects of about {:.0} triangles in a cube of side {:.1}, {} frames",
        args.objects, report.triangles_per_object, report.cube_side, args.frames
    );
    println!("{}", bounce_table(&report.rows).render());
    args.output.write(&report, || bounce_plot(&report.rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: BounceArgs,
    }

    #[test]
    fn small_dense_scene_collides_and_every_thread_count_agrees() {
        let cli = Cli::parse_from([
            "bounce",
            "--objects",
            "40",
            "--frames",
            "60",
            "--threads",
            "1,2",
            "--triangles",
            "200",
            "--fill",
            "0.2",
        ]);
        let report = run_bounce(&cli.args).unwrap();
        assert_eq!(report.rows.len(), 2);
        let stages = &report.rows[0].stages;
        assert!(stages.colliding_pairs > 0.0, "{stages:?}");
        assert!(
            stages.unseparated_pairs < stages.interesting_pairs,
            "{stages:?}"
        );
        assert!(
            report
                .rows
                .iter()
                .all(|r| r.p99_frame_us >= 0.0 && r.objects == 40)
        );
    }
}
