//! B3, orbiting spheres (the paper's Figure 4): the separating-plane pre-check against parry's GJK
//! and a bounding-box test.
//!
//! Two unit spheres of a given polygon count: A stays at the identity, B's centre orbits A at
//! distance d (the spheres touch at d = 2) in a plane tilted against the axes, advancing
//! `rotation_deg` degrees per step, while B spins by the same angle per step about an axis of its
//! own. Each algorithm answers "separated or not" for every step; the truth is parry's GJK on the
//! two convex polyhedra. A wrong "not separated" costs an exact test; a wrong "separated" would be
//! a missed collision, and is reported separately (it must stay zero).
//!
//! Algorithms: the pre-check from scratch at every step (`plane_cold`) and with the plane kept
//! from step to step (`plane_cached`), parry's GJK from scratch (`gjk_cold`) and warm-started
//! with the previous step's direction and simplex (`gjk_warm`), and world bounding boxes (`bbox`).
//! Timings are per batch of steps (no clock read per query), median over repeats.

use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use parry3d::query::details::intersection_test_support_map_support_map_with_params;
use parry3d::query::gjk::VoronoiSimplex;
use parry3d::shape::ConvexPolyhedron;
use serde::Serialize;

use crate::args::OutputArgs;
use crate::report::{self, LinePlot, Series, Table};
use vas_server::collision::broad_phase::Aabb;
use vas_server::collision::separating_plane::{PlaneSearch, SeparatingPlane};
use vas_server::geometry::{ConvexHull, shapes};

/// Centre distances of B3 (touching at 2.0), denser near touching.
pub const DEFAULT_DISTANCES: [f64; 12] = [
    1.7, 1.8, 1.9, 1.95, 1.99, 2.0, 2.001, 2.01, 2.05, 2.1, 2.2, 2.3,
];

/// The paper's polygon counts.
pub const DEFAULT_POLYGONS: [usize; 2] = [132, 2652];

/// Rotation speeds in degrees per step.
pub const DEFAULT_ROTATIONS: [f64; 4] = [1.0, 5.0, 15.0, 45.0];

/// Poses whose polyhedra are closer than this fraction of the touching distance (2) are exempt
/// from the wrong-answer bar: "within 0.1 % of touching".
const TOUCHING_BAND: f64 = 1e-3;

/// Command-line arguments of `vas-bench orbit`.
#[derive(Debug, Clone, clap::Args)]
pub struct OrbitArgs {
    /// Steps (queries) per distance, rotation speed and polygon count.
    #[arg(long, default_value_t = 5000, value_parser = clap::value_parser!(u32).range(1..))]
    samples: u32,
    /// Centre distances (comma-separated; the spheres touch at 2).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_DISTANCES,
          value_parser = crate::args::finite_number)]
    distances: Vec<f64>,
    /// Polygon counts of the spheres (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_POLYGONS)]
    polygons: Vec<usize>,
    /// Rotation speeds in degrees per step (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_ROTATIONS,
          value_parser = crate::args::finite_number)]
    rotations: Vec<f64>,
    /// Timed repetitions of each batch; the median is reported.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    repeats: u32,
    #[command(flatten)]
    output: OutputArgs,
}

/// The algorithms compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Algo {
    PlaneCold,
    PlaneCached,
    GjkCold,
    GjkWarm,
    Bbox,
}

impl Algo {
    const ALL: [Algo; 5] = [
        Algo::PlaneCold,
        Algo::PlaneCached,
        Algo::GjkCold,
        Algo::GjkWarm,
        Algo::Bbox,
    ];

    fn name(self) -> &'static str {
        match self {
            Algo::PlaneCold => "plane_cold",
            Algo::PlaneCached => "plane_cached",
            Algo::GjkCold => "gjk_cold",
            Algo::GjkWarm => "gjk_warm",
            Algo::Bbox => "bbox",
        }
    }
}

/// One (algorithm, polygon count, distance, rotation speed) cell of B3.
#[derive(Debug, Clone, Serialize)]
pub struct OrbitRow {
    /// Algorithm name.
    pub algo: &'static str,
    /// Triangles of each sphere.
    pub polygons: usize,
    /// Centre distance.
    pub distance: f64,
    /// Rotation speed, degrees per step.
    pub rotation_deg: f64,
    /// Mean time per query in microseconds (median over repeats).
    pub mean_us: f64,
    /// Wrong "not separated" answers (GJK found the polyhedra apart).
    pub wrong: usize,
    /// Wrong "not separated" answers at poses where the polyhedra are more than 0.1 % of the
    /// touching distance apart.
    pub wrong_clear: usize,
    /// Wrong "separated" answers (GJK found them intersecting): a bug if not zero.
    pub wrong_separated: usize,
    /// Steps at which the polyhedra are apart (by GJK).
    pub apart: usize,
    /// Steps run.
    pub samples: usize,
    /// Mean perceptron loops per query (zero for the other algorithms).
    pub mean_loops: f64,
}

/// How B3's figures compare with the bar of issue 4.
#[derive(Debug, Clone, Serialize)]
pub struct OrbitBar {
    /// Smallest `gjk_warm / plane_cached` time ratio at the largest polygon count over distances
    /// where the spheres are apart (bar: at least 5).
    pub min_speedup_over_warm_gjk: Option<f64>,
    /// Largest `plane_cached` time ratio between the largest and smallest polygon counts over
    /// distances where the spheres are apart (bar: at most 4).
    pub max_growth_with_polygons: Option<f64>,
    /// Largest fraction of wrong "not separated" answers of `plane_cached` and `plane_cold`, over
    /// the cells, counting only poses more than 0.1 % of the touching distance apart (bar: below
    /// 0.01).
    pub max_wrong_fraction: f64,
    /// All wrong "separated" answers (must be zero).
    pub wrong_separated: usize,
}

/// The JSON document of B3.
#[derive(Debug, Clone, Serialize)]
pub struct OrbitReport {
    /// Always "orbit".
    pub benchmark: &'static str,
    /// Steps per cell.
    pub samples: u32,
    /// Timed repetitions per cell.
    pub repeats: u32,
    /// The cells.
    pub rows: Vec<OrbitRow>,
    /// The bar.
    pub bar: OrbitBar,
}

/// A sphere as each algorithm sees it.
struct Sphere {
    polygons: usize,
    hull: ConvexHull,
    polyhedron: ConvexPolyhedron,
    local_bounds: Aabb,
}

impl Sphere {
    fn new(polygons: usize) -> Result<Sphere> {
        let mesh = shapes::sphere(1.0, polygons);
        let hull = ConvexHull::of(&mesh);
        let points: Vec<_> = hull.vertices().iter().map(|p| p.cast::<f32>()).collect();
        let polyhedron = ConvexPolyhedron::from_convex_hull(&points).with_context(|| {
            format!("parry cannot build the hull of the {polygons}-polygon sphere")
        })?;
        let (min, max) = mesh.bounding_box();
        Ok(Sphere {
            polygons: mesh.triangles().len(),
            hull,
            polyhedron,
            local_bounds: Aabb { min, max },
        })
    }
}

/// B's pose at step `step`: orbit and spin by `rotation_deg` degrees per step at centre distance
/// `distance`.
pub fn orbit_pose(distance: f64, rotation_deg: f64, step: u32) -> Isometry3<f64> {
    let angle = (rotation_deg * f64::from(step)).to_radians();
    let orbit_axis = Unit::new_normalize(Vector3::new(0.2, -0.3, 1.0));
    let start = orbit_axis.cross(&Vector3::x()).normalize() * distance;
    let spin_axis = Unit::new_normalize(Vector3::new(0.7, 0.5, -0.2));
    Isometry3::from_parts(
        Translation3::from(UnitQuaternion::from_axis_angle(&orbit_axis, angle) * start),
        UnitQuaternion::from_axis_angle(&spin_axis, angle),
    )
}

/// Runs `algo` over all `poses`, writing its answers ("separated") and returning the time and the
/// perceptron loops run.
fn run_batch(
    algo: Algo,
    a: &Sphere,
    b: &Sphere,
    poses: &[Isometry3<f64>],
    poses_f32: &[Isometry3<f32>],
    answers: &mut Vec<bool>,
) -> (Duration, u64) {
    answers.clear();
    let search = PlaneSearch::default();
    let mut loops = 0u64;
    let start = Instant::now();
    match algo {
        Algo::PlaneCold => {
            for pose in poses {
                let check = SeparatingPlane::new().check(&a.hull, &b.hull, pose, &search);
                loops += u64::from(check.loops);
                answers.push(check.separated);
            }
        }
        Algo::PlaneCached => {
            let mut plane = SeparatingPlane::new();
            for pose in poses {
                let check = plane.check(&a.hull, &b.hull, pose, &search);
                loops += u64::from(check.loops);
                answers.push(check.separated);
            }
        }
        Algo::GjkCold => {
            for pose in poses_f32 {
                let (hit, _) = intersection_test_support_map_support_map_with_params(
                    pose,
                    &a.polyhedron,
                    &b.polyhedron,
                    &mut VoronoiSimplex::new(),
                    None,
                );
                answers.push(!hit);
            }
        }
        Algo::GjkWarm => {
            let mut simplex = VoronoiSimplex::new();
            let mut direction = None;
            for pose in poses_f32 {
                let (hit, next) = intersection_test_support_map_support_map_with_params(
                    pose,
                    &a.polyhedron,
                    &b.polyhedron,
                    &mut simplex,
                    direction,
                );
                direction = Some(next);
                answers.push(!hit);
            }
        }
        Algo::Bbox => {
            for pose in poses {
                let b_box = Aabb::transformed(&b.local_bounds, pose);
                answers.push(!a.local_bounds.overlaps(&b_box));
            }
        }
    }
    (start.elapsed(), loops)
}

/// Runs B3 over every polygon count, rotation speed and distance.
pub fn run_orbit(args: &OrbitArgs) -> Result<OrbitReport> {
    let mut rows = Vec::new();
    let mut answers = Vec::with_capacity(args.samples as usize);
    for &polygons in &args.polygons {
        let a = Sphere::new(polygons)?;
        let b = Sphere::new(polygons)?;
        for &rotation_deg in &args.rotations {
            for &distance in &args.distances {
                let poses: Vec<_> = (0..args.samples)
                    .map(|step| orbit_pose(distance, rotation_deg, step))
                    .collect();
                let poses_f32: Vec<Isometry3<f32>> = poses.iter().map(|p| p.cast()).collect();
                run_batch(Algo::GjkCold, &a, &b, &poses, &poses_f32, &mut answers);
                let truth = answers.clone();
                let apart = truth.iter().filter(|&&apart| apart).count();
                let clear: Vec<bool> = poses_f32
                    .iter()
                    .map(|pose| {
                        let gap = parry3d::query::distance(
                            &Isometry3::identity(),
                            &a.polyhedron,
                            pose,
                            &b.polyhedron,
                        );
                        gap.is_ok_and(|gap| f64::from(gap) > 2.0 * TOUCHING_BAND)
                    })
                    .collect();
                for algo in Algo::ALL {
                    let mut means = Vec::new();
                    let mut loops = 0;
                    for _ in 0..args.repeats {
                        let (time, batch_loops) =
                            run_batch(algo, &a, &b, &poses, &poses_f32, &mut answers);
                        means.push(time.as_secs_f64() * 1e6 / poses.len() as f64);
                        loops = batch_loops;
                    }
                    let count = |wanted: bool| {
                        truth
                            .iter()
                            .zip(&answers)
                            .filter(|&(&apart, &separated)| apart == wanted && separated != apart)
                            .count()
                    };
                    let wrong_clear = (0..poses.len())
                        .filter(|&i| truth[i] && clear[i] && !answers[i])
                        .count();
                    rows.push(OrbitRow {
                        algo: algo.name(),
                        polygons: a.polygons,
                        distance,
                        rotation_deg,
                        mean_us: report::median(&mut means),
                        wrong: count(true),
                        wrong_clear,
                        wrong_separated: count(false),
                        apart,
                        samples: poses.len(),
                        mean_loops: loops as f64 / poses.len() as f64,
                    });
                }
            }
        }
    }
    let bar = bar(&rows);
    Ok(OrbitReport {
        benchmark: "orbit",
        samples: args.samples,
        repeats: args.repeats,
        rows,
        bar,
    })
}

/// Evaluates the bar of issue 4 on the rows.
fn bar(rows: &[OrbitRow]) -> OrbitBar {
    let find = |algo: &str, polygons: usize, distance: f64, rotation: f64| {
        rows.iter().find(|r| {
            r.algo == algo
                && r.polygons == polygons
                && r.distance == distance
                && r.rotation_deg == rotation
        })
    };
    let most = rows.iter().map(|r| r.polygons).max().unwrap_or(0);
    let least = rows.iter().map(|r| r.polygons).min().unwrap_or(0);
    let apart_cells = rows
        .iter()
        .filter(|r| r.algo == "plane_cached" && r.distance > 2.0);
    let mut speedups = Vec::new();
    let mut growths = Vec::new();
    for cell in apart_cells.filter(|r| r.polygons == most) {
        if let Some(gjk) = find("gjk_warm", most, cell.distance, cell.rotation_deg) {
            speedups.push(gjk.mean_us / cell.mean_us);
        }
        if let Some(small) = find("plane_cached", least, cell.distance, cell.rotation_deg)
            && least < most
        {
            growths.push(cell.mean_us / small.mean_us);
        }
    }
    let max_wrong_fraction = rows
        .iter()
        .filter(|r| r.algo.starts_with("plane"))
        .map(|r| r.wrong_clear as f64 / r.samples as f64)
        .fold(0.0, f64::max);
    OrbitBar {
        min_speedup_over_warm_gjk: speedups.into_iter().reduce(f64::min),
        max_growth_with_polygons: growths.into_iter().reduce(f64::max),
        max_wrong_fraction,
        wrong_separated: rows.iter().map(|r| r.wrong_separated).sum(),
    }
}

/// The rows as a text table.
pub fn orbit_table(rows: &[OrbitRow]) -> Table {
    let mut table = Table::new([
        "algo",
        "polygons",
        "distance",
        "rot_deg",
        "mean_us",
        "wrong",
        "clear",
        "wrong_sep",
        "apart",
        "loops",
    ]);
    for r in rows {
        table.push_row([
            r.algo.to_string(),
            r.polygons.to_string(),
            r.distance.to_string(),
            r.rotation_deg.to_string(),
            report::format_number(r.mean_us),
            r.wrong.to_string(),
            r.wrong_clear.to_string(),
            r.wrong_separated.to_string(),
            r.apart.to_string(),
            report::format_number(r.mean_loops),
        ]);
    }
    table
}

/// Time per query against distance for each algorithm and polygon count, averaged over rotation
/// speeds.
pub fn orbit_plot(rows: &[OrbitRow]) -> LinePlot {
    let mut keys: Vec<(&str, usize)> = rows.iter().map(|r| (r.algo, r.polygons)).collect();
    keys.dedup();
    keys.sort_unstable();
    keys.dedup();
    let series = keys
        .into_iter()
        .map(|(algo, polygons)| {
            let mut distances: Vec<f64> = rows.iter().map(|r| r.distance).collect();
            distances.sort_by(f64::total_cmp);
            distances.dedup();
            let points = distances
                .into_iter()
                .map(|d| {
                    let times: Vec<f64> = rows
                        .iter()
                        .filter(|r| r.algo == algo && r.polygons == polygons && r.distance == d)
                        .map(|r| r.mean_us)
                        .collect();
                    (d, times.iter().sum::<f64>() / times.len() as f64)
                })
                .collect();
            Series {
                name: format!("{algo} ({polygons})"),
                points,
            }
        })
        .collect();
    LinePlot {
        title: "B3 orbiting spheres: time per query (mean over rotation speeds)".into(),
        x_label: "centre distance (touching at 2)".into(),
        y_label: "time per query / us".into(),
        log_x: false,
        log_y: true,
        series,
    }
}

/// `vas-bench orbit`: runs B3, prints the table and the bar, writes JSON (and SVG).
pub fn run_cli(args: &OrbitArgs) -> Result<()> {
    let report = run_orbit(args)?;
    println!("{}", orbit_table(&report.rows).render());
    let bar = &report.bar;
    let show = |value: Option<f64>| value.map_or("n/a".to_owned(), report::format_number);
    println!(
        "bar: plane_cached vs gjk_warm at {} polygons, apart: min speed-up {} (>= 5)",
        report.rows.iter().map(|r| r.polygons).max().unwrap_or(0),
        show(bar.min_speedup_over_warm_gjk)
    );
    println!(
        "bar: plane_cached time growth from fewest to most polygons, apart: max {} (<= 4)",
        show(bar.max_growth_with_polygons)
    );
    println!(
        "bar: wrong 'not separated' with the polyhedra over 0.1% of touching apart: max {:.3}% \
         (< 1%); wrong 'separated': {} (must be 0)",
        bar.max_wrong_fraction * 100.0,
        bar.wrong_separated
    );
    args.output.write(&report, || orbit_plot(&report.rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: OrbitArgs,
    }

    #[test]
    fn small_orbit_run_finds_planes_when_apart_and_never_wrongly_separates() {
        let cli = Cli::parse_from([
            "orbit",
            "--samples",
            "300",
            "--distances",
            "1.8,2.2",
            "--polygons",
            "132",
            "--rotations",
            "10",
            "--repeats",
            "1",
        ]);
        let report = run_orbit(&cli.args).unwrap();
        assert_eq!(report.rows.len(), 2 * Algo::ALL.len());
        for row in &report.rows {
            assert_eq!(row.wrong_separated, 0, "{row:?}");
            if row.distance > 2.0 {
                assert_eq!(row.apart, 300);
                if row.algo.starts_with("plane") || row.algo.starts_with("gjk") {
                    assert_eq!(row.wrong, 0, "{row:?}");
                }
            } else {
                assert_eq!(row.apart, 0, "the 132-polygon spheres overlap at 1.8");
            }
        }
        assert!(orbit_plot(&report.rows).series.len() == Algo::ALL.len());
    }
}
